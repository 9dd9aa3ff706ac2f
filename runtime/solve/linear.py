"""Linear solves of the (saddle-point) systems of static and dynamic analyses."""

from __future__ import annotations

import functools

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
    spinning against each other).  The loaded BLAS libraries are found once per process
    (a fresh search costs 1-2 ms, a fixed cost of every analysis otherwise).
    """
    return _blas_controller().limit(limits=1, user_api="blas")


@functools.cache
def _blas_controller() -> threadpoolctl.ThreadpoolController:
    return threadpoolctl.ThreadpoolController()


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
    """Solve a symmetric banded system (upper LAPACK storage, see ``BandedFactor``)."""
    return BandedFactor(band).solve(rhs)


class BandedFactor:
    """Factorisation of a symmetric banded matrix given in upper LAPACK storage
    ((bandwidth + 1, n)): Cholesky when positive definite, otherwise a banded LU with
    partial pivoting of the mirrored full band.  Raises LinAlgError when singular."""

    def __init__(self, band: np.ndarray) -> None:
        self.u = band.shape[0] - 1
        self.cholesky = True
        try:
            self._factor = scipy.linalg.cholesky_banded(band, lower=False, check_finite=False)
            return
        except np.linalg.LinAlgError:
            self.cholesky = False
        u, n = self.u, band.shape[1]
        full = np.zeros((3 * u + 1, n))   # dgbtrf storage: u extra rows for the fill-in
        full[u: 2 * u + 1] = band
        for k in range(1, u + 1):          # lower diagonals mirror the upper ones
            full[2 * u + k, : -k] = band[u - k, k:]
        lu, pivots, info = scipy.linalg.lapack.dgbtrf(full, u, u)
        if info != 0:
            raise np.linalg.LinAlgError("singular banded matrix")
        self._factor = (lu, pivots)

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """Solution (n,) or (n, k) of the factorised system."""
        if self.cholesky:
            return scipy.linalg.cho_solve_banded((self._factor, False), rhs,
                                                 check_finite=False)
        lu, pivots = self._factor
        solution, info = scipy.linalg.lapack.dgbtrs(lu, self.u, self.u, rhs, pivots)
        return solution


class SchurSolver:
    """[[S, A^T], [A, 0]] [x; y] = [r; c] for a banded symmetric S (upper LAPACK storage)
    and a few joint rows A: S is factorised once, y from the small Schur complement
    A S^-1 A^T, then x = S^-1 (r - A^T y).  Needs S regular (dynamics: S contains M)."""

    def __init__(self, band: np.ndarray, joints: scipy.sparse.spmatrix) -> None:
        self.factor = BandedFactor(band)
        self.joints = joints
        self.m = joints.shape[0]
        if self.m:
            self.coupling = self.factor.solve(joints.T.toarray())   # S^-1 A^T, (n, m)
            self._schur = scipy.linalg.lu_factor(joints @ self.coupling, check_finite=False)

    def solve(self, rhs: np.ndarray, rhs_constraints: np.ndarray | None = None):
        """(x, y) with S x + A^T y = rhs and A x = rhs_constraints (zero if None)."""
        x = self.factor.solve(rhs)
        if not self.m:
            return x, np.zeros(0)
        c = np.zeros(self.m) if rhs_constraints is None else rhs_constraints
        y = scipy.linalg.lu_solve(self._schur, self.joints @ x - c, check_finite=False)
        return x - self.coupling @ y, y
