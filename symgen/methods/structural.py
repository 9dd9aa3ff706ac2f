"""The ``quadrature_structural`` family: Gauss quadrature at every call of the structural
laws of ``symgen.structural`` (the elastic line of the 2-node beams), with Kelvin-Voigt
damping.  The gram and cij methods take the law's pre-integrated invariants (general
storage); this family evaluates its strains point by point instead, the check that the
invariants do not share.

Each table row is a point of the centre line: per direction of ``structural.DIRECTIONS``
the n shape derivatives u_a there (the nodes' directions, constant, are taken exact from
``structural.direction_values`` instead), then per strain its section stiffness times the point's
weight (zero for the strains not sampled at that point: the axis points carry the axial,
bending and torsion strains, the node points the shear and cross-section ones).  With the
node-relative reference q0, displacements dq and r_a = sum_k u_ak q_k, a strain of
directions (a, b) measured from the reference is

    stretch (a = b):  eps = r0_a . dr_a + dr_a . dr_a / 2     ((r_a.r_a - r0_a.r0_a) / 2)
    product:          eps = r0_a . dr_b + dr_a . r0_b + dr_a . dr_b,

its row Z(k, c) = d eps / d q_kc = u_ak r_b[c] + u_bk r_a[c] (halved for a stretch), and
per point with weights w_i

    U = sum w eps^2 / 2,  force = -sum w eps Z,  Jacobian = -(sum w Z Z^T + S kron I),
    S_km = sum w eps (u_ak u_bm + u_bk u_am) (halved for a stretch).

Damping: eps_dot = Z . q_dot; force -alpha sum w eps_dot Z, d/de_dot = -alpha sum w Z Z^T,
d/de = -alpha (sum w Z Zdot^T + S_dot kron I), Zdot and S_dot as Z and S with the velocities
for r and eps_dot for eps.
"""

from __future__ import annotations

import sympy as sp

from symgen import derive, energies, structural
from symgen.element import ElementSpec
from symgen.ir import Array, Assign, Kernel, Loop, PointLoop, Temporaries, ref, refs
from symgen.methods.common import (
    DAMPING_KERNELS,
    KERNELS,
    coordinate_arrays,
    kernel_name,
    loop_tables,
    materialize,
    quantity_output,
    relative_velocities,
    store,
    translate,
)
from symgen.methods.damping import damping_arrays
from symgen.methods.quadrature import KERNEL_DOCS


def law_of(spec: ElementSpec) -> structural.StructuralLaw:
    """The structural law of ``spec`` (one: ``structural.STRUCTURAL_LAWS``)."""
    (law,) = [law for law in energies.applicable_laws(spec).values()
              if structural.is_structural(law)]
    return law


def table_width(spec: ElementSpec) -> int:
    """Doubles per table row: n per direction, then one weighted stiffness per strain."""
    return (len(structural.DIRECTIONS[spec.dim]) * spec.n_shape
            + len(law_of(spec).strains(spec.dim)))


