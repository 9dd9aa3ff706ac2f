"""Kernel builders: each evaluation method (and the invariant builders) as ``ir.Kernel``s.

Families (one generated module each, so a scene compiles only what it uses):

* ``invariants``       - shape-function tables, closed-form straight integrals, and the map
                         from integrals to stored invariants (straight pattern);
* ``invariants_general``  - the same map for the general (curved) pattern;
* ``quadrature``       - Gauss quadrature of eq. 23 at every call (the paper's baseline);
* ``cij``              - the paper's invariants C^ij, K1, U0 (eqs. 27-41); the storage
                         pattern only changes the sparse operators built at run time;
* ``gram_<variant>``   - the compact gram tensor Dm with U = g^T Dm g, g = DeltaG;
* ``laws``             - the material laws (symgen/laws.py): each law's coefficients per
                         domain, default shear corrections, and the closed-form straight
                         invariants of any law from its coefficients;
* ``quadrature_law``   - Gauss quadrature of any material law (symgen/laws.py) at every call,
                         with Kelvin-Voigt damping;
* ``damping_<variant>``   - Kelvin-Voigt damping through the gram tensor Dm (its own family,
                         so undamped models never compile it).

Each method family has ``force``, ``jacobian`` and ``energy`` kernels.  All translate the
positions to the element's first node first; ``gram`` and ``quadrature`` work in the
DeltaG / displacement-gradient form so the reference state cancels exactly.
"""

from __future__ import annotations

import sympy as sp

from symgen import derive, laws
from symgen.element import ElementSpec
from symgen.ir import (
    Array,
    Assign,
    Kernel,
    Loop,
    PointLoop,
    SparseProduct,
    Temporaries,
    emit_cse,
    ref,
    refs,
)

QUANTITIES = ("force", "jacobian", "energy")
#: The kernels of every method family: each computes the listed quantities in one pass
#: (a Newton iteration needs force and Jacobian together and shares their common part).
KERNELS = (("force",), ("jacobian",), ("energy",), ("force", "jacobian"))


def _kernel_name(quantities) -> str:
    return "_".join(quantities)


#: Kelvin-Voigt damping kernels (stress = D (eps + alpha eps_dot)) of the gram and
#: quadrature_law families: the damping force alone, its two Jacobians, and the elastic plus
#: damping force with both Jacobians in one pass.
DAMPING_KERNELS = ("damping_force", "damping_jacobians", "damped_force_jacobians")


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


def looped(spec: ElementSpec, family: str | None = None) -> bool:
    """Whether ``spec`` (or its gram, damping or quadrature ``family``) gets the looped
    forms."""
    if spec.n_shape > LOOPED_ABOVE:
        return True
    if family in ("quadrature", "quadrature_law"):
        return spec.ndof >= LOOPED_QUADRATURE_FROM
    if family is None or not family.startswith(("gram_", "damping_")):
        return False
    method, _, variant = family.partition("_")
    return len(derive.patterns(spec, variant).gram) > LOOPED_PATTERN_ABOVE[method]


#: Families that run once per element type before a simulation (invariants, law
#: coefficients): their speed hardly matters, so their C is compiled at -O0, in a fraction of
#: a second (beam3d's invariants_general: 0.3 s, 10 s at -O3); every other family at -O3.
#: The levels go to element.json ``optimization`` (runtime.kernels.loader passes them to the
#: JIT) and decide which kernels the C emitter splits into parts (symgen.emit).
PREPROCESSING = ("invariants", "invariants_general", "laws")


def optimization(family: str) -> int:
    """The C optimisation level (0 to 3) of ``family``."""
    return 0 if family in PREPROCESSING else 3


def families(spec: ElementSpec) -> list[str]:
    """Names of every kernel family generated for an element."""
    # the general (curved) svk map only where it is small (unrolled, it is the i4 -> stored
    # map of the whole general pattern); otherwise curved references take the law path
    general = ["invariants_general"] if not closed_as_data(spec) and len(
        derive.patterns(spec, "general").gram) <= LOOPED_PATTERN_ABOVE["gram"] else []
    return ["invariants", *general, "quadrature", "cij"] + [
        f"gram_{v}" for v in derive.VARIANTS] + ["laws", "quadrature_law"] + [
        f"damping_{v}" for v in derive.VARIANTS]


def build_family(spec: ElementSpec, family: str) -> list[Kernel]:
    """All kernels of one family."""
    if family == "invariants":
        if closed_as_data(spec):  # closed forms as data (closed.json), for the runtime
            return [_shape_values_kernel(spec), _shape_gradients_kernel(spec)]
        return invariant_kernels(spec)
    if family == "laws":
        return law_kernels(spec)
    if family == "invariants_general":
        return [_invariants_kernel(spec, "general")]
    if family == "quadrature_law":
        return [quadrature_law_kernel(spec, name)
                for name in [_kernel_name(q) for q in KERNELS] + list(DAMPING_KERNELS)]
    method, _, variant = family.partition("_")
    variant = variant or "straight"
    if method == "damping":
        builder = looped_damping_kernel if looped(spec, family) else gram_damping_kernel
        return [builder(spec, name, variant) for name in DAMPING_KERNELS]
    builder = {"quadrature": quadrature_kernel, "cij": cij_kernel,
               "gram": looped_gram_kernel if looped(spec, family) else gram_kernel}[method]
    return [builder(spec, quantities, variant) for quantities in KERNELS]


# --- common pieces -----------------------------------------------------------------------------


def _output(spec: ElementSpec, quantity: str) -> Array:
    size = {"force": spec.ndof, "jacobian": spec.ndof**2, "energy": 1}[quantity]
    doc = {
        "force": "elastic force -dU/de (N), per element",
        "jacobian": "d(force)/de (N/m), row-major ndof x ndof, per element",
        "energy": "strain energy U (J), per element",
    }[quantity]
    return Array(quantity, size, "output", doc)


def _coordinates(spec: ElementSpec, with_reference: bool) -> list[Array]:
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


def _translate(spec: ElementSpec, body: list, temps: Temporaries, with_reference: bool):
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


def _materialize(body: list, temps: Temporaries, exprs: list) -> list:
    """Assign every non-trivial expression of a stage to a temporary (with CSE)."""
    exprs = [sp.sympify(x) for x in exprs]
    replacements, reduced = sp.cse(exprs, symbols=temps, order="none")
    for symbol, expr in replacements:
        body.append(Assign(symbol.name, expr))
    out = []
    for expr in reduced:
        if expr.is_Atom:
            out.append(expr)
        else:
            symbol = next(temps)
            body.append(Assign(symbol.name, expr))
            out.append(symbol)
    return out


def _store(body: list, name: str, values: list, accumulate: bool = False) -> None:
    for i, value in enumerate(values):
        if value != 0 or not accumulate:
            body.append(Assign(f"{name}[{i}]", sp.sympify(value), accumulate))


def _store_symmetric(body: list, name: str, n: int, upper: dict, accumulate: bool) -> None:
    """Store a symmetric n x n matrix given its upper entries {(i, j): value}."""
    for i in range(n):
        for j in range(n):
            value = upper.get((min(i, j), max(i, j)), 0)
            if value != 0 or not accumulate:
                body.append(Assign(f"{name}[{i * n + j}]", sp.sympify(value), accumulate))


# --- invariant builders ------------------------------------------------------------------------


