"""Exact integrals of the straight reference at the shape-function level, fast.

With the domain's unit box (``x_a = s_a u_a``, symgen/domains.py) every shipped shape
function factors as ``s_k = c_k(params) phi_k(u)``: a monomial in the domain parameters
times a polynomial with rational coefficients in the unit coordinates.  Then every gradient
``ds_k/dx_a = (c_k / s_a) dphi_k/du_a``, every ``P^a_kl = b_ka b_la`` and every integral of a
product of them is *one* parameter monomial times a rational number, and the rational numbers
are bilinear forms of coefficient vectors with a moment matrix of the unit box:

    psi^ab_(kl)(mn) = int P^a_kl P^b_mn dV = monomial * (A_a M A_b^T)_(kl),(mn)

computed once per direction pair as exact integer matrix products (no symbolic integration,
no coordinate-level matrices: the plate's 136 x 136 pair tensor takes seconds).

A *closed value* is a dict ``{parameter exponents: Fraction}`` (a sum of monomials);
``to_sympy`` turns one into the canonical SymPy sum, which is what the older term-by-term
symbolic integration produced, so small elements keep their emitted code byte for byte.
"""

from __future__ import annotations

import operator
from dataclasses import dataclass
from fractions import Fraction
from functools import cache
from math import lcm

import numpy as np
import sympy as sp

from symgen.element import ElementSpec

Closed = dict  # {tuple of parameter exponents: Fraction}


def pairs(n: int) -> list[tuple[int, int]]:
    return [(k, m) for k in range(n) for m in range(k, n)]


@dataclass(frozen=True)
class Factored:
    """s_k = params^exps[k] * phi[k](u); grads[k][a] = (exponents, {powers: Fraction}) of
    ds_k/dx_a (empty polynomial when zero)."""

    exps: tuple[tuple[int, ...], ...]
    phi: tuple[dict, ...]
    grads: tuple[tuple[tuple[tuple[int, ...], dict], ...], ...]


def _add(a, b):
    return tuple(map(operator.add, a, b))