def structural_kernel(spec: ElementSpec, name: str) -> Kernel:
    """The kernel ``name`` (``KERNELS`` or ``DAMPING_KERNELS`` names) of the family."""
    d, n, ndof = spec.dim, spec.n_shape, spec.ndof
    names = structural.DIRECTIONS[d]
    strains = law_of(spec).strains(d)
    damped = name in DAMPING_KERNELS
    table = Array("table", table_width(spec), "table", "per centre-line point: the shape "
                  f"derivatives along {', '.join(names)} (n each), then per strain its "
                  "section stiffness times the weight (N m, N m^3)")
    arrays = [*coordinate_arrays(spec, True)]
    if damped:
        e_dot, tail = damping_arrays(spec, name)
        arrays += [e_dot, table, *tail]
        wanted = [a.name for a in tail if a.role == "output"]
    else:
        wanted = name.split("_")
        arrays += [table, *[quantity_output(spec, quantity) for quantity in wanted]]
    temps = Temporaries()
    body: list = []
    _, q0, dq = translate(spec, body, temps, with_reference=True)
    tab = refs("tab", table_width(spec))
    # a node's direction is the same at every point (its nodal vector: a unit selector), so
    # the kernel takes its exact values instead of the table's columns (a third less C)
    exact = structural.direction_values(spec)
    u = [exact[i] if "@" in name else tab[i * n:(i + 1) * n] for i, name in enumerate(names)]
    weights = tab[len(names) * n:]
    point: list = []

    def along(vectors, coordinates):
        return [materialize(point, temps, [sum(vectors[i][k] * coordinates[k * d + c]
                                               for k in range(n)) for c in range(d)])
                for i in range(len(names))]

    r0, dr = along(u, q0), along(u, dq)
    r = [materialize(point, temps, [a + b for a, b in zip(x0, dx, strict=True)])
         for x0, dx in zip(r0, dr, strict=True)]
    pairs = [(names.index(s.first), names.index(s.second)) for s in strains]

    def dot(a, b):
        return sum(x * y for x, y in zip(a, b, strict=True))

    def rows(vectors):
        """Z (or Zdot with the velocities' directions) of every strain."""
        out = []
        for a, b in pairs:
            half = sp.Rational(1, 2) if a == b else 1
            out.append(materialize(point, temps, [half * (u[a][k] * vectors[b][c]
                                                          + u[b][k] * vectors[a][c])
                                                  for k in range(n) for c in range(d)]))
        return out

    def geometric(measures):
        """S_km = sum w m (u_ak u_bm + u_bk u_am) (halved for a stretch), upper pairs."""
        return materialize(point, temps, [
            sum(w * m * (sp.Rational(1, 2) if a == b else 1) * (u[a][k] * u[b][p]
                                                                + u[b][k] * u[a][p])
                for w, m, (a, b) in zip(weights, measures, pairs, strict=True))
            for k, p in derive.pairs(n)])

    strain = materialize(point, temps, [
        dot(r0[a], dr[a]) + dot(dr[a], dr[a]) / 2 if a == b
        else dot(r0[a], dr[b]) + dot(dr[a], r0[b]) + dot(dr[a], dr[b]) for a, b in pairs])
    if name == "energy":
        store(point, "energy", [sum(w * e * e for w, e in zip(weights, strain, strict=True))
                                / 2], accumulate=True)
        body.append(PointLoop("table", tuple(point), _default_points(spec)))
        return _kernel(spec, name, arrays, body)
    z = rows(r)
    count = len(strains)
    force = [-sum(w * e * zi[i] for w, e, zi in zip(weights, strain, z, strict=True))
             for i in range(ndof)]
    rate = None
    if damped:
        alpha = ref("alpha", 0)
        qd = relative_velocities(spec)
        rate = materialize(point, temps, [dot(zi, qd) for zi in z])
        damping = [-alpha * sum(w * e * zi[i] for w, e, zi in zip(weights, rate, z,
                                                                  strict=True))
                   for i in range(ndof)]
        force = damping if name == "damping_force" else \
            [a + b for a, b in zip(force, damping, strict=True)]
    if "force" in wanted:
        store(point, "force", materialize(point, temps, force), accumulate=True)
    if "jacobian" in wanted:
        # Z and Y = w Z as local rows, S (or S + alpha S_dot) as GEO: loops (rows_product,
        # kron_full) instead of ndof^2 unrolled sums (beam3d: 1 MB of C otherwise)
        for row, values in enumerate(z):
            for i, value in enumerate(values):
                point.append(Assign(f"Z[{row * ndof + i}]", sp.sympify(value)))
                point.append(Assign(f"Y[{row * ndof + i}]", weights[row] * ref("Z", row * ndof
                                                                                + i)))
        upper = geometric(strain)
        if damped:
            upper = [x + alpha * y for x, y in zip(upper, geometric(rate), strict=True)]
            for row, values in enumerate(rows(along(u, qd))):
                for i, value in enumerate(values):
                    point.append(Assign(f"ZD[{row * ndof + i}]", sp.sympify(value)))
            point.append(Loop("rows_product", "jacobian", ("Y", "ZD", count), -alpha))
        pidx = derive.pair_index(n)
        for k in range(n):
            for p in range(n):
                point.append(Assign(f"GEO[{k * n + p}]", sp.sympify(upper[pidx[(k, p)]])))
        point.append(Loop("rows_product", "jacobian", ("Z", "Y", count), -1))
        point.append(Loop("kron_full", "jacobian", ("GEO",), -1))
        if damped:
            point.append(Loop("rows_product", "jacobian_dot", ("Z", "Y", count), -alpha))
        arrays += [Array("Z", count * ndof, "local", "d eps / d e per strain"),
                   Array("Y", count * ndof, "local", "w Z"),
                   Array("GEO", n * n, "local", "S (plus alpha S_dot), n x n")]
        if damped:
            arrays.append(Array("ZD", count * ndof, "local", "Z of the velocities"))
    body.append(PointLoop("table", tuple(point), _default_points(spec)))
    return _kernel(spec, name, arrays, body, "jacobian" in wanted)


def _default_points(spec: ElementSpec) -> int:
    """Axis points of the default rule plus the two nodes."""
    return spec.quadrature[0] + 2


def _kernel(spec: ElementSpec, name: str, arrays: list, body: list,
            loops: bool = False) -> Kernel:
    doc = KERNEL_DOCS[name]
    return Kernel(name, f"{doc[0].upper()}{doc[1:]} of the structural (elastic-line) law by "
                  "Gauss quadrature along the centre line at every call.", arrays, body,
                  loop_tables(spec, "straight") if loops else None)


def build(spec: ElementSpec) -> list[Kernel]:
    """The kernels of the ``quadrature_structural`` family (elastic and damping)."""
    names = [kernel_name(q) for q in KERNELS] + list(DAMPING_KERNELS)
    return [structural_kernel(spec, name) for name in names]
