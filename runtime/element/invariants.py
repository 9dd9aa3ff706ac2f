"""Pre-processing: the invariants of one element reference, closed form or by quadrature.

Closed form (straight references, any rigid placement): the generated ``integrals_straight``
kernel.  Quadrature (any reference, curved included): Gauss-Legendre over the local box with
the generated shape-function tables.  Both feed the generated ``invariants_<variant>`` map,
so the two paths differ only in how the four integrals (volume, mass, int P, int P P) are
obtained.
"""

from __future__ import annotations

import functools
import json
from dataclasses import dataclass
from fractions import Fraction

import numpy as np
import scipy.sparse

from runtime.kernels.kind import ElementKind, element_kind
from runtime.kernels.loader import KernelFamily


@dataclass(frozen=True)
class Integrals:
    """The four integrals of a reference: volume (m^3), mass and i2 (n x n), i4 (n^4)."""

    volume: float
    mass: np.ndarray
    i2: np.ndarray
    i4: np.ndarray


def domain_rule(kind: ElementKind, geometry, orders: tuple[int, ...],
                subdomain: str = "volume") -> tuple[np.ndarray, np.ndarray]:
    """Tensor Gauss-Legendre points (p, dim) in local coordinates and weights (p,) in m^3 over
    ``subdomain`` of the kind's reference domain (element.json ``domain``): a fixed axis of a
    subdomain contributes one point at its value and its extent to the weights, an axis of
    reduced integration its rule's points (whatever its order); a 2D domain's thickness
    scales the weights."""
    domain = kind.domain
    geometry = tuple(float(v) for v in geometry)
    values = domain.values(geometry)
    fixed = domain.fixed_axes(subdomain)
    reduced = domain.reduced_axes(subdomain)
    factor = float(domain.thickness_of(geometry))
    axes, weights = [], []
    for i, ((low, high), axis, order) in enumerate(zip(domain.bounds(geometry), domain.axes,
                                                       orders, strict=True)):
        scale = values[axis.scale]
        if i in fixed:
            axes.append(np.array([fixed[i] * scale]))
            weights.append(np.array([1.0]))
            factor *= high - low
            continue
        x, w = reduced[i] if i in reduced else np.polynomial.legendre.leggauss(order)
        axes.append(low + (x + 1) * (high - low) / 2)
        weights.append(w * (high - low) / 2)
    points = np.stack([g.ravel() for g in np.meshgrid(*axes, indexing="ij")], axis=1)
    weight = np.prod([g.ravel() for g in np.meshgrid(*weights, indexing="ij")], axis=0)
    return points, weight * factor


def gauss_rule(kind: ElementKind, geometry: tuple[float, float, float],
               orders: tuple[int, ...]) -> tuple[np.ndarray, np.ndarray]:
    """Tensor Gauss-Legendre points (p, dim) over the reference domain and weights (p,) in
    m^3 (in 2D the weights include the thickness ``width``)."""
    return domain_rule(kind, geometry, orders)


def shape_gradient_table(kind: ElementKind, family: KernelFamily, geometry,
                         points: np.ndarray) -> np.ndarray:
    """Structurally nonzero local shape gradients at ``points``: (p, pattern length)."""
    return family("shape_gradients", {"point": points, "geometry": np.asarray(geometry,
                                                                               float)})["gradients"]


def full_gradients(kind: ElementKind, table: np.ndarray) -> np.ndarray:
    """Expand a gradient table (p, pattern) into ds_k/dx_alpha arrays (p, n, dim)."""
    grads = np.zeros((table.shape[0], kind.n_shape, kind.dim))
    for j, (k, c) in enumerate(kind.gradient_pattern):
        grads[:, k, c] = table[:, j]
    return grads


def quadrature_table(kind: ElementKind, family: KernelFamily, geometry,
                     orders: tuple[int, ...]) -> np.ndarray:
    """Per-point table of the quadrature kernels: nonzero gradients, then the weight."""
    points, weights = gauss_rule(kind, geometry, orders)
    table = shape_gradient_table(kind, family, geometry, points)
    return np.ascontiguousarray(np.column_stack([table, weights]))


def reference_mapping(kind: ElementKind, e0: np.ndarray, grads: np.ndarray):
    """J0 = dr0/dx (p, dim, dim) at the points and its determinant (p,).

    Positions are taken relative to the first node first (the position shape functions'
    gradients sum to zero, so J0 is unchanged): an element far from the origin keeps the
    digits of its size instead of those of its distance."""
    q0 = e0.reshape(kind.n_shape, kind.dim).copy()
    positions = list(kind.position_vectors)
    q0[positions] -= q0[positions[0]]
    j0 = np.einsum("ka,pkb->pab", q0, grads)
    return j0, np.linalg.det(j0)


def degenerate(j0: np.ndarray) -> np.ndarray:
    """(p,) True where J0 (p, dim, dim) is degenerate, inverted or not finite: det J0 <=
    1e-12 relative to the scale of J0 (scaled first: scale**dim may overflow)."""
    scale = np.abs(j0).max()
    if not 0 < scale < np.inf:
        return np.ones(j0.shape[0], bool)
    return ~(np.linalg.det(j0 / scale) > 1e-12)


