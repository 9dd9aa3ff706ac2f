"""What every method's kernels share: the kernels of a method family (``KERNELS``,
``DAMPING_KERNELS``), the rules for the looped forms and the closed forms as data, the common
arrays (coordinates, outputs), the exact node-relative translation, CSE materialisation and
stores, and the pair tables of looped kernels."""

from __future__ import annotations

from functools import lru_cache

import sympy as sp

from symgen import derive, energies
from symgen.element import ElementSpec
from symgen.ir import Array, Assign, Temporaries, refs

QUANTITIES = ("force", "jacobian", "energy")
#: The kernels of every method family: each computes the listed quantities in one pass
#: (a Newton iteration needs force and Jacobian together and shares their common part).  The
#: Jacobian alone is the combined kernel's (``runtime.element.Element.elastic_jacobian``): a
#: kernel of its own would cost a few per cent less at run time but double the largest
#: functions a family compiles (beam3d's quadrature_law: 16 s to compile instead of 31).
KERNELS = (("force",), ("energy",), ("force", "jacobian"))


def kernel_name(quantities) -> str:
    """The name of the kernel that computes ``quantities`` (e.g. ``force_jacobian``)."""
    return "_".join(quantities)


#: Kelvin-Voigt damping kernels (stress = D (eps + alpha eps_dot)) of the gram and
#: quadrature_law families: the damping force alone, and the elastic plus damping force with
#: both Jacobians in one pass (the damping force's own d/de is that kernel's less the elastic
#: Jacobian: ``Element.internal_force_and_jacobians`` less ``Element.elastic_jacobian``).
DAMPING_KERNELS = ("damping_force", "damped_force_jacobians")


#: Elements with more shape functions than this get the looped forms: gram and damping
#: kernels as tight loops over pair tables (``Loop`` statements) instead of unrolled code,
#: and closed-form invariants as exact data tables (``closed.json``, evaluated by the
#: runtime) instead of unrolled closed-form kernels.
LOOPED_ABOVE = 9
#: ... and the gram (damping) families whose storage pattern has more entries than this are
#: looped in any element: unrolled they are megabytes of C that take minutes to compile
#: (beam3d's damping_general: 1 MB, 185 s).  Below, unrolled wins at run time and stays
#: (beam3d_3node's gram_straight: 0.84 against 1.87 us per force + Jacobian; beam3d's
#: damping_straight: 3.9 against 5.6 us per damped force + Jacobians, batch 1000).
LOOPED_PATTERN_ABOVE = {"gram": 700, "damping": 250}


#: Elements with at least this many coordinates keep their straight closed forms as exact
#: data (closed.json, evaluated by the runtime with the law algebra) instead of unrolled
#: closed-form kernels (beam3d_3node's took 15 s to compile, the plate's did not finish).
CLOSED_AS_DATA_FROM = 27


def closed_as_data(spec: ElementSpec) -> bool:
    """Whether the straight closed forms of ``spec`` are emitted as data (closed.json)."""
    return spec.n_shape > LOOPED_ABOVE or spec.ndof >= CLOSED_AS_DATA_FROM


#: ... and the quadrature families of elements with at least this many coordinates get the
#: looped Jacobian at each point (unrolled, beam3d_3node's quadrature_law took 200 s).
LOOPED_QUADRATURE_FROM = 27


#: ... and the quadrature families of elements with at least this many coordinates also loop
#: over the shape functions at each point (``ShapeLoop``: one copy of the per-shape-function
#: statements instead of one per function), where every shape function has every gradient
#: (a complete gradient pattern: the table holds ds/dx of shape function k at k dim + c).
#: Unrolled, the brick's (96) quadrature_law took 62 s to compile (docs/new-element.md 6).
SHAPE_LOOPED_FROM = 96


def shape_looped(spec: ElementSpec) -> bool:
    """Whether the quadrature families of ``spec`` loop over the shape functions at each
    point (``SHAPE_LOOPED_FROM``)."""
    return spec.ndof >= SHAPE_LOOPED_FROM and len(derive.gradient_pattern(spec)) == spec.ndof


def looped(spec: ElementSpec, method: str | None = None, variant: str = "straight") -> bool:
    """Whether ``spec`` (or its ``method``'s families, gram and damping ones of storage
    ``variant``) gets the looped forms."""
    if spec.n_shape > LOOPED_ABOVE:
        return True
    if method in ("quadrature", "quadrature_law"):
        return spec.ndof >= LOOPED_QUADRATURE_FROM
    if method not in LOOPED_PATTERN_ABOVE:
        return False
    return len(derive.patterns(spec, variant).gram) > LOOPED_PATTERN_ABOVE[method]


# --- common pieces -----------------------------------------------------------------------------