def _exact_dot(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """The product of two integer matrices, exact: in int64 where no sum can overflow (every
    term and partial sum bounded by max|x| max|y| times the inner size), else in Python
    integers (object arrays)."""
    if not x.size or not y.size:
        return np.zeros((x.shape[0], y.shape[1]), dtype=np.int64)
    bound = int(np.abs(x).max()) * int(np.abs(y).max()) * x.shape[1]
    if bound < 2**63:
        return x.astype(np.int64).dot(y.astype(np.int64))
    return x.astype(object).dot(y.astype(object))


@cache
def factored(spec: ElementSpec) -> Factored | None:
    """The factored shape functions, or None when one does not factor (then the generator
    falls back to term-by-term symbolic integration)."""
    domain = spec.domain
    unit = sp.symbols(f"u0:{spec.dim}", real=True)
    params = domain.parameters
    subs = domain.unit_substitution(unit)
    exps_all, phis = [], []
    for s in spec.shape_functions:
        expr = sp.expand(s.subs(subs, simultaneous=True))
        exps, poly = None, {}
        for term in sp.Add.make_args(expr):
            if term == 0:
                continue
            coeff, rest = term.as_coeff_Mul()
            if not coeff.is_Rational:
                return None
            powers = {k: v for k, v in rest.as_powers_dict().items() if k != 1}
            if set(powers) - set(unit) - set(params) or not all(
                    v.is_Integer for v in powers.values()):
                return None
            e_unit = tuple(int(powers.get(u, 0)) for u in unit)
            e_par = tuple(int(powers.get(p, 0)) for p in params)
            if min(e_unit) < 0 or (exps is not None and exps != e_par):
                return None
            exps = e_par
            poly[e_unit] = poly.get(e_unit, 0) + Fraction(int(coeff.p), int(coeff.q))
        poly = {k: v for k, v in poly.items() if v}
        exps_all.append(exps or (0,) * len(params))
        phis.append(poly)
    grads = []
    for exps, poly in zip(exps_all, phis, strict=True):
        row = []
        for a, axis in enumerate(domain.axes):
            d = {}
            for powers, c in poly.items():
                if powers[a]:
                    lowered = tuple(p - (i == a) for i, p in enumerate(powers))
                    d[lowered] = d.get(lowered, 0) + c * powers[a]
            scale = tuple(-(p == axis.scale) for p in params)
            row.append((_add(exps, scale), {k: v for k, v in d.items() if v}))
        grads.append(tuple(row))
    return Factored(tuple(exps_all), tuple(phis), tuple(grads))


def _product(p: dict, q: dict) -> dict:
    out: dict = {}
    for a, x in p.items():
        for b, y in q.items():
            key = _add(a, b)
            out[key] = out.get(key, 0) + x * y
    return {k: v for k, v in out.items() if v}


def _measure(spec: ElementSpec) -> tuple[int, ...]:
    """Parameter exponents of dV on the unit box: every axis scale and the thickness."""
    domain = spec.domain
    exps = [0] * 3
    for axis in domain.axes:
        exps[domain.parameters.index(axis.scale)] += 1
    if domain.thickness is not None:
        exps[domain.parameters.index(domain.thickness)] += 1
    return tuple(exps)


def _integrate(spec: ElementSpec, poly: dict, subdomain: str) -> Fraction:
    domain = spec.domain
    return sum((c * domain.unit_moment(powers, subdomain) for powers, c in poly.items()),
               Fraction(0)) * domain.fixed_extent(subdomain)


def psi_key(a: int, b: int, kl: tuple[int, int], mn: tuple[int, int]):
    """Canonical key of psi^ab_(kl),(mn): a <= b, sorted pairs, (kl) <= (mn) when a == b."""
    kl, mn = tuple(sorted(kl)), tuple(sorted(mn))
    if a > b:
        a, b, kl, mn = b, a, mn, kl
    if a == b and mn < kl:
        kl, mn = mn, kl
    return a, b, kl, mn


@dataclass(frozen=True)
class DomainTables:
    """Exact directional integrals of one subdomain: ``measure`` (closed), ``pi[(a, k, l)]``
    and ``psi[canonical key]`` as (exponents, Fraction), nonzero entries only."""

    measure: Closed
    pi: dict
    psi: dict


def _direction_polys(spec: ElementSpec, f: Factored):
    """Per direction a: {(k, l): (exponents, poly)} of the nonzero P^a_kl, k <= l."""
    out = []
    for a in range(spec.dim):
        table = {}
        for k, m in pairs(spec.n_shape):
            (ek, gk), (em, gm) = f.grads[k][a], f.grads[m][a]
            if gk and gm:
                table[(k, m)] = (_add(ek, em), _product(gk, gm))
        out.append(table)
    return out


@cache
def domain_tables(spec: ElementSpec, subdomain: str) -> DomainTables:
    """Exact ``measure``, ``pi`` and ``psi`` of the straight reference over ``subdomain``."""
    f = factored(spec)
    if f is None:
        raise ValueError(f"{spec.name}: shape functions do not factor into a parameter "
                         "monomial times a unit-box polynomial")
    domain = spec.domain
    measure = _measure(spec)
    extent = domain.fixed_extent(subdomain)
    directions = _direction_polys(spec, f)
    pi = {}
    for a, table in enumerate(directions):
        for kl, (exps, poly) in table.items():
            value = _integrate(spec, poly, subdomain)
            if value:
                pi[(a, *kl)] = (_add(exps, measure), value)
    # bilinear forms with the moment matrix, in exact integers
    basis = sorted({powers for table in directions for _, poly in table.values()
                    for powers in poly})
    index = {powers: i for i, powers in enumerate(basis)}
    moments = [[domain.unit_moment(_add(p, q), subdomain) for q in basis] for p in basis]
    den_m = lcm(*(m.denominator for row in moments for m in row)) if basis else 1
    mom = np.array([[int(m * den_m) for m in row] for row in moments], dtype=object)
    mats, keys, dens = [], [], []
    for table in directions:
        keys.append(list(table))
        den = lcm(*(c.denominator for _, poly in table.values() for c in poly.values()), 1)
        mat = np.zeros((len(table), len(basis)), dtype=object)
        for row, (_, poly) in enumerate(table.values()):
            for powers, c in poly.items():
                mat[row, index[powers]] = int(c * den)
        mats.append(mat)
        dens.append(den)
    psi = {}
    for a in range(spec.dim):
        if not keys[a]:
            continue
        left = _exact_dot(mats[a], mom)
        row_exps = [_add(directions[a][kl][0], measure) for kl in keys[a]]
        for b in range(a, spec.dim):
            if not keys[b]:
                continue
            values = _exact_dot(left, mats[b].T)
            if a == b:  # symmetric: each canonical key (psi_key) once, at kl <= mn
                values = np.triu(values)
            scale = Fraction(1, dens[a] * dens[b] * den_m) * extent
            rows, cols = np.nonzero(values)
            for i, j, value in zip(rows.tolist(), cols.tolist(), values[rows, cols].tolist(),
                                   strict=True):
                mn = keys[b][j]
                psi[(a, b, keys[a][i], mn)] = (_add(row_exps[i], directions[b][mn][0]),
                                               Fraction(value * scale.numerator,
                                                        scale.denominator))
    volume = domain.unit_moment((0,) * spec.dim, subdomain) * extent
    return DomainTables({measure: volume}, pi, psi)


@dataclass(frozen=True)
class StraightTables:
    """Exact integrals of the isotropic path: ``volume`` (closed), ``mass[(k, l)]``,
    ``i2[(k, l)]`` (k <= l) and ``i4[(a, b)]`` (quad_key order) as closed values (nonzero
    entries only)."""

    volume: Closed
    mass: dict
    i2: dict
    i4: dict


def _accumulate(target: dict, key, exps, value) -> None:
    entry = target.setdefault(key, {})
    total = entry[exps] + value if exps in entry else value
    if total:
        entry[exps] = total
    else:
        entry.pop(exps, None)
        if not entry:
            del target[key]


@cache
def straight_tables(spec: ElementSpec) -> StraightTables:
    """Volume, mass, int P and int P P of the straight reference, exact."""
    f = factored(spec)
    volume_tables = domain_tables(spec, "volume")
    n = spec.n_shape
    measure = _measure(spec)
    mass = {}
    for k, m in pairs(n):
        poly = _product(f.phi[k], f.phi[m])
        value = _integrate(spec, poly, "volume")
        mass[(k, m)] = {_add(_add(f.exps[k], f.exps[m]), measure): value} if value else {}
    i2: dict = {}
    for (_, k, m), (exps, value) in volume_tables.pi.items():
        _accumulate(i2, (k, m), exps, value)
    index = {km: i for i, km in enumerate(pairs(n))}
    i4: dict = {}
    for (a, b, kl, mn), (exps, value) in volume_tables.psi.items():
        # int P_kl P_mn = sum_xy psi^xy_(kl)(mn); for a < b the key (a, b, kl, mn) is the
        # xy = ab term and (a, b, mn, kl) the xy = ba one, the same key when kl == mn
        i, j = index[kl], index[mn]
        _accumulate(i4, (min(i, j), max(i, j)), exps,
                    2 * value if a != b and kl == mn else value)
    return StraightTables(volume_tables.measure, mass, i2, i4)


def monomial(spec: ElementSpec, exps: tuple[int, ...]) -> sp.Expr:
    out = sp.Integer(1)
    for p, e in zip(spec.domain.parameters, exps, strict=True):
        out *= p**e
    return out


def to_sympy(spec: ElementSpec, value) -> sp.Expr:
    """A closed value (dict) or one (exponents, Fraction) term as a canonical SymPy sum."""
    if isinstance(value, tuple):
        value = {value[0]: value[1]}
    return sp.Add(*[sp.Rational(c.numerator, c.denominator) * monomial(spec, exps)
                    for exps, c in value.items()])
