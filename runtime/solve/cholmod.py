"""SuiteSparse CHOLMOD, the sparse Cholesky factorisation of the ``sparse`` linear solver.

CHOLMOD (supernodal left-looking Cholesky with a fill-reducing ordering, AMD by default)
comes with the ``cvxopt`` wheel, which bundles SuiteSparse for Linux x86_64 and aarch64
(``cvxopt.libs/libcholmod-*.so*``).  This module opens that library through cffi in ABI
mode, so nothing is compiled against it: the Python engine and the static analysis call
it here, and the compiled step calls the same functions through the addresses
``functions()`` hands out (``templates/stepper.c.j2``), on the same symbolic analysis.

Only the stable head of CHOLMOD's public structs is declared (the fields every CHOLMOD
since version 1 begins with); ``cholmod_common`` is an opaque block larger than any
version's, initialised by ``cholmod_start``.  Matrices are given as the CSR pattern of a
symmetric matrix: read as compressed columns it is the same matrix, and with ``stype = 1``
CHOLMOD reads one triangle of it.
"""

from __future__ import annotations

import functools
import glob
import importlib.util
import os

import cffi
import numpy as np
import scipy.sparse

#: the head of CHOLMOD's structs (identical in CHOLMOD 3, 4 and 5; the compiled step
#: declares them too)
STRUCTS = """
typedef struct {
  size_t nrow, ncol, nzmax;
  void *p, *i, *nz, *x, *z;
  int stype, itype, xtype, dtype, sorted, packed;
} cholmod_sparse;
typedef struct {
  size_t nrow, ncol, nzmax, d;
  void *x, *z;
  int xtype, dtype;
} cholmod_dense;
typedef struct { size_t n, minor; void *Perm, *ColCount; } cholmod_factor;
"""
#: the functions used
CDEF = STRUCTS + """
int cholmod_start(void *common);
int cholmod_finish(void *common);
cholmod_factor *cholmod_analyze(cholmod_sparse *a, void *common);
int cholmod_factorize(cholmod_sparse *a, cholmod_factor *factor, void *common);
int cholmod_solve2(int system, cholmod_factor *factor, cholmod_dense *b, void *bset,
                   cholmod_dense **x, void **xset, cholmod_dense **y, cholmod_dense **e,
                   void *common);
int cholmod_free_factor(cholmod_factor **factor, void *common);
int cholmod_free_dense(cholmod_dense **dense, void *common);
"""
#: bytes reserved for cholmod_common (about 2.6 kB in CHOLMOD 3, 5 kB in CHOLMOD 5)
COMMON_BYTES = 1 << 16
#: byte offsets in cholmod_common (CHOLMOD 3 to 5) of grow0 (default 1.2), supernodal_switch
#: (40.0), supernodal (1: automatic) and print (3: errors and warnings on stdout), checked
#: before supernodal and print are set
GROW0, SUPERNODAL_SWITCH, SUPERNODAL, PRINT = 8, 40, 48, 144
#: byte offsets in cholmod_common (CHOLMOD 3) of nmethods (default 0), method[0].ordering
#: (1: CHOLMOD_GIVEN), postorder (1) and metis_dswitch (0.66, a check of the layout)
NMETHODS, METHOD0_ORDERING, POSTORDER, METIS_DSWITCH = 168, 316, 1864, 1880
#: CHOLMOD_NATURAL: the matrix's own order
NATURAL = 0
#: CHOLMOD_SUPERNODAL: always the supernodal L L^T, which stops at the first pivot that is
#: not positive (the simplicial L D L^T of small matrices would go on through an indefinite
#: matrix without pivoting); CHOLMOD_SIMPLICIAL: the simplicial L D L^T, which does that on
#: purpose for quasi-definite saddle systems (``runtime.solve.linear.KKTSystem``)
ALWAYS_SUPERNODAL, SIMPLICIAL = 2, 0
#: CHOLMOD_INT, CHOLMOD_REAL, CHOLMOD_DOUBLE, CHOLMOD_A (solve A x = b)
INT, REAL, DOUBLE, SYSTEM_A = 0, 1, 0, 0
#: functions the compiled step calls through their addresses
FUNCTIONS = ("cholmod_factorize", "cholmod_solve2")


