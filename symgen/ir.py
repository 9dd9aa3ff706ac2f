"""A tiny kernel language: what a template needs to print one batched kernel.

A kernel runs its ``body`` once per element of a batch.  Array elements are written
``name[i]`` in both backends, so one expression printer serves C and NumPy; the templates
only differ in how arrays are declared, loaded and stored.

Array roles:
* ``batch``  - one row per element (input), may be broadcast (stride 0);
* ``shared`` - one array for the whole batch (invariants, material constants);
* ``output`` - one row per element (result);
* ``local``  - per-element scratch vector (needed where a sparse product reads or writes);
* ``table``  - one row per point of the optional point loop (quadrature tables);
* ``csr``    - a sparse matrix shared by the batch, used by ``SparseProduct``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import sympy as sp


@dataclass(frozen=True)
class Array:
    """A named array of ``size`` doubles per element (or per point, or shared)."""

    name: str
    size: int
    role: str
    doc: str = ""


@dataclass(frozen=True)
class Assign:
    """``target = expr`` (or ``+=`` when ``accumulate``); a plain symbol target is a temporary."""

    target: str
    expr: sp.Expr
    accumulate: bool = False


@dataclass(frozen=True)
class SparseProduct:
    """``target = matrix @ source`` for local/output vectors; ``nnz`` is for operation counts."""

    target: str
    matrix: str
    source: str
    rows: int
    nnz: int


@dataclass(frozen=True)
class PointLoop:
    """Repeat ``body`` for every row of the table ``table`` (e.g. every Gauss point)."""

    table: str
    body: tuple
    default_points: int


@dataclass(frozen=True)
class ShapeLoop:
    """Repeat ``body`` for every shape function k = 0 .. ``count`` - 1: its array elements
    index by ``k`` (``shape_ref``), so one copy of the per-shape-function statements serves
    all of them (large elements: ``symgen.methods.common.shape_looped``)."""

    count: int
    body: tuple


#: The loop index of a ``ShapeLoop`` as its statements print it.
SHAPE_INDEX = "k"


def shape_ref(name: str, stride: int, offset: int = 0) -> sp.Symbol:
    """The symbol printed as ``name[stride*k + offset]`` (k the ``ShapeLoop`` index)."""
    tail = f" + {offset}" if offset else ""
    return sp.Symbol(f"{name}[{stride}*{SHAPE_INDEX}{tail}]", real=True)


@dataclass
class Kernel:
    """One batched kernel: signature arrays in call order plus the per-element body."""

    name: str
    doc: str
    arrays: list[Array]
    body: list = field(default_factory=list)
    #: for kernels with ``Loop`` statements: n, d, np (pairs), ndof, nnz (gram pattern) and
    #: ``tables`` {name: ints} (pair_k, pair_m, pair_index, pattern_a, pattern_b)
    loop_tables: dict | None = None

    def role(self, role: str) -> list[Array]:
        """The arrays of one role, in signature order."""
        return [a for a in self.arrays if a.role == role]

    def array(self, name: str) -> Array:
        """The array called ``name``."""
        return next(a for a in self.arrays if a.name == name)


def ref(name: str, index: int) -> sp.Symbol:
    """The symbol printed as ``name[index]``."""
    return sp.Symbol(f"{name}[{index}]", real=True)


def refs(name: str, size: int) -> list[sp.Symbol]:
    """``ref(name, i)`` for i in range(size)."""
    return [ref(name, i) for i in range(size)]


class Temporaries:
    """Numbered temporaries t0, t1, ... unique within one kernel (the first ``start``)."""

    def __init__(self, prefix: str = "t", start: int = 0) -> None:
        self.prefix = prefix
        self.count = start

    def __iter__(self):
        return self

    def __next__(self) -> sp.Symbol:
        symbol = sp.Symbol(f"{self.prefix}{self.count}", real=True)
        self.count += 1
        return symbol


def emit_cse(body: list, outputs: list[tuple[str, sp.Expr, bool]], temps: Temporaries) -> None:
    """Append common-subexpression-eliminated statements computing ``outputs``.

    outputs: (target, expr, accumulate) triples; their expressions share temporaries.
    """
    replacements, reduced = sp.cse([expr for _, expr, _ in outputs], symbols=temps,
                                   order="none")
    for symbol, expr in replacements:
        body.append(Assign(symbol.name, expr))
    for (target, _, accumulate), expr in zip(outputs, reduced, strict=True):
        if expr != 0 or not accumulate:
            body.append(Assign(target, expr, accumulate))


def count_operations(expr: sp.Expr) -> int:
    """Floating-point operations to evaluate ``expr`` as printed (add, mul, div each 1)."""
    if expr.is_Atom:
        return 0
    if expr.is_Add:
        return len(expr.args) - 1 + sum(count_operations(a) for a in expr.args)
    if expr.is_Mul:
        factors = [a for a in expr.args if a not in (sp.S.NegativeOne,)]
        return max(len(factors) - 1, 0) + sum(count_operations(a) for a in factors)
    if expr.is_Pow:
        base, exponent = expr.args
        if exponent.is_Integer:
            return abs(int(exponent)) - 1 + (1 if exponent < 0 else 0) + count_operations(base)
        return 1 + count_operations(base)
    return 1 + sum(count_operations(a) for a in expr.args)


def kernel_operations(kernel: Kernel, points: int | None = None) -> int:
    """Operations per element of one kernel call (point loops counted ``points`` times)."""

    def count(statements, repeat: int) -> int:
        total = 0
        for st in statements:
            if isinstance(st, Assign):
                total += repeat * (count_operations(st.expr) + (1 if st.accumulate else 0))
            elif isinstance(st, SparseProduct):
                total += repeat * 2 * st.nnz
            elif isinstance(st, PointLoop):
                total += count(st.body, repeat * (points or st.default_points))
            elif isinstance(st, ShapeLoop):
                total += count(st.body, repeat * st.count)
            elif isinstance(st, Loop):
                t = kernel.loop_tables
                total += repeat * LOOP_OPS[st.op](t["n"], t["d"], t["np"], t["nnz"], st.args)
        return total

    return count(kernel.body, 1)


# --- looped operations (large elements): tight loops over pair tables -------------------------
#
# For an element with n shape functions in dim d, the pairs (k, m), k <= m, of the gram form
# are stored in row order; the family tables ``pair_k``, ``pair_m`` (npairs) and
# ``pair_index`` (n * n: the pair of (k, m) and (m, k)) and the gram pattern tables
# ``pattern_a``, ``pattern_b`` (its (a, b) entries) drive the loops, so the emitted code does
# not grow with the pattern.  ``scale`` is an expression (a number, or e.g. alpha[0]).


@dataclass(frozen=True)
class Loop:
    """One looped operation ``op`` on named arrays (see ``LOOP_OPS``)."""

    op: str
    target: str
    args: tuple
    scale: object = 1
    variant: str = ""


#: op: (description, operation count per element given (n, d, npairs, nnz)).
LOOP_OPS = {
    # target[a] = 0 for a < args[0]
    "zero": lambda n, d, p, z, a: 0,
    # target[a] += scale sum_c left[k d + c] right[m d + c], a = (k, m); args (left, right)
    "pair_products": lambda n, d, p, z, a: p * (2 * d + 1),
    # target[a] += scale sum_b D_ab source[b] (D symmetric from the pattern); args (values, source)
    "sym_pattern": lambda n, d, p, z, a: 4 * z,
    # target[k d + c] += scale sum_m T'(k, m) q[m d + c]; args (h, q)
    "pair_force": lambda n, d, p, z, a: n * n * (2 * d + 1),
    # W[a ndof + j] += scale sum_b D_ab Gamma_b,j(q); args (values, q)
    "gamma": lambda n, d, p, z, a: 2 * z * 2 * d * 2,
    # J[i ndof + j] += scale sum_a Gamma_a,i(q) W[a ndof + j]; args (q, W)
    "gamma_t": lambda n, d, p, z, a: p * 2 * d * n * d * 2,
    # J[(p d + c) ndof + q d + c] += scale T'(p, q); args (h,)
    "kron_pair": lambda n, d, p, z, a: n * n * (d + 1),
    # target[a] = q[s] q[t], a = (s, t), s <= t < ndof; args (q,)
    "dof_products": lambda n, d, p, z, a: n * d * (n * d + 1) // 2,
    # target[i] += scale sum_j (K2 + K1 kron I)_ij q[j]; args (q, k2, k1)
    "cij_force": lambda n, d, p, z, a: 3 * (n * d) ** 2,
    # target[i ndof + j] += scale ((K2 + K1 kron I)_ij + second[i ndof + j]); args (k2, k1,
    # second)
    "cij_jacobian": lambda n, d, p, z, a: 3 * (n * d) ** 2,
    # target[0] += e^T K2 e / 4 + e^T (K1 kron I) e / 2 + u0; args (q, k2, k1, u0)
    "cij_energy": lambda n, d, p, z, a: 3 * (n * d) ** 2,
    # target[i ndof + j] += scale sum_r X[r ndof + i] Y[r ndof + j]; args (X, Y, rows)
    "rows_product": lambda n, d, p, z, a: 2 * a[2] * (n * d) ** 2,
    # target[(k d + c) ndof + p d + c] += scale G[k n + p]; args (G,)
    "kron_full": lambda n, d, p, z, a: n * n * (d + 1),
    # target[k n + p] = sum_c left[k d + c] right[p d + c] (the geometric b S b^T from b and
    # S b); args (left, right)
    "shape_products": lambda n, d, p, z, a: n * n * 2 * d,
    # target[i] += scale source[i] for i < size; args (source, size)
    "axpy": lambda n, d, p, z, a: 2 * a[1],
    # target[0] += scale sum_i left[i] right[i], i < size; args (left, right, size)
    "dot": lambda n, d, p, z, a: 2 * a[2],
}