def quantity_output(spec: ElementSpec, quantity: str) -> Array:
    size = {"force": spec.ndof, "jacobian": spec.ndof**2, "energy": 1}[quantity]
    doc = {
        "force": "elastic force -dU/de (N), per element",
        "jacobian": "d(force)/de (N/m), row-major ndof x ndof, per element",
        "energy": "strain energy U (J), per element",
    }[quantity]
    return Array(quantity, size, "output", doc)


def coordinate_arrays(spec: ElementSpec, with_reference: bool) -> list[Array]:
    arrays = [Array("e", spec.ndof, "batch", "element coordinates e, node-major")]
    if with_reference:
        arrays.append(Array("e0", spec.ndof, "batch", "reference coordinates e0"))
    return arrays


def _two_difference(body: list, temps: Temporaries, a, c):
    """s = fl(a - c) and its exact rounding error (Knuth's TwoSum with binary steps only)."""
    steps = []
    for expr in (a - c, None, None, None, None, None):
        steps.append(next(temps))
        if expr is not None:
            body.append(Assign(steps[-1].name, expr))
    s, bv, av, da, db, err = steps
    body.append(Assign(bv.name, s - a))
    body.append(Assign(av.name, s - bv))
    body.append(Assign(da.name, a - av))
    body.append(Assign(db.name, c + bv))
    body.append(Assign(err.name, da - db))
    return s, err


def translate(spec: ElementSpec, body: list, temps: Temporaries, with_reference: bool):
    """Positions relative to the element's first node.

    Returns (q, q0, dq), each a list of ndof expressions: translated current coordinates,
    translated reference, and their difference (None entries when no reference).  The first
    node's position becomes exactly zero.  Position differences carry their rounding errors
    (TwoSum), so dq is accurate to its own last bit whether the element sits far from the
    origin, far from its reference, or both.
    """
    d = spec.dim
    e, e0 = refs("e", spec.ndof), refs("e0", spec.ndof)
    first = spec.position_vectors[0]
    q, q0, dq = list(e), list(e0), [None] * spec.ndof
    for k in range(spec.n_shape):
        for c in range(d):
            i = k * d + c
            if k == first:
                q[i] = q0[i] = dq[i] = sp.Integer(0)
                continue
            if k in spec.position_vectors:
                q[i], error = _two_difference(body, temps, e[i], e[first * d + c])
                if with_reference:
                    q0[i], error0 = _two_difference(body, temps, e0[i], e0[first * d + c])
                    coarse, fine, dq[i] = next(temps), next(temps), next(temps)
                    body.append(Assign(coarse.name, q[i] - q0[i]))
                    body.append(Assign(fine.name, error - error0))
                    body.append(Assign(dq[i].name, coarse + fine))
            elif with_reference:
                dq[i] = next(temps)
                body.append(Assign(dq[i].name, e[i] - e0[i]))
    return q, q0, dq


#: Stages ``materialize`` keeps (the latest): a few hundred per element.
MATERIALIZED_CACHE = 2048


def materialize(body: list, temps: Temporaries, exprs: list) -> list:
    """Assign every non-trivial expression of a stage to a temporary (with CSE)."""
    statements, out, temps.count = _materialized(tuple(sp.sympify(x) for x in exprs),
                                                 temps.prefix, temps.count)
    body.extend(statements)
    return list(out)


@lru_cache(maxsize=MATERIALIZED_CACHE)
def _materialized(exprs: tuple, prefix: str, start: int) -> tuple[tuple, tuple, int]:
    """``materialize`` with temporaries numbered ``prefix`` from ``start``: the statements,
    the values (temporaries or atoms) and the next number.  Cached: families of one element
    repeat whole stages (the damping kernels of ``damping`` and ``damping_curvature``, the
    elastic parts of a family's kernels), and CSE is most of a stage's time."""
    temps = Temporaries(prefix, start)
    replacements, reduced = sp.cse(list(exprs), symbols=temps, order="none")
    statements = [Assign(symbol.name, expr) for symbol, expr in replacements]
    out = []
    for expr in reduced:
        if expr.is_Atom:
            out.append(expr)
        else:
            symbol = next(temps)
            statements.append(Assign(symbol.name, expr))
            out.append(symbol)
    return tuple(statements), tuple(out), temps.count


def store(body: list, name: str, values: list, accumulate: bool = False) -> None:
    for i, value in enumerate(values):
        if value != 0 or not accumulate:
            body.append(Assign(f"{name}[{i}]", sp.sympify(value), accumulate))


def store_symmetric(body: list, name: str, n: int, upper: dict, accumulate: bool) -> None:
    """Store a symmetric n x n matrix given its upper entries {(i, j): value}."""
    for i in range(n):
        for j in range(n):
            value = upper.get((min(i, j), max(i, j)), 0)
            if value != 0 or not accumulate:
                body.append(Assign(f"{name}[{i * n + j}]", sp.sympify(value), accumulate))