class NotPositiveDefinite(ArithmeticError):
    """CHOLMOD stopped at a non-positive pivot (the matrix is indefinite or singular)."""


def library_path() -> str | None:
    """The CHOLMOD shared library of the installed cvxopt wheel, or None without one."""
    spec = importlib.util.find_spec("cvxopt")
    if spec is None or not spec.submodule_search_locations:
        return None
    package = next(iter(spec.submodule_search_locations))
    found = sorted(glob.glob(os.path.join(os.path.dirname(package), "cvxopt.libs",
                                          "libcholmod*.so*")))
    return found[0] if found else None


def available() -> bool:
    """Whether CHOLMOD can be loaded (the ``sparse`` solver needs it)."""
    return _library() is not None


@functools.cache
def _library():
    """(ffi, lib) of CHOLMOD, or None when it is missing or does not load."""
    path = library_path()
    if path is None:
        return None
    ffi = cffi.FFI()
    ffi.cdef(CDEF)
    try:
        # cvxopt's own module loads CHOLMOD's dependencies (BLAS, AMD, ...), which the
        # library itself finds by name only among those already loaded
        importlib.import_module("cvxopt.cholmod")
        return ffi, ffi.dlopen(path)
    except (ImportError, OSError):
        return None


def _loaded():
    loaded = _library()
    if loaded is None:
        raise RuntimeError("linear_solver: \"sparse\" needs SuiteSparse CHOLMOD, which the "
                           "cvxopt wheel ships (pip install cvxopt); use \"banded\"")
    return loaded


def functions() -> dict[str, int]:
    """Addresses of ``FUNCTIONS`` (for the compiled step)."""
    ffi, lib = _loaded()
    return {name: int(ffi.cast("uintptr_t", getattr(lib, name))) for name in FUNCTIONS}


def address(pointer) -> int:
    """The address of a cffi pointer of this module (to hand to another cffi module)."""
    ffi, _ = _loaded()
    return int(ffi.cast("uintptr_t", pointer))


