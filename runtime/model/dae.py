"""The differential-algebraic system that the dynamic solvers see (both engines).

    M_ff a + M_fp a_p + A_f^T lambda = F(q_full, t)         (free coordinates)
    A_f q_free + A_p q_p + A_x q_x = b                       (joints)

``q_full`` (size,) holds every coordinate of the model; ``q_free`` (nf,) the unknowns;
``q_p`` the prescribed coordinates (hub rotations: known values, rates and accelerations
at every time); ``q_x`` the fixed ones (clamps, pins: held at their initial values); ``b``
the joint offsets (0 but for rows held at their reference value: symmetry planes).
``F`` is the elastic force of the element groups plus the external loads, each a constant
vector times a time law, or a state-dependent generalised force (follower loads f(q),
Python loads f(t, q, v): ``StateLoads``) times its time law, whose Jacobians join the
elastic ones in the CSR pattern of ``Model.pattern`` (non-symmetric: ``DAESystem.symmetric``
is then False; df/dv joins the damping part of the Newton matrix).
A ``DAESystem`` is built once from a ``Model`` and holds only arrays and the element groups;
the Python engine (``runtime.solve.python_engine``) and the compiled engine
(``runtime.solve.compiled_engine``) both consume it, nothing else of the model.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.sparse

from runtime.model.errors import SceneError
from runtime.model.items.python_loads import PythonForce
from runtime.model.model import Model


@dataclass(frozen=True)
class ElementGroup:
    """Elements that share one set of invariants (a body, or the elements of one shape of a
    body meshed from a file: ``Model.groups``): kernels, maps, references."""

    name: str
    kind: str                 # element kind, e.g. "beam3d"
    family: str               # kernel family, e.g. "gram_straight"
    dofs: np.ndarray          # (elements, ndof) int32 global coordinate indices
    e0: np.ndarray            # (elements, ndof) reference coordinates
    element: object           # the runtime.Element whose invariants and kernels they use


@dataclass(frozen=True)
class Hub:
    """A node whose gradients follow a rigid rotation R(theta(t)) about ``axis``."""

    coordinates: np.ndarray   # (vectors, dim) global indices of the node's nodal vectors
    reference: np.ndarray     # (vectors, dim) reference nodal vectors
    rotated: np.ndarray       # (vectors,) bool: gradient (rotated) or position (held)
    law: object               # time law of the angle theta (rad)
    axis: np.ndarray          # (3,) rotation axis (3D); unused in 2D


class DAESystem:
    """Sizes, mass, element groups, joints, loads and prescribed motion of a model.

    Built from a model and the full initial coordinates ``q_full`` (fixed coordinates keep
    their values from it).  Arrays over free coordinates are in the order of ``free``.
    """

    def __init__(self, model: Model, q_full: np.ndarray) -> None:
        self.model = model
        self.dim, self.size = model.dim, model.size
        self.free, self.fixed, self.prescribed = model.free, model.fixed, model.prescribed
        self.fixed_values = np.array(q_full, dtype=float)
        # column of each prescribed coordinate among the prescribed ones (-1 elsewhere)
        self._prescribed_position = np.full(self.size, -1)
        self._prescribed_position[self.prescribed] = np.arange(self.prescribed.size)
        self.scale = model.length_scale()
        self.mass_ff, self.mass_fp = model.mass_ff, model.mass_fp
        self.bandwidth = model.bandwidth
        self.mass_band = model.mass_banded          # (bandwidth + 1, nf), LAPACK upper
        self.joints_free = model.joints_free.tocsr()
        self.joints_prescribed = model.joints_prescribed.tocsr()
        self.joint_fixed_part = np.asarray(model.joints[:, self.fixed]
                                           @ self.fixed_values[self.fixed]).ravel() \
            - model.joint_offsets
        self.groups = [ElementGroup(b.name, b.element.kind.name, b.element.family,
                                    b.element_dofs.astype(np.int32), b.element_e0, b.element)
                       for b in model.groups]
        loads = model.nominal_loads()
        self.load_laws = [law for law, _ in loads]
        self.load_vectors = (np.array([vector[self.free] for _, vector in loads])
                             if loads else np.zeros((0, self.free.size)))
        self.state_loads = StateLoads(model)
        #: whether the iteration matrices are symmetric (no follower load)
        self.symmetric = not self.state_loads
        self.hubs = [self._hub(node, law, axis) for node, law, axis in model.hubs]
        # initial velocities of the free coordinates (m/s; the model's initial conditions)
        self.initial_velocity = model.initial_velocities()[self.free]
        self.projector = self._projector()
        #: the quadratic constraint rows Phi(q) = 0 (rigid bodies, 3D joints); their
        #: multipliers follow the joints' (``constraint_rows`` in all)
        self.holonomic = model.holonomic
        self.nonlinear = bool(self.holonomic)
        self.constraint_rows = self.joints + self.holonomic.rows

    @property
    def damped(self) -> bool:
        """Whether forces depend on velocities (Kelvin-Voigt damping in some material)."""
        return self.model.damped

    def internal_forces(self, q_full: np.ndarray, v_full: np.ndarray, jacobian: bool):
        """Elastic (plus damping) force (size,) and the free-free Jacobian data with respect
        to q and to v (CSR order of ``model.pattern``; None when not asked or undamped)."""
        return self.model.internal_forces_damped(q_full, v_full if self.damped else None,
                                                 jacobian)

    def dissipation_power(self, q: np.ndarray, v: np.ndarray, qp: np.ndarray,
                          vp: np.ndarray) -> float:
        """Power (W) dissipated by damping at free coordinates and velocities (q, v)."""
        if not self.damped:
            return 0.0
        return self.model.dissipation_power(self.full_coordinates(q, qp),
                                            self.full_velocities(v, vp))

    @property
    def joints(self) -> int:
        """Number of joint rows (Lagrange multipliers)."""
        return self.joints_free.shape[0]

    def _hub(self, node: int, law, axis: np.ndarray) -> Hub:
        m = self.model
        coordinates = m.held_dofs(node).reshape(-1, self.dim)
        rotated = np.array([name != "r" for name in m.body_of(node).kind.held_vectors])
        return Hub(coordinates, m.reference[coordinates], rotated, law,
                   np.asarray(axis, float) / np.linalg.norm(axis))

    def _projector(self) -> np.ndarray:
        """(nf, joints) M^-1 A^T (A M^-1 A^T)^-1 of the mass-orthogonal projection onto the
        joints (the paper's integrator projects positions and velocities every step)."""
        if not self.joints:
            return np.zeros((self.free.size, 0))
        factor = scipy.linalg.cholesky_banded(self.mass_band, lower=False)
        minv_at = scipy.linalg.cho_solve_banded((factor, False),
                                                self.joints_free.T.toarray())
        schur = self.joints_free @ minv_at
        return np.linalg.solve(schur.T, minv_at.T).T

    # --- all constraint rows: the linear joints, then the quadratic rows ----------------
    # (used only when ``nonlinear``: a model with linear joints alone keeps their constant
    # rows and the precomputed ``projector``)

    def constraint_matrix(self, q_full: np.ndarray) -> scipy.sparse.csr_matrix:
        """[A_f; Phi_q,f(q)] (constraint_rows, nf): the free columns of every row at q_full."""
        return self.model.constraint_rows(q_full)

    def violation(self, q_full: np.ndarray) -> np.ndarray:
        """[A q; Phi(q)] (constraint_rows,) at the coordinates q_full (size,)."""
        return self.model.constraint_values(q_full)

    def velocity_violation(self, q_full: np.ndarray, v_full: np.ndarray) -> np.ndarray:
        """[A v; Phi_q(q) v] (constraint_rows,) at q_full and the velocities v_full."""
        return np.concatenate([self.model.joints @ v_full,
                               self.holonomic.jacobian(q_full) @ v_full])

    def acceleration_violation(self, q_full: np.ndarray, v_full: np.ndarray,
                               a_full: np.ndarray) -> np.ndarray:
        """[A a; Phi_q a + v^T H v] (constraint_rows,): the second time derivative of the
        constraints at q_full, v_full and the accelerations a_full (size,)."""
        return np.concatenate([self.model.joints @ a_full,
                               self.holonomic.jacobian(q_full) @ a_full
                               + self.holonomic.curvature(q_full, v_full)])

    def constraint_forces(self, q_full: np.ndarray, multipliers: np.ndarray) -> np.ndarray:
        """A_f^T lambda_joints + Phi_q,f(q)^T lambda_rows (nf,) for the multipliers
        (constraint_rows,)."""
        nj = self.joints
        force = self.holonomic.jacobian_free(q_full).T @ multipliers[nj:]
        if nj:
            force += self.joints_free.T @ multipliers[:nj]
        return force

    def geometric_stiffness(self, multipliers: np.ndarray, q_full: np.ndarray) -> np.ndarray:
        """(Phi_q^T lambda)_q (pattern nnz,) at q_full of the quadratic rows' multipliers
        (taken from the constraint_rows multipliers)."""
        return self.model.holonomic_stiffness(multipliers[self.joints:], q_full)

    def full_accelerations(self, a_free: np.ndarray, a_prescribed: np.ndarray) -> np.ndarray:
        """a_full (size,): fixed coordinates at rest."""
        return self.full_velocities(a_free, a_prescribed)

    # --- time-dependent data, vectorised over the step times of a block ------------------

    def prescribed_motion(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Values, rates and accelerations (each (len(times), prescribed)) of the prescribed
        coordinates at ``times`` (s)."""
        times = np.atleast_1d(np.asarray(times, float))
        n = times.size
        q, v, a = (np.zeros((n, self.prescribed.size)) for _ in range(3))
        for hub in self.hubs:
            theta, rate, acc = hub.law.sample(times)
            rot, d_rot, dd_rot = rotations(self.dim, hub.axis, theta)
            for k, rotated in enumerate(hub.rotated):
                cols = self._prescribed_position[hub.coordinates[k]]
                ref = hub.reference[k]
                if not rotated:
                    q[:, cols] = ref
                    continue
                q[:, cols] = rot @ ref
                v[:, cols] = rate[:, None] * (d_rot @ ref)
                a[:, cols] = acc[:, None] * (d_rot @ ref) + rate[:, None] ** 2 * (dd_rot @ ref)
        for coordinate, driver in self.model.drivers:    # rheonomic rows' coefficients
            column = self._prescribed_position[coordinate]
            q[:, column], v[:, column], a[:, column] = driver.sample(times)
        return q, v, a

    def load_factors(self, times: np.ndarray) -> np.ndarray:
        """(len(times), loads) values of the loads' time laws at ``times`` (s)."""
        times = np.atleast_1d(np.asarray(times, float))
        factors = np.zeros((times.size, len(self.load_laws)))
        for k, law in enumerate(self.load_laws):
            factors[:, k] = law.sample(times)[0]
        return factors

    # --- full vectors ------------------------------------------------------------------

    def full_coordinates(self, q_free: np.ndarray, q_prescribed: np.ndarray) -> np.ndarray:
        """q_full (size,): free and prescribed parts, fixed ones at their held values; rows
        (k, nf) and (k, np) give (k, size)."""
        q_full = np.broadcast_to(self.fixed_values, (*q_free.shape[:-1], self.size)).copy()
        q_full[..., self.free] = q_free
        q_full[..., self.prescribed] = q_prescribed
        return q_full

    def full_velocities(self, v_free: np.ndarray, v_prescribed: np.ndarray) -> np.ndarray:
        """v_full (size,): fixed coordinates at rest; rows give (k, size)."""
        v_full = np.zeros((*v_free.shape[:-1], self.size))
        v_full[..., self.free] = v_free
        v_full[..., self.prescribed] = v_prescribed
        return v_full


class StateLoads:
    """The loads of a model that depend on its state (``Load.follows``): follower loads
    f(q) and Python loads f(t, q, v) (``runtime.model.items.python_loads``), each scaled
    by its load factor, assembled over the whole model (force (size,)) with their Jacobians
    df/dq and df/dv in the free-free CSR pattern of the model's elastic Jacobian
    (``Model.pattern``: a load acts within an element's coordinates or a node's, which the
    pattern holds).  ``len`` is the number of such loads."""

    def __init__(self, model: Model) -> None:
        self.size, self.nnz = model.size, model.pattern.nnz
        self.scene_loads = len(model.scene.loads)
        #: (index among the scene's loads, state force, slots (m, k, k) of the Jacobian
        #: entries in the pattern, -1 where a coordinate is not free)
        self.loads = []
        for index, load in enumerate(model.scene.loads):
            if not load.follows:
                continue
            evaluate = load.state_force(model)
            dofs = evaluate.dofs if hasattr(evaluate, "dofs") else evaluate.maps.dofs
            slots = model.slots(dofs, outside=True)
            if (slots == -2).any():
                if isinstance(evaluate, PythonForce):
                    raise SceneError(f"load[{index}].nodes: a Python load's nodes must share "
                                     "an element (its Jacobian couples their coordinates, "
                                     "which must lie in one element's); list the nodes of one "
                                     "element, or split the load")
                raise AssertionError("a follower load acts outside the Jacobian pattern")
            self.loads.append((index, evaluate, slots))

    def __len__(self) -> int:
        return len(self.loads)

    @property
    def turning(self) -> list:
        """Its loads that count turns (torsional springs: ``turned``, ``accept``), as
        entries of ``loads``."""
        return [entry for entry in self.loads if hasattr(entry[1], "turned")]

    def reset_turns(self) -> None:
        """Start counting turns afresh (a new run: every spring's ``turned`` 0)."""
        for _, evaluate, _ in self.turning:
            evaluate.turned = 0.0

    def count_turns(self, angles: np.ndarray) -> None:
        """Count every torsional spring's turns from its joint angle in ``angles`` (loads,;
        rad, by scene load index: ``spring_angles``)."""
        for index, evaluate, _ in self.turning:
            evaluate.turned = float(angles[index])

    def accept(self, q_full: np.ndarray) -> None:
        """Count the turns of the torsional springs up to the accepted state q_full (size,)."""
        for _, evaluate, _ in self.turning:
            evaluate.accept(q_full)

    def spring_angles(self, q_full: np.ndarray, near: np.ndarray | None = None) -> np.ndarray:
        """The joint angles phi (rad) of the torsional springs at the states q_full
        (k, size), by scene load index (k, loads; 0 for the other loads): the branches
        within half a turn of ``near`` (k, loads; default each spring's ``turned``)."""
        angles = np.zeros((q_full.shape[0], self.scene_loads))
        for index, evaluate, _ in self.turning:
            for row, q in enumerate(q_full):
                angles[row, index] = evaluate.joint_angle(
                    q, None if near is None else float(near[row, index]))
        return angles

    @property
    def python_loads(self) -> list[PythonForce]:
        """The state forces of its Python loads."""
        return [evaluate for _, evaluate, _ in self.loads if isinstance(evaluate, PythonForce)]

    @property
    def compiled(self) -> list:
        """Its loads that the compiled step evaluates itself (force elements: ``compiled()``,
        ``runtime.model.items.force_elements``), as entries of ``loads``."""
        return [entry for entry in self.loads if hasattr(entry[1], "compiled")]

    @property
    def called(self) -> list:
        """Its other loads (follower and Python loads), which the compiled step calls back."""
        return [entry for entry in self.loads if not hasattr(entry[1], "compiled")]

    def evaluate(self, q_full: np.ndarray, factors: np.ndarray, jacobian: bool,
                 v_full: np.ndarray | None = None, t: float = 0.0, loads=None):
        """Force (size,) in N and, if asked, the Jacobian data (pattern nnz,) with respect to
        q and to v (None when no load reads velocities) at coordinates q_full and velocities
        v_full (size,; None: at rest) at time t (s), with the load factors of every scene
        load ``factors`` (loads,); of the entries ``loads`` of ``self.loads`` (default
        all)."""
        force = np.zeros(self.size)
        data = np.zeros(self.nnz) if jacobian else None
        data_dot = None
        for index, evaluate, slots in self.loads if loads is None else loads:
            factor = factors[index]
            moving = getattr(evaluate, "reads_velocity", False)
            if moving:
                patches = evaluate(q_full, jacobian, v_full, t)
            else:
                patches = evaluate(q_full, jacobian)
            force += np.bincount(patches.dofs.ravel(), factor * patches.force.ravel(),
                                 self.size)
            if jacobian:
                keep = slots >= 0
                data += np.bincount(slots[keep], factor * patches.jacobian[keep], self.nnz)
                if moving:
                    data_dot = (np.zeros(self.nnz) if data_dot is None else data_dot) + \
                        np.bincount(slots[keep], factor * patches.jacobian_dot[keep], self.nnz)
        return force, data, data_dot


def rotations(dim: int, axis: np.ndarray, theta: np.ndarray):
    """R(theta), dR/dtheta, d2R/dtheta2 for every angle, each (len(theta), dim, dim): in the
    plane (dim 2) or about the unit ``axis`` (dim 3, Rodrigues)."""
    c, s = np.cos(theta)[:, None, None], np.sin(theta)[:, None, None]
    if dim == 2:
        rot = np.concatenate([np.concatenate([c, -s], 2), np.concatenate([s, c], 2)], 1)
        d_rot = np.concatenate([np.concatenate([-s, -c], 2), np.concatenate([c, -s], 2)], 1)
        return rot, d_rot, -rot
    cross = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    outer, eye = np.outer(axis, axis), np.eye(3)
    rot = c * eye + s * cross + (1 - c) * outer
    d_rot = -s * eye + c * cross + s * outer
    dd_rot = -c * eye - s * cross + c * outer
    return rot, d_rot, dd_rot
