"""Holonomic constraints that are not linear in the coordinates: ``Phi(q) = 0``.

The linear joints of a model (``A q = 0``: ``runtime.model.items.constraints.Joint``) keep
their constant rows; every other constraint row is a ``QuadraticBlock``: rows

    phi_i(x) = 1/2 x^T H_i x + g_i . x + c_i,        x = q[dofs]  (k,)

with constant symmetric Hessians H_i (k, k).  Every constraint of the natural coordinates of
rigid bodies is of this form (unit length and orthogonality of the body's unit vectors, a
body axis perpendicular to another body's or to a node's gradients, a body point at a point
of the ground), so the exact Jacobian ``Phi_q = H x + g``, the velocity terms of the
acceleration constraint ``Phi_q a + v^T H v = 0`` (scleronomic: ``Phi_t = Phi_tt = 0``)
and the constraint geometric stiffness ``(Phi_q^T lambda)_q = sum_i lambda_i H_i`` (which
the Newton matrices need for quadratic convergence) are exact by construction.
Rheonomic rows (prescribed joint motion) are ``DrivenBlock``s: rows

    phi_i(y, f) = sum_k f_k psi_ik(y),        psi_ik quadratic in y as above,

whose time coefficients f_k(t) (``Driver``: a time law, or the cosine or sine of an angle
law) are *driver coordinates* of the model: prescribed coordinates without mass, with their
values, rates and accelerations at every step, as a hub's.  Over the full coordinates
x = [y, f] the rows are then scleronomic, so the machinery of the quadratic rows holds them
exactly: ``Phi_t = Phi_f f'`` is the driver columns of the Jacobian times the driver rates,
and the acceleration constraint ``Phi_x x'' + x'^T Phi_xx x' = Phi_q a + v^T Phi_qq v
+ 2 Phi_qt v + Phi_tt`` (the Jacobian over all coordinates times the accelerations, which
holds ``Phi_f f''``, plus ``curvature``) comes out of the full second derivative, which is
constant in y and linear in f (the driver coordinates are never free, so the Newton
matrices see ``sum_k f_k H_ik``).
``HolonomicConstraints`` assembles the blocks of a model over its coordinates.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse

from runtime.model.sliding_rows import SlidingBlock
from runtime.model.time_laws import Law

__all__ = ["Driver", "DrivenBlock", "HolonomicConstraints", "QuadraticBlock"]


@dataclass(frozen=True)
class QuadraticBlock:
    """Constraint rows of one item (``owner`` names its scene key, e.g. ``body[2]``) on the
    global coordinates ``dofs`` (k,): Hessians ``hessians`` (m, k, k), linear parts
    ``linear`` (m, k) and constants ``constant`` (m,) (units of the rows: m or 1)."""

    owner: str
    dofs: np.ndarray
    hessians: np.ndarray
    linear: np.ndarray
    constant: np.ndarray

    @property
    def rows(self) -> int:
        return self.constant.size

    def value(self, x: np.ndarray) -> np.ndarray:
        """phi (m,) at x = q[dofs] (k,)."""
        return (0.5 * np.einsum("mij,i,j->m", self.hessians, x, x) + self.linear @ x
                + self.constant)

    def jacobian(self, x: np.ndarray) -> np.ndarray:
        """d phi / dx (m, k) at x (k,)."""
        return self.hessians @ x + self.linear

    def curvature(self, x: np.ndarray, v: np.ndarray) -> np.ndarray:
        """v^T H_i v (m,) at velocities v = qdot[dofs] (k,) (H constant: x unused): the
        velocity term of the acceleration constraint (d/dt of Phi_q v = Phi_q a + v^T H v)."""
        return np.einsum("mij,i,j->m", self.hessians, v, v)

    def hessian(self, x: np.ndarray) -> np.ndarray:
        """d2 phi / dx2 (m, k, k): the constant H_i."""
        return self.hessians

    @property
    def terms(self) -> tuple[tuple[QuadraticBlock, int], ...]:
        """Its rows as terms (quadratic rows, coordinate of their factor; -1: 1)."""
        return ((self, -1),)

    @property
    def coupled(self) -> np.ndarray:
        """The coordinate sets its Hessian couples (1, k): all of its coordinates."""
        return self.dofs[None, :]


@dataclass(frozen=True)
class Driver:
    """A driver coordinate (module docstring): the time coefficient f(t) of rheonomic rows
    from the time law ``law``: the law itself (``function`` "value", e.g. a displacement in
    m) or the cosine or sine of it ("cos", "sin": an angle law in rad)."""

    law: Law
    function: str = "value"

    def sample(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(f, f', f'') at the ``times`` (s), each times.shape."""
        theta, rate, acceleration = self.law.sample(np.atleast_1d(np.asarray(times, float)))
        if self.function == "value":
            return theta, rate, acceleration
        c, s = np.cos(theta), np.sin(theta)
        if self.function == "cos":
            return c, -s * rate, -c * rate**2 - s * acceleration
        return s, c * rate, -s * rate**2 + c * acceleration


