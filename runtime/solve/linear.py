"""Linear solves of the (saddle-point) systems of static and dynamic analyses.

The Newton iterations of both engines and of the static analysis factorise matrices of one
sparsity pattern, the free-free ``Model.pattern``, given by their values in the pattern's CSR
order.  A linear solver (``LINEAR_SOLVERS``, names in ``runtime.catalog.LINEAR_SOLVERS``)
does the structural work once per model and factorises each matrix:

* ``banded``: the band of the node-major numbering (LAPACK storage), Cholesky when positive
  definite, banded LU otherwise: O(n b^2), the fastest for chains of beams;
* ``sparse``: CHOLMOD's supernodal Cholesky after a fill-reducing ordering (AMD), the
  symbolic analysis once (``runtime.solve.cholmod``); SuperLU (SciPy) for matrices that are
  not positive definite or not symmetric: for plates, meshes and mechanisms.

``choose`` picks one per model by the shape of its pattern, or takes the scene's.
Joints go through a Schur complement of the factorised matrix (``SchurSolver``).
"""

from __future__ import annotations

import functools
import weakref

import numpy as np
import scipy.linalg
import scipy.linalg.lapack
import scipy.sparse
import scipy.sparse.linalg
import threadpoolctl

from runtime import catalog
from runtime.solve import cholmod

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
        self._factor = _banded_lu(full, u)

    @classmethod
    def lu(cls, full: np.ndarray, bandwidth: int) -> BandedFactor:
        """Banded LU of a general matrix in dgbtrf storage ((3 b + 1, n), entry (i, j) at
        [2 b + i - j, j], b = ``bandwidth`` below and above the diagonal)."""
        factor = cls.__new__(cls)
        factor.u, factor.cholesky = bandwidth, False
        factor._factor = _banded_lu(full, bandwidth)
        return factor

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """Solution (n,) or (n, k) of the factorised system."""
        if self.cholesky:
            return scipy.linalg.cho_solve_banded((self._factor, False), rhs,
                                                 check_finite=False)
        lu, pivots = self._factor
        solution, info = scipy.linalg.lapack.dgbtrs(lu, self.u, self.u, rhs, pivots)
        return solution


def _banded_lu(full: np.ndarray, bandwidth: int):
    lu, pivots, info = scipy.linalg.lapack.dgbtrf(full, bandwidth, bandwidth)
    if info != 0:
        raise np.linalg.LinAlgError("singular banded matrix")
    return lu, pivots


class SchurSolver:
    """[[S, A^T], [A, 0]] [x; y] = [r; c] for a factorised S (``factor``: a banded symmetric
    S in upper LAPACK storage, or any factorisation with ``solve``) and a few joint rows A:
    y from the small Schur complement A S^-1 A^T, then x = S^-1 (r - A^T y).  Needs S
    regular (dynamics: S contains M)."""

    def __init__(self, factor, joints: scipy.sparse.spmatrix) -> None:
        self.factor = BandedFactor(factor) if isinstance(factor, np.ndarray) else factor
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


#: the constraint block of the KKT matrix is -delta I with delta this times
#: (largest |C|)^2 / (largest S_ii): small against C S^-1 C^T, which it must not shift, and
#: large enough that a pivot of the constraint block met before its coordinates' (the
#: ordering does not know them apart) does not lose more digits than the refinements win back
KKT_REGULARISATION = 1e-8
#: refinement steps of a KKT solve against the unregularised system (each gains about
#: -log10(KKT_REGULARISATION) digits): the solves that must be exact, as the trapezoidal
#: projection onto the joints
KKT_REFINEMENTS = 1
#: refinement steps of the Newton iterations' KKT solves: none.  Their regularised solution
#: is an inexact Newton step (relative error about KKT_REGULARISATION; the residual and the
#: constraints are evaluated exactly, so the iteration converges to the same root in the
#: same iterations), and the refinement's second solve and product were 30 % of a
#: 200-joint chain's step with auto Newton (``ancf bench steps --joints 200``)
ITERATION_KKT_REFINEMENTS = 0
#: the constraint rows from which joints go through the KKT system instead of the Schur
#: complement (whose multi-column solve and dense LU grow with the rows: 92-98 % of a step
#: at 50-200 spherical joints, ``ancf bench steps --joints``)
KKT_ROWS = 48