def geometry_subs(spec: ElementSpec, name: str) -> dict:
    return dict(zip(spec.domain.parameters, refs(name, 3), strict=True))


def geometry_doc(spec: ElementSpec) -> str:
    return f"{', '.join(spec.domain.labels)} in m"


def relative_velocities(spec: ElementSpec) -> list:
    """Velocities relative to the element's first node (its position rows become zero)."""
    d = spec.dim
    v = refs("e_dot", spec.ndof)
    first = spec.position_vectors[0]
    out = list(v)
    for k in spec.position_vectors:
        for c in range(d):
            out[k * d + c] = sp.Integer(0) if k == first else v[k * d + c] - v[first * d + c]
    return out


def loop_tables(spec: ElementSpec, variant: str) -> dict:
    """Sizes and tables of the ``Loop`` statements (see ``symgen.ir``)."""
    n = spec.n_shape
    pairs = derive.pairs(n)
    pidx = derive.pair_index(n)
    pattern = derive.patterns(spec, variant).gram
    return {"n": n, "d": spec.dim, "np": len(pairs), "ndof": spec.ndof, "nnz": len(pattern),
            "tables": {"pair_k": [k for k, _ in pairs], "pair_m": [m for _, m in pairs],
                       "pair_index": [pidx[(k, m)] for k in range(n) for m in range(n)],
                       "pattern_a": [a for a, _ in pattern],
                       "pattern_b": [b for _, b in pattern]}}


def looped_start(spec: ElementSpec, body: list, velocities: bool,
                 temps: Temporaries | None = None, current: bool = True) -> list[Array]:
    """Node-relative coordinates into the local arrays Q (unless not ``current``), Q0, DQ
    (and QD): unrolled, with the exact position differences of ``translate`` (temporaries
    from ``temps``, by default a fresh numbering)."""
    q, q0, dq = translate(spec, body, temps or Temporaries(), with_reference=True)
    named = [("Q", q, "coordinates relative to the first node")] if current else []
    named += [("Q0", q0, "reference coordinates relative to the first node"),
              ("DQ", dq, "displacements relative to the first node")]
    if velocities:
        named.append(("QD", relative_velocities(spec), "velocities relative to the first node"))
    for name, values, _ in named:
        for i, value in enumerate(values):
            body.append(Assign(f"{name}[{i}]", sp.sympify(value)))
    return [Array(name, spec.ndof, "local", doc) for name, _, doc in named]


def gram_gradient(vec: list, pairs: list, d: int, a: int, p: int, c: int):
    """d g_a / d Q_pc of the gram entry of pair ``a`` = (k, m), with the coordinates ``vec``
    for Q (Gamma; Gammadot with the velocities)."""
    k, m = pairs[a]
    if k == m == p:
        return 2 * vec[p * d + c]
    if k == p:
        return vec[m * d + c]
    if m == p:
        return vec[k * d + c]
    return 0


def invariant_outputs(spec: ElementSpec, pattern: derive.Patterns, k1_doc: str,
                      u0_doc: str) -> list[Array]:
    """The output arrays of the stored invariants (mass, k1, gram, cij, u0) of an invariants
    kernel, with the descriptions ``k1_doc`` and ``u0_doc``."""
    npairs = len(derive.pairs(spec.n_shape))
    return [Array("mass", npairs, "output", "shape-level mass matrix (kg), upper triangle"),
            Array("k1", npairs, "output", k1_doc),
            Array("gram", len(pattern.gram), "output", "gram matrix Dm, gram-pattern order"),
            Array("cij", len(pattern.cij), "output", "c^{kp}_{mq} of C^ij, cij-pattern order"),
            Array("u0", 1, "output", u0_doc), *gram_linear_arrays(spec, "output")]


def gram_linear_arrays(spec: ElementSpec, role: str, bending: str = "simple") -> list[Array]:
    """The linear term of the gram form (the cable's pre-integrated simple bending,
    ``symgen.energies``) as an array of ``role``, or none for energies without one and for
    the exact-curvature bending (by quadrature instead)."""
    if not energies.is_cable(spec) or bending != "simple":
        return []
    return [Array("gram_linear", len(derive.pairs(spec.n_shape)), role,
                  "linear term of U in DeltaG (N m, bending), upper-pair order")]


def gram_linear(spec: ElementSpec, bending: str = "simple") -> list:
    """The entries of the gram form's linear term (zeros where ``gram_linear_arrays`` has
    none)."""
    npairs = len(derive.pairs(spec.n_shape))
    if not gram_linear_arrays(spec, "shared", bending):
        return [0] * npairs
    return refs("gram_linear", npairs)
