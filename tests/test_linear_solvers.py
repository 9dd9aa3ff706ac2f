"""The linear solvers (``runtime.solve.linear``) against SciPy's sparse and dense solves:
symmetric positive definite, symmetric indefinite and non-symmetric matrices of one
pattern, several right-hand sides, joints through the Schur complement, singular matrices
reported as singular; the CHOLMOD binding on its own."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg
import scipy.sparse
import scipy.sparse.linalg

from runtime.catalog import LINEAR_SOLVERS
from runtime.solve import cholmod, linear


def _grid_pattern(n: int = 12, block: int = 3) -> scipy.sparse.csr_matrix:
    """The pattern of a 2D grid of n x n nodes with ``block`` coordinates each, nodes coupled
    to their 8 neighbours (a plate-like mesh)."""
    index = np.arange(n * n).reshape(n, n)
    pairs = []
    for di in (-1, 0, 1):
        for dj in (-1, 0, 1):
            a = index[max(0, -di): n - max(0, di), max(0, -dj): n - max(0, dj)]
            b = index[max(0, di): n + min(0, di) or None, max(0, dj): n + min(0, dj) or None]
            pairs.append(np.c_[a.ravel(), b.ravel()])
    nodes = np.concatenate(pairs)
    node_graph = scipy.sparse.csr_matrix((np.ones(len(nodes)), (nodes[:, 0], nodes[:, 1])),
                                         shape=(n * n, n * n))
    pattern = scipy.sparse.kron(node_graph, np.ones((block, block)), format="csr")
    pattern.sort_indices()
    return pattern


def _values(pattern, rng, shift: float, symmetric: bool = True) -> np.ndarray:
    """Values of a matrix of ``pattern``: symmetric (random + transpose) plus ``shift`` I."""
    random = scipy.sparse.csr_matrix((rng.standard_normal(pattern.nnz), pattern.indices,
                                      pattern.indptr), shape=pattern.shape)
    matrix = random + random.T if symmetric else random
    matrix = matrix + shift * scipy.sparse.eye(pattern.shape[0])
    return linear.pattern_values(matrix, pattern)


def _matrix(pattern, values) -> scipy.sparse.csr_matrix:
    return scipy.sparse.csr_matrix((values, pattern.indices, pattern.indptr),
                                   shape=pattern.shape)


@pytest.mark.parametrize("name", LINEAR_SOLVERS)
@pytest.mark.parametrize("shift, cholesky", [(40.0, True), (0.5, False)])
def test_symmetric_solves_match_scipy(name, shift, cholesky):
    # shift 40 makes the matrix diagonally dominant (positive definite); 0.5 leaves it
    # indefinite, where both solvers fall back to an LU
    rng = np.random.default_rng(3)
    pattern = _grid_pattern()
    values = _values(pattern, rng, shift)
    matrix = _matrix(pattern, values)
    eigenvalues = np.linalg.eigvalsh(matrix.toarray())
    assert (eigenvalues.min() > 0) == cholesky
    rhs = rng.standard_normal((pattern.shape[0], 3))
    expected = scipy.sparse.linalg.spsolve(matrix.tocsc(), rhs)
    factor = linear.make(name, pattern).factor(values)
    assert factor.cholesky == cholesky
    scale = np.abs(expected).max()
    assert np.abs(factor.solve(rhs) - expected).max() <= 1e-11 * scale
    assert np.abs(factor.solve(rhs[:, 0]) - expected[:, 0]).max() <= 1e-11 * scale


@pytest.mark.parametrize("name", LINEAR_SOLVERS)
def test_non_symmetric_solves_match_a_dense_solve(name):
    rng = np.random.default_rng(4)
    pattern = _grid_pattern(8)
    values = _values(pattern, rng, 30.0, symmetric=False)
    matrix = _matrix(pattern, values).toarray()
    assert np.abs(matrix - matrix.T).max() > 1.0
    rhs = rng.standard_normal(pattern.shape[0])
    expected = scipy.linalg.solve(matrix, rhs)
    solution = linear.make(name, pattern, symmetric=False).factor(values).solve(rhs)
    assert np.abs(solution - expected).max() <= 1e-11 * np.abs(expected).max()


@pytest.mark.parametrize("name", LINEAR_SOLVERS)
def test_one_analysis_serves_many_matrices(name):
    rng = np.random.default_rng(5)
    pattern = _grid_pattern(6)
    solver = linear.make(name, pattern)
    for shift in (30.0, 60.0, 0.3, 45.0):      # positive definite, indefinite, and back
        values = _values(pattern, rng, shift)
        rhs = rng.standard_normal(pattern.shape[0])
        expected = scipy.sparse.linalg.spsolve(_matrix(pattern, values).tocsc(), rhs)
        solution = solver.factor(values).solve(rhs)
        assert np.abs(solution - expected).max() <= 1e-11 * np.abs(expected).max()


@pytest.mark.parametrize("name", LINEAR_SOLVERS)
def test_a_singular_matrix_is_reported_singular(name):
    # two coordinates with no stiffness at all: zero rows and columns
    pattern = _grid_pattern(5)
    values = _values(pattern, np.random.default_rng(6), 40.0)
    matrix = _matrix(pattern, values).tolil()
    matrix[:2, :] = 0.0
    matrix[:, :2] = 0.0
    values = linear.pattern_values(matrix.tocsr(), pattern)
    with pytest.raises(np.linalg.LinAlgError):
        linear.make(name, pattern).factor(values)


@pytest.mark.parametrize("name", LINEAR_SOLVERS)
def test_joints_through_the_schur_complement_match_the_saddle_point(name):
    rng = np.random.default_rng(7)
    pattern = _grid_pattern(6)
    n = pattern.shape[0]
    values = _values(pattern, rng, 40.0)
    joints = scipy.sparse.random(5, n, density=0.05, random_state=8, format="csr")
    joints = joints + scipy.sparse.csr_matrix((np.ones(5), (np.arange(5), np.arange(5))),
                                              shape=(5, n))
    rhs, rhs_joints = rng.standard_normal(n), rng.standard_normal(5)
    saddle = scipy.sparse.bmat([[_matrix(pattern, values), joints.T], [joints, None]])
    expected = scipy.sparse.linalg.spsolve(saddle.tocsc(), np.r_[rhs, rhs_joints])
    x, y = linear.SchurSolver(linear.make(name, pattern).factor(values), joints).solve(
        rhs, rhs_joints)
    assert np.abs(np.r_[x, y] - expected).max() <= 1e-10 * np.abs(expected).max()


def test_cholmod_factorises_in_place_and_names_the_failing_column():
    pattern = _grid_pattern(4)
    values = _values(pattern, np.random.default_rng(9), 40.0)
    cholesky = cholmod.Cholesky(pattern)
    cholesky.values[:] = values                  # the compiled step fills this buffer
    cholesky.factorize()
    rhs = np.arange(pattern.shape[0], dtype=float)
    expected = scipy.sparse.linalg.spsolve(_matrix(pattern, values).tocsc(), rhs)
    assert np.abs(cholesky.solve(rhs) - expected).max() <= 1e-12 * np.abs(expected).max()
    with pytest.raises(cholmod.NotPositiveDefinite, match="column"):
        cholesky.factorize(-values)


def test_cholmod_factorises_the_matrix_in_its_factors_order(monkeypatch):
    """The lower triangle of P A P^T, gathered from the pattern-order values and analysed in
    its natural order (no transpose per factorisation), solves as scipy's direct solve; a
    CHOLMOD whose common block has another layout keeps the factor's own permutation."""
    pattern = _grid_pattern(6)
    values = _values(pattern, np.random.default_rng(4), 40.0)
    matrix = _matrix(pattern, values).tocsc()
    rhs = np.random.default_rng(5).standard_normal((pattern.shape[0], 3))
    expected = scipy.sparse.linalg.spsolve(matrix, rhs)
    permuted = cholmod.Cholesky(pattern)
    assert permuted.source is not None
    assert np.array_equal(np.sort(permuted.perm), np.arange(pattern.shape[0]))
    assert not np.array_equal(permuted.perm, np.arange(pattern.shape[0]))   # AMD reorders
    monkeypatch.setattr(cholmod, "_natural_order", lambda common: False)
    own = cholmod.Cholesky(pattern)
    assert own.source is None and own.perm is None
    for cholesky in (permuted, own):
        cholesky.factorize(values)
        assert np.abs(cholesky.solve(rhs) - expected).max() <= 1e-12 * np.abs(expected).max()
        assert np.abs(cholesky.solve(rhs[:, 0]) - expected[:, 0]).max() <= (
            1e-12 * np.abs(expected).max())
    assert np.abs(permuted.solve(rhs) - own.solve(rhs)).max() <= 1e-14 * np.abs(expected).max()


