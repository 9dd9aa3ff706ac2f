"""Linear solves of the (saddle-point) systems of static and dynamic analyses."""

from __future__ import annotations

import numpy as np
import scipy.linalg
import scipy.linalg.lapack
import scipy.sparse
import scipy.sparse.linalg
import threadpoolctl

#: Systems up to this size are solved dense (LAPACK beats SuperLU's overhead there).
DENSE_LIMIT = 1500


def single_threaded_blas():
    """Context in which BLAS/LAPACK run on one thread.

    The banded and small dense factorisations of the analyses gain nothing from threads:
    measured on 2 cores, a 10,000-element step took 86 ms single-threaded, 168 ms with
    OpenBLAS threads, and minutes when another process kept the other core busy (threads
    spinning against each other).
    """
    return threadpoolctl.threadpool_limits(limits=1, user_api="blas")


class SaddleSolver:
    """Factorisation of [[S, A^T], [A, 0]] (A may have no rows), reused for many solves."""

    def __init__(self, matrix: scipy.sparse.spmatrix, constraints: scipy.sparse.spmatrix):
        self.n, self.m = matrix.shape[0], constraints.shape[0]
        if self.m:
            system = scipy.sparse.bmat([[matrix, constraints.T], [constraints, None]])
        else:
            system = matrix
        if system.shape[0] <= DENSE_LIMIT:
            dense = system.toarray() if scipy.sparse.issparse(system) else system
            self._lu = scipy.linalg.lu_factor(dense, check_finite=False)
            self._solve = lambda rhs: scipy.linalg.lu_solve(self._lu, rhs, check_finite=False)
        else:
            lu = scipy.sparse.linalg.splu(scipy.sparse.csc_matrix(system))
            self._solve = lu.solve

    def solve(self, rhs: np.ndarray, rhs_constraints: np.ndarray | None = None):
        """(x, y) with S x + A^T y = rhs and A x = rhs_constraints."""
        if self.m:
            full = np.concatenate([rhs, rhs_constraints if rhs_constraints is not None
                                   else np.zeros(self.m)])
            sol = self._solve(full)
            return sol[: self.n], sol[self.n:]
        return self._solve(rhs), np.zeros(0)


def solve_symmetric_banded(band: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    """Solve a symmetric banded system (upper LAPACK storage): Cholesky when positive
    definite, otherwise a banded LU of the mirrored full band.  Cost O(n b^2)."""
    _, solution, info = scipy.linalg.lapack.dpbsv(band, rhs, lower=0)
    if info == 0:
        return solution
    if info < 0:  # pragma: no cover - an argument error is a bug here
        raise ValueError(f"dpbsv: illegal argument {-info}")
    else:  # not positive definite
        u = band.shape[0] - 1
        full = np.zeros((2 * u + 1, band.shape[1]))
        full[: u + 1] = band
        for k in range(1, u + 1):  # lower diagonals mirror the upper ones
            full[u + k, : -k] = band[u - k, k:]
        return scipy.linalg.solve_banded((u, u), full, rhs, check_finite=False)