class KKTSystem:
    """Saddle systems [[S, C^T], [C, 0]] of one structure (S of the CSR ``pattern`` (n, n),
    C of the CSR structure ``rows`` (m, n)) by CHOLMOD's simplicial L D L^T of the
    quasi-definite [[S, C^T], [C, -delta I]] (fill-reducing ordering and symbolic analysis
    once, here; ``KKT_REGULARISATION``), each solve refined ``refinements`` times against
    the unregularised system (``KKT_REFINEMENTS``; the Newton iterations'
    ``ITERATION_KKT_REFINEMENTS``).  Used instead of the Schur complement of many constraint
    rows (``KKT_ROWS``): one sparse factorisation of n + m, no m-column solve, no dense LU."""

    def __init__(self, pattern: scipy.sparse.csr_matrix, rows: scipy.sparse.csr_matrix,
                 refinements: int = KKT_REFINEMENTS) -> None:
        n, m = pattern.shape[0], rows.shape[0]
        self.n, self.m = n, m
        self.refinements = refinements
        self.rows_structure = rows.tocoo()
        s_rows, s_cols = _coordinates(pattern)
        r_rows, r_cols = self.rows_structure.row, self.rows_structure.col
        # the KKT entries, each tagged with its source: S entry k -> k, C entry k -> below
        # (n + row, col) and above (col, n + row), the constraint diagonal
        sources = [(s_rows, s_cols), (n + r_rows, r_cols), (r_cols, n + r_rows),
                   (n + np.arange(m), n + np.arange(m))]
        tags = np.concatenate([np.arange(len(r)) + offset for (r, _), offset in zip(
            sources, np.cumsum([0] + [len(r) for r, _ in sources[:-1]]), strict=True)])
        kkt = scipy.sparse.csr_matrix(
            (tags + 1.0, (np.concatenate([r for r, _ in sources]),
                          np.concatenate([c for _, c in sources]))), shape=(n + m, n + m))
        kkt.sort_indices()
        self.pattern = kkt
        slot = np.empty(kkt.nnz, np.int64)
        slot[kkt.data.astype(np.int64) - 1] = np.arange(kkt.nnz)
        cuts = np.cumsum([len(r) for r, _ in sources])
        #: KKT slots (values order) of S's entries, of C's below and above, of the diagonal
        self.s_slots, self.below_slots, self.above_slots, self.diagonal_slots = np.split(
            slot, cuts[:-1])
        #: S's diagonal entries (pattern order)
        self.s_diagonal = np.flatnonzero(s_rows == s_cols)
        self.cholesky = cholmod.Cholesky(kkt, indefinite=True)

    def values(self, s_values: np.ndarray, c_values: np.ndarray) -> np.ndarray:
        """The KKT values in the pattern's order of S (``pattern`` order) and C (the
        structure's entries, in ``rows_structure`` order), the constraint block -delta I."""
        values = np.zeros(self.pattern.nnz)
        values[self.s_slots] = s_values
        values[self.below_slots] = c_values
        values[self.above_slots] = c_values
        diagonal = s_values[self.s_diagonal] if self.n else np.ones(1)
        largest = float(np.abs(c_values).max(initial=0.0))
        delta = KKT_REGULARISATION * largest ** 2 / max(float(np.abs(diagonal).max()), 1e-300)
        values[self.diagonal_slots] = -delta
        return values

    def factor(self, s_values: np.ndarray, rows: scipy.sparse.spmatrix) -> KKTFactor:
        """The factorisation of [[S, C^T], [C, 0]] with S's ``s_values`` (pattern order) and
        the constraint rows ``rows`` (m, n; their entries within the structure).  Raises
        LinAlgError when CHOLMOD meets a zero pivot (a singular saddle system)."""
        structure = self.rows_structure
        rows = scipy.sparse.csr_matrix(rows)
        c_values = np.asarray(rows[structure.row, structure.col]).ravel()
        if np.count_nonzero(rows.data) > np.count_nonzero(c_values):
            raise RuntimeError("KKTSystem: constraint rows outside the structure analysed")
        values = self.values(s_values, c_values)
        try:
            self.cholesky.factorize(values)
        except cholmod.NotPositiveDefinite:       # L D L^T stops only at a zero pivot
            raise np.linalg.LinAlgError("singular saddle-point system (a zero pivot)") \
                from None
        exact = values.copy()
        exact[self.diagonal_slots] = 0.0
        matrix = scipy.sparse.csr_matrix((exact, self.pattern.indices, self.pattern.indptr),
                                         shape=self.pattern.shape)
        return KKTFactor(self, matrix)