def test_cholmod_releases_its_factor_without_naming_c_types():
    """The finaliser runs wherever the garbage collector starts, also inside cffi's
    non-reentrant parser (a kernel's cdef): naming a C type there waited forever."""
    pattern = _grid_pattern(3)
    cholesky = cholmod.Cholesky(pattern)
    cholesky.factorize(_values(pattern, np.random.default_rng(2), 40.0))
    cholesky.solve(np.ones(pattern.shape[0]))   # solution buffers to free too

    class OnlyNull:                    # the cffi module with every type-naming call refused
        NULL = cholesky._ffi.NULL

        def __getattr__(self, name):
            raise AssertionError(f"__del__ called ffi.{name}")

    cholesky._ffi = OnlyNull()
    cholesky.__del__()
    cholesky.factor = OnlyNull.NULL     # freed: the collector's call returns at once


def test_the_choice_rejects_unknown_solvers_naming_the_key():
    with pytest.raises(ValueError, match=r"solver.linear_solver: expected one of banded"):
        linear.choose(_grid_pattern(3), "cholesky")


def test_cholmod_column_counts_measure_the_factor():
    # a chain of blocks (a beam) fills nothing under a minimum-degree ordering: L holds the
    # upper triangle's entries exactly; a 2D grid fills in, within the dense triangle
    chain = scipy.sparse.kron(scipy.sparse.diags_array([1.0, 1.0, 1.0], offsets=[-1, 0, 1],
                                                        shape=(30, 30)),
                              np.ones((4, 4)), format="csr")
    chain.sort_indices()
    counts = cholmod.Cholesky(chain).column_counts()
    assert counts.shape == (120,) and counts.min() >= 1
    assert counts.sum() == scipy.sparse.triu(chain).nnz
    grid = _grid_pattern(12)
    n = grid.shape[0]
    counts = cholmod.Cholesky(grid).column_counts()
    assert scipy.sparse.triu(grid).nnz < counts.sum() < n * (n + 1) // 2