@dataclass(frozen=True)
class DrivenBlock:
    """Rheonomic constraint rows of one item (module docstring): ``phi_i = sum_k f_k
    psi_ik(y)`` with the quadratic terms ``parts`` (each a ``QuadraticBlock`` on the same
    coordinates y and rows) and ``factors`` (per term the driver coordinate f_k, -1 for
    f_k = 1).  Its ``dofs`` are y then the driver coordinates (in the order of the terms),
    and x = q[dofs] holds both."""

    owner: str
    parts: tuple[QuadraticBlock, ...]
    factors: tuple[int, ...]

    def __post_init__(self) -> None:
        first = self.parts[0]
        assert all(np.array_equal(p.dofs, first.dofs) and p.rows == first.rows
                   for p in self.parts), "the terms of a driven block share coordinates"
        drivers = np.array([f for f in self.factors if f >= 0], np.int64)
        object.__setattr__(self, "dofs", np.concatenate([first.dofs, drivers]))
        #: per term its column among the dofs (-1: the constant factor 1)
        columns, column = [], first.dofs.size
        for factor in self.factors:
            columns.append(column if factor >= 0 else -1)
            column += factor >= 0
        object.__setattr__(self, "_columns", columns)

    @property
    def rows(self) -> int:
        return self.parts[0].rows

    @property
    def terms(self) -> tuple[tuple[QuadraticBlock, int], ...]:
        return tuple(zip(self.parts, self.factors, strict=True))

    @property
    def coupled(self) -> np.ndarray:
        """The coordinate sets its Hessian couples (1, k): all of its coordinates."""
        return self.dofs[None, :]

    def _split(self, x: np.ndarray, constant: float) -> tuple[np.ndarray, list[float]]:
        """(y, the factor of every term) of x = q[dofs] (or of velocities: ``constant``
        0, the rate of the factor 1)."""
        return x[:self.parts[0].dofs.size], [constant if c < 0 else float(x[c])
                                             for c in self._columns]

    def value(self, x: np.ndarray) -> np.ndarray:
        """phi (m,) at x (k,)."""
        y, f = self._split(x, 1.0)
        return sum(fk * part.value(y) for fk, part in zip(f, self.parts, strict=True))

    def jacobian(self, x: np.ndarray) -> np.ndarray:
        """d phi / dx (m, k): sum_k f_k (H_k y + g_k) on y, psi_k(y) on the drivers."""
        y, f = self._split(x, 1.0)
        out = np.zeros((self.rows, self.dofs.size))
        for fk, part, column in zip(f, self.parts, self._columns, strict=True):
            out[:, :y.size] += fk * part.jacobian(y)
            if column >= 0:
                out[:, column] = part.value(y)
        return out

    def curvature(self, x: np.ndarray, v: np.ndarray) -> np.ndarray:
        """x'^T phi_xx x' (m,) at x and the velocities v = x' (k,): v_y^T (sum f_k H_k) v_y
        + 2 sum_k f_k' (H_k y + g_k) . v_y (the 2 Phi_qt v of the acceleration
        constraint)."""
        y, f = self._split(x, 1.0)
        vy, rates = self._split(v, 0.0)
        return sum(fk * part.curvature(y, vy) + 2 * rate * (part.jacobian(y) @ vy)
                   for fk, rate, part in zip(f, rates, self.parts, strict=True))

    def hessian(self, x: np.ndarray) -> np.ndarray:
        """d2 phi / dx2 (m, k, k): sum_k f_k H_k on y-y, H_k y + g_k on y-f_k."""
        y, f = self._split(x, 1.0)
        n = y.size
        out = np.zeros((self.rows, self.dofs.size, self.dofs.size))
        for fk, part, column in zip(f, self.parts, self._columns, strict=True):
            out[:, :n, :n] += fk * part.hessians
            if column >= 0:
                slope = part.jacobian(y)
                out[:, :n, column] = slope
                out[:, column, :n] = slope
        return out


#: the block types: quadratic rows, rheonomic rows, a point sliding on a line body
#: (``runtime.model.sliding_rows``: not polynomial in the coordinates, its parameter
#: eliminated); each has ``dofs``, ``rows``, ``coupled``, ``terms`` and value, jacobian,
#: curvature and hessian at x = q[dofs]
Block = QuadraticBlock | DrivenBlock | SlidingBlock