def checked_reference(kind: ElementKind, family: KernelFamily, geometry, e0: np.ndarray,
                      orders: tuple[int, ...]):
    """Gauss points, weights, local gradients (p, n, dim), J0 and det J0 of reference ``e0``.

    Raises ValueError when the mapping is degenerate or inverted (det J0 <= 0) at a point.
    """
    points, weights = gauss_rule(kind, geometry, orders)
    grads = full_gradients(kind, shape_gradient_table(kind, family, geometry, points))
    j0, det = reference_mapping(kind, e0, grads)
    bad = np.flatnonzero(degenerate(j0))
    if bad.size:
        where = points[bad[0]]
        raise ValueError(
            f"e0: the reference mapping is degenerate or inverted (det J0 = {det[bad[0]]:.3g} "
            f"<= 0 at local point {np.array2string(where, precision=4)}); expected an e0 whose "
            "gradients span a right-handed frame at every quadrature point")
    return points, weights, grads, j0, det


def numeric_integrals(kind: ElementKind, family: KernelFamily, geometry, e0: np.ndarray,
                      orders: tuple[int, ...]) -> Integrals:
    """The four integrals of any reference ``e0`` by Gauss quadrature of order ``orders``.

    Raises ValueError when the reference mapping is degenerate or inverted (det J0 <= 0).
    """
    points, weights, grads, j0, det = checked_reference(kind, family, geometry, e0, orders)
    values = family("shape_values", {"point": points,
                                     "geometry": np.asarray(geometry, float)})["values"]
    b = np.einsum("pka,pab->pkb", grads, np.linalg.inv(j0))
    p_matrix = np.einsum("pka,pla->pkl", b, b)
    wdet = weights * det
    return Integrals(
        volume=float(wdet.sum()),
        mass=np.einsum("p,pk,pl->kl", wdet, values, values),
        i2=np.einsum("p,pkl->kl", wdet, p_matrix),
        i4=np.einsum("p,pkl,pmn->klmn", wdet, p_matrix, p_matrix, optimize=True),
    )


def straight_integrals(kind: ElementKind, family: KernelFamily, geometry) -> dict:
    """Closed-form integrals of the straight reference, in the straight storage pattern."""
    return family("integrals_straight", {"geometry": np.asarray(geometry, float)[None, :]})


def _upper(matrix: np.ndarray) -> np.ndarray:
    return matrix[np.triu_indices(matrix.shape[0])]


def pattern_integrals(kind: ElementKind, variant: str, integrals: Integrals) -> dict:
    """Numeric integrals arranged as the inputs of ``invariants_<variant>``."""
    rows, cols = np.triu_indices(kind.n_shape)
    keys = kind.pattern(variant, "i4")
    i4 = integrals.i4[rows[keys[:, 0]], cols[keys[:, 0]], rows[keys[:, 1]], cols[keys[:, 1]]]
    return {"i4": i4[None, :], "i2": _upper(integrals.i2)[None, :],
            "mass_shape": _upper(integrals.mass)[None, :],
            "volume": np.array([[integrals.volume]])}


def stored_invariants(family: KernelFamily, variant: str, integrals: dict,
                      material: tuple[float, float, float]) -> dict[str, np.ndarray]:
    """Mass, K1, gram, cij and U0 arrays (1-D) from integrals (as ``pattern_integrals``)."""
    inputs = dict(integrals, material=np.asarray(material, float))
    out = family(f"invariants_{variant}", inputs)
    return {name: value[0] for name, value in out.items()}


def is_straight(kind: ElementKind, e0: np.ndarray, geometry, rtol: float = 1e-12) -> bool:
    """Whether ``e0`` is a rigid placement of the straight (flat) reference of ``geometry``
    (length, height, width; a bare number is the length): closed forms apply.

    Compares Gram matrices Q0 Q0^T after translating to the first node: they are invariant
    under rotation, so any rotated straight beam qualifies.  They are invariant under
    reflection too: the orientation is checked separately (``checked_reference``).
    """
    def gram(e):
        q = e.reshape(kind.n_shape, kind.dim).copy()
        first = kind.position_vectors[0]
        q[list(kind.position_vectors)] -= q[first]
        return q @ q.T

    geometry = tuple(np.atleast_1d(np.asarray(geometry, float)))
    reference = gram(kind.straight_reference(*geometry))
    return bool(np.allclose(gram(e0), reference, rtol=0, atol=rtol * np.abs(reference).max()))


def cij_operators(kind: ElementKind, variant: str, cij: np.ndarray):
    """Sparse operators of the cij kernels from the stored c^{kp}_{mq} values.

    Returns (k2, jacobian): K2 upper triangle = k2 @ p and the double sum of eq. 38 =
    jacobian @ p, with p the coordinate products e_s e_t (s <= t) in row-major order.
    C^{(k,a),(p,b)} holds c^{kp}_{mq} at ((m,a), (q,b)).  Both are linear in ``cij``: their
    structure and the maps from ``cij`` to their entries are built once per kind and
    variant (``_cij_structure``; seconds for the brick's 96 coordinates), each element
    then sums its values into them (``_operator``).
    """
    return tuple(_operator(structure, np.asarray(cij, float))
                 for structure in _cij_structure(kind.name, variant))


