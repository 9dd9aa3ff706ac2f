"""Gauss quadrature at every call: the ``quadrature`` family (eq. 23, St. Venant-Kirchhoff,
the paper's baseline) and the ``quadrature_law`` family (any material law of ``symgen.laws``,
with Kelvin-Voigt damping), and the looped point Jacobian of large elements."""

from __future__ import annotations

from functools import cache

import sympy as sp

from symgen import derive, energies, laws
from symgen.element import ElementSpec
from symgen.ir import (
    Array,
    Assign,
    Kernel,
    Loop,
    PointLoop,
    ShapeLoop,
    Temporaries,
    ref,
    refs,
    shape_ref,
)
from symgen.methods.common import (
    DAMPING_KERNELS,
    KERNELS,
    coordinate_arrays,
    kernel_name,
    loop_tables,
    looped,
    looped_start,
    materialize,
    quantity_output,
    relative_velocities,
    shape_looped,
    store,
    store_symmetric,
    translate,
)
from symgen.methods.damping import damping_arrays

#: What each kernel of the quadrature_law families computes (their docstrings).
KERNEL_DOCS = {"force": "elastic force", "energy": "strain energy",
               "force_jacobian": "elastic force and Jacobian",
               "damping_force": "Kelvin-Voigt damping force",
               "damped_force_jacobians": "elastic plus damping force and its Jacobians with "
               "respect to e and e_dot"}


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
    arrays = [*coordinate_arrays(spec, True),
              Array("material", 2, "shared", "Lame lambda and shear modulus G (Pa)"),
              Array("table", width_, "table",
                    "per Gauss point: nonzero ds/dx (gradient-pattern order), then weight (m^3)"),
              *[quantity_output(spec, quantity) for quantity in quantities]]
    temps = Temporaries()
    body: list = []
    shapes = shape_looped(spec)
    if shapes:
        arrays += [*looped_start(spec, body, False, temps, current=False),
                   *_shape_locals(spec, ("J0", "H"))]
    else:
        _, q0, dq = translate(spec, body, temps, with_reference=True)
    lam_, g_ = refs("material", 2)
    tab = refs("tab", width_)
    point: list = []
    if shapes:
        ds_row = sp.Matrix(1, d, [shape_ref("tab", d, c) for c in range(d)])
        j0 = _shape_sums(spec, point, {"J0": "Q0"}, ds_row)["J0"]
    else:
        ds = sp.zeros(n, d)
        for j, (k, c) in enumerate(pattern):
            ds[k, c] = tab[j]
        j0 = sp.Matrix(d, d, materialize(point, temps, list(sp.Matrix(n, d, q0).T * ds)))
    det = materialize(point, temps, [j0.det(method="berkowitz")])[0]
    inv_det = materialize(point, temps, [1 / det])[0]
    j0_inv = sp.Matrix(d, d, materialize(point, temps, list(j0.adjugate() * inv_det)))
    if shapes:
        b = _shape_gradients(spec, point, ds_row, j0_inv)
        h = _shape_sums(spec, point, {"H": "DQ"}, b)["H"]
    else:
        b = sp.Matrix(n, d, materialize(point, temps, list(ds * j0_inv)))
        h = sp.Matrix(d, d, materialize(point, temps, list(sp.Matrix(n, d, dq).T * b)))
    strain = sp.Matrix(d, d, materialize(point, temps, list((h + h.T + h.T * h) / 2)))
    trace = materialize(point, temps, [strain.trace()])[0]
    wdet = materialize(point, temps, [tab[-1] * det])[0]
    if "energy" in quantities:
        energy = wdet * (lam_ / 2 * trace**2 + g_ * sum(x * x for x in strain))
        store(point, "energy", [energy], accumulate=True)
    if "force" in quantities or "jacobian" in quantities:
        stress = sp.Matrix(d, d, materialize(
            point, temps, list(lam_ * trace * sp.eye(d) + 2 * g_ * strain)))
        f = sp.eye(d) + h
        if "force" in quantities and shapes:
            _shape_force(spec, point, temps, b, stress, f, -wdet)
        elif "force" in quantities:
            bs = sp.Matrix(n, d, materialize(point, temps, list(b * stress)))
            force = -wdet * (bs * f.T)
            store(point, "force", list(force), accumulate=True)
        if "jacobian" in quantities and looped(spec, "quadrature"):
            dn = sp.Matrix(d, d, lambda x_, y_: lam_ + (2 * g_ if x_ == y_ else 0))
            _looped_point_jacobian(spec, point, b, f, stress, dn,
                                   [g_] * len(laws.shear_pairs(d)), -wdet, shapes=shapes)
        elif "jacobian" in quantities:
            a = sp.Matrix(n, d, materialize(point, temps, list(b * f.T)))
            bsb = materialize(point, temps, [(b[k, :] * stress * b[p, :].T)[0]
                                              for k, p in derive.pairs(n)])
            bb = materialize(point, temps, [(b[k, :] * b[p, :].T)[0]
                                             for k, p in derive.pairs(n)])
            ff = materialize(point, temps, [(f[x, :] * f[yy, :].T)[0]
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
            names = materialize(point, temps, list(upper.values()))
            store_symmetric(point, "jacobian", spec.ndof, dict(zip(upper, names, strict=True)),
                             accumulate=True)
    body.append(PointLoop("table", tuple(point), _default_points(spec)))
    if looped(spec, "quadrature") and "jacobian" in quantities:
        arrays += _point_locals(spec, damped=False, gradients=not shapes)
    return Kernel(kernel_name(quantities), f"Elastic {' and '.join(quantities)} by Gauss "
                  "quadrature at every call (no invariants).", arrays, body,
                  loop_tables(spec, "straight") if looped(spec, "quadrature") else None)


def _default_points(spec: ElementSpec) -> int:
    total = 1
    for order in spec.quadrature:
        total *= order
    return total


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
    quantities = {"damping_force": ("force",),
                  "damped_force_jacobians": ("force", "jacobian", "jacobian_dot")}.get(
        name, tuple(name.split("_")))
    arrays = [*coordinate_arrays(spec, True)]
    if damped:
        e_dot, tail = damping_arrays(spec, name)
        arrays.append(e_dot)
    table = Array("table", width_, "table",
                  "per point: nonzero ds/dx (gradient-pattern order), U^-1 upper triangle, "
                  "law coefficients times weight and det J0 (N m)")
    arrays.append(table)
    if damped:
        arrays += tail
    else:
        arrays += [quantity_output(spec, quantity) for quantity in quantities]
    temps = Temporaries()
    body: list = []
    shapes = shape_looped(spec)
    sums = {"F0": "Q0", "DF": "DQ", **({"FD": "QD"} if damped else {})}
    if shapes:
        arrays += [*looped_start(spec, body, damped, temps, current=False),
                   *_shape_locals(spec, tuple(sums))]
    else:
        _, q0, dq = translate(spec, body, temps, with_reference=True)
        qd = relative_velocities(spec) if damped else None
    alpha = ref("alpha", 0)
    tab = refs("tab", width_)
    offset = len(pattern)
    u_inv = sp.zeros(d, d)
    for j, (a, b) in enumerate(upper_d):
        u_inv[a, b] = tab[offset + j]
    offset += len(upper_d)
    coefficient = dict(zip(layout, tab[offset:], strict=True))
    dn = sp.Matrix(d, d, lambda a, b: coefficient[(min(a, b), max(a, b))])
    dshear = [coefficient[(d + s, d + s)] for s in range(len(shears))]
    point: list = []
    if shapes:
        ds_row = sp.Matrix(1, d, [shape_ref("tab", d, c) for c in range(d)])
        bmat = _shape_gradients(spec, point, ds_row, u_inv)
        gradients = _shape_sums(spec, point, sums, bmat)
        f0, df = gradients["F0"], gradients["DF"]
    else:
        ds = sp.zeros(n, d)
        for j, (k, c) in enumerate(pattern):
            ds[k, c] = tab[j]
        bmat = sp.Matrix(n, d, materialize(point, temps, list(ds * u_inv)))
        f0 = sp.Matrix(d, d, materialize(point, temps, list(sp.Matrix(n, d, q0).T * bmat)))
        df = sp.Matrix(d, d, materialize(point, temps, list(sp.Matrix(n, d, dq).T * bmat)))
    strain = (f0.T * df + df.T * f0 + df.T * df) / 2
    f = sp.Matrix(d, d, materialize(point, temps, list(f0 + df)))
    eps = materialize(point, temps, [strain[a, a] for a in range(d)]
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
        store(point, "energy", [sum(x * y for x, y in zip(eps, sigma, strict=True)) / 2],
               accumulate=True)
    if damped:
        fdot = gradients["FD"] if shapes else sp.Matrix(d, d, materialize(
            point, temps, list(sp.Matrix(n, d, qd).T * bmat)))
        eps_dot = materialize(point, temps, [
            sum(f[c, a] * fdot[c, a] for c in range(d)) for a in range(d)] + [
            sum(f[c, a] * fdot[c, b] + fdot[c, a] * f[c, b] for c in range(d))
            for a, b in shears])
        sigma_d = [alpha * x for x in stress_of(eps_dot)]
        total = sigma_d if sigma is None else [x + y for x, y in zip(sigma, sigma_d, strict=True)]
    else:
        total = sigma
    if "force" in quantities or "jacobian" in quantities:
        s_total = sp.Matrix(d, d, materialize(point, temps, list(tensor(total))))
    if "force" in quantities and shapes:
        _shape_force(spec, point, temps, bmat, s_total, f, -1)
    elif "force" in quantities:
        bs = sp.Matrix(n, d, materialize(point, temps, list(bmat * s_total)))
        store(point, "force", list(-(bs * f.T)), accumulate=True)
    if "jacobian" in quantities and looped(spec, "quadrature_law"):
        _looped_point_jacobian(spec, point, bmat, f, s_total, dn, dshear, -1,
                               fdot=fdot if damped else None, shapes=shapes)
    elif "jacobian" in quantities:
        z = [materialize(point, temps, row) for row in z_of(f)]
        y = [materialize(point, temps, row) for row in _law_rows(dn, dshear, z, d)]
        geometric = materialize(point, temps, [(bmat[k, :] * s_total * bmat[p, :].T)[0]
                                                for k, p in derive.pairs(n)])
        pidx = derive.pair_index(n)

        def geo(i: int, j: int):
            (k, a), (p, b) = divmod(i, d), divmod(j, d)
            return geometric[pidx[(k, p)]] if a == b else 0

        if not damped:
            upper = {(i, j): -(sum(zi[i] * yi[j] for zi, yi in zip(z, y, strict=True))
                               + geo(i, j)) for i, j in derive.pairs(ndof)}
            names = materialize(point, temps, list(upper.values()))
            store_symmetric(point, "jacobian", ndof, dict(zip(upper, names, strict=True)),
                             accumulate=True)
        else:
            zdot = [materialize(point, temps, row) for row in z_of(fdot)]
            material = dict(zip(derive.pairs(ndof), materialize(point, temps, [
                sum(zi[i] * yi[j] for zi, yi in zip(z, y, strict=True))
                for i, j in derive.pairs(ndof)]), strict=True))
            full = []
            for i in range(ndof):
                for j in range(ndof):
                    value = (alpha * sum(yi[i] * zd[j] for yi, zd in zip(y, zdot, strict=True))
                             + material[(min(i, j), max(i, j))])
                    full.append(-(value + geo(i, j)))
            store(point, "jacobian", materialize(point, temps, full), accumulate=True)
            upper = {ij: -alpha * value for ij, value in material.items()}
            names = materialize(point, temps, list(upper.values()))
            store_symmetric(point, "jacobian_dot", ndof, dict(zip(upper, names, strict=True)),
                             accumulate=True)
    body.append(PointLoop("table", tuple(point), _default_law_points(spec)))
    if looped(spec, "quadrature_law") and "jacobian" in quantities:
        arrays += _point_locals(spec, damped, gradients=not shapes)
    doc = KERNEL_DOCS[name]
    return Kernel(name, f"{doc[0].upper()}{doc[1:]} of any law by Gauss quadrature at every "
                  "call (volume and axis rules).", arrays, body,
                  loop_tables(spec, "straight") if looped(spec, "quadrature_law") else None)


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


def _z_rows(bmat, fmat, n: int, d: int) -> list:
    """Z_I(k, c) = d eps_I / d Q_kc (Voigt rows) with gradients ``bmat`` and the deformation
    gradient ``fmat``."""
    rows = [[bmat[k, a] * fmat[c, a] for k in range(n) for c in range(d)] for a in range(d)]
    rows += [[bmat[k, a] * fmat[c, b] + bmat[k, b] * fmat[c, a] for k in range(n)
              for c in range(d)] for a, b in laws.shear_pairs(d)]
    return rows


def _point_locals(spec: ElementSpec, damped: bool, gradients: bool = True) -> list[Array]:
    """The local arrays of the looped point Jacobian (with the gradients BM unless
    ``_shape_locals`` declares them)."""
    size = laws.voigt_size(spec.dim) * spec.ndof
    arrays = [Array("Z", size, "local", "d eps / d e per Voigt row"),
              Array("Y", size, "local", "D Z"),
              *([_gradients_array(spec)] if gradients else []),
              Array("SB", spec.ndof, "local", "S b per shape function"),
              Array("GEO", spec.n_shape**2, "local", "b S b^T")]
    if damped:
        arrays.append(Array("ZD", size, "local", "d eps_dot / d e_dot per Voigt row"))
    return arrays


def _looped_point_jacobian(spec: ElementSpec, point: list, bmat, fmat, smat, dn, dshear,
                           scale, fdot=None, shapes: bool = False) -> None:
    """The Jacobian at one point as loops (large elements): Z and Y = D Z, b and S b stored
    (unrolled, small), b S b^T by a loop, then jacobian += scale (sum_I Z_I Y_I^T +
    (b S b^T) kron I); with ``fdot``
    (damping) jacobian += scale (alpha sum_I Y_I Zdot_I^T + geometric + material) and
    jacobian_dot += scale alpha sum_I Z_I Y_I^T.  With ``shapes`` (``shape_looped``),
    ``bmat`` is the row of shape function k already in BM (``_shape_gradients``) and Z, Y,
    S b (and Zdot) are written for that k in one ``ShapeLoop``."""
    n, d, ndof = spec.n_shape, spec.dim, spec.ndof
    rows = laws.voigt_size(d)
    written = 1 if shapes else n        # shape functions written out
    body: list = [] if shapes else point

    def at(name: str, r: int, i: int):
        """The symbol of name[r ndof + i], i = k d + c (k the loop index with ``shapes``)."""
        return shape_ref(name, d, r * ndof + i) if shapes else ref(name, r * ndof + i)

    def rows_of(name: str, values: list) -> None:
        for r, row in enumerate(values):
            for i, value in enumerate(row):
                body.append(Assign(at(name, r, i).name, sp.sympify(value)))

    rows_of("Z", _z_rows(bmat, fmat, written, d))
    zref = [[at("Z", r, i) for i in range(written * d)] for r in range(rows)]
    rows_of("Y", _law_rows(dn, dshear, zref, d))
    for k in range(written):      # b S b^T by a loop over b and S b (n^2 unrolled: slow
        stress_b = smat * bmat[k, :].T    # to compile, the brick's 1024 of them)
        for c in range(d):
            if not shapes:
                body.append(Assign(f"BM[{k * d + c}]", sp.sympify(bmat[k, c])))
            body.append(Assign(at("SB", 0, k * d + c).name, sp.sympify(stress_b[c])))
    if shapes:
        if fdot is not None:
            rows_of("ZD", _z_rows(bmat, fdot, written, d))
        point.append(ShapeLoop(n, tuple(body)))
    point.append(Loop("shape_products", "GEO", ("BM", "SB")))
    if fdot is None:
        point.append(Loop("rows_product", "jacobian", ("Z", "Y", rows), scale))
    else:
        alpha = ref("alpha", 0)
        if not shapes:
            rows_of("ZD", _z_rows(bmat, fdot, n, d))
        point.append(Loop("rows_product", "jacobian", ("Y", "ZD", rows), scale * alpha))
        point.append(Loop("rows_product", "jacobian", ("Z", "Y", rows), scale))
        point.append(Loop("rows_product", "jacobian_dot", ("Z", "Y", rows), scale * alpha))
    point.append(Loop("kron_full", "jacobian", ("GEO",), scale))


def _gradients_array(spec: ElementSpec) -> Array:
    return Array("BM", spec.ndof, "local", "shape gradients b, node-major")


def _shape_locals(spec: ElementSpec, sums: tuple[str, ...]) -> list[Array]:
    """The local arrays of the shape-looped points: the gradients BM and the d x d sums
    (``_shape_sums``) named ``sums``."""
    return [_gradients_array(spec), *[Array(name, spec.dim**2, "local", SHAPE_SUMS[name])
                                      for name in sums]]


#: The d x d sums over the shape functions of the shape-looped points (row-major).
SHAPE_SUMS = {"J0": "Q0^T ds, the reference Jacobian", "H": "DQ^T b, the displacement gradient",
              "F0": "Q0^T b, the reference deformation gradient",
              "DF": "DQ^T b, the displacement gradient", "FD": "QD^T b, its rate"}


def _shape_gradients(spec: ElementSpec, point: list, ds_row, right) -> sp.Matrix:
    """BM[k d + a] = (ds_k right)_a for every shape function k in one ``ShapeLoop``, from
    the row ``ds_row`` (1 x d) of shape function k; returns that row of BM (1 x d)."""
    d = spec.dim
    values = list(ds_row * right)
    point.append(ShapeLoop(spec.n_shape, tuple(
        Assign(shape_ref("BM", d, a).name, sp.sympify(value)) for a, value in enumerate(values))))
    return sp.Matrix(1, d, [shape_ref("BM", d, a) for a in range(d)])


def _shape_sums(spec: ElementSpec, point: list, sums: dict[str, str], row) -> dict:
    """target = source^T b for each {target: source} of ``sums`` (d x d, row-major: entry
    (c, a) sums source[k d + c] row_a over the shape functions k) in one ``ShapeLoop``,
    ``row`` (1 x d) the row of shape function k; returns each target's matrix of entries."""
    d = spec.dim
    body = []
    for target, source in sums.items():
        point.append(Loop("zero", target, (d * d,)))
        body += [Assign(f"{target}[{c * d + a}]", shape_ref(source, d, c) * row[a], True)
                 for c in range(d) for a in range(d)]
    point.append(ShapeLoop(spec.n_shape, tuple(body)))
    return {target: sp.Matrix(d, d, refs(target, d * d)) for target in sums}


def _shape_force(spec: ElementSpec, point: list, temps: Temporaries, row, stress, fmat,
                 scale) -> None:
    """force[k d + c] += scale ((row S) F^T)_c for every shape function k in one
    ``ShapeLoop``, ``row`` (1 x d) the gradients of shape function k."""
    d = spec.dim
    body: list = []
    stress_b = sp.Matrix(1, d, materialize(body, temps, list(row * stress)))
    body += [Assign(shape_ref("force", d, c).name, sp.sympify(value), True)
             for c, value in enumerate(scale * (stress_b * fmat.T))]
    point.append(ShapeLoop(spec.n_shape, tuple(body)))


def cable_table_width(spec: ElementSpec, bending: str = "simple") -> int:
    """Doubles per point of a cable's quadrature table: ds/dx, d2s/dx2, two weights and,
    for a bending model with one (``energies.reference_curvature``), the reference
    curvature."""
    return 2 * spec.n_shape + 2 + int(energies.reference_curvature(spec, bending))


def cable_quadrature_kernel(spec: ElementSpec, name: str, bending: str = "simple") -> Kernel:
    """Gauss quadrature of the cable energy (``symgen.energies``) with the ``bending`` model
    along the axis at every call, with Kelvin-Voigt damping.  Each table row is an axis
    point: ds/dx, d2s/dx2, and the weights of the axial part (EA dx) and of the bending part
    (EI dx) (``cable_point``)."""
    damped = name in DAMPING_KERNELS
    arrays = [*coordinate_arrays(spec, True)]
    if damped:
        e_dot, tail = damping_arrays(spec, name)
        arrays += [e_dot, cable_table_array(spec, bending), *tail]
    else:
        arrays += [cable_table_array(spec, bending),
                   *[quantity_output(spec, quantity) for quantity in name.split("_")]]
    temps = Temporaries()
    body: list = []
    _, q0, dq = translate(spec, body, temps, with_reference=True)
    point = cable_point(spec, name, q0, dq, temps, bending, axial=True)
    body.append(PointLoop("table", tuple(point), spec.quadrature[0]))
    doc = KERNEL_DOCS[name]
    model = "" if bending == "simple" else f" ({bending.replace('_', ' ')} bending)"
    return Kernel(name, f"{doc[0].upper()}{doc[1:]} of the cable energy{model} by Gauss "
                  "quadrature along the axis at every call.", arrays, body)


def cable_table_array(spec: ElementSpec, bending: str = "simple") -> Array:
    """The per-point table of the cable's quadrature loops (``cable_table_width``)."""
    kappa0 = (", reference curvature r0_x x r0_xx / |r0_x|^2 (1/m)"
              if energies.reference_curvature(spec, bending) else "")
    return Array("table", cable_table_width(spec, bending), "table", "per axis point: ds/dx, "
                 "d2s/dx2, weights of the axial part (EA dx / |r0_x|^3, N m) and of the bending "
                 f"part (EI dx / |r0_x|, N m^3){kappa0}")


def cable_point(spec: ElementSpec, name: str, q0: list, dq: list, temps: Temporaries,
                bending: str, axial: bool) -> list:
    """The statements at one axis point (table row ``tab``) of the cable kernel ``name``
    (``KERNELS`` or ``DAMPING_KERNELS`` names), accumulated into its outputs: the energy
    and the dissipation potential over alpha of ``energies.point_energy`` and
    ``energies.point_dissipation`` with the ``bending`` model (the bending part alone unless
    ``axial``), and their exact derivatives (F = -dU/de - alpha dPhi/de_dot) at the
    node-relative reference ``q0`` and displacements ``dq``: by SymPy for the polynomial
    parts, in closed form for the exact curvature (``_exact_bending``)."""
    point, temps.count = _cable_point(spec, name, tuple(q0), tuple(dq), temps.prefix,
                                      temps.count, bending, axial)
    return list(point)


@cache
def _cable_point(spec: ElementSpec, name: str, q0: tuple, dq: tuple, prefix: str, start: int,
                 bending: str, axial: bool) -> tuple[tuple, int]:
    """``cable_point`` with its temporaries numbered ``prefix`` from ``start``: the statements
    and the next number.  Cached: the elastic kernels of ``quadrature`` and ``quadrature_law``
    are the same, and so are the bending loops of ``gram_curvature`` and ``cij_curvature``."""
    temps = Temporaries(prefix, start)
    n = spec.n_shape
    tab = refs("tab", cable_table_width(spec, bending))
    s1, s2, w_bending = tab[:n], tab[n:2 * n], tab[2 * n + 1]
    w_axial = tab[2 * n] if axial else 0
    if name in DAMPING_KERNELS:
        wanted = [a.name for a in damping_arrays(spec, name)[1] if a.role == "output"]
    else:
        wanted = name.split("_")
    point: list = []
    if bending == "simple":
        outputs = _derived(spec, name, wanted, s1, s2, q0, dq, w_axial, w_bending)
    else:
        kappa0 = tab[2 * n + 2] if energies.reference_curvature(spec, bending) else 0
        current = [a + b for a, b in zip(q0, dq, strict=True)]
        outputs = _exact_bending(spec, name, wanted, point, temps, s1, s2, current, w_bending,
                                 kappa0)
        if axial:
            extra = _derived(spec, name, wanted, s1, s2, q0, dq, w_axial, 0)
            outputs = {q: [a + b for a, b in zip(v, extra[q], strict=True)]
                       for q, v in outputs.items()}
    if name == "energy":
        store(point, "energy", outputs["energy"], accumulate=True)
        return tuple(point), temps.count
    for quantity in wanted:
        store(point, quantity, materialize(point, temps, outputs[quantity]), accumulate=True)
    return tuple(point), temps.count


def _derived(spec: ElementSpec, name: str, wanted: list, s1, s2, q0, dq, w_axial,
             w_bending) -> dict[str, list]:
    """The ``wanted`` outputs (flat, row-major) of the cable kernel ``name`` at one point for
    the polynomial energy of ``energies.point_energy`` (simple bending, or the axial part
    alone with ``w_bending = 0``): its SymPy derivatives at the reference ``q0`` plus ``dq``."""
    ndof = spec.ndof
    shift = sp.symbols(f"dq0:{ndof}")
    rate = sp.symbols(f"qd0:{ndof}")
    energy, force, stiffness = _elastic_derivatives(spec, tuple(s1), tuple(s2), tuple(q0),
                                                    w_axial, w_bending)
    subs = dict(zip(shift, dq, strict=True))
    if name == "energy":
        return {"energy": [energy.xreplace(subs)]}
    if name in DAMPING_KERNELS:
        damping, jacobian, jacobian_dot = _damping_derivatives(
            spec, tuple(s1), tuple(s2), tuple(q0), w_axial, w_bending)
        subs.update(zip(rate, relative_velocities(spec), strict=True))
        if name == "damped_force_jacobians":
            damping = [a + b for a, b in zip(force, damping, strict=True)]
            jacobian = [[a + b for a, b in zip(ra, rb, strict=True)]
                        for ra, rb in zip(stiffness, jacobian, strict=True)]
        outputs = {"force": damping, "jacobian": jacobian, "jacobian_dot": jacobian_dot}
    else:
        outputs = {"force": force, "jacobian": stiffness}
    flat = {q: v if q == "force" else [x for row in v for x in row] for q, v in outputs.items()}
    return {q: [v.xreplace(subs) for v in flat[q]] for q in wanted}


@cache
def _elastic_derivatives(spec: ElementSpec, s1: tuple, s2: tuple, q0: tuple, w_axial,
                         w_bending) -> tuple:
    """``energies.point_energy`` at the reference ``q0`` plus the displacements dq0, dq1, ...
    (symbols), its force -dU/d dq (ndof) and stiffness (ndof x ndof lists).  Cached: every
    kernel of a family derives them (``_derived``)."""
    shift = sp.symbols(f"dq0:{spec.ndof}")
    energy = energies.point_energy(s1, s2, q0, shift, spec.dim, w_axial, w_bending)
    force = [-sp.diff(energy, v) for v in shift]
    return energy, force, [[sp.diff(f, v) for v in shift] for f in force]


@cache
def _damping_derivatives(spec: ElementSpec, s1: tuple, s2: tuple, q0: tuple, w_axial,
                         w_bending) -> tuple:
    """The damping force -alpha dPhi/d qd (``energies.point_dissipation`` in the current
    position q0 + dq, velocities qd0, qd1, ... relative to the first node, symbols) and its
    Jacobians with respect to dq and qd (ndof x ndof lists).  Cached as
    ``_elastic_derivatives``."""
    shift = sp.symbols(f"dq0:{spec.ndof}")
    rate = sp.symbols(f"qd0:{spec.ndof}")
    alpha = ref("alpha", 0)
    current = [a + b for a, b in zip(q0, shift, strict=True)]
    dissipation = alpha * energies.point_dissipation(s1, s2, current, rate, spec.dim, w_axial,
                                                     w_bending)
    damping = [-sp.diff(dissipation, v) for v in rate]
    return (damping, [[sp.diff(f, v) for v in shift] for f in damping],
            [[sp.diff(f, v) for v in rate] for f in damping])


def _exact_bending(spec: ElementSpec, name: str, wanted: list, point: list,
                   temps: Temporaries, s1, s2, q: list, weight, kappa0) -> dict[str, list]:
    """The ``wanted`` outputs (flat, row-major) of the exact-curvature bending at one point,
    U = w/2 |kappa - kappa0|^2 with kappa = c / g, c = r_x x r_xx, g = |r_x|^2, in closed
    form at the current node-relative coordinates ``q`` (intermediates materialised into
    ``point``).  Per component of kappa, with dg and dc the (constant-shape) gradients of g
    and c and m = kappa - kappa0:

      dk = (dc - kappa dg) / g,   H = d2 kappa = (d2c - dk dg^T - dg dk^T - kappa d2g) / g,
      F = -w sum m dk,   K = -w sum (dk dk^T + m H),

    d2c_(ka)(lb) = (s'_k s''_l - s'_l s''_k) (e_a x e_b), d2g_(ka)(lb) = 2 s'_k s'_l d_ab.
    Damping (kappa_dot = dk . q_dot): F_d = -alpha w sum kappa_dot dk, d/de_dot = -alpha w
    sum dk dk^T, d/de = -alpha w sum (dk (H q_dot)^T + kappa_dot H)."""
    d, n, ndof = spec.dim, spec.n_shape, spec.ndof
    unit = [[int(a == b) for b in range(d)] for a in range(d)]
    dofs = [(k, a) for k in range(n) for a in range(d)]

    def along(weights, vec):
        return [sum(w * vec[k * d + c] for k, w in enumerate(weights)) for c in range(d)]

    rx, rxx = (materialize(point, temps, along(w, q)) for w in (s1, s2))
    g, inv_g = materialize(point, temps, [sum(x * x for x in rx), 1 / sum(x * x for x in rx)])
    cross = materialize(point, temps, energies.cross(rx, rxx))
    kappa = materialize(point, temps, [c * inv_g for c in cross])
    measure = materialize(point, temps, [kappa[0] - kappa0, *kappa[1:]])
    if name == "energy":
        return {"energy": [weight * sum(m * m for m in measure) / 2]}
    dg = materialize(point, temps, [2 * s1[k] * rx[a] for k, a in dofs])
    dc = [[s1[k] * x + s2[k] * y for k, a in dofs for x, y in
           [(energies.cross(unit[a], rxx)[v], energies.cross(rx, unit[a])[v])]]
          for v in range(len(cross))]
    dk = [materialize(point, temps, [(c - kv * g_) * inv_g for c, g_ in zip(row, dg, strict=True)])
          for row, kv in zip(dc, kappa, strict=True)]

    hessians = _curvature_hessians(spec, tuple(s1), tuple(s2), tuple(map(tuple, dk)),
                                   tuple(dg), tuple(kappa), inv_g)

    def hessian(v: int, i: int, j: int):
        return hessians[v][i][j]

    components = range(len(cross))
    force = [-weight * sum(measure[v] * dk[v][i] for v in components) for i in range(ndof)]
    stiffness = [[-weight * sum(dk[v][i] * dk[v][j] + measure[v] * hessian(v, i, j)
                                for v in components) for j in range(ndof)]
                 for i in range(ndof)]
    if name not in DAMPING_KERNELS:
        flat = {"force": force, "jacobian": [x for row in stiffness for x in row]}
        return {q: flat[q] for q in wanted}
    alpha = ref("alpha", 0)
    qd = relative_velocities(spec)
    rdx, rdxx = along(s1, qd), along(s2, qd)
    rate = materialize(point, temps, [sum(x * y for x, y in zip(row, qd, strict=True))
                                      for row in dk])
    scale = -alpha * weight
    # H q_dot per component: (d2c q_dot - dk (dg . q_dot) - dg kappa_dot - kappa d2g q_dot) / g
    dg_rate = 2 * sum(x * y for x, y in zip(rx, rdx, strict=True))
    h_rate = [materialize(point, temps, [
        (s1[k] * energies.cross(unit[a], rdxx)[v] - s2[k] * energies.cross(unit[a], rdx)[v]
         - dk[v][i] * dg_rate - dg[i] * rate[v] - kappa[v] * 2 * s1[k] * rdx[a]) * inv_g
        for i, (k, a) in enumerate(dofs)]) for v in components]
    damping = [scale * sum(rate[v] * dk[v][i] for v in components) for i in range(ndof)]
    jacobian = [[scale * sum(dk[v][i] * h_rate[v][j] + rate[v] * hessian(v, i, j)
                             for v in components) for j in range(ndof)] for i in range(ndof)]
    jacobian_dot = [[scale * sum(dk[v][i] * dk[v][j] for v in components)
                     for j in range(ndof)] for i in range(ndof)]
    if name == "damped_force_jacobians":
        damping = [a + b for a, b in zip(force, damping, strict=True)]
        jacobian = [[a + b for a, b in zip(ra, rb, strict=True)]
                    for ra, rb in zip(stiffness, jacobian, strict=True)]
    flat = {"force": damping, "jacobian": [x for row in jacobian for x in row],
            "jacobian_dot": [x for row in jacobian_dot for x in row]}
    return {q: flat[q] for q in wanted}


@cache
def _curvature_hessians(spec: ElementSpec, s1: tuple, s2: tuple, dk: tuple, dg: tuple,
                        kappa: tuple, inv_g) -> tuple:
    """H[v][i][j] = d2 kappa_v / d q_i d q_j = (d2c - dk dg^T - dg dk^T - kappa d2g) / g
    (``_exact_bending``) from the materialised dk, dg, kappa and 1/g.  Cached: the kernels of
    the exact-curvature families with one translation share them (their bending loops start
    from the same temporaries)."""
    d, n = spec.dim, spec.n_shape
    unit = [[int(a == b) for b in range(d)] for a in range(d)]
    dofs = [(k, a) for k in range(n) for a in range(d)]

    def hessian(v: int, i: int, j: int):
        (k, a), (m, b) = dofs[i], dofs[j]
        d2c = (s1[k] * s2[m] - s1[m] * s2[k]) * energies.cross(unit[a], unit[b])[v]
        d2g = 2 * s1[k] * s1[m] if a == b else 0
        return (d2c - dk[v][i] * dg[j] - dg[i] * dk[v][j] - kappa[v] * d2g) * inv_g

    return tuple(tuple(tuple(hessian(v, i, j) for j in range(len(dofs)))
                       for i in range(len(dofs))) for v in range(len(dk)))


def build(spec: ElementSpec) -> list[Kernel]:
    """The kernels of the ``quadrature`` family (of the cable energy for cable elements)."""
    if energies.is_cable(spec):
        return [cable_quadrature_kernel(spec, kernel_name(q)) for q in KERNELS]
    return [quadrature_kernel(spec, quantities, "straight") for quantities in KERNELS]


def build_law(spec: ElementSpec) -> list[Kernel]:
    """The kernels of the ``quadrature_law`` family (elastic and damping)."""
    names = [kernel_name(q) for q in KERNELS] + list(DAMPING_KERNELS)
    if energies.is_cable(spec):
        return [cable_quadrature_kernel(spec, name) for name in names]
    return [quadrature_law_kernel(spec, name) for name in names]