class HolonomicConstraints:
    """The quadratic constraint rows of a model (``blocks``, in order) over its ``size``
    coordinates, of which ``free`` (nf,) are the unknowns.  ``rows`` counts them (their
    multipliers follow those of the linear joints).  The Jacobian has a fixed structure
    (``structure``: CSR (rows, size), one row's columns its block's ``dofs``), so its values
    alone (``jacobian_data``) go to the compiled engine."""

    def __init__(self, blocks: list[Block], size: int, free: np.ndarray) -> None:
        self.blocks = list(blocks)
        self.size = size
        self.rows = sum(block.rows for block in self.blocks)
        counts = [np.full(block.rows, block.dofs.size) for block in self.blocks]
        indptr = np.concatenate([[0], np.cumsum(np.concatenate(counts))]) if counts \
            else np.zeros(1)
        indices = np.concatenate([np.tile(block.dofs, block.rows) for block in self.blocks]) \
            if self.blocks else np.zeros(0)
        self.structure = scipy.sparse.csr_matrix(
            (np.ones(indices.size), indices.astype(np.int32), indptr.astype(np.int32)),
            shape=(self.rows, size))
        position = np.full(size, -1)
        position[free] = np.arange(free.size)
        columns = position[self.structure.indices]
        #: entries of the structure on free coordinates, and their free column
        self._free_entries = np.flatnonzero(columns >= 0)
        rows = np.repeat(np.arange(self.rows), np.diff(self.structure.indptr))
        #: the CSR structure (rows, nf) of the free columns (row-major, as ``structure``)
        self.free_indptr = np.concatenate(
            [[0], np.cumsum(np.bincount(rows[self._free_entries], minlength=self.rows))]
        ).astype(np.int32)
        self.free_indices = columns[self._free_entries].astype(np.int32)
        self._free_shape = (self.rows, free.size)

    def __bool__(self) -> bool:
        return self.rows > 0

    def _each(self, q_full: np.ndarray, method: str) -> np.ndarray:
        parts = [getattr(block, method)(q_full[block.dofs]) for block in self.blocks]
        return np.concatenate([p.ravel() for p in parts]) if parts else np.zeros(0)

    def value(self, q_full: np.ndarray) -> np.ndarray:
        """Phi (rows,) at the coordinates q_full (size,)."""
        return self._each(q_full, "value")

    def jacobian_data(self, q_full: np.ndarray) -> np.ndarray:
        """The values of Phi_q at q_full in the order of ``structure`` (nnz,)."""
        return self._each(q_full, "jacobian")

    def jacobian(self, q_full: np.ndarray) -> scipy.sparse.csr_matrix:
        """Phi_q (rows, size) at q_full."""
        s = self.structure
        return scipy.sparse.csr_matrix((self.jacobian_data(q_full), s.indices, s.indptr),
                                       shape=s.shape)

    def jacobian_free(self, q_full: np.ndarray) -> scipy.sparse.csr_matrix:
        """The free columns of Phi_q (rows, nf) at q_full."""
        return scipy.sparse.csr_matrix((self.jacobian_free_data(q_full), self.free_indices,
                                        self.free_indptr), shape=self._free_shape)

    def jacobian_free_data(self, q_full: np.ndarray) -> np.ndarray:
        """The values of the free columns of Phi_q at q_full (``free_indices`` order)."""
        return self.jacobian_data(q_full)[self._free_entries]

    def curvature(self, q_full: np.ndarray, v_full: np.ndarray) -> np.ndarray:
        """v^T Phi_qq v (rows,) at q_full and the velocities v_full (size,): v^T H v, and
        with driven rows their Phi_tt + 2 Phi_qt v less Phi_f f'' (``DrivenBlock``)."""
        parts = [block.curvature(q_full[block.dofs], v_full[block.dofs])
                 for block in self.blocks]
        return np.concatenate(parts) if parts else np.zeros(0)

    def stiffness_blocks(self, multipliers: np.ndarray,
                         q_full: np.ndarray) -> list[np.ndarray]:
        """sum_i lambda_i phi_i,xx (k, k) of every block at q_full for the multipliers
        (rows,) of these rows: the constraint geometric stiffness (Phi_q^T lambda)_q."""
        out, first = [], 0
        for block in self.blocks:
            out.append(np.tensordot(multipliers[first:first + block.rows],
                                    block.hessian(q_full[block.dofs]), 1))
            first += block.rows
        return out