class KKTFactor:
    """One factorised saddle system of a ``KKTSystem``, valid until its next factorisation:
    ``solve`` as ``SchurSolver.solve``."""

    def __init__(self, system: KKTSystem, matrix: scipy.sparse.csr_matrix) -> None:
        self.system, self.matrix = system, matrix

    def solve(self, rhs: np.ndarray, rhs_constraints: np.ndarray | None = None):
        """(x, y) with S x + C^T y = rhs and C x = rhs_constraints (zero if None)."""
        n, m = self.system.n, self.system.m
        full = np.concatenate([rhs, np.zeros(m) if rhs_constraints is None
                               else rhs_constraints])
        cholesky = self.system.cholesky
        solution = cholesky.solve(full)
        for _ in range(self.system.refinements):
            solution += cholesky.solve(full - self.matrix @ solution)
        return solution[:n], solution[n:]


class SparseFactor:
    """The factorisation of one matrix by a ``SparseSolver``: CHOLMOD's Cholesky when it
    holds, else SciPy's SuperLU.  Valid until the solver factorises the next matrix."""

    def __init__(self, cholesky, lu=None) -> None:
        self._cholesky, self._lu = cholesky, lu
        self.cholesky = lu is None

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """Solution (n,) or (n, k) of the factorised system."""
        return self._cholesky.solve(rhs) if self._lu is None else self._lu.solve(rhs)


class BandedSolver:
    """``banded``: matrices of ``pattern`` in LAPACK band storage, factorised by
    ``BandedFactor`` (Cholesky, or banded LU); not symmetric: banded LU of the full band."""

    name = "banded"

    def __init__(self, pattern: scipy.sparse.csr_matrix, symmetric: bool = True) -> None:
        self.pattern, self.symmetric = pattern, symmetric
        rows, cols = _coordinates(pattern)
        n = pattern.shape[0]
        self.bandwidth = int(np.abs(rows - cols).max(initial=0))
        upper = rows <= cols
        self._upper_slots = np.flatnonzero(upper)
        self._upper_index = (self.bandwidth + rows[upper] - cols[upper]) * n + cols[upper]
        # dgbtrf storage (3 b + 1, n): entry (i, j) at [2 b + i - j, j]
        self._full_index = (2 * self.bandwidth + rows - cols) * n + cols

    def band(self, values: np.ndarray) -> np.ndarray:
        """Upper LAPACK band ((bandwidth + 1, n)) of the symmetric matrix ``values``."""
        n = self.pattern.shape[0]
        band = np.zeros((self.bandwidth + 1) * n)
        band[self._upper_index] = values[self._upper_slots]
        return band.reshape(self.bandwidth + 1, n)

    def factor(self, values: np.ndarray):
        """The factorisation of the matrix ``values`` (pattern order).  LinAlgError when
        singular."""
        if self.symmetric:
            return BandedFactor(self.band(values))
        n, b = self.pattern.shape[0], self.bandwidth
        full = np.zeros((3 * b + 1) * n)
        full[self._full_index] = values
        return BandedFactor.lu(full.reshape(3 * b + 1, n), b)


class SparseSolver:
    """``sparse``: matrices of ``pattern`` by CHOLMOD (ordering and symbolic analysis once,
    here), SuperLU when a matrix is not positive definite or ``symmetric`` is False."""

    name = "sparse"

    def __init__(self, pattern: scipy.sparse.csr_matrix, symmetric: bool = True) -> None:
        self.pattern, self.symmetric = pattern, symmetric
        self.cholesky = cholmod.Cholesky(pattern) if symmetric else None

    def factor(self, values: np.ndarray) -> SparseFactor:
        """The factorisation of the matrix ``values`` (pattern order).  LinAlgError when
        singular."""
        if self.cholesky is not None:
            try:
                self.cholesky.factorize(values)
                return SparseFactor(self.cholesky)
            except cholmod.NotPositiveDefinite:
                pass
        return SparseFactor(self.cholesky, superlu(self.pattern, values))


