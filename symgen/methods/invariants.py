"""The invariant builders of the ``invariants`` families: shape-function tables, the
closed-form straight integrals, and the map from integrals to stored invariants (straight and
general storage patterns)."""

from __future__ import annotations

import sympy as sp

from symgen import derive, energies, structural
from symgen.element import ElementSpec
from symgen.ir import Array, Kernel, Temporaries, emit_cse, ref, refs
from symgen.methods.common import closed_as_data, geometry_doc, geometry_subs, invariant_outputs


def build(spec: ElementSpec, variant: str) -> list[Kernel]:
    """The kernels of the invariants family of storage ``variant``: for the straight one the
    shape tables, closed-form straight integrals and the straight integrals -> invariants
    (only the shape tables where the closed forms are data, closed.json, for the runtime);
    for the general one the integrals -> invariants map."""
    if variant != "straight":
        return [_invariants_kernel(spec, variant)]
    if energies.is_cable(spec):  # invariants through the law path, quadrature tables
        return [_shape_values_kernel(spec), _shape_gradients_kernel(spec),
                _shape_curvatures_kernel(spec), _section_kernel(spec)]
    tables = [_shape_values_kernel(spec), _shape_gradients_kernel(spec)]
    if any(structural.is_structural(law) for law in derive.applicable_laws(spec).values()):
        tables.append(_structural_directions_kernel(spec))
    if closed_as_data(spec):
        return tables
    return [*tables, _straight_integrals_kernel(spec), _invariants_kernel(spec, "straight")]


def _point_kernel(spec: ElementSpec, name: str, doc: str, output: str, output_doc: str,
                  values: list) -> Kernel:
    """A kernel that evaluates ``values`` (expressions in the local coordinates and the
    domain parameters) at a batch of local points into ``output``."""
    arrays = [Array("point", spec.dim, "batch", "local coordinates (x, y[, z]) in m"),
              Array("geometry", 3, "shared", geometry_doc(spec)),
              Array(output, len(values), "output", output_doc)]
    subs = {**geometry_subs(spec, "geometry"),
            **dict(zip(spec.coordinates, refs("point", spec.dim), strict=True))}
    body: list = []
    emit_cse(body, [(f"{output}[{k}]", value.subs(subs), False)
                    for k, value in enumerate(values)], Temporaries())
    return Kernel(name, doc, arrays, body)


def _shape_values_kernel(spec: ElementSpec) -> Kernel:
    return _point_kernel(spec, "shape_values", "Shape functions at local points.", "values",
                         "shape functions s_k", list(spec.shape_functions))


def _shape_gradients_kernel(spec: ElementSpec) -> Kernel:
    grads = derive.shape_gradients(spec)
    return _point_kernel(spec, "shape_gradients",
                         "Local shape-function gradients at local points.", "gradients",
                         "structurally nonzero ds_k/dx_alpha, in gradient-pattern order",
                         [grads[k, c] for k, c in derive.gradient_pattern(spec)])


def _shape_curvatures_kernel(spec: ElementSpec) -> Kernel:
    """d2 s_k / dx2 (the bending part of the cable energy, ``symgen.energies``)."""
    return _point_kernel(spec, "shape_curvatures",
                         "Second shape-function derivatives along x at local points.",
                         "curvatures", "d2 s_k / dx2 (1/m^2)",
                         [sp.diff(s, spec.coordinates[0], 2) for s in spec.shape_functions])


def _structural_directions_kernel(spec: ElementSpec) -> Kernel:
    """The shape derivatives of the directions of the structural laws on the centre line
    (``symgen.structural.DIRECTIONS``) at axial positions (the point's y, z are ignored)."""
    names = structural.DIRECTIONS[spec.dim]
    values = [v for row in structural.direction_values(spec) for v in row]
    return _point_kernel(spec, "structural_directions",
                         "Shape derivatives of the centre-line directions at local points.",
                         "directions", f"d s_k / d({'), d('.join(names)}) on the centre line "
                         "(direction-major, n each; 1/m, 1/m^2)", values)


def _section_kernel(spec: ElementSpec) -> Kernel:
    """Area and bending second moment of the section of a cable (``symgen.energies``)."""
    arrays = [Array("geometry", 3, "batch", geometry_doc(spec)),
              Array("section", 2, "output", "area A (m^2), second moment I (m^4)")]
    subs = geometry_subs(spec, "geometry")
    body: list = []
    emit_cse(body, [("section[0]", energies.area(spec).subs(subs), False),
                    ("section[1]", energies.second_moment(spec).subs(subs), False)],
             Temporaries())
    return Kernel("section", "Cross-section area and bending second moment.", arrays, body)


def _integral_arrays(spec: ElementSpec, pattern: derive.Patterns, role: str) -> list[Array]:
    npairs = len(derive.pairs(spec.n_shape))
    return [Array("i4", len(pattern.i4), role, "int P_kl P_mn dV0 in i4-pattern order"),
            Array("i2", npairs, role, "int P dV0, upper triangle"),
            Array("mass_shape", npairs, role, "int s s^T dV0 (m^3), upper triangle"),
            Array("volume", 1, role, "int dV0 (m^3)")]


def _straight_integrals_kernel(spec: ElementSpec) -> Kernel:
    pattern = derive.patterns(spec, "straight")
    integrals = derive.straight_integrals(spec)
    subs = geometry_subs(spec, "geometry")
    arrays = [Array("geometry", 3, "batch", geometry_doc(spec)),
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
              *invariant_outputs(spec, pattern, "shape-level K1 of eq. 29 (N/m), upper triangle",
                                 "U0 of eqs. 40-41 (J)")]
    outputs = [(f"{name}[{i}]", sp.sympify(v).subs(material), False)
               for name, vals in values.items() for i, v in enumerate(vals)]
    body: list = []
    emit_cse(body, outputs, Temporaries())
    return Kernel(f"invariants_{variant}",
                  f"Stored invariants from integrals ({variant} storage pattern).", arrays, body)
