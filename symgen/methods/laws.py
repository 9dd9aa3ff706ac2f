"""The kernels of the ``laws`` family (material laws of ``symgen.laws``): each law's
coefficients per domain, its default shear corrections, and the closed-form straight
invariants of any law from its coefficients."""

from __future__ import annotations

import sympy as sp

from symgen import derive, energies, laws, structural
from symgen.element import ElementSpec
from symgen.ir import Array, Kernel, Temporaries, emit_cse, ref, refs
from symgen.methods.common import closed_as_data, geometry_doc, geometry_subs, invariant_outputs


def build(spec: ElementSpec) -> list[Kernel]:
    """Per law its coefficients per domain (and default shear corrections), and the closed-form
    straight invariants of any law from its coefficients."""
    applicable = derive.applicable_laws(spec).values()
    built = [_structural_stiffness_kernel(spec, law) if structural.is_structural(law)
             else _law_coefficients_kernel(spec, law) for law in applicable]
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


def _structural_stiffness_kernel(spec: ElementSpec, law: structural.StructuralLaw) -> Kernel:
    """The section stiffness of each strain of a structural law (``symgen.structural``) from
    E, nu, the shear corrections and the section."""
    arrays, subs = _law_material(spec, law)
    strains = law.strains(spec.dim)
    subs.update(geometry_subs(spec, "geometry"))
    arrays = [arrays[0], Array("geometry", 3, "shared", geometry_doc(spec)), *arrays[1:],
              Array("stiffness", len(strains), "output", "section stiffness per strain ("
                    + "; ".join(f"{s.name}: {s.doc}" for s in strains) + "; N, N m^2)")]
    body: list = []
    emit_cse(body, [(f"stiffness[{i}]", sp.sympify(s.stiffness).subs(subs), False)
                    for i, s in enumerate(strains)], Temporaries())
    return Kernel(f"law_{law.name}", f"Section stiffnesses of the strains of {law.name}: "
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
    size = len(laws.coefficient_layout(spec.dim))
    parts = [(derive.straight_domain_integrals(spec, domain), refs(domain, size))
             for domain in derive.straight_law_domains(spec)]
    density = ref("density", 0)
    values = derive.law_invariant_values(spec, pattern, parts,
                                         derive.straight_integrals(spec).mass, density)
    if energies.is_cable(spec):  # the simple bending's modulus, 0 for the exact curvature
        bending = energies.bending_terms(spec, derive.pairs(spec.n_shape), ref("bending", 0))
        values["k1"] = [a + b for a, b in zip(values["k1"], bending["k1"], strict=True)]
        values["gram_linear"] = bending["gram_linear"]
    subs = geometry_subs(spec, "geometry")
    names = ", ".join(laws.coefficient_names(spec.dim))
    arrays = [Array("geometry", 3, "batch", geometry_doc(spec)),
              *[Array(domain, size, "shared", f"law coefficients ({names}) on the {domain} "
                      "(Pa)") for domain in derive.straight_law_domains(spec)],
              Array("density", 1, "shared", "density rho (kg/m^3)"),
              *([Array("bending", 1, "shared", "modulus of the pre-integrated (simple) "
                       "bending part (Pa): the E11 coefficient on the axis, 0 for a law "
                       "whose bending is by quadrature")] if energies.is_cable(spec) else []),
              *invariant_outputs(spec, pattern, "shape-level K1 (N/m), upper triangle",
                                 "energy of e = 0 (J)")]
    outputs = [(f"{name}[{i}]", sp.sympify(v).subs(subs), False)
               for name, vals in values.items() for i, v in enumerate(vals)]
    body: list = []
    emit_cse(body, outputs, Temporaries())
    return Kernel("law_invariants_straight",
                  "Stored invariants of any law of the straight element, closed form from its "
                  "law coefficients per domain.", arrays, body)
