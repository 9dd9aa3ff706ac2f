"""``ancf invariants``: symbolic (closed-form) against quadrature invariants, with costs.

For a straight reference the closed forms are exact, so the comparison measures the
quadrature's round-off; for a curved reference (an arc) there is no closed form and the
requested quadrature is compared with one of four times the order in every direction.
"""

from __future__ import annotations

import time

import numpy as np

from runtime.element import invariants as inv
from runtime.element.element import lame
from runtime.element.reference import bent_reference
from runtime.kernels.kind import element_kind
from runtime.kernels.loader import kernel_family

#: Element and material used for the comparison (SI units).
GEOMETRY = (1.0, 0.1, 0.1)
MATERIAL = {"E": 2.1e11, "nu": 0.3, "rho": 7800.0}
FAMILIES = {"mass": "mass", "C^ij": "cij", "K1": "k1", "D (gram)": "gram"}


def _timed(function, *args):
    start = time.perf_counter()
    result = function(*args)
    return result, time.perf_counter() - start


def _symbolic_derivation_s(kind: str) -> float | None:
    """Seconds SymPy takes to derive the closed-form integrals (None if symgen is absent)."""
    try:
        from symgen import derive
        from symgen.elements import get
    except ImportError:  # runtime installed without the generator
        return None
    from symgen import closed

    spec = get(kind)
    for cached in (derive.straight_integrals, closed.straight_tables, closed.domain_tables,
                   closed.factored):
        cached.cache_clear()
    from symgen.methods.common import closed_as_data

    if closed.factored(spec) is not None and closed_as_data(spec):
        # large elements: the exact tables only (what the generator emits for them)
        return _timed(closed.straight_tables, spec)[1]
    return _timed(derive.straight_integrals, spec)[1]


def curved_reference(meta):
    """The curved reference of the comparison: the element bent along x onto a circle of
    radius 2 m (an arc for beams, a cylindrical panel for plates; runtime.element.reference)."""
    return bent_reference(meta, GEOMETRY, 2.0)


def _law_pair(meta, builders, law: str, backend: str, reference: str, e0, orders):
    """(exact, numeric) law invariants and their times, the exact label, and a function giving
    the straight reference's entries outside the straight gram pattern (relative)."""
    laws = kernel_family(meta.name, "laws", backend)
    corrections = (inv.default_corrections(laws, law, MATERIAL["E"], MATERIAL["nu"])
                   if meta.laws[law].corrections else ())
    coefficients = inv.law_coefficients(meta, laws, law, MATERIAL["E"], MATERIAL["nu"],
                                        corrections)
    variant = "straight" if reference == "straight" else "general"

    def by_quadrature(variant_, orders_):
        rules = inv.law_rules(meta, builders, GEOMETRY, e0, orders_)
        return inv.numeric_law_invariants(meta, builders, variant_, GEOMETRY, rules,
                                          coefficients, MATERIAL["rho"])

    if reference == "straight":
        if inv.has_closed_tables(meta):   # exact tables (closed.json)
            exact, exact_s = _timed(lambda: inv.closed_law_invariants(
                meta, GEOMETRY, coefficients, MATERIAL["rho"]))
        elif inv.straight_by_quadrature(meta):   # the exact Gauss rule of load time
            exact, exact_s = _timed(by_quadrature, variant, meta.exact_orders)
        else:
            exact, exact_s = _timed(lambda: inv.straight_law_invariants(
                laws, GEOMETRY, coefficients, MATERIAL["rho"]))
        label = ("load-time quadrature " + "x".join(map(str, meta.exact_orders))
                 if inv.straight_by_quadrature(meta) else "closed form")
    else:
        orders_exact = tuple(4 * o for o in orders)
        exact, exact_s = _timed(by_quadrature, variant, orders_exact)
        label = f"quadrature {'x'.join(map(str, orders_exact))}"
    numeric, numeric_s = _timed(by_quadrature, variant, orders)

    def off_pattern() -> float:
        full = by_quadrature("general", orders)["gram"]
        keys = [tuple(k) for k in meta.pattern("general", "gram").tolist()]
        stored = {tuple(k) for k in meta.pattern("straight", "gram").tolist()}
        outside = np.array([key not in stored for key in keys])
        return float(np.abs(full[outside]).max(initial=0.0) / np.abs(full).max())

    return exact, exact_s, numeric, numeric_s, label, off_pattern