def _configure(common, indefinite: bool) -> None:
    """Supernodal L L^T only (``indefinite``: the simplicial L D L^T), and no messages (a
    matrix not positive definite is reported to the caller, not printed).  RuntimeError when
    ``common`` has not the layout these offsets assume (a CHOLMOD this module does not
    know)."""
    ffi, _ = _loaded()
    doubles, ints = ffi.cast("double *", common), ffi.cast("int *", common)
    defaults = (doubles[GROW0 // 8], doubles[SUPERNODAL_SWITCH // 8], ints[SUPERNODAL // 4],
                ints[PRINT // 4])
    if defaults != (1.2, 40.0, 1, 3):
        raise RuntimeError(f"CHOLMOD at {library_path()}: unknown layout of cholmod_common "
                           f"(defaults {defaults}); use linear_solver \"banded\"")
    ints[SUPERNODAL // 4] = SIMPLICIAL if indefinite else ALWAYS_SUPERNODAL
    ints[PRINT // 4] = 0


def _natural_order(common) -> bool:
    """Make the next analysis on ``common`` keep the matrix's order (one method, the
    natural ordering, no postorder): False, with ``common`` untouched, when its layout is
    not the one these offsets assume."""
    ffi, _ = _loaded()
    doubles, ints = ffi.cast("double *", common), ffi.cast("int *", common)
    if (ints[NMETHODS // 4], ints[METHOD0_ORDERING // 4], ints[POSTORDER // 4],
            doubles[METIS_DSWITCH // 8]) != (0, 1, 1, 0.66):
        return False
    ints[NMETHODS // 4], ints[METHOD0_ORDERING // 4], ints[POSTORDER // 4] = 1, NATURAL, 0
    return True


class Cholesky:
    """Sparse Cholesky of symmetric matrices of one CSR pattern (n, n): the symbolic
    analysis (ordering, elimination tree, supernodes) once, here; ``factorize(values)`` per
    matrix, ``solve(rhs)`` per right-hand side.  ``values`` (nnz,) are in the pattern's
    order and must stay alive and unchanged between a factorisation and its solves only as
    long as the caller reuses the buffer ``self.values`` (which it may fill instead).
    ``indefinite``: the simplicial L D L^T without pivoting instead, for quasi-definite
    matrices (it stops only at a zero pivot)."""

    def __init__(self, pattern, indefinite: bool = False) -> None:
        ffi, lib = _loaded()
        self._ffi, self._lib = ffi, lib
        self.n = pattern.shape[0]
        self.indptr = np.ascontiguousarray(pattern.indptr, np.int32)
        self.indices = np.ascontiguousarray(pattern.indices, np.int32)
        #: the matrix values (pattern order); filled by ``factorize`` or by the caller
        self.values = np.zeros(self.indices.size)
        self._common_block = ffi.new("char[]", COMMON_BYTES)
        self.common = ffi.cast("void *", self._common_block)
        lib.cholmod_start(self.common)
        _configure(self._common_block, indefinite)
        #: the permuted matrix's values gathered from ``values`` (``permuted[k] =
        #: values[source[k]]``) and the permutation (solve: x[perm] = B^-1 b[perm]), or None
        self.source = self.perm = self.permuted = None
        self.matrix = self._sparse(self.indptr, self.indices, self.values, 1)
        self.factor = self._analyze()
        self._permute_before_factorising()
        #: CHOLMOD's solution buffers, allocated by the first solve and reused
        self.handles = ffi.new("cholmod_dense *[3]")
        #: the factor's handle for ``__del__``, made here: a finaliser runs wherever the
        #: garbage collector starts, possibly inside cffi's (non-reentrant) parser, so it
        #: must not name C types (``ffi.new("...")`` there waits for itself forever)
        self._factor_handle = ffi.new("cholmod_factor **", self.factor)

    def _sparse(self, indptr: np.ndarray, indices: np.ndarray, values: np.ndarray,
                stype: int):
        """A cholmod_sparse over the arrays (compressed columns; ``stype`` 1: the upper
        triangle is read, -1: the lower)."""
        ffi = self._ffi
        a = ffi.new("cholmod_sparse *")
        a.nrow = a.ncol = self.n
        a.nzmax = indices.size
        a.p = ffi.cast("void *", ffi.from_buffer(indptr))
        a.i = ffi.cast("void *", ffi.from_buffer(indices))
        a.x = ffi.cast("void *", ffi.from_buffer(values))
        a.nz = a.z = ffi.NULL
        a.stype, a.itype, a.xtype, a.dtype, a.sorted, a.packed = stype, INT, REAL, DOUBLE, 1, 1
        return a

    def _analyze(self):
        factor = self._lib.cholmod_analyze(self.matrix, self.common)
        if factor == self._ffi.NULL:
            raise MemoryError("CHOLMOD: the symbolic analysis failed (out of memory)")
        return factor

    def _permute_before_factorising(self) -> None:
        """Analyse the lower triangle of P A P^T (P: the fill-reducing, postordered order of
        the first analysis) in its natural order: ``cholmod_factorize`` then factorises
        the matrix as given, where with a permutation it transposes A into that triangle at
        every call (14 % of a 32 x 32 plate's factorisation, 15 % of the 200-joint chain's
        KKT L D L^T).  The triangle is gathered from A's upper entries, as CHOLMOD's
        transpose takes them: the same matrix (the solutions agree with the permuting
        factor's to round-off, 2e-17 on a plate).  Kept as analysed when ``common``'s layout
        is unknown."""
        ffi, lib = self._ffi, self._lib
        if not _natural_order(self._common_block):
            return
        perm = np.frombuffer(ffi.buffer(ffi.cast("int *", self.factor.Perm), 4 * self.n),
                             np.int32).copy()
        upper = scipy.sparse.triu(scipy.sparse.csr_matrix(
            (np.arange(self.indices.size, dtype=float), self.indices, self.indptr),
            shape=(self.n, self.n))).tocoo()
        inverse = np.empty_like(perm)
        inverse[perm] = np.arange(self.n, dtype=np.int32)
        rows, cols = inverse[upper.row], inverse[upper.col]
        lower = scipy.sparse.csc_matrix(
            (upper.data, (np.maximum(rows, cols), np.minimum(rows, cols))),
            shape=(self.n, self.n))
        lower.sort_indices()
        self._lower_indptr = np.ascontiguousarray(lower.indptr, np.int32)
        self._lower_indices = np.ascontiguousarray(lower.indices, np.int32)
        source = np.ascontiguousarray(lower.data.astype(np.int32))
        permuted = np.zeros(source.size)
        matrix = self._sparse(self._lower_indptr, self._lower_indices, permuted, -1)
        first, self.matrix = self.factor, matrix
        self.factor = self._analyze()
        lib.cholmod_free_factor(ffi.new("cholmod_factor **", first), self.common)
        self.source, self.perm, self.permuted = source, perm, permuted

    def column_counts(self) -> np.ndarray:
        """Entries of each column of the factor L (n,), diagonal included, from the symbolic
        analysis: ``sum(counts)`` is nnz(L), ``sum(counts**2)`` the factorisation's flops."""
        counts = self._ffi.cast("int *", self.factor.ColCount)
        return np.frombuffer(self._ffi.buffer(counts, 4 * self.n), np.int32).astype(np.int64)

    def factorize(self, values: np.ndarray | None = None) -> None:
        """Numeric factorisation of the matrix ``values`` (default: ``self.values`` as
        filled by the caller).  Raises NotPositiveDefinite."""
        if values is not None:
            self.values[:] = values
        if self.source is not None:
            np.take(self.values, self.source, out=self.permuted)
        self._lib.cholmod_factorize(self.matrix, self.factor, self.common)
        if self.factor.minor < self.n:
            raise NotPositiveDefinite(f"not positive definite at column {self.factor.minor}")

    def solve(self, rhs: np.ndarray) -> np.ndarray:
        """Solution (n,) or (n, k) of the factorised system."""
        ffi = self._ffi
        rhs = np.asarray(rhs, dtype=float)
        if self.perm is not None:
            rhs = rhs[self.perm]
        b = np.ascontiguousarray(rhs.T)         # column-major (n, k)
        columns = 1 if rhs.ndim == 1 else rhs.shape[1]
        dense = ffi.new("cholmod_dense *")
        dense.nrow, dense.ncol, dense.nzmax, dense.d = self.n, columns, self.n * columns, self.n
        dense.x = ffi.cast("void *", ffi.from_buffer(b))
        dense.z = ffi.NULL
        dense.xtype, dense.dtype = REAL, DOUBLE
        h = self.handles
        self._lib.cholmod_solve2(SYSTEM_A, self.factor, dense, ffi.NULL, h + 0, ffi.NULL,
                                 h + 1, h + 2, self.common)
        x = np.frombuffer(ffi.buffer(ffi.cast("double *", h[0].x), 8 * self.n * columns))
        x = x.copy() if rhs.ndim == 1 else x.reshape(columns, self.n).T.copy()
        if self.perm is None:
            return x
        solution = np.empty_like(x)
        solution[self.perm] = x
        return solution

    def __del__(self) -> None:
        lib, ffi = getattr(self, "_lib", None), getattr(self, "_ffi", None)
        if lib is None or getattr(self, "factor", ffi.NULL) == ffi.NULL:
            return
        for k in range(3):
            if self.handles[k] != ffi.NULL:
                lib.cholmod_free_dense(self.handles + k, self.common)
        lib.cholmod_free_factor(self._factor_handle, self.common)
        lib.cholmod_finish(self.common)