def invariant_kernels(spec: ElementSpec) -> list[Kernel]:
    """Shape tables, closed-form straight integrals and the straight integrals -> invariants."""
    return [_shape_values_kernel(spec), _shape_gradients_kernel(spec),
            _straight_integrals_kernel(spec), _invariants_kernel(spec, "straight")]


def _geometry_subs(spec: ElementSpec, name: str) -> dict:
    return dict(zip(spec.domain.parameters, refs(name, 3), strict=True))


def _geometry_doc(spec: ElementSpec) -> str:
    return f"{', '.join(spec.domain.labels)} in m"


def _shape_values_kernel(spec: ElementSpec) -> Kernel:
    arrays = [Array("point", spec.dim, "batch", "local coordinates (x, y[, z]) in m"),
              Array("geometry", 3, "shared", _geometry_doc(spec)),
              Array("values", spec.n_shape, "output", "shape functions s_k")]
    subs = {**_geometry_subs(spec, "geometry"),
            **dict(zip(spec.coordinates, refs("point", spec.dim), strict=True))}
    body: list = []
    emit_cse(body, [(f"values[{k}]", s.subs(subs), False)
                    for k, s in enumerate(spec.shape_functions)], Temporaries())
    return Kernel("shape_values", "Shape functions at local points.", arrays, body)


def _shape_gradients_kernel(spec: ElementSpec) -> Kernel:
    pattern = derive.gradient_pattern(spec)
    grads = derive.shape_gradients(spec)
    arrays = [Array("point", spec.dim, "batch", "local coordinates (x, y[, z]) in m"),
              Array("geometry", 3, "shared", _geometry_doc(spec)),
              Array("gradients", len(pattern), "output",
                    "structurally nonzero ds_k/dx_alpha, in gradient-pattern order")]
    subs = {**_geometry_subs(spec, "geometry"),
            **dict(zip(spec.coordinates, refs("point", spec.dim), strict=True))}
    body: list = []
    emit_cse(body, [(f"gradients[{j}]", grads[k, c].subs(subs), False)
                    for j, (k, c) in enumerate(pattern)], Temporaries())
    return Kernel("shape_gradients", "Local shape-function gradients at local points.",
                  arrays, body)


def _integral_arrays(spec: ElementSpec, pattern: derive.Patterns, role: str) -> list[Array]:
    npairs = len(derive.pairs(spec.n_shape))
    return [Array("i4", len(pattern.i4), role, "int P_kl P_mn dV0 in i4-pattern order"),
            Array("i2", npairs, role, "int P dV0, upper triangle"),
            Array("mass_shape", npairs, role, "int s s^T dV0 (m^3), upper triangle"),
            Array("volume", 1, role, "int dV0 (m^3)")]


def _straight_integrals_kernel(spec: ElementSpec) -> Kernel:
    pattern = derive.patterns(spec, "straight")
    integrals = derive.straight_integrals(spec)
    subs = _geometry_subs(spec, "geometry")
    arrays = [Array("geometry", 3, "batch", _geometry_doc(spec)),
              *_integral_arrays(spec, pattern, "output")]
    pairs = derive.pairs(spec.n_shape)
    outputs = [(f"i4[{j}]", integrals.i4(key), False) for j, key in enumerate(pattern.i4)]
    outputs += [(f"i2[{a}]", integrals.i2[k, m], False) for a, (k, m) in enumerate(pairs)]
    outputs += [(f"mass_shape[{a}]", integrals.mass[k, m], False)
                for a, (k, m) in enumerate(pairs)]
    outputs += [("volume[0]", integrals.volume, False)]
    body: list = []
    emit_cse(body, [(t, sp.sympify(x).subs(subs), acc) for t, x, acc in outputs],
             Temporaries())
    return Kernel("integrals_straight",
                  "Closed-form integrals of the straight element (exact polynomial integration).",
                  arrays, body)


def _invariants_kernel(spec: ElementSpec, variant: str) -> Kernel:
    pattern = derive.patterns(spec, variant)
    n = spec.n_shape
    npairs = len(derive.pairs(n))
    i4_of = dict(zip(pattern.i4, refs("i4", len(pattern.i4)), strict=True))
    i2 = sp.Matrix(n, n, lambda k, m: ref("i2", derive.pair_index(n)[(k, m)]))
    mass = sp.Matrix(n, n, lambda k, m: ref("mass_shape", derive.pair_index(n)[(k, m)]))
    integrals = derive.Integrals(ref("volume", 0), mass, i2,
                                 lambda key: i4_of.get(key, sp.Integer(0)))
    values = derive.invariant_values(spec, pattern, integrals)
    material = dict(zip((derive.lam, derive.shear, derive.rho), refs("material", 3),
                        strict=True))
    arrays = [*_integral_arrays(spec, pattern, "batch"),
              Array("material", 3, "shared", "Lame lambda (Pa), shear modulus G (Pa), "
                    "density rho (kg/m^3)"),
              Array("mass", npairs, "output", "shape-level mass matrix (kg), upper triangle"),
              Array("k1", npairs, "output", "shape-level K1 of eq. 29 (N/m), upper triangle"),
              Array("gram", len(pattern.gram), "output", "gram matrix Dm, gram-pattern order"),
              Array("cij", len(pattern.cij), "output", "c^{kp}_{mq} of C^ij, cij-pattern order"),
              Array("u0", 1, "output", "U0 of eqs. 40-41 (J)")]
    outputs = [(f"{name}[{i}]", sp.sympify(v).subs(material), False)
               for name, vals in values.items() for i, v in enumerate(vals)]
    body: list = []
    emit_cse(body, outputs, Temporaries())
    return Kernel(f"invariants_{variant}",
                  f"Stored invariants from integrals ({variant} storage pattern).", arrays, body)


# --- material laws (symgen/laws.py) -------------------------------------------------------------


def law_kernels(spec: ElementSpec) -> list[Kernel]:
    """Per law its coefficients per domain (and default shear corrections), and the closed-form
    straight invariants of any law from its coefficients."""
    applicable = derive.applicable_laws(spec).values()
    built = [_law_coefficients_kernel(spec, law) for law in applicable]
    built += [_law_correction_kernel(spec, law) for law in applicable
              if law.default_corrections is not None]
    if closed_as_data(spec):  # closed forms as data (closed.json), for the runtime
        derive.check_law_patterns(spec)
        return built
    return built + [_law_invariants_straight_kernel(spec)]


def _law_material(spec: ElementSpec, law: laws.Law) -> tuple[list[Array], dict]:
    arrays = [Array("material", 2, "batch", "Young's modulus E (Pa), Poisson's ratio nu")]
    subs = dict(zip((laws.young, laws.poisson), refs("material", 2), strict=True))
    if law.default_corrections is not None:
        names = laws.correction_names(spec.dim)
        arrays.append(Array("correction", len(names), "batch",
                            f"shear correction factors {', '.join(names)}"))
        subs.update(zip(laws.corrections(spec.dim), refs("correction", len(names)),
                        strict=True))
    return arrays, subs


def _law_coefficients_kernel(spec: ElementSpec, law: laws.Law) -> Kernel:
    size = len(laws.coefficient_layout(spec.dim))
    arrays, subs = _law_material(spec, law)
    names = ", ".join(laws.coefficient_names(spec.dim))
    arrays += [Array(domain, size, "output", f"law coefficients ({names}) on the {domain} (Pa)")
               for domain in derive.law_domains(spec)]
    coefficients = law.domain_coefficients(spec.dim)
    body: list = []
    emit_cse(body, [(f"{domain}[{i}]", sp.sympify(value).subs(subs), False)
                    for domain in derive.law_domains(spec)
                    for i, value in enumerate(coefficients[domain])], Temporaries())
    return Kernel(f"law_{law.name}", f"Law coefficients per domain of {law.name}: "
                  f"{law.description}.", arrays, body)