def superlu(pattern: scipy.sparse.csr_matrix, values: np.ndarray):
    """SciPy's SuperLU of the matrix ``values`` of ``pattern`` (LinAlgError when singular)."""
    matrix = scipy.sparse.csr_matrix((values, pattern.indices, pattern.indptr),
                                     shape=pattern.shape)
    try:
        return scipy.sparse.linalg.splu(matrix.tocsc())
    except RuntimeError as error:     # "Factor is exactly singular"
        raise np.linalg.LinAlgError(str(error)) from None


LINEAR_SOLVERS = {"banded": BandedSolver, "sparse": SparseSolver}
assert tuple(LINEAR_SOLVERS) == catalog.LINEAR_SOLVERS

#: the automatic choice takes ``sparse`` when the band holds more than this many times the
#: entries of the pattern's upper triangle.  Chains of beams: 1.3-1.6 (banded is twice as
#: fast); square plates: 1.8 at 4 x 4 and 2.6 at 8 x 8 (banded 1.5-2x faster), 4.3 at
#: 16 x 16 and 7.8 at 32 x 32 (sparse 1.4x and 2x faster; ``ancf bench steps``, docs/design.md)
BAND_FILL_LIMIT = 4.0


def band_fill(pattern: scipy.sparse.csr_matrix) -> float:
    """Entries of the upper band over the entries of the upper triangle of ``pattern``."""
    rows, cols = _coordinates(pattern)
    bandwidth = int(np.abs(rows - cols).max(initial=0))
    return pattern.shape[0] * (bandwidth + 1) / max(1, int(np.count_nonzero(rows <= cols)))


def choose(pattern: scipy.sparse.csr_matrix, requested: str | None = None) -> str:
    """The linear solver for matrices of ``pattern``: ``requested``, or ``sparse`` when the
    band would hold more than ``BAND_FILL_LIMIT`` times the pattern's entries (plates,
    meshes) and CHOLMOD is installed, else ``banded`` (chains).  ValueError naming the
    option for an unknown name or a sparse solver without CHOLMOD."""
    if requested is None:
        sparse = band_fill(pattern) > BAND_FILL_LIMIT and cholmod.available()
        return "sparse" if sparse else "banded"
    if requested not in LINEAR_SOLVERS:
        raise ValueError(f"solver.linear_solver: expected one of "
                         f"{', '.join(LINEAR_SOLVERS)}, got {requested!r}")
    if requested == "sparse" and not cholmod.available():
        raise ValueError("solver.linear_solver: \"sparse\" needs SuiteSparse CHOLMOD, which "
                         "the cvxopt wheel ships (pip install cvxopt); use \"banded\"")
    return requested


def requested(model) -> str | None:
    """The linear solver a model's scene asks for (None: automatic)."""
    return model.scene.solver.linear_solver


def make(name: str, pattern: scipy.sparse.csr_matrix, symmetric: bool = True):
    """A linear solver ``name`` (``LINEAR_SOLVERS``) for matrices of ``pattern``."""
    return LINEAR_SOLVERS[name](pattern, symmetric)


_BY_MODEL: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def for_model(model):
    """The linear solver of ``model`` (chosen by ``choose`` from its scene), made once per
    model and kept as long as the model lives (the static analysis calls it per iteration)."""
    solver = _BY_MODEL.get(model)
    if solver is None:
        solver = make(choose(model.pattern, requested(model)), model.pattern)
        _BY_MODEL[model] = solver
    return solver


def pattern_values(matrix: scipy.sparse.spmatrix, pattern: scipy.sparse.csr_matrix) -> np.ndarray:
    """The entries of ``matrix`` at the entries of ``pattern``, in its order (nnz,)."""
    rows, cols = _coordinates(pattern)
    return np.asarray(scipy.sparse.csr_matrix(matrix)[rows, cols]).ravel()


def _coordinates(pattern: scipy.sparse.csr_matrix) -> tuple[np.ndarray, np.ndarray]:
    """(rows, cols) of the entries of a CSR ``pattern``, in its order."""
    rows = np.repeat(np.arange(pattern.shape[0]), np.diff(pattern.indptr))
    return rows, pattern.indices.astype(np.int64)