def compare(kind: str, reference: str = "straight", orders=None, backend: str = "numpy",
            law: str = "svk") -> dict:
    """Rows of the comparison and the storage counts, as a dict (see ``report``).

    law: a material law of docs/laws.md; ``svk`` compares the integrals of the isotropic
    path, any other law its closed-form (straight) or high-order quadrature (curved)
    invariants against quadrature with its volume and axis rules.
    """
    meta = element_kind(kind)
    orders = tuple(orders or meta.quadrature)
    if len(orders) != meta.dim or min(orders) < 1:
        raise ValueError(f"--quadrature: expected {meta.dim} positive orders, got {orders}")
    if reference not in ("straight", "curved"):
        raise ValueError(f"--reference: expected straight or curved, got {reference!r}")
    if law not in meta.laws:
        raise ValueError(f"--law: expected one of {', '.join(meta.laws)}, got {law!r}")
    if meta.laws[law].structural:
        raise ValueError(f"--law: {law} is a structural law: its invariants are the exact "
                         "quadrature of its strains along the centre line, with no closed "
                         "form or Voigt coefficients to compare (docs/laws.md)")
    if meta.energy.structural:
        return _compare_cable(meta, reference, orders, backend, law)
    if law != "svk" or inv.through_laws(meta) or (
            reference == "curved" and "invariants_general" not in meta.families):
        # kinds whose svk invariants come from the law path (closed forms as data tables, or
        # no general svk map) compare through it too
        result = _compare_law(meta, reference, orders, backend, law)
        if law == "svk" and reference == "straight" and not inv.straight_by_quadrature(meta):
            result["sympy_s"] = _symbolic_derivation_s(kind)
        return result
    lam, shear = lame(MATERIAL["E"], MATERIAL["nu"])
    material = (lam, shear, MATERIAL["rho"])
    builders = kernel_family(kind, "invariants", backend)
    if reference == "straight":
        variant, e0 = "straight", meta.straight_reference(*GEOMETRY)
        mapping = builders
        exact, exact_s = _timed(lambda: inv.stored_invariants(
            mapping, variant, inv.straight_integrals(meta, builders, GEOMETRY), material))
        exact_label = "closed form"
        orders_exact = None
    else:
        variant = "general"
        e0 = curved_reference(meta)
        mapping = kernel_family(kind, "invariants_general", backend)
        orders_exact = tuple(4 * o for o in orders)
        exact, exact_s = _timed(lambda: inv.stored_invariants(mapping, variant, (
            inv.pattern_integrals(meta, variant, inv.numeric_integrals(
                meta, builders, GEOMETRY, e0, orders_exact))), material))
        exact_label = f"quadrature {'x'.join(map(str, orders_exact))}"

    def by_quadrature():
        integrals = inv.numeric_integrals(meta, builders, GEOMETRY, e0, orders)
        return inv.stored_invariants(mapping, variant, inv.pattern_integrals(
            meta, variant, integrals), material), integrals

    (numeric, integrals), numeric_s = _timed(by_quadrature)
    rows = []
    for label, key in FAMILIES.items():
        a, b = exact[key], numeric[key]
        diff = float(np.abs(a - b).max())
        rows.append({"family": label, "entries": int(a.size), "max_abs_diff": diff,
                     "max_rel_diff": diff / float(np.abs(a).max())})
    off_pattern = None
    if variant == "straight":
        rows_, cols_ = np.triu_indices(meta.n_shape)
        keys = meta.pattern("straight", "i4")
        mask = np.ones((rows_.size, rows_.size), bool)
        mask[keys[:, 0], keys[:, 1]] = False
        full = integrals.i4[rows_[:, None], cols_[:, None], rows_[None, :], cols_[None, :]]
        off_pattern = float(np.abs(full[np.triu(mask)]).max() / np.abs(full).max())
    return {
        "kind": kind, "reference": reference, "orders": orders, "exact_label": exact_label,
        "law": "svk", "rows": rows, "exact_s": exact_s, "quadrature_s": numeric_s,
        "sympy_s": _symbolic_derivation_s(kind) if reference == "straight" else None,
        "structural_zeros_rel": off_pattern, "storage": _storage(meta, variant),
    }


def _storage(meta, variant: str) -> dict:
    npairs_dof = meta.ndof * (meta.ndof + 1) // 2
    npairs = meta.n_shape * (meta.n_shape + 1) // 2
    return {
        "cij_nonzeros": meta.cij_sizes[variant]["k2_nnz"],
        "cij_dense": npairs_dof * meta.ndof**2,
        "gram_nonzeros": len(meta.pattern(variant, "gram")),
        "gram_dense": npairs * npairs,
        "k1_mass_entries": npairs,
    }


def _compare_law(meta, reference: str, orders, backend: str, law: str) -> dict:
    builders = kernel_family(meta.name, "invariants", backend)
    if reference == "straight":
        variant, e0 = "straight", meta.straight_reference(*GEOMETRY)
    else:
        variant = "general"
        e0 = curved_reference(meta)
    exact, exact_s, numeric, numeric_s, label, off_pattern = _law_pair(
        meta, builders, law, backend, reference, e0, orders)
    rows = []
    for name, key in FAMILIES.items():
        a, b = exact[key], numeric[key]
        diff = float(np.abs(a - b).max())
        rows.append({"family": name, "entries": int(a.size), "max_abs_diff": diff,
                     "max_rel_diff": diff / float(np.abs(a).max())})
    return {
        "kind": meta.name, "reference": reference, "orders": orders, "exact_label": label,
        "law": law, "rows": rows, "exact_s": exact_s, "quadrature_s": numeric_s,
        "sympy_s": None, "structural_zeros_rel": off_pattern() if variant == "straight" else None,
        "storage": _storage(meta, variant),
    }


