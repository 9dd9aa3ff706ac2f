"""Derivations shared by every element: gradients, integrals over the box, invariant algebra.

Notation (docs/design.md section 6): ``n`` shape functions, ``B`` (n x dim) their gradients with
respect to the reference position r0, ``P = B B^T``.  Everything an evaluation method needs
is a linear combination of four integrals over the reference volume:

* ``volume`` = int dV0,
* ``mass``   = int s s^T dV0              (n x n; times rho and kron I_dim: the mass matrix),
* ``i2``     = int P dV0                  (n x n; gives K1 of eq. 29),
* ``i4``     = int P_kl P_mn dV0          (n^4; gives C^ij of eq. 35 and the gram tensor D).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from functools import cache

import sympy as sp

from symgen.element import ElementSpec

lam, shear, rho = sp.symbols("lambda G rho", positive=True)


def pairs(n: int) -> list[tuple[int, int]]:
    """Upper-triangle index pairs (k, l), k <= l, in row order: the symmetric-storage order."""
    return [(k, m) for k in range(n) for m in range(k, n)]


def pair_index(n: int) -> dict[tuple[int, int], int]:
    """Position of (k, l) and (l, k) in ``pairs(n)``."""
    index = {}
    for a, (k, m) in enumerate(pairs(n)):
        index[(k, m)] = index[(m, k)] = a
    return index


def quad_key(n: int, k: int, m: int, p: int, q: int) -> tuple[int, int]:
    """Canonical (a, b), a <= b, of the i4 entry int P_km P_pq (symmetric in k<->m, p<->q, swap)."""
    index = pair_index(n)
    a, b = index[(k, m)], index[(p, q)]
    return (a, b) if a <= b else (b, a)


def shape_gradients(spec: ElementSpec) -> sp.Matrix:
    """d s_k / d x_alpha in the local box coordinates, an n x dim matrix of polynomials."""
    return sp.Matrix(
        [[sp.expand(sp.diff(s, c)) for c in spec.coordinates] for s in spec.shape_functions]
    )


def gradient_pattern(spec: ElementSpec) -> list[tuple[int, int]]:
    """Structurally nonzero entries (k, alpha) of the shape-function gradient matrix."""
    grads = shape_gradients(spec)
    return [(k, c) for k in range(spec.n_shape) for c in range(spec.dim) if grads[k, c] != 0]


def box_integral(spec: ElementSpec, expr: sp.Expr) -> sp.Expr:
    """Exact integral of a polynomial in the local coordinates over the straight element
    volume (the element's domain, times the thickness in 2D), factored."""
    return sp.factor(spec.domain.integrate(expr))


@dataclass(frozen=True)
class Integrals:
    """Integrals of one element reference, symbolic or numeric.

    i4 maps a canonical key (a, b) (see ``quad_key``) to int P P; missing keys are zero.
    mass and i2 are n x n, volume a scalar.
    """

    volume: object
    mass: object
    i2: object
    i4: Callable[[tuple[int, int]], object]


@cache
def straight_integrals(spec: ElementSpec) -> Integrals:
    """Closed-form integrals of the straight reference (J0 = I, so B = ds/dx), in the domain
    parameters, factored (from the exact tables of ``symgen.closed``)."""
    from symgen import closed

    tables = closed.straight_tables(spec)
    n = spec.n_shape
    mass = sp.Matrix(n, n, lambda k, m: sp.factor(
        closed.to_sympy(spec, tables.mass[(min(k, m), max(k, m))])))
    i2 = sp.Matrix(n, n, lambda k, m: sp.factor(
        closed.to_sympy(spec, tables.i2.get((min(k, m), max(k, m)), {}))))
    i4_values: dict[tuple[int, int], sp.Expr] = {}

    def i4(key):
        if key not in i4_values:
            value = tables.i4.get(key)
            i4_values[key] = sp.Integer(0) if not value else sp.factor(
                closed.to_sympy(spec, value))
        return i4_values[key]

    return Integrals(sp.factor(closed.to_sympy(spec, tables.volume)), mass, i2, i4)


# --- invariant algebra: from the four integrals to what each method stores -------------------


def cij_value(spec: ElementSpec, i4: Callable, k: int, p: int, m: int, q: int) -> object:
    """Entry c^{kp}_{mq} of the shape-level C^ij invariant (eq. 35 with eq. 28 and 33).

    C^{(k,a),(p,b)} has c^{kp}_{mq} at ((m,a), (q,b)) and zeros elsewhere:
    c^{kp}_{mq} = int (lambda/2 P_km P_qp + G P_kq P_mp) dV0.
    """
    n = spec.n_shape
    return lam / 2 * i4(quad_key(n, k, m, q, p)) + shear * i4(quad_key(n, k, q, m, p))


def gram_value(spec: ElementSpec, i4: Callable, a: int, b: int) -> object:
    """Entry (a, b) of the symmetric gram matrix Dm with U = g^T Dm g, g_a = DeltaG_(k,l).

    Dm_ab = mu_a mu_b Dsym_klmn with mu = 1 on diagonal pairs and 2 off them, and the fully
    symmetrised tensor Dsym_klmn = lambda/8 int P_kl P_mn + G/8 int (P_km P_ln + P_kn P_lm).
    """
    n = spec.n_shape
    (k, m), (p, q) = pairs(n)[a], pairs(n)[b]
    mu = (1 if k == m else 2) * (1 if p == q else 2)
    value = lam / 8 * i4(quad_key(n, k, m, p, q)) + shear / 8 * (
        i4(quad_key(n, k, p, m, q)) + i4(quad_key(n, k, q, m, p))
    )
    return mu * value


def strain_energy_constant(spec: ElementSpec, volume: object) -> object:
    """U0 of eqs. 40-41: the energy of e = 0, (dim^2 lambda + 2 dim G) V / 8."""
    d = spec.dim
    return (d * d * lam + 2 * d * shear) * volume / 8


def k1_value(spec: ElementSpec, i2: object, k: int, m: int) -> object:
    """Shape-level K1 of eqs. 29/31: -(dim lambda + 2 G)/2 int P_km (times I_dim)."""
    return -(spec.dim * lam + 2 * shear) / 2 * i2[k, m]


@dataclass(frozen=True)
class Patterns:
    """Which invariant entries an evaluation variant stores, in storage order.

    i4: canonical keys (a, b) of the i4 integrals; gram: (a, b), a <= b, entries of Dm;
    cij: (k, p, m, q), k <= p, entries c^{kp}_{mq}.  The ``straight`` variant keeps only
    the structurally nonzero entries of the straight reference; ``general`` keeps all.
    """

    variant: str
    i4: tuple[tuple[int, int], ...]
    gram: tuple[tuple[int, int], ...]
    cij: tuple[tuple[int, int, int, int], ...]


VARIANTS = ("straight", "general")


@cache
def patterns(spec: ElementSpec, variant: str) -> Patterns:
    """Storage patterns of ``variant`` (see ``Patterns``), found exactly for straight."""
    from symgen import closed

    if variant not in VARIANTS:
        raise ValueError(f"variant must be one of {VARIANTS}, got {variant!r}")
    n = spec.n_shape
    npairs = len(pairs(n))
    all_i4 = [(a, b) for a in range(npairs) for b in range(a, npairs)]
    if variant == "general":
        all_cij = [(k, p, m, q) for k in range(n) for p in range(k, n) for m in range(n)
                   for q in range(n)]
        return Patterns(variant, tuple(all_i4), tuple(all_i4), tuple(all_cij))
    i4 = closed.straight_tables(spec).i4
    index = pair_index(n)

    def key(k, m, p, q):
        a, b = index[(k, m)], index[(p, q)]
        return (a, b) if a <= b else (b, a)

    def both_zero(first, second):
        """The sum of two closed i4 values is zero (exactly)."""
        total = dict(i4.get(first, {}))
        for exps, value in i4.get(second, {}).items():
            total[exps] = total.get(exps, 0) + value
        return not any(total.values())

    gram = []
    upper = pairs(n)
    for a, b in all_i4:
        (k, m), (p, q) = upper[a], upper[b]
        if key(k, m, p, q) in i4 or not both_zero(key(k, p, m, q), key(k, q, m, p)):
            gram.append((a, b))
    cij = [(k, p, m, q) for k in range(n) for p in range(k, n) for m in range(n)
           for q in range(n) if key(k, m, q, p) in i4 or key(k, q, m, p) in i4]
    return Patterns(variant, tuple(key for key in all_i4 if key in i4), tuple(gram),
                    tuple(cij))


def invariant_values(
    spec: ElementSpec, pattern: Patterns, integrals: Integrals
) -> dict[str, Sequence[object]]:
    """Everything the kernels store, as flat lists in storage order.

    Keys: ``mass`` and ``k1`` (upper triangles of the n x n shape-level matrices; the full
    matrices are these times I_dim), ``gram`` (Dm), ``cij`` (c^{kp}_{mq}), ``u0``.
    Works on symbolic and numeric integrals alike.
    """
    n = spec.n_shape
    return {
        "mass": [rho * integrals.mass[k, m] for k, m in pairs(n)],
        "k1": [k1_value(spec, integrals.i2, k, m) for k, m in pairs(n)],
        "gram": [gram_value(spec, integrals.i4, a, b) for a, b in pattern.gram],
        "cij": [cij_value(spec, integrals.i4, *kpmq) for kpmq in pattern.cij],
        "u0": [strain_energy_constant(spec, integrals.volume)],
    }


# --- material laws: directional integrals per domain and the law algebra ----------------------
#
# With b = ds/dr0 expressed in the local element frame (b = ds/dx for a straight element) and
# P^a_kl = b_ka b_la (one matrix per local direction a), every invariant of a law of the
# orthotropic form (symgen/laws.py) is a combination of
#   measure  = int dV0,   pi^a_kl = int P^a_kl dV0,   psi^ab_(kl),(mn) = int P^a_kl P^b_mn dV0
# over the domain of each part.  The isotropic i4 above is sum_ab psi^ab.


@dataclass(frozen=True)
class DomainIntegrals:
    """Directional integrals of one domain: ``measure``, ``pi(a, k, l)``,
    ``psi(a, b, (k, l), (m, n))`` (symbolic or numeric; missing entries are zero)."""

    measure: object
    pi: Callable[[int, int, int], object]
    psi: Callable[[int, int, tuple[int, int], tuple[int, int]], object]


def _psi_key(a: int, b: int, kl: tuple[int, int], mn: tuple[int, int]):
    """Canonical key of psi^ab_(kl),(mn): a <= b, sorted pairs, (kl) <= (mn) when a == b."""
    from symgen.closed import psi_key

    return psi_key(a, b, kl, mn)


@cache
def straight_domain_integrals(spec: ElementSpec, domain: str) -> DomainIntegrals:
    """Closed-form directional integrals of the straight reference over ``domain`` (a
    subdomain of the element's domain): measure and pi factored, psi as canonical sums."""
    from symgen import closed

    tables = closed.domain_tables(spec, domain)
    zero = sp.Integer(0)
    pi = {key: sp.factor(closed.to_sympy(spec, value)) for key, value in tables.pi.items()}
    psi: dict = {}

    def psi_value(a, b, kl, mn):
        key = _psi_key(a, b, kl, mn)
        if key not in psi:
            value = tables.psi.get(key)
            psi[key] = zero if value is None else closed.to_sympy(spec, value)
        return psi[key]

    return DomainIntegrals(
        sp.factor(closed.to_sympy(spec, tables.measure)),
        lambda a, k, m: pi.get((a, min(k, m), max(k, m)), zero),
        psi_value)


def _law_blocks(dim: int, coefficients):
    """(normal dim x dim, shear list) of a domain's law coefficients."""
    from symgen import laws

    normal = [[0] * dim for _ in range(dim)]
    shear = []
    for (i, j), value in zip(laws.coefficient_layout(dim), coefficients, strict=True):
        if i < dim:
            normal[i][j] = normal[j][i] = value
        else:
            shear.append(value)
    return normal, shear


def _normal_part(normal, psi, first: tuple[int, int], second: tuple[int, int]) -> object:
    """sum_ab DN_ab psi^ab_(first)(second) over the nonzero entries of the normal block."""
    total = 0
    for x, row in enumerate(normal):
        for y, value in enumerate(row):
            if value != 0:
                total += value * psi(x, y, first, second)
    return total


def law_gram_value(spec: ElementSpec, parts, a: int, b: int) -> object:
    """Entry (a, b) of the gram matrix Dm of a law, from ``parts`` = [(DomainIntegrals,
    coefficients)].  Dm_ab = mu_a mu_b Dsym_klmn with, per domain,
    Dsym = 1/8 sum_ab DN_ab psi^ab_(kl)(mn)
         + 1/8 sum_shear DS (psi^ab_(km)(ln) + psi^ab_(kn)(lm) + psi^ab_(lm)(kn) + psi^ab_(ln)(km)).
    """
    from symgen import laws

    d = spec.dim
    (k, m), (p, q) = pairs(spec.n_shape)[a], pairs(spec.n_shape)[b]
    mu = (1 if k == m else 2) * (1 if p == q else 2)
    total = 0
    for integrals, coefficients in parts:
        normal, shear = _law_blocks(d, coefficients)
        psi = integrals.psi
        total += _normal_part(normal, psi, (k, m), (p, q)) / 8
        for (x, y), value in zip(laws.shear_pairs(d), shear, strict=True):
            if value != 0:
                total += value / 8 * (psi(x, y, (k, p), (m, q)) + psi(x, y, (k, q), (m, p))
                                      + psi(x, y, (m, p), (k, q)) + psi(x, y, (m, q), (k, p)))
    return mu * total


def law_cij_value(spec: ElementSpec, parts, k: int, p: int, m: int, q: int) -> object:
    """Entry c^{kp}_{mq} of a law (see ``cij_value``); per domain
    c = 1/2 sum_ab DN_ab psi^ab_(km)(pq) + sum_shear DS (psi^ab + psi^ba)_(kq)(mp),
    which for the isotropic law is exactly ``cij_value``."""
    from symgen import laws

    d = spec.dim
    total = 0
    for integrals, coefficients in parts:
        normal, shear = _law_blocks(d, coefficients)
        psi = integrals.psi
        total += _normal_part(normal, psi, (k, m), (p, q)) / 2
        for (x, y), value in zip(laws.shear_pairs(d), shear, strict=True):
            if value != 0:
                total += value * (psi(x, y, (k, q), (m, p)) + psi(y, x, (k, q), (m, p)))
    return total


def law_k1_value(spec: ElementSpec, parts, k: int, m: int) -> object:
    """Shape-level K1 of a law: -1/2 sum_a (sum_c DN_ac) pi^a_km, summed over domains."""
    total = 0
    for integrals, coefficients in parts:
        normal, _ = _law_blocks(spec.dim, coefficients)
        for x in range(spec.dim):
            total -= sum(normal[x]) * integrals.pi(x, k, m) / 2
    return total


def law_u0_value(spec: ElementSpec, parts) -> object:
    """U0 of a law (the energy of e = 0): 1/8 sum_ab DN_ab times each domain's measure."""
    total = 0
    for integrals, coefficients in parts:
        normal, _ = _law_blocks(spec.dim, coefficients)
        total += sum(sum(row) for row in normal) * integrals.measure / 8
    return total


def law_invariant_values(spec: ElementSpec, pattern: Patterns, parts, mass,
                         density) -> dict[str, Sequence[object]]:
    """What the kernels store for a law (keys as ``invariant_values``); ``mass`` is the
    shape-level int s s^T dV0 (n x n) and ``parts`` = [(DomainIntegrals, coefficients)]."""
    n = spec.n_shape
    return {
        "mass": [density * mass[k, m] for k, m in pairs(n)],
        "k1": [law_k1_value(spec, parts, k, m) for k, m in pairs(n)],
        "gram": [law_gram_value(spec, parts, a, b) for a, b in pattern.gram],
        "cij": [law_cij_value(spec, parts, *kpmq) for kpmq in pattern.cij],
        "u0": [law_u0_value(spec, parts)],
    }


def law_domains(spec: ElementSpec) -> tuple[str, ...]:
    """Subdomains of the element's domain that some applicable law integrates a part over
    (``volume`` always), in ``laws.DOMAINS`` order."""
    from symgen import laws

    used = {"volume"} | {part.domain for law in applicable_laws(spec).values()
                         for part in law.parts(spec.dim)}
    return tuple(d for d in laws.DOMAINS if d in used and d in spec.domain.subdomain_names)


def straight_law_domains(spec: ElementSpec) -> tuple[str, ...]:
    """The law domains integrated exactly (no axis of reduced integration): the laws on
    these alone share the straight storage patterns of svk (``check_law_patterns``)."""
    return tuple(d for d in law_domains(spec) if not spec.domain.reduced_axes(d))


def law_storage(spec: ElementSpec, law) -> str:
    """The storage variant of ``law``'s invariants for a straight element: ``straight`` (the
    svk patterns, closed form) when every part integrates exactly, else ``general`` (reduced
    integration fills entries that exact integration leaves zero: invariants by quadrature)."""
    exact = set(straight_law_domains(spec))
    return "straight" if all(part.domain in exact for part in law.parts(spec.dim)) \
        else "general"


def applicable_laws(spec: ElementSpec) -> dict:
    """The laws of the element's energy (``symgen.energies``) whose every part integrates over
    a subdomain the element's domain has."""
    from symgen import energies

    return energies.applicable_laws(spec)


def check_law_patterns(spec: ElementSpec) -> None:
    """Raise ValueError unless every law of the orthotropic form (any coefficients on any
    domain) is zero outside the straight storage patterns, so the straight kernels (found
    for the isotropic law) serve every law.  Exact: each generic coefficient multiplies a sum
    of closed-form integrals, checked to vanish."""
    from symgen import closed, laws

    n, d = spec.n_shape, spec.dim
    pattern = patterns(spec, "straight")
    normal = [(x, yy) for x in range(d) for yy in range(x, d)]
    tables = [closed.domain_tables(spec, domain).psi for domain in straight_law_domains(spec)]

    def vanishes(psi, terms) -> bool:
        total: dict = {}
        for a, b, kl, mn in terms:
            entry = psi.get(closed.psi_key(a, b, kl, mn))
            if entry is not None:
                total[entry[0]] = total.get(entry[0], 0) + entry[1]
        return not any(total.values())

    def groups_gram(k, m, p, q):
        for x, yy in normal:
            yield [(x, yy, (k, m), (p, q))] + ([(yy, x, (k, m), (p, q))] if x != yy else [])
        for x, yy in laws.shear_pairs(d):
            yield [(x, yy, (k, p), (m, q)), (x, yy, (k, q), (m, p)),
                   (x, yy, (m, p), (k, q)), (x, yy, (m, q), (k, p))]

    def groups_cij(k, p, m, q):
        for x, yy in normal:
            yield [(x, yy, (k, m), (p, q))] + ([(yy, x, (k, m), (p, q))] if x != yy else [])
        for x, yy in laws.shear_pairs(d):
            yield [(x, yy, (k, q), (m, p)), (yy, x, (k, q), (m, p))]

    stored = set(pattern.gram)
    npairs = len(pairs(n))
    for a in range(npairs):
        for b in range(a, npairs):
            if (a, b) in stored:
                continue
            (k, m), (p, q) = pairs(n)[a], pairs(n)[b]
            if not all(vanishes(psi, g) for psi in tables for g in groups_gram(k, m, p, q)):
                raise ValueError(f"{spec.name}: gram entry {(a, b)} of a law is outside the "
                                 "straight pattern")
    stored = set(pattern.cij)
    for kpmq in ((k, p, m, q) for k in range(n) for p in range(k, n) for m in range(n)
                 for q in range(n)):
        if kpmq not in stored and not all(vanishes(psi, g) for psi in tables
                                          for g in groups_cij(*kpmq)):
            raise ValueError(f"{spec.name}: cij entry {kpmq} of a law is outside the straight "
                             "pattern")