def _operator(structure: tuple, cij: np.ndarray) -> scipy.sparse.csr_matrix:
    """The CSR matrix of a ``_cij_structure`` entry with the values ``cij``."""
    indptr, indices, shape, sources, starts = structure
    return scipy.sparse.csr_matrix((np.add.reduceat(cij[sources], starts), indices.copy(),
                                    indptr.copy()), shape=shape)


@functools.cache
def _cij_structure(name: str, variant: str) -> tuple[tuple, tuple]:
    """For K2 and the Jacobian of eq. 38 of the kind ``name``: (indptr, indices, shape,
    sources, starts) with the CSR entries (sorted, duplicates summed) the sums of
    ``cij[sources]`` from each of ``starts`` to the next (``_summing_structure``)."""
    kind = element_kind(name)
    d, ndof = kind.dim, kind.ndof
    pattern = kind.pattern(variant, "cij")
    pair = np.full((ndof, ndof), -1)
    rows, cols = np.triu_indices(ndof)
    pair[rows, cols] = pair[cols, rows] = np.arange(rows.size)
    a, b = np.meshgrid(np.arange(d), np.arange(d), indexing="ij")
    a, b = a.ravel(), b.ravel()
    k, p, m, q = (pattern[:, None, j] for j in range(4))
    i, j = k * d + a, p * d + b              # C^ij with i = (k,a), j = (p,b)
    s, t = m * d + a, q * d + b              # its nonzero at (s, t)
    source = np.broadcast_to(np.arange(len(pattern))[:, None], i.shape)
    keep = i <= j
    i, j, s, t, source = (x[keep] for x in (i, j, s, t, source))
    k2 = _summing_structure(pair[i, j], pair[s, t], source, (rows.size, rows.size))
    # eq. 38: row i gets C_st p_jt at column s and C_st p_js at column t; the mirrored
    # pair (j, i) uses the same C (K2 is symmetric), except on the diagonal i == j.
    mirror = i != j
    jr = np.concatenate([i * ndof + s, i * ndof + t, (j * ndof + s)[mirror],
                         (j * ndof + t)[mirror]])
    jc = np.concatenate([pair[j, t], pair[j, s], pair[i, t][mirror], pair[i, s][mirror]])
    js = np.concatenate([source, source, source[mirror], source[mirror]])
    jacobian = _summing_structure(jr, jc, js, (ndof * ndof, rows.size))
    return k2, jacobian


def _summing_structure(rows: np.ndarray, cols: np.ndarray, source: np.ndarray,
                       shape: tuple) -> tuple:
    """(indptr, indices, shape, sources, starts) of the CSR matrix whose entry (r, c) sums
    the values at ``source`` of every (rows, cols) pair at it: the pairs' sources in the
    entries' order and where each entry's begin.  The pairs are ordered by two
    stable sorts, columns then rows (radix sorts for 16-bit indices: the brick's 11
    million pairs in a fraction of a second)."""
    index = np.int16 if max(shape) <= np.iinfo(np.int16).max else np.int64
    rows, cols = rows.astype(index), cols.astype(index)
    order = np.argsort(cols, kind="stable")
    order = order[np.argsort(rows[order], kind="stable")]
    sorted_rows, sorted_cols = rows[order], cols[order]
    first = np.ones(order.size, bool)          # the first pair of each entry
    first[1:] = (sorted_rows[1:] != sorted_rows[:-1]) | (sorted_cols[1:] != sorted_cols[:-1])
    starts = np.flatnonzero(first)             # in the sorted pairs: the entries' first
    indptr = np.searchsorted(sorted_rows[starts], np.arange(shape[0] + 1)).astype(np.int32)
    return (indptr, sorted_cols[starts].astype(np.int32), shape,
            source[order].astype(np.int32), starts)


# --- material laws (symgen/laws.py): coefficients, Gauss rules per domain, invariants -----------


def law_coefficients(kind: ElementKind, laws: KernelFamily, law: str, E: float, nu: float,
                     corrections=()) -> dict[str, np.ndarray]:
    """Law coefficients (Pa) per domain (``volume``, ``axis``) of ``law`` for E (Pa), nu and
    the shear corrections (only for laws that take them)."""
    inputs = {"material": np.array([[E, nu]], dtype=float)}
    if kind.laws[law].corrections:
        inputs["correction"] = np.asarray(corrections, dtype=float)[None, :]
    out = laws(f"law_{law}", inputs)
    return {domain: out[domain][0] for domain in kind.law_domains}


def default_corrections(laws: KernelFamily, law: str, E: float, nu: float) -> tuple:
    """The law's default shear-correction factors for E (Pa) and nu."""
    out = laws(f"law_{law}_correction", {"material": np.array([[E, nu]], dtype=float)})
    return tuple(float(k) for k in out["correction"][0])


