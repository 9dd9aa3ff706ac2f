"""Force elements: the linear point-to-point spring-damper, the torsional spring-damper of a
revolute joint, and a torque on a rigid body.

The points are nodes of meshed bodies, points of rigid bodies (or point masses), or a fixed
anchor; each position is linear in its coordinates, so with x = q[dofs] (k,) the vector
between them is ``d = D x + d_0`` (D (3, k) constant, d_0 the anchor).  With L = |d|,
n = d / L and the rate L' = n . D x', the force along the element is
``f = k (L - L0) + c L'`` and the generalised force is ``Q = -f D^T n``; its exact Jacobians

    dQ/dx  = -D^T [k n n^T + c n (D x' - n L')^T / L + f (I - n n^T) / L] D,
    dQ/dx' = -c D^T n n^T D

(``SpringDamperForce``; both engines evaluate it as a state load, ``runtime.model.dae``).

The torsional spring-damper (``TorsionalSpringForce``) acts on the relative rotation phi of
a joint about its axis, given by two quadratic forms [C, S] = sqrt(rho) [cos phi, sin phi] of its
coordinates (``runtime.model.items.body_joints.angle_forms``; rho = C^2 + S^2):
phi = atan2(S, C), with the exact gradient and Hessian

    phi_x  = (C S_x - S C_x) / rho,
    phi_xx = (S_x C_x^T - C_x S_x^T + C S_xx - S C_xx) / rho
             - phi_x (2 C C_x + 2 S S_x)^T / rho;

its moment m = k (phi - phi_0) + c phi' (phi' = phi_x . x') gives Q = -m phi_x, with
dQ/dx = -phi_x (k phi_x + c phi_xx x')^T - m phi_xx and dQ/dx' = -c phi_x phi_x^T.  The
spring counts turns: phi is unwrapped from ``turned``, its angle at the last accepted state
(0 at the start of a run), as phi = turned + remainder(atan2(S, C) - turned, 2 pi): smooth
in x for any rotation of less than half a turn per step, so the derivatives above hold; the
engines move ``turned`` on at every accepted step (``accept``).

The linear bushing (``BushingForce``) acts on six quadratic forms delta(x) of the
coordinates (relative displacements and small rotations of two frames), with the energy
delta^T K delta / 2 and the damping C: with J = delta_x, H_i the Hessians and the
generalised stress m = K delta + C J x',

    Q = -J^T m,   dQ/dx = -J^T K J - sum_i m_i H_i - J^T C [H_i x']_i,   dQ/dx' = -J^T C J.

Every force element is also data for the compiled step (``compiled``: a ``CompiledForce``):
rows y(x) = 1/2 x^T H x + g . x + c of its coordinates (a ``QuadraticBlock``: the spring's
d, the joint's [C, S], the bushing's delta) and a law of the generalised stress m(y, y')
on them (``FORCE_LAWS``), so that, with J = y_x and y' = J x', one generic evaluation

    Q = -J^T m,   dQ/dx = -J^T (m_y J + m_y' [H_i x']_i) - sum_i m_i H_i,
    dQ/dx' = -J^T m_y' J

holds them all (``templates/stepper.c.j2``, ``force_elements``); the law ``direct`` takes
the rows as the force itself (Q = y, dQ/dx = J: the body torque, quadratic in the
coordinates).  The classes here evaluate their own formulas: the Python engine's, and the
independent check of the compiled one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from runtime.model.holonomic import QuadraticBlock
from runtime.model.items.follower import Patches
from runtime.model.items.python_loads import MotionPatches
from runtime.model.items.rigid import PERP

__all__ = ["FORCE_LAWS", "BodyTorqueForce", "BushingForce", "CompiledForce",
           "SpringDamperForce", "TorsionalSpringForce"]

#: the laws of the compiled force elements, in the order of the step's codes
#: (``templates/stepper.c.j2``): their parameters are those of ``CompiledForce``
FORCE_LAWS = ("spring_damper", "torsional_spring", "bushing", "direct")


@dataclass(frozen=True)
class CompiledForce:
    """A force element as data of the compiled step (module docstring): its ``law`` (one of
    ``FORCE_LAWS``), its rows ``forms`` (on its coordinates ``forms.dofs``; the law
    ``direct``: one row per coordinate, the force on it) and the law's ``parameters``:
    spring_damper [k, c, L0], torsional_spring [k, c, phi_0], bushing [K (36, row-major),
    C (36)], direct []."""

    law: str
    forms: QuadraticBlock
    parameters: np.ndarray

    def __post_init__(self) -> None:
        assert self.law in FORCE_LAWS, self.law
        if self.law == "direct":
            assert self.forms.rows == self.forms.dofs.size


class SpringDamperForce:
    """The state force of a spring-damper of ``stiffness`` k (N/m), ``damping`` c (N s/m) and
    rest length ``length`` L0 (m) over the coordinates ``dofs`` (k,), with the map
    ``difference`` D (dim, k) and the constant ``offset`` d_0 (dim,) of d = D x + d_0.  Reads
    velocities (``reads_velocity``)."""

    reads_velocity = True

    def __init__(self, dofs: np.ndarray, difference: np.ndarray, offset: np.ndarray,
                 stiffness: float, damping: float, length: float) -> None:
        self.dofs = np.asarray(dofs, np.int64)[None, :]
        self.difference, self.offset = difference, np.asarray(offset, float)
        self.stiffness, self.damping, self.length = stiffness, damping, length

    def compiled(self) -> CompiledForce:
        """Its data for the compiled step: the rows d = D x + d_0, three of them (the step's
        law is 3D: a 2D spring's third row is 0)."""
        k, dim = self.dofs.shape[1], self.difference.shape[0]
        forms = QuadraticBlock("spring_damper", self.dofs[0], np.zeros((3, k, k)),
                               np.vstack([self.difference, np.zeros((3 - dim, k))]),
                               np.concatenate([self.offset, np.zeros(3 - dim)]))
        return CompiledForce("spring_damper", forms,
                             np.array([self.stiffness, self.damping, self.length]))

    def vector(self, q: np.ndarray) -> np.ndarray:
        """d (dim,) at the coordinates q (size,)."""
        return self.difference @ q[self.dofs[0]] + self.offset

    def energy(self, q: np.ndarray) -> float:
        """The energy k (L - L0)^2 / 2 (J) in its spring at q (size,)."""
        return 0.5 * self.stiffness * (float(np.linalg.norm(self.vector(q))) - self.length) ** 2

    def __call__(self, q: np.ndarray, jacobian: bool, v: np.ndarray | None = None,
                 t: float = 0.0) -> MotionPatches:
        dofs = self.dofs[0]
        D = self.difference
        d = self.vector(q)
        length = float(np.linalg.norm(d))
        if length == 0.0:
            raise ZeroDivisionError("a spring-damper of zero length has no direction")
        n = d / length
        rate_vector = np.zeros(D.shape[0]) if v is None else D @ v[dofs]
        rate = float(n @ rate_vector)
        f = self.stiffness * (length - self.length) + self.damping * rate
        force = -f * (D.T @ n)
        if not jacobian:
            return MotionPatches(self.dofs, force[None], None, None)
        across = (np.eye(n.size) - np.outer(n, n)) / length
        inner = (self.stiffness * np.outer(n, n)
                 + self.damping * np.outer(n, rate_vector - n * rate) / length + f * across)
        d_q = -D.T @ inner @ D
        d_v = -self.damping * D.T @ np.outer(n, n) @ D
        return MotionPatches(self.dofs, force[None], d_q[None], d_v[None])


class TorsionalSpringForce:
    """The state force of a torsional spring-damper of ``stiffness`` k (N m/rad),
    ``damping`` c (N m s/rad) and free angle ``angle`` phi_0 (rad) on the relative rotation
    phi of a joint, given by its ``forms`` (a ``QuadraticBlock`` of the two rows [C, S] =
    sqrt(rho) [cos phi, sin phi] on its coordinates; module docstring); phi counts turns
    from ``turned`` (rad), its value at the last accepted state.  Reads velocities
    (``reads_velocity``)."""

    reads_velocity = True

    def __init__(self, forms: QuadraticBlock, stiffness: float, damping: float,
                 angle: float) -> None:
        self.forms = forms
        self.dofs = np.asarray(forms.dofs, np.int64)[None, :]
        self.stiffness, self.damping, self.angle = stiffness, damping, angle
        #: the unwrapped joint angle phi (rad) at the last accepted state (``accept``)
        self.turned = 0.0

    def compiled(self) -> CompiledForce:
        """Its data for the compiled step: the rows [C, S]."""
        return CompiledForce("torsional_spring", self.forms,
                             np.array([self.stiffness, self.damping, self.angle]))

    def joint_angle(self, q: np.ndarray, near: float | None = None) -> float:
        """The joint angle phi (rad) at the coordinates q (size,): the branch of atan2(S, C)
        within half a turn of ``near`` (default ``turned``)."""
        c, s = self.forms.value(q[self.dofs[0]])
        near = self.turned if near is None else near
        return near + math.remainder(math.atan2(s, c) - near, 2.0 * math.pi)

    def accept(self, q: np.ndarray) -> None:
        """Count the turns up to the accepted coordinates q (size,)."""
        self.turned = self.joint_angle(q)

    def deflection(self, q: np.ndarray, near: float | None = None) -> float:
        """phi - phi_0 (rad) at the coordinates q (size,), phi near ``near`` (``joint_angle``)."""
        return self.joint_angle(q, near) - self.angle

    def energy(self, q: np.ndarray, near: float | None = None) -> float:
        """The energy k (phi - phi_0)^2 / 2 (J) in its spring at q (size,), phi near
        ``near`` (``joint_angle``)."""
        return 0.5 * self.stiffness * self.deflection(q, near) ** 2

    def __call__(self, q: np.ndarray, jacobian: bool, v: np.ndarray | None = None,
                 t: float = 0.0) -> MotionPatches:
        x = q[self.dofs[0]]
        (c, s), (dc, ds) = self.forms.value(x), self.forms.jacobian(x)
        rho = c * c + s * s
        if rho == 0.0:
            raise ZeroDivisionError("a torsional spring whose joint vectors vanish")
        grad = (c * ds - s * dc) / rho                          # phi_x (k,)
        rate_vector = np.zeros_like(x) if v is None else v[self.dofs[0]]
        moment = self.stiffness * self.deflection(q) + self.damping * float(grad @ rate_vector)
        force = -moment * grad
        if not jacobian:
            return MotionPatches(self.dofs, force[None], None, None)
        hc, hs = self.forms.hessians
        hessian = ((np.outer(ds, dc) - np.outer(dc, ds) + c * hs - s * hc) / rho
                   - np.outer(grad, 2 * c * dc + 2 * s * ds) / rho)
        d_q = (-np.outer(grad, self.stiffness * grad + self.damping * (hessian @ rate_vector))
               - moment * hessian)
        d_v = -self.damping * np.outer(grad, grad)
        return MotionPatches(self.dofs, force[None], d_q[None], d_v[None])


class BushingForce:
    """The state force of a linear bushing (module docstring) on the six rows of ``forms``
    (a ``QuadraticBlock``: displacements in m, small rotations in rad), ``stiffness`` K
    and ``damping`` C (6, 6; N/m, N/rad, N m/m, N m/rad and their rates).  Reads
    velocities (``reads_velocity``)."""

    reads_velocity = True

    def __init__(self, forms: QuadraticBlock, stiffness: np.ndarray,
                 damping: np.ndarray) -> None:
        self.forms = forms
        self.dofs = np.asarray(forms.dofs, np.int64)[None, :]
        self.stiffness, self.damping = np.asarray(stiffness), np.asarray(damping)

    def compiled(self) -> CompiledForce:
        """Its data for the compiled step: the rows delta."""
        return CompiledForce("bushing", self.forms,
                             np.concatenate([self.stiffness.ravel(), self.damping.ravel()]))

    def deflection(self, q: np.ndarray) -> np.ndarray:
        """delta (6,) at the coordinates q (size,)."""
        return self.forms.value(q[self.dofs[0]])

    def energy(self, q: np.ndarray) -> float:
        """The energy delta^T K delta / 2 (J) in its springs at q (size,)."""
        delta = self.deflection(q)
        return 0.5 * float(delta @ self.stiffness @ delta)

    def __call__(self, q: np.ndarray, jacobian: bool, v: np.ndarray | None = None,
                 t: float = 0.0) -> MotionPatches:
        x = q[self.dofs[0]]
        rate_vector = np.zeros_like(x) if v is None else v[self.dofs[0]]
        slope = self.forms.jacobian(x)                              # J (6, k)
        stress = self.stiffness @ self.forms.value(x) + self.damping @ (slope @ rate_vector)
        force = -slope.T @ stress
        if not jacobian:
            return MotionPatches(self.dofs, force[None], None, None)
        hessians = self.forms.hessians
        d_q = (-slope.T @ self.stiffness @ slope - np.tensordot(stress, hessians, 1)
               - slope.T @ self.damping @ (hessians @ rate_vector))
        d_v = -slope.T @ self.damping @ slope
        return MotionPatches(self.dofs, force[None], d_q[None], d_v[None])


def _cross_matrix(x: np.ndarray) -> np.ndarray:
    """[x]_x (3, 3): [x]_x y = x cross y."""
    return np.array([[0.0, -x[2], x[1]], [x[2], 0.0, -x[0]], [-x[1], x[0], 0.0]])


class BodyTorqueForce:
    """A torque ``torque`` T (N m) about the body axis n (``axis``, body coordinates, unit)
    of a rigid body in natural coordinates [r0, u_1, u_2, u_3] at ``dofs`` (12,): the
    moment M = T sum_b n_b u_b turns with the body.  Its generalised force does the virtual
    work M . d theta of the rotations d u_a = d theta x u_a: ``Q_a = M x u_a / 2`` (then
    sum_a u_a x Q_a = M for an orthonormal frame), with the exact Jacobian
    ``dQ_a/du_c = (T n_c [u_a]_x^T + delta_ac [M]_x) / 2``.  In 2D ([r0, u] at ``dofs``
    (4,), the torque about z, ``axis`` unused) d u = d theta perp(u): ``Q_u = T perp(u)``
    (u . u = 1), linear, with the constant Jacobian T PERP."""

    def __init__(self, dofs: np.ndarray, axis: np.ndarray, torque: float) -> None:
        self.dofs = np.asarray(dofs, np.int64)[None, :]
        self.axis, self.torque = np.asarray(axis, float), float(torque)
        self.planar = self.dofs.shape[1] == 4

    def compiled(self) -> CompiledForce:
        """Its data for the compiled step: Q itself, quadratic in the coordinates with the
        Hessians H_i whose columns are the (linear) Jacobian at the unit coordinates; in 2D
        linear (no Hessians, the constant Jacobian)."""
        dofs = self.dofs[0]
        if self.planar:
            jacobian = self(np.zeros(int(dofs.max()) + 1), True).jacobian[0]
            forms = QuadraticBlock("body_torque", dofs, np.zeros((4, 4, 4)), jacobian,
                                   np.zeros(4))
            return CompiledForce("direct", forms, np.zeros(0))
        hessians = np.empty((12, 12, 12))
        for column in range(12):
            unit = np.zeros(int(dofs.max()) + 1)
            unit[dofs[column]] = 1.0
            hessians[:, :, column] = self(unit, True).jacobian[0]
        forms = QuadraticBlock("body_torque", dofs, hessians, np.zeros((12, 12)),
                               np.zeros(12))
        return CompiledForce("direct", forms, np.zeros(0))

    def __call__(self, q: np.ndarray, jacobian: bool) -> Patches:
        if self.planar:
            d_q = np.zeros((4, 4))
            d_q[2:, 2:] = self.torque * PERP
            force = d_q @ q[self.dofs[0]]
            return Patches(self.dofs, force[None], d_q[None] if jacobian else None)
        axes = q[self.dofs[0][3:]].reshape(3, 3)           # rows u_1, u_2, u_3
        moment = self.torque * (self.axis @ axes)         # M (3,)
        force = np.zeros(12)
        for a in range(3):
            force[3 + 3 * a:6 + 3 * a] = 0.5 * np.cross(moment, axes[a])
        if not jacobian:
            return Patches(self.dofs, force[None], None)
        d_q = np.zeros((12, 12))
        spin = _cross_matrix(moment)
        for a in range(3):
            rows = slice(3 + 3 * a, 6 + 3 * a)
            for c in range(3):
                block = -0.5 * self.torque * self.axis[c] * _cross_matrix(axes[a])
                if a == c:
                    block = block + 0.5 * spin
                d_q[rows, 3 + 3 * c:6 + 3 * c] = block
        return Patches(self.dofs, force[None], d_q[None])