def test_kkt_system_solves_the_saddle_point_to_round_off():
    # [[S, C^T], [C, 0]] through the regularised L D L^T and one refinement, against
    # SciPy's LU of the exact saddle system; a second matrix of the same structure reuses
    # the analysis
    pattern = _grid_pattern(6)
    n = pattern.shape[0]
    rng = np.random.default_rng(4)
    rows = scipy.sparse.random(30, n, density=0.05, random_state=5, format="csr")
    system = linear.KKTSystem(pattern, rows)
    for shift in (40.0, 80.0):
        values = _values(pattern, rng, shift)
        factor = system.factor(values, rows)
        rhs, rhs_rows = rng.standard_normal(n), rng.standard_normal(30)
        saddle = scipy.sparse.bmat([[_matrix(pattern, values), rows.T], [rows, None]])
        expected = scipy.sparse.linalg.spsolve(saddle.tocsc(), np.r_[rhs, rhs_rows])
        x, y = factor.solve(rhs, rhs_rows)
        assert np.abs(np.r_[x, y] - expected).max() <= 1e-12 * np.abs(expected).max()
    # rows with an entry outside the analysed structure are refused, not dropped
    other = scipy.sparse.random(30, n, density=0.05, random_state=6, format="csr")
    with pytest.raises(RuntimeError, match="outside the structure"):
        system.factor(values, other)
