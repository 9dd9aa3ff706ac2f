"""State-dependent (follower) loads: generalised forces f(q) with their exact Jacobians df/dq.

A follower load is evaluated at points of elements (a node, Gauss points along an edge or a
beam axis, Gauss points over a plate's mid-surface).  At a point, the position, and the
gradient vectors that define its frame, are linear in the element coordinates q_e (n,):
``r = N q_e``, ``a = A q_e``, ``b = B q_e`` with constant maps (dim, n) from the shape
functions.  Every formula below is written once with ``Dual`` numbers (a value and its
derivative with respect to q_e), so the Jacobian is exact (to round-off) by construction.

Frames: in 3D the modified Gram-Schmidt frame of an ordered pair (a, b) of gradients:
``u = a/|a|``, ``v`` the unit part of b normal to u, ``w = u x v``; the pair (r_x, r_y) gives
the columns (t1, t2, t3) = (u, v, w) (the frame of ``frame =`` sensors,
``runtime.element.reference.gradient_frame``), (r_y, r_z) gives (w, u, v) and (r_z, r_x)
gives (v, w, u) (cyclic).  Forces follow the first frame (the second on nodes without r_x);
moments act on a section, the frame of the section's gradients: (r_y, r_z) at a beam or
plate node and along a plate edge x = const, (r_z, r_x) along an edge y = const.  In 2D
the frame of one vector a: ``t1 = a/|a|``, ``t2 = t1`` turned by +90 degrees (forces: a =
r_x, or r_y turned by -90 degrees; moments: the angle of a = r_y, of r_x on a cable).

Rotation of the frame (its virtual rotation d theta, with d t = d theta x t for every column):

    d theta . w = v . da / |a|,   d theta . v = -w . da / |a|,
    d theta . u = (w . db - (b . u)(w . da) / |a|) / |b_n|          (b_n = b - (b . u) u)

so a moment M does the virtual work M . d theta = alpha . da + beta . db with

    alpha = ((M.w) v - (M.v) w - (M.u)(b.u)/|b_n| w) / |a|,   beta = (M.u) / |b_n| w,

and its generalised force is ``A^T alpha + B^T beta``.  In 2D, d theta = (a x da) / |a|^2
and the force is ``A^T (M perp(a) / |a|^2)``.  A follower moment is M = R m (m its
components in the frame, constant: M.u etc. are constants); a fixed one is constant in space.
A follower force is ``N^T (R f)``.  A pressure p on a plate's mid-surface acts along the unit
normal n = (r_x x r_y)/|r_x x r_y| per unit reference area: ``N^T p n dA0``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["Dual", "FrameLoad", "Patches", "PointMaps", "PressureLoad"]


class Dual:
    """A value (..., d) and its derivative (..., d, n) with respect to n coordinates (forward
    mode); scalars are kept as (..., 1).  Only the operations the loads use."""

    __slots__ = ("val", "der")

    def __init__(self, val: np.ndarray, der: np.ndarray) -> None:
        self.val, self.der = val, der

    @staticmethod
    def linear(maps: np.ndarray, q: np.ndarray) -> Dual:
        """``maps @ q``: maps (..., d, n), q (..., n)."""
        return Dual(np.einsum("...dn,...n->...d", maps, q), maps)

    def __add__(self, other: Dual) -> Dual:
        return Dual(self.val + other.val, self.der + other.der)

    def __sub__(self, other: Dual) -> Dual:
        return Dual(self.val - other.val, self.der - other.der)

    def __neg__(self) -> Dual:
        return Dual(-self.val, -self.der)

    def __mul__(self, other: Dual | np.ndarray | float) -> Dual:
        if isinstance(other, Dual):
            return Dual(self.val * other.val, self.der * other.val[..., None]
                        + self.val[..., None] * other.der)
        other = np.asarray(other, float)
        return Dual(self.val * other, self.der * other[..., None])

    __rmul__ = __mul__

    def __truediv__(self, other: Dual) -> Dual:
        inverse = 1.0 / other.val
        return self * Dual(inverse, -other.der * (inverse * inverse)[..., None])

    def dot(self, other: Dual | np.ndarray) -> Dual:
        """Scalar product over the last axis (a scalar (..., 1))."""
        product = self * other
        return Dual(product.val.sum(-1, keepdims=True), product.der.sum(-2, keepdims=True))

    def norm(self) -> Dual:
        square = self.dot(self)
        root = np.sqrt(square.val)
        return Dual(root, square.der / (2 * root)[..., None])

    def cross(self, other: Dual) -> Dual:
        """Vector product of 3-vectors."""
        val = np.cross(self.val, other.val)
        der = (np.cross(self.der, other.val[..., :, None], axis=-2)
               + np.cross(self.val[..., :, None], other.der, axis=-2))
        return Dual(val, der)

    def perp(self) -> Dual:
        """A 2-vector turned by +90 degrees: (-y, x)."""
        return Dual(np.stack([-self.val[..., 1], self.val[..., 0]], -1),
                    np.stack([-self.der[..., 1, :], self.der[..., 0, :]], -2))


@dataclass
class Patches:
    """Generalised forces of a load on groups of coordinates: global coordinate indices
    ``dofs`` (m, k), forces ``force`` (m, k) in N (per coordinate) and their Jacobians
    ``jacobian`` (m, k, k) = d force / d q[dofs] (None when not asked)."""

    dofs: np.ndarray
    force: np.ndarray
    jacobian: np.ndarray | None


@dataclass
class PointMaps:
    """Points of ``m`` coordinate groups (elements, or single nodes), ``p`` per group: the
    global coordinates ``dofs`` (m, n) and per point the linear maps (m or 1, p, dim, n) of
    the position ``position`` and of the frame's gradients ``a`` and ``b`` (``b`` None in 2D),
    the frame ``order`` (the axes of (a, b): "xy", "yz" or "zx"; "" in 2D), and the
    weights ``weights`` (m or 1, p) (m, m^2 or 1 per point)."""

    dofs: np.ndarray
    position: np.ndarray
    a: np.ndarray
    b: np.ndarray | None
    order: str
    weights: np.ndarray

    def frame(self, q_e: np.ndarray) -> tuple[list[Dual], Dual, Dual | None, Dual | None]:
        """Frame columns [t1, t2(, t3)] at element coordinates q_e (m, n), and the vectors
        (a, b) and |b_n| the rotation needs (b, |b_n| None in 2D)."""
        a = Dual.linear(self.a, q_e[:, None, :])
        if self.b is None:
            u = a / a.norm()
            return [u, u.perp()], a, None, None
        b = Dual.linear(self.b, q_e[:, None, :])
        u = a / a.norm()
        normal = b - u * b.dot(u)
        length = normal.norm()
        v = normal / length
        w = u.cross(v)
        first = "xyz".index(self.order[0])
        columns = [u, u, u]
        for k, vector in enumerate((u, v, w)):
            columns[(first + k) % 3] = vector
        return columns, a, b, length

    def apply(self, vector: Dual, maps: np.ndarray, jacobian: bool):
        """Weighted sums over the points of maps^T vector: forces (m, n) and Jacobians
        (m, n, n) (None when not asked)."""
        shape = vector.val.shape[:2]
        weighted = np.broadcast_to(self.weights, shape)[..., None, None] * maps
        force = np.einsum("mpdn,mpd->mn", weighted, vector.val)
        if not jacobian:
            return force, None
        return force, np.einsum("mpdn,mpdk->mnk", weighted, vector.der)

    def local(self, q0: np.ndarray, vector: np.ndarray) -> np.ndarray:
        """Components (m, p, dim) in the frames at coordinates q0 (size,) of a vector given
        in global components (dim,)."""
        frame = self.frame(q0[self.dofs])[0]
        return np.stack([np.sum(t.val * np.asarray(vector, float), -1) for t in frame], -1)


def _columns(vectors: list[Dual], components: np.ndarray) -> Dual:
    """sum_c components[..., c] * vectors[c]: the vector of frame components (m, p, dim)."""
    total = vectors[0] * components[..., 0:1]
    for c in range(1, len(vectors)):
        total = total + vectors[c] * components[..., c:c + 1]
    return total


@dataclass
class FrameLoad:
    """A follower force ``force`` (m, p, dim) in N (or N/m) at the points of ``maps`` or a
    follower moment ``moment`` (m, p, 3) in N m (or N m/m), both as components in the
    deformed frame (constant); in 2D the moment (m, p, 1) is about z."""

    maps: PointMaps
    force: np.ndarray | None = None
    moment: np.ndarray | None = None

    def __call__(self, q: np.ndarray, jacobian: bool) -> Patches:
        maps = self.maps
        frame, a, b, length = maps.frame(q[maps.dofs])
        if self.force is not None:
            force, jac = maps.apply(_columns(frame, self.force), maps.position, jacobian)
            return Patches(maps.dofs, force, jac)
        if b is None:
            force, jac = maps.apply(a.perp() * self.moment / a.dot(a), maps.a, jacobian)
            return Patches(maps.dofs, force, jac)
        # M . d theta = alpha . da + beta . db with M.u, M.v, M.w the constant components
        axes = ["xyz".index(maps.order[0]) + k for k in range(3)]
        u, v, w = (frame[i % 3] for i in axes)
        mu, mv, mw = (self.moment[..., i % 3:i % 3 + 1] for i in axes)
        alpha = (v * mw - w * mv - w * (b.dot(u) / length) * mu) / a.norm()
        beta = w * mu / length
        force, jac = maps.apply(alpha, maps.a, jacobian)
        force_b, jac_b = maps.apply(beta, maps.b, jacobian)
        return Patches(maps.dofs, force + force_b, None if jac is None else jac + jac_b)


@dataclass
class PressureLoad:
    """A pressure ``pressure`` (Pa) along the unit normal r_x x r_y of a plate mid-surface,
    per unit reference area, at the points of ``maps`` (``a``, ``b``: the maps of r_x and
    r_y; weights: Gauss weights times dA0 in m^2)."""

    maps: PointMaps
    pressure: float

    def __call__(self, q: np.ndarray, jacobian: bool) -> Patches:
        maps = self.maps
        q_e = q[maps.dofs]
        a = Dual.linear(maps.a, q_e[:, None, :])
        b = Dual.linear(maps.b, q_e[:, None, :])
        normal = a.cross(b)
        unit = normal / normal.norm()
        force, jac = maps.apply(unit * self.pressure, maps.position, jacobian)
        return Patches(maps.dofs, force, jac)