def _compare_cable(meta, reference: str, orders, backend: str, law: str) -> dict:
    """A cable's closed-form straight invariants (``law_invariants_straight``) against the
    same by quadrature along the axis (``cable_invariants``), or for an arc (the laws that
    take curved references) the quadrature against one of four times the order: the axial
    part and, for the simple bending model, its pre-integrated bending; the exact curvature
    has no invariant (its bending is Gauss quadrature at every call, noted in the
    result)."""
    info = meta.laws[law]
    if reference != "straight" and "general" not in info.variants:
        raise ValueError(f"--reference: {meta.name} with law {law} takes straight references "
                         f"only: {info.curved}")
    builders = kernel_family(meta.name, "invariants", backend)
    laws = kernel_family(meta.name, "laws", backend)
    coefficients = inv.law_coefficients(meta, laws, law, MATERIAL["E"], MATERIAL["nu"], ())
    bending = info.bending
    modulus = float(coefficients["axis"][0]) if bending == "simple" else 0.0
    if reference == "straight":
        label = "closed form"
        exact, exact_s = _timed(lambda: inv.straight_law_invariants(
            laws, GEOMETRY, coefficients, MATERIAL["rho"], modulus))
        numeric, numeric_s = _timed(lambda: inv.cable_invariants(
            meta, builders, GEOMETRY, orders, coefficients, MATERIAL["rho"], modulus))
    else:  # an arc: no closed form, quadrature of four times the order as the reference
        e0, finer = curved_reference(meta), tuple(4 * o for o in orders)
        label = f"quadrature {'x'.join(map(str, finer))}"
        exact, exact_s = _timed(lambda: inv.cable_invariants(
            meta, builders, GEOMETRY, finer, coefficients, MATERIAL["rho"], modulus, e0,
            "general"))
        numeric, numeric_s = _timed(lambda: inv.cable_invariants(
            meta, builders, GEOMETRY, orders, coefficients, MATERIAL["rho"], modulus, e0,
            "general"))
    rows = []
    for name, key in {**FAMILIES, "bending term (gram)": "gram_linear"}.items():
        a, b = exact[key], numeric[key]
        scale = float(np.abs(a).max())
        if scale == 0.0 and not np.abs(b).any():
            continue  # no pre-integrated bending (exact curvature)
        diff = float(np.abs(a - b).max())
        rows.append({"family": name, "entries": int(a.size), "max_abs_diff": diff,
                     "max_rel_diff": diff / scale})
    return {
        "kind": meta.name, "reference": reference, "orders": orders,
        "exact_label": label, "law": law, "rows": rows, "exact_s": exact_s,
        "quadrature_s": numeric_s, "sympy_s": None, "structural_zeros_rel": None,
        "storage": _storage(meta, "straight" if reference == "straight" else "general"),
        "note": None if bending == "simple" else (
            f"bending ({bending.replace('_', ' ')}): rational in the coordinates, no "
            f"invariant; Gauss quadrature of order {orders[0]} along the axis at every call"),
    }


def report(result: dict) -> str:
    """Markdown text of ``compare``'s result."""
    orders = "x".join(map(str, result["orders"]))
    law = f", law {result['law']}" if result.get("law", "svk") != "svk" else ""
    lines = [f"### {result['kind']}, {result['reference']} reference{law}: "
             f"{result['exact_label']} vs quadrature {orders}", "",
             "| invariant | stored entries | max abs diff | max rel diff |",
             "|---|---:|---:|---:|"]
    for row in result["rows"]:
        lines.append(f"| {row['family']} | {row['entries']} | {row['max_abs_diff']:.3e} | "
                     f"{row['max_rel_diff']:.3e} |")
    lines += ["", f"- time, {result['exact_label']}: {result['exact_s'] * 1e3:.2f} ms; "
              f"quadrature {orders}: {result['quadrature_s'] * 1e3:.2f} ms"]
    if result["sympy_s"] is not None:
        lines.append(f"- time, SymPy derivation of the closed forms (offline, once): "
                     f"{result['sympy_s']:.2f} s")
    if result["structural_zeros_rel"] is not None:
        lines.append(f"- entries outside the symbolic sparsity pattern, by quadrature: "
                     f"max {result['structural_zeros_rel']:.2e} relative (structural zeros)")
    if result.get("note"):
        lines.append(f"- {result['note']}")
    s = result["storage"]
    lines.append(f"- storage: C^ij {s['cij_nonzeros']} nonzeros (dense {s['cij_dense']}); "
                 f"D {s['gram_nonzeros']} unique nonzeros (dense {s['gram_dense']}); "
                 f"K1 and mass {s['k1_mass_entries']} entries each")
    return "\n".join(lines) + "\n"
