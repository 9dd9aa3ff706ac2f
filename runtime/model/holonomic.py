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
``HolonomicConstraints`` assembles the blocks of a model over its coordinates.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse

__all__ = ["HolonomicConstraints", "QuadraticBlock"]


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

    def curvature(self, v: np.ndarray) -> np.ndarray:
        """v^T H_i v (m,) at velocities v = qdot[dofs] (k,): the velocity term of the
        acceleration constraint (d/dt of Phi_q v = Phi_q a + v^T H v)."""
        return np.einsum("mij,i,j->m", self.hessians, v, v)


class HolonomicConstraints:
    """The quadratic constraint rows of a model (``blocks``, in order) over its ``size``
    coordinates, of which ``free`` (nf,) are the unknowns.  ``rows`` counts them (their
    multipliers follow those of the linear joints).  The Jacobian has a fixed structure
    (``structure``: CSR (rows, size), one row's columns its block's ``dofs``), so its values
    alone (``jacobian_data``) go to the compiled engine."""

    def __init__(self, blocks: list[QuadraticBlock], size: int, free: np.ndarray) -> None:
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

    def curvature(self, v_full: np.ndarray) -> np.ndarray:
        """v^T H v (rows,) at the velocities v_full (size,)."""
        return self._each(v_full, "curvature")

    def stiffness_blocks(self, multipliers: np.ndarray) -> list[np.ndarray]:
        """sum_i lambda_i H_i (k, k) of every block for the multipliers (rows,) of these
        rows: the constraint geometric stiffness (Phi_q^T lambda)_q."""
        out, first = [], 0
        for block in self.blocks:
            out.append(np.tensordot(multipliers[first:first + block.rows], block.hessians, 1))
            first += block.rows
        return out