@dataclass(frozen=True)
class LawRule:
    """Gauss rule of one law domain for a reference: local points (p, dim), the local
    gradient table (p, pattern), U^-1 (p, dim, dim) with J0 = R0 U (R0 the local frame: the
    Gram-Schmidt orthonormalisation of dr0/dx, dr0/dy[, dr0/dz]) and weights times det J0
    (p,), in m^3 (the axis rule includes the cross-section area h w)."""

    domain: str
    points: np.ndarray
    table: np.ndarray
    u_inv: np.ndarray
    wdet: np.ndarray


def axis_rule(kind: ElementKind, geometry, order: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre points on the beam axis (y = z = 0) and weights times the area h w."""
    return subdomain_rule(kind, geometry, (order,) * kind.dim, "axis")


def subdomain_rule(kind: ElementKind, geometry, orders: tuple[int, ...],
                   subdomain: str) -> tuple[np.ndarray, np.ndarray]:
    """The Gauss rule of a law domain: ``volume`` with ``orders``; a lower-dimensional
    subdomain (the beam ``axis``, the plate ``midsurface``) with the orders of its free axes
    (a beam's axis rule has order ``orders[0]``), its fixed axes' extents in the weights."""
    return domain_rule(kind, geometry, orders, subdomain)


def law_rules(kind: ElementKind, family: KernelFamily, geometry, e0: np.ndarray,
              orders: tuple[int, ...]) -> dict[str, LawRule]:
    """The Gauss rule of every law domain of the kind (``volume`` with ``orders``, the
    others with the orders of their free axes).

    Raises ValueError when the reference mapping is degenerate or inverted at a point.
    """
    rules = {}
    for domain in kind.law_domains:
        points, weights = subdomain_rule(kind, geometry, orders, domain)
        table = shape_gradient_table(kind, family, geometry, points)
        j0, det = reference_mapping(kind, e0, full_gradients(kind, table))
        if degenerate(j0).any():
            raise ValueError("e0: the reference mapping is degenerate or inverted on the "
                             f"{domain} rule; expected gradients spanning a right-handed frame")
        upper = np.swapaxes(np.linalg.cholesky(np.einsum("pab,pac->pbc", j0, j0)), 1, 2)
        rules[domain] = LawRule(domain, points, table, np.linalg.inv(upper), weights * det)
    return rules


def _cable_metric(kind: ElementKind, first: np.ndarray, e0: np.ndarray | None) -> np.ndarray:
    """|r0_x| at the points of the shape-gradient table ``first`` (p, n) of a cable (ones for
    the default reference, parameterised by arc length); ValueError where it vanishes."""
    if e0 is None:
        return np.ones(first.shape[0])
    metric = np.linalg.norm(first @ e0.reshape(kind.n_shape, kind.dim), axis=1)
    if not (metric > 1e-12 * np.abs(e0).max()).all():
        raise ValueError("e0: the reference tangent r0_x vanishes at a Gauss point; expected "
                         "a cable reference with a nonzero tangent everywhere")
    return metric


def cable_table(kind: ElementKind, family: KernelFamily, geometry, order: int,
                coefficients: dict[str, np.ndarray], e0: np.ndarray | None = None,
                curvature: bool = False) -> np.ndarray:
    """Per-point table of a cable's quadrature kernels: at the Gauss points of order ``order``
    on the axis, ds/dx, d2s/dx2, and the weights of the axial part (E11 coefficient on the
    axis times the weight, which holds the area, over a0^3: EA dx / a0^3, N m) and of the
    bending part (the same modulus times I dx / a0, N m^3), a0 = |r0_x| of the reference
    ``e0`` (1 for the default straight one); with ``curvature`` (the planar exact curvature,
    the cable law that takes curved references) the reference curvature r0_x x r0_xx /
    |r0_x|^2 (1/m); symgen/energies.py."""
    points, weights = subdomain_rule(kind, geometry, (order,) * kind.dim, "axis")
    shared = np.asarray(geometry, float)
    first = shape_gradient_table(kind, family, geometry, points)
    second = family("shape_curvatures", {"point": points, "geometry": shared})["curvatures"]
    area, moment = family("section", {"geometry": shared[None, :]})["section"][0]
    modulus = float(coefficients["axis"][0])
    metric = _cable_metric(kind, first, e0)
    columns = [first, second, weights * modulus / metric**3,
               weights * modulus * moment / area / metric]
    if curvature:
        q0 = (kind.straight_reference(*geometry) if e0 is None else e0).reshape(kind.n_shape,
                                                                                 kind.dim)
        r0x, r0xx = first @ q0, second @ q0
        columns.append((r0x[:, 0] * r0xx[:, 1] - r0x[:, 1] * r0xx[:, 0]) / metric**2)
    return np.ascontiguousarray(np.column_stack(columns))


def cable_invariants(kind: ElementKind, family: KernelFamily, geometry, orders,
                     coefficients: dict[str, np.ndarray], density: float,
                     bending: float | None = None, e0: np.ndarray | None = None,
                     variant: str = "straight") -> dict[str, np.ndarray]:
    """Mass, K1, gram, cij, U0 and the gram form's linear term of a cable by quadrature (the
    straight closed forms come from the generated ``law_invariants_straight``): the axial
    part through ``law_algebra`` of storage ``variant`` with b = (ds/dx) / a0 on the axis
    rule of order ``orders[0]`` and the weights times a0 (a0 = |r0_x| of the reference
    ``e0``, 1 for the default straight one: the strain E11 = (r_x.r_x - r0_x.r0_x) /
    (2 a0^2) per reference arc length), the mass int rho s s a0 dV, the bending part
    EI K_kl, K = int s_k'' s_l'' dx, added to K1, and ``gram_linear`` = EI mu K / 4 (mu = 1
    on the diagonal, 2 off it); symgen/energies.py.  ``bending``: the modulus E of the
    pre-integrated (simple) bending, default the E11 coefficient on the axis; 0 for the exact
    curvature (bending by quadrature)."""
    points, weights = subdomain_rule(kind, geometry, (orders[0],) * kind.dim, "axis")
    shared = np.asarray(geometry, float)
    b = full_gradients(kind, shape_gradient_table(kind, family, geometry, points))
    metric = _cable_metric(kind, b[:, :, 0], e0)
    b, measure = b / metric[:, None, None], weights * metric
    p_dir = np.einsum("pka,pla->pakl", b, b)
    none = {domain: np.zeros_like(value) for domain, value in coefficients.items()}
    parts = [(coefficients["axis"] if domain == "axis" else none[domain],
              lambda: np.einsum("p,pakl,pbmn->abklmn", measure, p_dir, p_dir, optimize=True),
              np.einsum("p,pakl->akl", measure, p_dir), measure.sum())
             for domain in kind.law_domains]
    volume, volume_weights = domain_rule(kind, geometry, orders)
    volume_weights = volume_weights * _cable_metric(
        kind, full_gradients(kind, shape_gradient_table(kind, family, geometry, volume))[:, :, 0],
        e0)
    values = family("shape_values", {"point": volume, "geometry": shared})["values"]
    mass = np.einsum("p,pk,pl->kl", volume_weights, values, values)
    stored = law_algebra(kind, variant, parts, mass, density)
    second = family("shape_curvatures", {"point": points, "geometry": shared})["curvatures"]
    area, moment = family("section", {"geometry": shared[None, :]})["section"][0]
    modulus = float(coefficients["axis"][0]) if bending is None else bending
    stiffness = modulus * moment * np.einsum(
        "p,pk,pl->kl", weights / area, second, second)
    rows, cols = np.triu_indices(kind.n_shape)
    stored["k1"] = stored["k1"] + stiffness[rows, cols]
    stored["gram_linear"] = np.where(rows == cols, 1, 2) * stiffness[rows, cols] / 4
    return stored


def law_table(kind: ElementKind, rules: dict[str, LawRule],
              coefficients: dict[str, np.ndarray]) -> np.ndarray:
    """Per-point table of the ``quadrature_law`` kernels: local gradients, U^-1 upper
    triangle, law coefficients times weight and det J0; domains without a part are left out."""
    rows, cols = np.triu_indices(kind.dim)
    blocks = []
    for domain, rule in rules.items():
        coefficient = np.asarray(coefficients[domain], float)
        if not coefficient.any():
            continue
        blocks.append(np.column_stack([rule.table, rule.u_inv[:, rows, cols],
                                       rule.wdet[:, None] * coefficient[None, :]]))
    return np.ascontiguousarray(np.concatenate(blocks))


def _law_blocks(kind: ElementKind, coefficient: np.ndarray):
    """(normal block (dim, dim), shear list) of a domain's law coefficients."""
    d = kind.dim
    normal = np.zeros((d, d))
    rows, cols = np.triu_indices(d)
    count = rows.size
    normal[rows, cols] = normal[cols, rows] = coefficient[:count]
    return normal, coefficient[count:]


def shear_pairs(dim: int) -> list[tuple[int, int]]:
    """Local axes of the shear strains in Voigt order (as symgen.laws.shear_pairs)."""
    return [(0, 1)] if dim == 2 else [(1, 2), (0, 2), (0, 1)]


def numeric_law_invariants(kind: ElementKind, family: KernelFamily, variant: str, geometry,
                           rules: dict[str, LawRule], coefficients: dict[str, np.ndarray],
                           density: float) -> dict[str, np.ndarray]:
    """Mass, K1, gram, cij and U0 (as ``stored_invariants``) of a law by quadrature.

    With b the shape gradients in the local frame and T^ab_klmn = sum_p w P^a_kl P^b_mn
    (P^a_kl = b_ka b_la), per domain (symgen.derive.law_gram_value and friends):
    Dsym = 1/8 sum DN_ab T^ab_klmn + 1/8 sum_shear DS (T^ab_kmln + T^ab_knlm + T^ab_lmkn
    + T^ab_lnkm); c^{kp}_{mq} = 1/2 sum DN_ab T^ab_kmpq + sum_shear DS (T^ab + T^ba)_kqmp;
    K1 = -1/2 sum_a (sum_c DN_ac) int P^a; U0 = 1/8 sum DN times the domain's measure.
    """
    parts = []
    for domain, rule in rules.items():
        b = np.einsum("pka,pab->pkb", full_gradients(kind, rule.table), rule.u_inv)
        p_dir = np.einsum("pka,pla->pakl", b, b)
        parts.append((coefficients[domain],
                      lambda rule=rule, p_dir=p_dir: np.einsum(
                          "p,pakl,pbmn->abklmn", rule.wdet, p_dir, p_dir, optimize=True),
                      np.einsum("p,pakl->akl", rule.wdet, p_dir), rule.wdet.sum()))
    volume = rules["volume"]
    values = family("shape_values", {"point": volume.points,
                                     "geometry": np.asarray(geometry, float)})["values"]
    mass = np.einsum("p,pk,pl->kl", volume.wdet, values, values)
    return law_algebra(kind, variant, parts, mass, density)


def law_algebra(kind: ElementKind, variant: str, parts, mass: np.ndarray,
                density: float) -> dict[str, np.ndarray]:
    """Mass, K1, gram, cij and U0 from the directional integrals of each law domain.

    parts: per domain (law coefficients, a function giving T^ab_klmn = int P^a_kl P^b_mn as
    a (dim, dim, n, n, n, n) array, int P^a (dim, n, n), the measure); mass: int s s^T.
    Per domain (symgen.derive.law_gram_value and friends):
    Dsym = 1/8 sum DN_ab T^ab_klmn + 1/8 sum_shear DS (T^ab_kmln + T^ab_knlm + T^ab_lmkn
    + T^ab_lnkm); c^{kp}_{mq} = 1/2 sum DN_ab T^ab_kmpq + sum_shear DS (T^ab + T^ba)_kqmp;
    K1 = -1/2 sum_a (sum_c DN_ac) int P^a; U0 = 1/8 sum DN times the domain's measure.
    """
    n, d = kind.n_shape, kind.dim
    dsym = np.zeros((n, n, n, n))
    cfull = np.zeros((n, n, n, n))         # c[k, p, m, q]
    k1 = np.zeros((n, n))
    u0 = 0.0
    for coefficient, tensor, pi, measure in parts:
        normal, shear = _law_blocks(kind, np.asarray(coefficient, float))
        if not (normal.any() or shear.any()):
            continue
        t = tensor()
        dsym += np.einsum("ab,abklmn->klmn", normal, t) / 8
        cfull += np.einsum("ab,abkmpq->kpmq", normal, t) / 2
        for value, (x, y) in zip(shear, shear_pairs(d), strict=True):
            txy = t[x, y]
            dsym += value / 8 * (np.einsum("kmln->klmn", txy) + np.einsum("knlm->klmn", txy)
                                 + np.einsum("lmkn->klmn", txy) + np.einsum("lnkm->klmn", txy))
            both = txy + t[y, x]
            cfull += value * np.einsum("kqmp->kpmq", both)
        k1 -= np.einsum("a,akl->kl", normal.sum(axis=1), pi) / 2
        u0 += normal.sum() * measure / 8
    return _stored(kind, variant, dsym, cfull, k1, u0, mass * density)


def _stored(kind: ElementKind, variant: str, dsym: np.ndarray, cfull: np.ndarray,
            k1: np.ndarray, u0: float, mass: np.ndarray) -> dict[str, np.ndarray]:
    """The stored invariants (as ``stored_invariants``) of storage ``variant`` from the full
    tensors: Dsym (n, n, n, n), c[k, p, m, q], K1 and the mass (n, n), U0."""
    n = kind.n_shape
    rows, cols = np.triu_indices(n)
    gram = kind.pattern(variant, "gram")
    a_k, a_m = rows[gram[:, 0]], cols[gram[:, 0]]
    b_k, b_m = rows[gram[:, 1]], cols[gram[:, 1]]
    mu = np.where(a_k == a_m, 1, 2) * np.where(b_k == b_m, 1, 2)
    cij = kind.pattern(variant, "cij")
    return {"mass": mass[rows, cols], "k1": k1[rows, cols],
            "gram": mu * dsym[a_k, a_m, b_k, b_m],
            "cij": cfull[cij[:, 0], cij[:, 1], cij[:, 2], cij[:, 3]],
            "u0": np.array([u0])}


# --- structural laws (symgen/structural.py): strains of the centre line ----------------------


def structural_stiffness(kind: ElementKind, laws: KernelFamily, law: str, E: float,
                         nu: float, corrections, geometry) -> np.ndarray:
    """The section stiffness (N, N m^2) of each strain of the structural law ``law``
    (``LawInfo.strains`` order) for E (Pa), nu, the shear corrections and the geometry."""
    inputs = {"material": np.array([[E, nu]], dtype=float),
              "geometry": np.asarray(geometry, float)}
    if kind.laws[law].corrections:
        inputs["correction"] = np.asarray(corrections, dtype=float)[None, :]
    return laws(f"law_{law}", inputs)["stiffness"][0]


def structural_table(kind: ElementKind, family: KernelFamily, law: str, geometry,
                     orders: tuple[int, ...], stiffness: np.ndarray) -> np.ndarray:
    """Per-point table of a structural law (``quadrature_structural`` kernels, and the
    source of its invariants): at the points of each domain its strains are sampled on (the
    axis rule of order ``orders[0]``, the nodes), the shape derivatives of the law's
    directions on the centre line, then per strain its stiffness times the point's weight
    along x (m) where the strain is sampled on that domain, zero elsewhere."""
    info = kind.laws[law]
    shared = np.asarray(geometry, float)
    area = shared[1] * shared[2]      # the axis rules' weights hold the section h w
    blocks = []
    for domain in dict.fromkeys(strain["domain"] for strain in info.strains):
        points, weights = subdomain_rule(kind, geometry, orders, domain)
        directions = family("structural_directions", {"point": points,
                                                      "geometry": shared})["directions"]
        on = np.array([strain["domain"] == domain for strain in info.strains])
        blocks.append(np.column_stack([directions, (weights / area)[:, None]
                                       * np.where(on, stiffness, 0.0)[None, :]]))
    return np.ascontiguousarray(np.concatenate(blocks))


def structural_invariants(kind: ElementKind, family: KernelFamily, law: str, variant: str,
                          geometry, orders: tuple[int, ...], table: np.ndarray,
                          density: float) -> dict[str, np.ndarray]:
    """Mass, K1, gram, cij and U0 of a structural law from its ``structural_table``: each
    strain of directions (a, b) with weights W is the law algebra's normal strain of
    P^a = u_a u_a^T (a = b: (r_a.r_a - 1)/2) or its shear between P^a and P^b (r_a . r_b),
    with T^ab_klmn = sum_p W P^a_kl P^b_mn (``law_algebra``); the mass int rho s s^T dV0 on
    the volume rule of ``orders`` (a straight reference: det J0 = 1)."""
    info, n = kind.laws[law], kind.n_shape
    count = len(info.directions)
    u = table[:, :count * n].reshape(-1, count, n)
    dsym = np.zeros((n, n, n, n))
    cfull = np.zeros((n, n, n, n))
    k1 = np.zeros((n, n))
    u0 = 0.0
    for i, strain in enumerate(info.strains):
        weight = table[:, count * n + i]
        a, b = strain["directions"]
        pa, pb = (np.einsum("pk,pl->pkl", u[:, c], u[:, c]) for c in (a, b))
        t = np.einsum("p,pkl,pmq->klmq", weight, pa, pb)
        if a == b:
            dsym += t / 8
            cfull += np.einsum("kmpq->kpmq", t) / 2
            k1 -= np.einsum("p,pkl->kl", weight, pa) / 2
            u0 += weight.sum() / 8
            continue
        dsym += (np.einsum("kmln->klmn", t) + np.einsum("knlm->klmn", t)
                 + np.einsum("lmkn->klmn", t) + np.einsum("lnkm->klmn", t)) / 8
        cfull += np.einsum("kqmp->kpmq", t + np.einsum("klmq->mqkl", t))
    points, weights = domain_rule(kind, geometry, orders)
    values = family("shape_values", {"point": points,
                                     "geometry": np.asarray(geometry, float)})["values"]
    mass = np.einsum("p,pk,pl->kl", weights, values, values)
    return _stored(kind, variant, dsym, cfull, k1, u0, mass * density)


# --- closed forms as data (elements with closed.json, symgen.emit.closed_tables) ------------


@functools.cache
def _closed_data(kind_name: str) -> dict:
    from runtime.catalog import generated_dir

    data = json.loads((generated_dir() / kind_name / "closed.json").read_text())
    out = {"shape": np.array(data["shape_exponents"], dtype=np.int64),
           "measure": np.array(data["measure_exponents"], dtype=np.int64), "domains": {}}

    def split(rows, count):
        rows = np.array(rows, dtype=object).reshape(-1, count + 2)
        index = rows[:, :count].astype(np.int64)
        value = np.array([float(Fraction(int(p), int(q))) for p, q in rows[:, count:]])
        return index, value

    for domain, tables in data["domains"].items():
        out["domains"][domain] = {"measure": float(Fraction(*tables["measure"])),
                                  "pi": split(tables["pi"], 3), "psi": split(tables["psi"], 6)}
    out["mass"] = split(data["mass"], 2)
    return out


def has_closed_tables(kind: ElementKind) -> bool:
    """Whether the kind's straight closed forms are data (closed.json) rather than kernels."""
    return bool(kind.closed_tables)


def straight_by_quadrature(kind: ElementKind) -> bool:
    """Whether the kind's straight invariants are integrated at load time by an exact Gauss
    rule (element.json ``straight_invariants``: its closed forms would be too large to ship)."""
    return kind.straight_invariants == "quadrature"


def through_laws(kind: ElementKind) -> bool:
    """Whether the kind's svk invariants go through the law path (no generated svk maps):
    closed forms as data, or straight invariants by quadrature."""
    return has_closed_tables(kind) or straight_by_quadrature(kind)


#: quadrature_law_invariants' results by (kind, backend, geometry, coefficients, density),
#: at most STRAIGHT_QUADRATURE_CACHED of them (the oldest goes first; 6 MB each for the brick)
_STRAIGHT_QUADRATURE: dict[tuple, dict[str, np.ndarray]] = {}
STRAIGHT_QUADRATURE_CACHED = 16


def quadrature_law_invariants(kind: ElementKind, family: KernelFamily, geometry,
                              coefficients: dict[str, np.ndarray],
                              density: float) -> dict[str, np.ndarray]:
    """Straight invariants of a law (straight pattern) by the Gauss rule of the kind's
    ``exact_orders`` on its straight reference of ``geometry``: exact, as the closed forms
    (the integrands are polynomials).  Cached per kind, geometry, law coefficients and
    density (a box body's elements share one entry); the arrays are read-only."""
    geometry = tuple(float(v) for v in geometry)
    key = (kind.name, family.backend, geometry, float(density),
           tuple((domain, tuple(np.asarray(value, float).tolist()))
                 for domain, value in sorted(coefficients.items())))
    if key not in _STRAIGHT_QUADRATURE:
        rules = law_rules(kind, family, geometry, kind.straight_reference(*geometry),
                          kind.exact_orders)
        out = numeric_law_invariants(kind, family, "straight", geometry, rules,
                                     coefficients, density)
        for value in out.values():
            value.flags.writeable = False
        if len(_STRAIGHT_QUADRATURE) >= STRAIGHT_QUADRATURE_CACHED:
            del _STRAIGHT_QUADRATURE[next(iter(_STRAIGHT_QUADRATURE))]
        _STRAIGHT_QUADRATURE[key] = out
    return _STRAIGHT_QUADRATURE[key]


def closed_parts(kind: ElementKind, geometry, coefficients: dict[str, np.ndarray]):
    """(parts, mass) of ``law_algebra`` for the straight reference of ``geometry`` from the
    exact tables: every entry is its rational times its monomial in the parameters."""
    data = _closed_data(kind.name)
    params = np.asarray(geometry, float)
    n, d = kind.n_shape, kind.dim
    names = kind.domain.parameters
    unit = np.zeros((d, 3), dtype=np.int64)        # exponents of 1 / s_a
    for a, axis in enumerate(kind.domain.axes):
        unit[a, names.index(axis.scale)] = 1
    shape = data["shape"]

    def monomial(exps):
        return np.prod(params[None, :] ** exps, axis=1)

    parts = []
    for domain, tables in data["domains"].items():
        (index, value), measure = tables["pi"], tables["measure"]
        a, k, m = index.T
        pi = np.zeros((d, n, n))
        e_pi = shape[k] + shape[m] - 2 * unit[a] + data["measure"]
        pi[a, k, m] = pi[a, m, k] = value * monomial(e_pi)
        index, value = tables["psi"]

        def tensor(index=index, value=value):
            a, b, k, l_, m, q = index.T
            exps = (shape[k] + shape[l_] - 2 * unit[a] + shape[m] + shape[q] - 2 * unit[b]
                    + data["measure"])
            v = value * monomial(exps)
            t = np.zeros((d, d, n, n, n, n))
            for kk, ll in ((k, l_), (l_, k)):
                for mm, qq in ((m, q), (q, m)):
                    t[a, b, kk, ll, mm, qq] = v
                    t[b, a, mm, qq, kk, ll] = v
            return t

        volume = measure * np.prod(params ** data["measure"])
        parts.append((coefficients[domain], tensor, pi, volume))
    (index, value) = data["mass"]
    k, m = index.T
    mass = np.zeros((n, n))
    mass[k, m] = mass[m, k] = value * monomial(shape[k] + shape[m] + data["measure"])
    return parts, mass


def closed_law_invariants(kind: ElementKind, geometry, coefficients: dict[str, np.ndarray],
                          density: float) -> dict[str, np.ndarray]:
    """Closed-form straight invariants of a law from the exact tables (straight pattern)."""
    parts, mass = closed_parts(kind, geometry, coefficients)
    return law_algebra(kind, "straight", parts, mass, density)


def straight_law_invariants(family: KernelFamily, geometry, coefficients: dict[str, np.ndarray],
                            density: float, bending: float | None = None
                            ) -> dict[str, np.ndarray]:
    """Closed-form invariants of a law for the straight reference (``law_invariants_straight``);
    ``bending``: a cable's modulus of the pre-integrated simple bending (Pa; 0 when its
    bending is by quadrature, None for a continuum)."""
    # the kernel takes the exactly integrated domains (laws with reduced integration store
    # general invariants, so their coefficients there are zero)
    taken = {a["name"] for a in family.signatures["law_invariants_straight"]["arrays"]}
    inputs = {"geometry": np.asarray(geometry, float)[None, :], "density": np.array([density]),
              **{domain: np.asarray(value, float) for domain, value in coefficients.items()
                 if domain in taken},
              **({"bending": np.array([bending])} if bending is not None else {})}
    return {name: value[0] for name, value in family("law_invariants_straight", inputs).items()}