def _law_correction_kernel(spec: ElementSpec, law: laws.Law) -> Kernel:
    names = laws.correction_names(spec.dim)
    arrays = [Array("material", 2, "batch", "Young's modulus E (Pa), Poisson's ratio nu"),
              Array("correction", len(names), "output",
                    f"default shear correction factors {', '.join(names)}")]
    subs = dict(zip((laws.young, laws.poisson), refs("material", 2), strict=True))
    body: list = []
    emit_cse(body, [(f"correction[{i}]", sp.sympify(value).subs(subs), False)
                    for i, value in enumerate(law.default_corrections(spec.dim))], Temporaries())
    return Kernel(f"law_{law.name}_correction",
                  f"Default shear correction factors of {law.name}.", arrays, body)


def _law_invariants_straight_kernel(spec: ElementSpec) -> Kernel:
    derive.check_law_patterns(spec)  # the straight patterns of svk serve every law
    pattern = derive.patterns(spec, "straight")
    npairs = len(derive.pairs(spec.n_shape))
    size = len(laws.coefficient_layout(spec.dim))
    parts = [(derive.straight_domain_integrals(spec, domain), refs(domain, size))
             for domain in derive.law_domains(spec)]
    density = ref("density", 0)
    values = derive.law_invariant_values(spec, pattern, parts,
                                         derive.straight_integrals(spec).mass, density)
    subs = _geometry_subs(spec, "geometry")
    names = ", ".join(laws.coefficient_names(spec.dim))
    arrays = [Array("geometry", 3, "batch", _geometry_doc(spec)),
              *[Array(domain, size, "shared", f"law coefficients ({names}) on the {domain} "
                      "(Pa)") for domain in derive.law_domains(spec)],
              Array("density", 1, "shared", "density rho (kg/m^3)"),
              Array("mass", npairs, "output", "shape-level mass matrix (kg), upper triangle"),
              Array("k1", npairs, "output", "shape-level K1 (N/m), upper triangle"),
              Array("gram", len(pattern.gram), "output", "gram matrix Dm, gram-pattern order"),
              Array("cij", len(pattern.cij), "output", "c^{kp}_{mq} of C^ij, cij-pattern order"),
              Array("u0", 1, "output", "energy of e = 0 (J)")]
    outputs = [(f"{name}[{i}]", sp.sympify(v).subs(subs), False)
               for name, vals in values.items() for i, v in enumerate(vals)]
    body: list = []
    emit_cse(body, outputs, Temporaries())
    return Kernel("law_invariants_straight",
                  "Stored invariants of any law of the straight element, closed form from its "
                  "law coefficients per domain.", arrays, body)


# --- quadrature: eq. 23 at every call ----------------------------------------------------------


def quadrature_table_width(spec: ElementSpec) -> int:
    """Doubles per quadrature point: nonzero shape gradients, then the weight."""
    return len(derive.gradient_pattern(spec)) + 1


def quadrature_kernel(spec: ElementSpec, quantities, variant: str = "") -> Kernel:
    """Gauss quadrature of the St. Venant-Kirchhoff energy, force or Jacobian at every call.

    Per point: J0 = Q0^T dS, B = dS J0^-1, H = dQ^T B, E = (H + H^T + H^T H)/2 (exact at the
    reference), S = lambda tr(E) I + 2 G E, F = I + H.
    """
    d, n = spec.dim, spec.n_shape
    pattern = derive.gradient_pattern(spec)
    width_ = quadrature_table_width(spec)
    arrays = [*_coordinates(spec, True),
              Array("material", 2, "shared", "Lame lambda and shear modulus G (Pa)"),
              Array("table", width_, "table",
                    "per Gauss point: nonzero ds/dx (gradient-pattern order), then weight (m^3)"),
              *[_output(spec, quantity) for quantity in quantities]]
    temps = Temporaries()
    body: list = []
    _, q0, dq = _translate(spec, body, temps, with_reference=True)
    lam_, g_ = refs("material", 2)
    tab = refs("tab", width_)
    ds = sp.zeros(n, d)
    for j, (k, c) in enumerate(pattern):
        ds[k, c] = tab[j]
    Q0 = sp.Matrix(n, d, q0)
    dQ = sp.Matrix(n, d, dq)
    point: list = []
    j0 = sp.Matrix(d, d, _materialize(point, temps, list(Q0.T * ds)))
    det = _materialize(point, temps, [j0.det(method="berkowitz")])[0]
    inv_det = _materialize(point, temps, [1 / det])[0]
    j0_inv = sp.Matrix(d, d, _materialize(point, temps, list(j0.adjugate() * inv_det)))
    b = sp.Matrix(n, d, _materialize(point, temps, list(ds * j0_inv)))
    h = sp.Matrix(d, d, _materialize(point, temps, list(dQ.T * b)))
    strain = sp.Matrix(d, d, _materialize(point, temps, list((h + h.T + h.T * h) / 2)))
    trace = _materialize(point, temps, [strain.trace()])[0]
    wdet = _materialize(point, temps, [tab[-1] * det])[0]
    if "energy" in quantities:
        energy = wdet * (lam_ / 2 * trace**2 + g_ * sum(x * x for x in strain))
        _store(point, "energy", [energy], accumulate=True)
    if "force" in quantities or "jacobian" in quantities:
        stress = sp.Matrix(d, d, _materialize(
            point, temps, list(lam_ * trace * sp.eye(d) + 2 * g_ * strain)))
        f = sp.eye(d) + h
        if "force" in quantities:
            bs = sp.Matrix(n, d, _materialize(point, temps, list(b * stress)))
            force = -wdet * (bs * f.T)
            _store(point, "force", list(force), accumulate=True)
        if "jacobian" in quantities and looped(spec, "quadrature"):
            dn = sp.Matrix(d, d, lambda x_, y_: lam_ + (2 * g_ if x_ == y_ else 0))
            _looped_point_jacobian(spec, point, b, f, stress, dn,
                                   [g_] * len(laws.shear_pairs(d)), -wdet)
        elif "jacobian" in quantities:
            a = sp.Matrix(n, d, _materialize(point, temps, list(b * f.T)))
            bsb = _materialize(point, temps, [(b[k, :] * stress * b[p, :].T)[0]
                                              for k, p in derive.pairs(n)])
            bb = _materialize(point, temps, [(b[k, :] * b[p, :].T)[0]
                                             for k, p in derive.pairs(n)])
            ff = _materialize(point, temps, [(f[x, :] * f[yy, :].T)[0]
                                             for x, yy in derive.pairs(d)])
            pidx, didx = derive.pair_index(n), derive.pair_index(d)
            upper = {}
            for i, j in derive.pairs(spec.ndof):
                (k, ca), (p, cb) = divmod(i, d), divmod(j, d)
                value = (lam_ * a[k, ca] * a[p, cb] + g_ * a[k, cb] * a[p, ca]
                         + g_ * bb[pidx[(k, p)]] * ff[didx[(ca, cb)]])
                if ca == cb:
                    value += bsb[pidx[(k, p)]]
                upper[(i, j)] = -wdet * value
            names = _materialize(point, temps, list(upper.values()))
            _store_symmetric(point, "jacobian", spec.ndof, dict(zip(upper, names, strict=True)),
                             accumulate=True)
    body.append(PointLoop("table", tuple(point), _default_points(spec)))
    if looped(spec, "quadrature") and "jacobian" in quantities:
        arrays += _point_locals(spec, damped=False)
    return Kernel(_kernel_name(quantities), f"Elastic {' and '.join(quantities)} by Gauss "
                  "quadrature at every call (no invariants).", arrays, body,
                  _loop_tables(spec, "straight") if looped(spec, "quadrature") else None)


def _default_points(spec: ElementSpec) -> int:
    total = 1
    for order in spec.quadrature:
        total *= order
    return total


# --- cij: the paper's invariants ---------------------------------------------------------------


def cij_sizes(spec: ElementSpec, variant: str) -> dict[str, int]:
    """Rows and structural nonzeros of the two sparse operators of the cij method."""
    d = spec.dim
    pattern = derive.patterns(spec, variant)
    k2 = sum(d * d if k < p else d * (d + 1) // 2 for k, p, _, _ in pattern.cij)
    jac = sum(4 * d * d if k < p else 2 * d * d for k, p, _, _ in pattern.cij)
    return {"k2_rows": len(derive.pairs(spec.ndof)), "k2_nnz": k2,
            "jacobian_rows": spec.ndof**2, "jacobian_nnz": jac,
            "products": len(derive.pairs(spec.ndof))}


def cij_kernel(spec: ElementSpec, quantities, variant: str = "straight") -> Kernel:
    """The paper's method: (K2)_ij = e^T C^ij e, F = -(K2 + K1) e, eq. 38, eq. 39.

    K2 (upper triangle) and the double sum of eq. 38 are sparse products of shared CSR
    operators, assembled from the stored C^ij once per element set, with the vector of
    coordinate products p_st = e_s e_t (s <= t).
    """
    d, n, ndof = spec.dim, spec.n_shape, spec.ndof
    sizes = cij_sizes(spec, variant)
    npairs_dof = sizes["k2_rows"]
    arrays = [*_coordinates(spec, False),
              Array("k1", len(derive.pairs(n)), "shared", "shape-level K1, upper triangle"),
              Array("u0", 1, "shared", "U0 (J)"),
              Array("k2_matrix", npairs_dof, "csr",
                    "maps coordinate products p to the upper triangle of K2"),
              Array("products", npairs_dof, "local", "p_st = e_s e_t, s <= t"),
              Array("k2", npairs_dof, "local", "upper triangle of K2(e)")]
    if "jacobian" in quantities:
        arrays.append(Array("jacobian_matrix", ndof * ndof, "csr",
                            "maps p to sum_j sum_s e_s (C^ij + C^ij^T)_sk e_j of eq. 38"))
        arrays.append(Array("second", ndof * ndof, "local", "the double sum of eq. 38"))
    arrays += [_output(spec, quantity) for quantity in quantities]
    if looped(spec):
        return _looped_cij_kernel(spec, quantities, variant, arrays)
    temps = Temporaries()
    body: list = []
    q, _, _ = _translate(spec, body, temps, with_reference=False)
    for a, (s, t) in enumerate(derive.pairs(ndof)):
        body.append(Assign(f"products[{a}]", sp.sympify(q[s] * q[t])))
    body.append(SparseProduct("k2", "k2_matrix", "products", npairs_dof, sizes["k2_nnz"]))
    pidx_dof, pidx = derive.pair_index(ndof), derive.pair_index(n)
    k1 = refs("k1", len(derive.pairs(n)))

    def k1_entry(i: int, j: int):
        (k, ca), (p, cb) = divmod(i, d), divmod(j, d)
        return k1[pidx[(k, p)]] if ca == cb else 0

    k2 = refs("k2", npairs_dof)
    doc = {"energy": "strain energy by eq. 39", "force": "elastic force F = -(K2(e) + K1) e, "
           "eqs. 25-35", "jacobian": "elastic Jacobian by eq. 38"}
    kernel = Kernel(_kernel_name(quantities),
                    "; ".join(doc[q] for q in quantities).capitalize() + ".", arrays, body)
    if "energy" in quantities:
        quartic = sum((1 if i == j else 2) * q[i] * k2[pidx_dof[(i, j)]] * q[j]
                      for i, j in derive.pairs(ndof))
        quadratic = sum((1 if i == j else 2) * q[i] * k1_entry(i, j) * q[j]
                        for i, j in derive.pairs(ndof))
        _store(body, "energy", [quartic / 4 + quadratic / 2 + ref("u0", 0)])
        if quantities == ("energy",):
            return kernel
    stiffness = _materialize(body, temps, [k2[pidx_dof[(i, j)]] + k1_entry(i, j)
                                           for i, j in derive.pairs(ndof)])
    if "force" in quantities:
        force = [-sum(stiffness[pidx_dof[(i, j)]] * q[j] for j in range(ndof))
                 for i in range(ndof)]
        _store(body, "force", force)
    if "jacobian" not in quantities:
        return kernel
    body.append(SparseProduct("second", "jacobian_matrix", "products", ndof * ndof,
                              sizes["jacobian_nnz"]))
    second = refs("second", ndof * ndof)
    _store(body, "jacobian", [-stiffness[pidx_dof[(i, k)]] - second[i * ndof + k]
                              for i in range(ndof) for k in range(ndof)])
    return kernel


# --- gram: U = g^T Dm g with g = DeltaG ----------------------------------------------------


def gram_kernel(spec: ElementSpec, quantities, variant: str) -> Kernel:
    """Gram form: g = DeltaG = Q0 dQ^T + dQ Q^T (upper), h = Dm g, U = g.h, F = -T' Q.

    T'_kk = 4 h_kk, T'_kl = 2 h_kl.  Jacobian: -(2 Gamma^T Dm Gamma + T' kron I) with
    Gamma = dg/de, built as W = Dm Gamma first.
    """
    d, n, ndof = spec.dim, spec.n_shape, spec.ndof
    pattern = derive.patterns(spec, variant)
    arrays = [*_coordinates(spec, True),
              Array("gram", len(pattern.gram), "shared", "gram matrix Dm, gram-pattern order"),
              *[_output(spec, quantity) for quantity in quantities]]
    doc = {"energy": "strain energy U = g^T Dm g", "force": "elastic force F = -T' Q",
           "jacobian": "elastic Jacobian -(2 Gamma^T Dm Gamma + T' kron I)"}
    temps = Temporaries()
    body: list = []
    q, q0, dq = _translate(spec, body, temps, with_reference=True)
    pairs = derive.pairs(n)
    pidx = derive.pair_index(n)
    node = lambda vec, k: [vec[k * d + c] for c in range(d)]  # noqa: E731
    g = _materialize(body, temps, [
        sum(a0 * b1 + a1 * b2 for a0, b1, a1, b2 in
            zip(node(q0, k), node(dq, m), node(dq, k), node(q, m), strict=True))
        for k, m in pairs])
    dm = {}
    for v, (a, b) in enumerate(pattern.gram):
        dm[(a, b)] = dm[(b, a)] = ref("gram", v)
    hvec = _materialize(body, temps, [
        sum(dm[(a, b)] * g[b] for b in range(len(pairs)) if (a, b) in dm)
        for a in range(len(pairs))])
    kernel = Kernel(_kernel_name(quantities),
                    "; ".join(doc[q] for q in quantities).capitalize() + ".", arrays, body)
    if "energy" in quantities:
        _store(body, "energy", [sum(x * y for x, y in zip(g, hvec, strict=True))])

    def tprime(k: int, m: int):
        return (4 if k == m else 2) * hvec[pidx[(k, m)]]

    if "force" in quantities:
        force = [-sum(tprime(k, m) * q[m * d + c] for m in range(n))
                 for k in range(n) for c in range(d)]
        _store(body, "force", force)
    if "jacobian" not in quantities:
        return kernel

    def gamma(a: int, p: int, c: int):
        """d g_a / d Q_pc."""
        k, m = pairs[a]
        if k == m == p:
            return 2 * q[p * d + c]
        if k == p:
            return q[m * d + c]
        if m == p:
            return q[k * d + c]
        return 0

    w_exprs = {}
    for a in range(len(pairs)):
        for p in range(n):
            for c in range(d):
                w_exprs[(a, p, c)] = sum(
                    dm[(a, b)] * gamma(b, p, c) for b in range(len(pairs))
                    if (a, b) in dm and p in pairs[b])
    w_names = dict(zip(w_exprs, _materialize(body, temps, list(w_exprs.values())), strict=True))
    upper = {}
    for i, j in derive.pairs(ndof):
        (p, b), (qn, c) = divmod(i, d), divmod(j, d)
        value = 2 * sum(gamma(a, p, b) * w_names[(a, qn, c)] for a in range(len(pairs))
                        if p in pairs[a])
        if b == c:
            value += tprime(p, qn)
        upper[(i, j)] = -value
    names = _materialize(body, temps, list(upper.values()))
    _store_symmetric(body, "jacobian", ndof, dict(zip(upper, names, strict=True)), False)
    return kernel


# --- Kelvin-Voigt damping in gram form ---------------------------------------------------------


def _velocities(spec: ElementSpec) -> list:
    """Velocities relative to the element's first node (its position rows become zero)."""
    d = spec.dim
    v = refs("e_dot", spec.ndof)
    first = spec.position_vectors[0]
    out = list(v)
    for k in spec.position_vectors:
        for c in range(d):
            out[k * d + c] = sp.Integer(0) if k == first else v[k * d + c] - v[first * d + c]
    return out


def _damping_arrays(spec: ElementSpec, name: str) -> tuple[Array, list[Array]]:
    """The e_dot input, alpha, and the outputs of a damping kernel ``name``."""
    e_dot = Array("e_dot", spec.ndof, "batch", "element velocities de/dt, node-major")
    alpha = Array("alpha", 1, "shared", "Kelvin-Voigt damping coefficient alpha (s)")
    force_doc = {"damping_force": "damping force -alpha int (deps/de)^T D eps_dot dV0 (N)",
                 "damped_force_jacobians": "elastic plus damping force (N)"}
    outputs = []
    if name in force_doc:
        outputs.append(Array("force", spec.ndof, "output", force_doc[name]))
    if name != "damping_force":
        which = "damping force" if name == "damping_jacobians" else "elastic plus damping force"
        outputs += [Array("jacobian", spec.ndof**2, "output",
                          f"d({which})/de (N/m), row-major ndof x ndof"),
                    Array("jacobian_dot", spec.ndof**2, "output",
                          f"d({which})/d(e_dot) (N s/m), row-major ndof x ndof")]
    return e_dot, [alpha, *outputs]


def gram_damping_kernel(spec: ElementSpec, name: str, variant: str) -> Kernel:
    """Kelvin-Voigt damping through the gram invariant: the dissipation is alpha gd^T Dm gd
    with gd = dG/dt = Qdot Q^T + Q Qdot^T (upper), so with hd = Dm (alpha gd) the damping
    force is -T'(hd) Q, d/de_dot = -2 alpha Gamma^T Dm Gamma and d/de = -(2 alpha Gamma^T Dm
    Gammadot + T'(hd) kron I) (Gammadot = Gamma of Qdot).  The one-pass kernel uses
    h = Dm (g + alpha gd) for the elastic plus damping force and its Jacobian."""
    d, n, ndof = spec.dim, spec.n_shape, spec.ndof
    pattern = derive.patterns(spec, variant)
    e_dot, tail = _damping_arrays(spec, name)
    arrays = [*_coordinates(spec, True), e_dot,
              Array("gram", len(pattern.gram), "shared", "gram matrix Dm, gram-pattern order"),
              *tail]
    temps = Temporaries()
    body: list = []
    q, q0, dq = _translate(spec, body, temps, with_reference=True)
    qd = _velocities(spec)
    alpha = ref("alpha", 0)
    pairs = derive.pairs(n)
    pidx = derive.pair_index(n)
    node = lambda vec, k: [vec[k * d + c] for c in range(d)]  # noqa: E731
    combined = name == "damped_force_jacobians"
    gd = _materialize(body, temps, [
        alpha * sum(a * b + c * e for a, b, c, e in
                    zip(node(qd, k), node(q, m), node(q, k), node(qd, m), strict=True))
        for k, m in pairs])
    if combined:
        g = _materialize(body, temps, [
            sum(a0 * b1 + a1 * b2 for a0, b1, a1, b2 in
                zip(node(q0, k), node(dq, m), node(dq, k), node(q, m), strict=True))
            for k, m in pairs])
        strain = _materialize(body, temps, [x + y for x, y in zip(g, gd, strict=True)])
    else:
        strain = gd
    dm = {}
    for v, (a, b) in enumerate(pattern.gram):
        dm[(a, b)] = dm[(b, a)] = ref("gram", v)
    hvec = _materialize(body, temps, [
        sum(dm[(a, b)] * strain[b] for b in range(len(pairs)) if (a, b) in dm)
        for a in range(len(pairs))])

    def tprime(k: int, m: int):
        return (4 if k == m else 2) * hvec[pidx[(k, m)]]

    doc = {"damping_force": "Kelvin-Voigt damping force -T'(Dm alpha gd) Q",
           "damping_jacobians": "Jacobians of the damping force with respect to e and e_dot",
           "damped_force_jacobians": "elastic plus damping force and its Jacobians with "
           "respect to e and e_dot, in one pass"}[name]
    kernel = Kernel(name, doc + " (gram form).", arrays, body)
    if name != "damping_jacobians":
        _store(body, "force", [-sum(tprime(k, m) * q[m * d + c] for m in range(n))
                               for k in range(n) for c in range(d)])
    if name == "damping_force":
        return kernel

    def gamma(vec, a: int, p: int, c: int):
        """d g_a / d Q_pc with the matrix ``vec`` for Q (Gamma, or Gammadot with Qdot)."""
        k, m = pairs[a]
        if k == m == p:
            return 2 * vec[p * d + c]
        if k == p:
            return vec[m * d + c]
        if m == p:
            return vec[k * d + c]
        return 0

    def dm_times(vec, scale):
        exprs = {}
        for a in range(len(pairs)):
            for p in range(n):
                for c in range(d):
                    exprs[(a, p, c)] = scale * sum(
                        dm[(a, b)] * gamma(vec, b, p, c) for b in range(len(pairs))
                        if (a, b) in dm and p in pairs[b])
        return dict(zip(exprs, _materialize(body, temps, list(exprs.values())), strict=True))

    w = dm_times(q, 1)              # Dm Gamma
    wd = dm_times(qd, alpha)        # Dm alpha Gammadot

    def gamma_t(other, i: int, j: int):
        (p, b), (qn, c) = divmod(i, d), divmod(j, d)
        return sum(gamma(q, a, p, b) * other[(a, qn, c)] for a in range(len(pairs))
                   if p in pairs[a])

    material = dict(zip(derive.pairs(ndof), _materialize(
        body, temps, [gamma_t(w, i, j) for i, j in derive.pairs(ndof)]), strict=True))
    full = []
    for i in range(ndof):
        for j in range(ndof):
            (p, b), (qn, c) = divmod(i, d), divmod(j, d)
            value = 2 * gamma_t(wd, i, j)
            if combined:
                value += 2 * material[(min(i, j), max(i, j))]
            if b == c:
                value += tprime(p, qn)
            full.append(-value)
    _store(body, "jacobian", _materialize(body, temps, full))
    upper = {ij: -2 * alpha * value for ij, value in material.items()}
    names = _materialize(body, temps, list(upper.values()))
    _store_symmetric(body, "jacobian_dot", ndof, dict(zip(upper, names, strict=True)), False)
    return kernel


# --- quadrature of any law at every call ------------------------------------------------------


def quadrature_law_table_width(spec: ElementSpec) -> int:
    """Doubles per point of the quadrature_law table: nonzero ds/dx, U^-1 upper, coefficients."""
    return (len(derive.gradient_pattern(spec)) + laws.voigt_size(spec.dim)
            + len(laws.coefficient_layout(spec.dim)))


def quadrature_law_kernel(spec: ElementSpec, name: str) -> Kernel:
    """Gauss quadrature of any law (symgen/laws.py) at every call, with Kelvin-Voigt damping.

    Each table row is a point of a domain's rule (volume points, then axis points): the local
    shape gradients ds/dx, the inverse of U (J0 = R0 U, R0 the local frame, U upper
    triangular), and the point's law coefficients times weight and det J0.  With b = ds U^-1
    (gradients in the local frame), F0 = Q0^T b, dF = dQ^T b, F = F0 + dF, the local strain is
    E = (F0^T dF + dF^T F0 + dF^T dF)/2, eps its Voigt form, sigma = D eps, and (Z_I the
    derivative of eps_I with respect to the coordinates)
      force = -b S F^T,  Jacobian = -(sum_IJ D_IJ Z_I Z_J + b S b^T kron I).
    Damping: eps_dot = Z edot, sigma_d = alpha D eps_dot; its force is -b S_d F^T,
    d/de_dot = -alpha sum D Z Z and d/de = -(alpha sum_J Y_J Zdot_J + b S_d b^T kron I) with
    Y_J = sum_I D_IJ Z_I and Zdot = Z with Fdot = Qdot^T b in place of F.
    """
    d, n, ndof = spec.dim, spec.n_shape, spec.ndof
    pattern = derive.gradient_pattern(spec)
    layout = laws.coefficient_layout(d)
    shears = laws.shear_pairs(d)
    upper_d = derive.pairs(d)
    width_ = quadrature_law_table_width(spec)
    damped = name in DAMPING_KERNELS
    quantities = {"damping_force": ("force",), "damping_jacobians": ("jacobian", "jacobian_dot"),
                  "damped_force_jacobians": ("force", "jacobian", "jacobian_dot")}.get(
        name, tuple(name.split("_")))
    arrays = [*_coordinates(spec, True)]
    if damped:
        e_dot, tail = _damping_arrays(spec, name)
        arrays.append(e_dot)
    table = Array("table", width_, "table",
                  "per point: nonzero ds/dx (gradient-pattern order), U^-1 upper triangle, "
                  "law coefficients times weight and det J0 (N m)")
    arrays.append(table)
    if damped:
        arrays += tail
    else:
        arrays += [_output(spec, quantity) for quantity in quantities]
    temps = Temporaries()
    body: list = []
    _, q0, dq = _translate(spec, body, temps, with_reference=True)
    qd = _velocities(spec) if damped else None
    alpha = ref("alpha", 0)
    tab = refs("tab", width_)
    ds = sp.zeros(n, d)
    for j, (k, c) in enumerate(pattern):
        ds[k, c] = tab[j]
    offset = len(pattern)
    u_inv = sp.zeros(d, d)
    for j, (a, b) in enumerate(upper_d):
        u_inv[a, b] = tab[offset + j]
    offset += len(upper_d)
    coefficient = dict(zip(layout, tab[offset:], strict=True))
    dn = sp.Matrix(d, d, lambda a, b: coefficient[(min(a, b), max(a, b))])
    dshear = [coefficient[(d + s, d + s)] for s in range(len(shears))]
    point: list = []
    bmat = sp.Matrix(n, d, _materialize(point, temps, list(ds * u_inv)))
    f0 = sp.Matrix(d, d, _materialize(point, temps, list(sp.Matrix(n, d, q0).T * bmat)))
    df = sp.Matrix(d, d, _materialize(point, temps, list(sp.Matrix(n, d, dq).T * bmat)))
    strain = (f0.T * df + df.T * f0 + df.T * df) / 2
    f = sp.Matrix(d, d, _materialize(point, temps, list(f0 + df)))
    eps = _materialize(point, temps, [strain[a, a] for a in range(d)]
                       + [2 * strain[a, b] for a, b in shears])

    def stress_of(voigt):
        normal = [sum(dn[a, b] * voigt[b] for b in range(d)) for a in range(d)]
        return normal + [dshear[s] * voigt[d + s] for s in range(len(shears))]

    def tensor(voigt):
        s_mat = sp.zeros(d, d)
        for a in range(d):
            s_mat[a, a] = voigt[a]
        for s, (a, b) in enumerate(shears):
            s_mat[a, b] = s_mat[b, a] = voigt[d + s]
        return s_mat

    def z_of(fmat):
        """Z_I(k, c) = d eps_I / d Q_kc with the deformation gradient ``fmat``."""
        rows = [[bmat[k, a] * fmat[c, a] for k in range(n) for c in range(d)] for a in range(d)]
        rows += [[bmat[k, a] * fmat[c, b] + bmat[k, b] * fmat[c, a] for k in range(n)
                  for c in range(d)] for a, b in shears]
        return rows

    sigma = stress_of(eps) if not name.startswith("damping") else None
    if name == "energy":
        _store(point, "energy", [sum(x * y for x, y in zip(eps, sigma, strict=True)) / 2],
               accumulate=True)
    if damped:
        fdot = sp.Matrix(d, d, _materialize(point, temps, list(sp.Matrix(n, d, qd).T * bmat)))
        eps_dot = _materialize(point, temps, [
            sum(f[c, a] * fdot[c, a] for c in range(d)) for a in range(d)] + [
            sum(f[c, a] * fdot[c, b] + fdot[c, a] * f[c, b] for c in range(d))
            for a, b in shears])
        sigma_d = [alpha * x for x in stress_of(eps_dot)]
        total = sigma_d if sigma is None else [x + y for x, y in zip(sigma, sigma_d, strict=True)]
    else:
        total = sigma
    if "force" in quantities or "jacobian" in quantities:
        s_total = sp.Matrix(d, d, _materialize(point, temps, list(tensor(total))))
    if "force" in quantities:
        bs = sp.Matrix(n, d, _materialize(point, temps, list(bmat * s_total)))
        _store(point, "force", list(-(bs * f.T)), accumulate=True)
    if "jacobian" in quantities and looped(spec, "quadrature_law"):
        if not damped:
            _looped_point_jacobian(spec, point, bmat, f, s_total, dn, dshear, -1)
        else:
            _looped_point_jacobian(spec, point, bmat, f, s_total, dn, dshear, -1,
                                   material=name == "damped_force_jacobians", fdot=fdot)
    elif "jacobian" in quantities:
        z = [_materialize(point, temps, row) for row in z_of(f)]
        y = [_materialize(point, temps, row) for row in _law_rows(dn, dshear, z, d)]
        geometric = _materialize(point, temps, [(bmat[k, :] * s_total * bmat[p, :].T)[0]
                                                for k, p in derive.pairs(n)])
        pidx = derive.pair_index(n)

        def geo(i: int, j: int):
            (k, a), (p, b) = divmod(i, d), divmod(j, d)
            return geometric[pidx[(k, p)]] if a == b else 0

        if not damped:
            upper = {(i, j): -(sum(zi[i] * yi[j] for zi, yi in zip(z, y, strict=True))
                               + geo(i, j)) for i, j in derive.pairs(ndof)}
            names = _materialize(point, temps, list(upper.values()))
            _store_symmetric(point, "jacobian", ndof, dict(zip(upper, names, strict=True)),
                             accumulate=True)
        else:
            zdot = [_materialize(point, temps, row) for row in z_of(fdot)]
            material = dict(zip(derive.pairs(ndof), _materialize(point, temps, [
                sum(zi[i] * yi[j] for zi, yi in zip(z, y, strict=True))
                for i, j in derive.pairs(ndof)]), strict=True))
            full = []
            for i in range(ndof):
                for j in range(ndof):
                    value = alpha * sum(yi[i] * zd[j] for yi, zd in zip(y, zdot, strict=True))
                    if name == "damped_force_jacobians":
                        value += material[(min(i, j), max(i, j))]
                    full.append(-(value + geo(i, j)))
            _store(point, "jacobian", _materialize(point, temps, full), accumulate=True)
            upper = {ij: -alpha * value for ij, value in material.items()}
            names = _materialize(point, temps, list(upper.values()))
            _store_symmetric(point, "jacobian_dot", ndof, dict(zip(upper, names, strict=True)),
                             accumulate=True)
    body.append(PointLoop("table", tuple(point), _default_law_points(spec)))
    if looped(spec, "quadrature_law") and "jacobian" in quantities:
        arrays += _point_locals(spec, damped)
    doc = {"force": "elastic force", "jacobian": "elastic Jacobian", "energy": "strain energy",
           "force_jacobian": "elastic force and Jacobian",
           "damping_force": "Kelvin-Voigt damping force",
           "damping_jacobians": "Jacobians of the damping force with respect to e and e_dot",
           "damped_force_jacobians": "elastic plus damping force and its Jacobians with "
           "respect to e and e_dot"}[name]
    return Kernel(name, f"{doc[0].upper()}{doc[1:]} of any law by Gauss quadrature at every "
                  "call (volume and axis rules).", arrays, body,
                  _loop_tables(spec, "straight") if looped(spec, "quadrature_law") else None)


def _law_rows(dn, dshear, z, d: int) -> list:
    """Y_J = sum_I D_IJ Z_I for rows Z_I of an orthotropic-form law (normal block, shear
    diagonal)."""
    rows = [[sum(dn[a, b] * z[b][i] for b in range(d)) for i in range(len(z[0]))]
            for a in range(d)]
    rows += [[dshear[s] * x for x in z[d + s]] for s in range(len(dshear))]
    return rows


def _default_law_points(spec: ElementSpec) -> int:
    """Volume points plus axis points of the default rule."""
    return _default_points(spec) + spec.quadrature[0]


# --- looped forms (large elements): gram and damping as loops over pair tables ---------------


def _loop_tables(spec: ElementSpec, variant: str) -> dict:
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


def _looped_start(spec: ElementSpec, body: list, velocities: bool) -> list[Array]:
    """Node-relative coordinates into the local arrays Q, Q0, DQ (and QD): unrolled, with
    the exact position differences of ``_translate``."""
    temps = Temporaries()
    q, q0, dq = _translate(spec, body, temps, with_reference=True)
    named = [("Q", q, "coordinates relative to the first node"),
             ("Q0", q0, "reference coordinates relative to the first node"),
             ("DQ", dq, "displacements relative to the first node")]
    if velocities:
        named.append(("QD", _velocities(spec), "velocities relative to the first node"))
    for name, values, _ in named:
        for i, value in enumerate(values):
            body.append(Assign(f"{name}[{i}]", sp.sympify(value)))
    return [Array(name, spec.ndof, "local", doc) for name, _, doc in named]


def looped_gram_kernel(spec: ElementSpec, quantities, variant: str) -> Kernel:
    """``gram_kernel`` as tight loops over the pair and pattern tables (large elements):
    g = Q0 dQ^T + dQ Q^T, h = Dm g, U = g.h, F = -T'(h) Q,
    J = -(2 Gamma^T (Dm Gamma) + T'(h) kron I)."""
    npairs = len(derive.pairs(spec.n_shape))
    pattern = derive.patterns(spec, variant)
    body: list = []
    local = _looped_start(spec, body, velocities=False)
    local += [Array("g", npairs, "local", "DeltaG, upper triangle"),
              Array("h", npairs, "local", "Dm g")]
    body += [Loop("zero", "g", (npairs,)), Loop("pair_products", "g", ("Q0", "DQ")),
             Loop("pair_products", "g", ("DQ", "Q")), Loop("zero", "h", (npairs,)),
             Loop("sym_pattern", "h", ("gram", "g"))]
    if "energy" in quantities:
        body.append(Loop("dot", "energy", ("g", "h", npairs)))
    if "force" in quantities:
        body.append(Loop("pair_force", "force", ("h", "Q"), -1))
    if "jacobian" in quantities:
        local.append(Array("W", npairs * spec.ndof, "local", "Dm Gamma"))
        body += [Loop("zero", "W", (npairs * spec.ndof,)), Loop("gamma", "W", ("gram", "Q")),
                 Loop("gamma_t", "jacobian", ("Q", "W"), -2),
                 Loop("kron_pair", "jacobian", ("h",), -1)]
    doc = {"energy": "strain energy U = g^T Dm g", "force": "elastic force F = -T' Q",
           "jacobian": "elastic Jacobian -(2 Gamma^T Dm Gamma + T' kron I)"}
    arrays = [*_coordinates(spec, True),
              Array("gram", len(pattern.gram), "shared", "gram matrix Dm, gram-pattern order"),
              *[_output(spec, quantity) for quantity in quantities], *local]
    return Kernel(_kernel_name(quantities),
                  "; ".join(doc[q] for q in quantities).capitalize() + " (looped).", arrays,
                  body, _loop_tables(spec, variant))


def looped_damping_kernel(spec: ElementSpec, name: str, variant: str) -> Kernel:
    """``gram_damping_kernel`` as tight loops (large elements): gd = alpha (Qd Q^T + Q Qd^T),
    h = Dm (gd [+ g]), force -T'(h) Q, d/de = -(2 Gamma^T Dm (alpha Gammadot [+ Gamma])
    + T'(h) kron I), d/de_dot = -2 alpha Gamma^T Dm Gamma."""
    npairs, ndof = len(derive.pairs(spec.n_shape)), spec.ndof
    pattern = derive.patterns(spec, variant)
    e_dot, tail = _damping_arrays(spec, name)
    alpha = ref("alpha", 0)
    combined = name == "damped_force_jacobians"
    body: list = []
    local = _looped_start(spec, body, velocities=True)
    local += [Array("strain", npairs, "local", "alpha dG/dt (+ DeltaG), upper triangle"),
              Array("h", npairs, "local", "Dm strain")]
    body += [Loop("zero", "strain", (npairs,)), Loop("pair_products", "strain", ("QD", "Q"), alpha),
             Loop("pair_products", "strain", ("Q", "QD"), alpha)]
    if combined:
        body += [Loop("pair_products", "strain", ("Q0", "DQ")),
                 Loop("pair_products", "strain", ("DQ", "Q"))]
    body += [Loop("zero", "h", (npairs,)), Loop("sym_pattern", "h", ("gram", "strain"))]
    if name != "damping_jacobians":
        body.append(Loop("pair_force", "force", ("h", "Q"), -1))
    if name != "damping_force":
        local.append(Array("W", npairs * ndof, "local", "Dm Gamma, then Dm (Gamma [+] alpha "
                           "Gammadot)"))
        body += [Loop("zero", "W", (npairs * ndof,)), Loop("gamma", "W", ("gram", "Q")),
                 Loop("gamma_t", "jacobian_dot", ("Q", "W"), -2 * alpha)]
        if combined:
            body.append(Loop("gamma", "W", ("gram", "QD"), alpha))
            body.append(Loop("gamma_t", "jacobian", ("Q", "W"), -2))
        else:
            body += [Loop("zero", "W", (npairs * ndof,)), Loop("gamma", "W", ("gram", "QD")),
                     Loop("gamma_t", "jacobian", ("Q", "W"), -2 * alpha)]
        body.append(Loop("kron_pair", "jacobian", ("h",), -1))
    doc = {"damping_force": "Kelvin-Voigt damping force -T'(Dm alpha gd) Q",
           "damping_jacobians": "Jacobians of the damping force with respect to e and e_dot",
           "damped_force_jacobians": "elastic plus damping force and its Jacobians with "
           "respect to e and e_dot, in one pass"}[name]
    arrays = [*_coordinates(spec, True), e_dot,
              Array("gram", len(pattern.gram), "shared", "gram matrix Dm, gram-pattern order"),
              *tail, *local]
    return Kernel(name, doc + " (gram form, looped).", arrays, body,
                  _loop_tables(spec, variant))


def _looped_cij_kernel(spec: ElementSpec, quantities, variant: str, arrays: list) -> Kernel:
    """``cij_kernel`` with its coordinate-level parts as loops (large elements): the products
    p_st, K2 = k2_matrix p and the double sum of eq. 38 as sparse products, force, Jacobian
    and energy as loops over the coordinates."""
    ndof = spec.ndof
    sizes = cij_sizes(spec, variant)
    temps = Temporaries()
    body: list = []
    q, _, _ = _translate(spec, body, temps, with_reference=False)
    for i, value in enumerate(q):
        body.append(Assign(f"Q[{i}]", sp.sympify(value)))
    body.append(Loop("dof_products", "products", ("Q",)))
    body.append(SparseProduct("k2", "k2_matrix", "products", sizes["k2_rows"],
                              sizes["k2_nnz"]))
    if "energy" in quantities:
        body.append(Loop("cij_energy", "energy", ("Q", "k2", "k1", "u0")))
    if "force" in quantities:
        body.append(Loop("cij_force", "force", ("Q", "k2", "k1"), -1))
    if "jacobian" in quantities:
        body.append(SparseProduct("second", "jacobian_matrix", "products", ndof * ndof,
                                  sizes["jacobian_nnz"]))
        body.append(Loop("cij_jacobian", "jacobian", ("k2", "k1", "second"), -1))
    doc = {"energy": "strain energy by eq. 39", "force": "elastic force F = -(K2(e) + K1) e, "
           "eqs. 25-35", "jacobian": "elastic Jacobian by eq. 38"}
    arrays = [*arrays, Array("Q", ndof, "local", "coordinates relative to the first node")]
    return Kernel(_kernel_name(quantities),
                  "; ".join(doc[q] for q in quantities).capitalize() + " (looped).", arrays,
                  body, _loop_tables(spec, "straight"))


def _z_rows(bmat, fmat, n: int, d: int) -> list:
    """Z_I(k, c) = d eps_I / d Q_kc (Voigt rows) with gradients ``bmat`` and the deformation
    gradient ``fmat``."""
    rows = [[bmat[k, a] * fmat[c, a] for k in range(n) for c in range(d)] for a in range(d)]
    rows += [[bmat[k, a] * fmat[c, b] + bmat[k, b] * fmat[c, a] for k in range(n)
              for c in range(d)] for a, b in laws.shear_pairs(d)]
    return rows


def _point_locals(spec: ElementSpec, damped: bool) -> list[Array]:
    size = laws.voigt_size(spec.dim) * spec.ndof
    arrays = [Array("Z", size, "local", "d eps / d e per Voigt row"),
              Array("Y", size, "local", "D Z"),
              Array("GEO", spec.n_shape**2, "local", "b S b^T")]
    if damped:
        arrays.append(Array("ZD", size, "local", "d eps_dot / d e_dot per Voigt row"))
    return arrays


def _looped_point_jacobian(spec: ElementSpec, point: list, bmat, fmat, smat, dn, dshear,
                           scale, material: bool = True, fdot=None) -> None:
    """The Jacobian at one point as loops (large elements): Z and Y = D Z stored (unrolled,
    small), then jacobian += scale (sum_I Z_I Y_I^T + (b S b^T) kron I); with ``fdot``
    (damping) jacobian += scale (alpha sum_I Y_I Zdot_I^T + geometric [+ material]) and
    jacobian_dot += scale alpha sum_I Z_I Y_I^T."""
    n, d, ndof = spec.n_shape, spec.dim, spec.ndof
    rows = laws.voigt_size(d)
    for r, row in enumerate(_z_rows(bmat, fmat, n, d)):
        for i, value in enumerate(row):
            point.append(Assign(f"Z[{r * ndof + i}]", sp.sympify(value)))
    zref = [[ref("Z", r * ndof + i) for i in range(ndof)] for r in range(rows)]
    for r, row in enumerate(_law_rows(dn, dshear, zref, d)):
        for i, value in enumerate(row):
            point.append(Assign(f"Y[{r * ndof + i}]", sp.sympify(value)))
    for k in range(n):
        for p in range(n):
            point.append(Assign(f"GEO[{k * n + p}]",
                                sp.sympify((bmat[k, :] * smat * bmat[p, :].T)[0])))
    if fdot is None:
        point.append(Loop("rows_product", "jacobian", ("Z", "Y", rows), scale))
    else:
        alpha = ref("alpha", 0)
        for r, row in enumerate(_z_rows(bmat, fdot, n, d)):
            for i, value in enumerate(row):
                point.append(Assign(f"ZD[{r * ndof + i}]", sp.sympify(value)))
        point.append(Loop("rows_product", "jacobian", ("Y", "ZD", rows), scale * alpha))
        if material:
            point.append(Loop("rows_product", "jacobian", ("Z", "Y", rows), scale))
        point.append(Loop("rows_product", "jacobian_dot", ("Z", "Y", rows), scale * alpha))
    point.append(Loop("kron_full", "jacobian", ("GEO",), scale))
