"""Reference domains of elements: symbols, bounds, exact integration, Gauss rules.

A domain is a box in local coordinates.  Each axis ``x_a`` spans ``[low_a s_a, high_a s_a]``
with ``s_a`` a geometric parameter (a length) and ``low_a, high_a`` rational numbers, so that
``x_a = s_a u_a`` maps the *unit box* ``u_a in [low_a, high_a]`` onto it.  A 2D domain may
have a ``thickness`` parameter that scales every area into a volume.

Named *subdomains* are what material-law parts integrate over (symgen/laws.py):

* ``volume``: the whole box (times the thickness in 2D);
* a lower-dimensional part fixes some axes at a unit value (the beam ``axis``: y = z = 0;
  the plate ``midsurface``: z = 0); its measure is the integral over the free axes times the
  extents of the fixed ones (and the thickness in 2D), e.g. ``h w int_0^l f(x, 0, 0) dx``;
* an axis of a subdomain whose value is the name of a rule of ``AXIS_RULES`` is integrated
  by that rule instead of exactly (*reduced integration*, the beam's ``volume_gauss2``,
  ``volume_lobatto2``, ``axis_lobatto2``: x by the 2-point Gauss-Legendre rule, or by the
  2-point Gauss-Lobatto rule at the ends x = 0, l; the plate's ``volume_gauss2x2``: x and y
  by the 2-point Gauss rule).  The rules are symmetric, so every moment
  of a monomial is rational and the closed forms stay exact.

Everything an element derives (invariants, kernels, reference geometry, quadrature tables)
reads the domain; nothing else in the generator knows which box an element has.

Shipped domains: ``beam(dim)`` (x in [0, l], y in [-h/2, h/2], z in [-w/2, w/2]; in 2D w is
the thickness), ``plate()`` (x in [0, a], y in [0, b], z in [-t/2, t/2]) and ``box()`` (x,
y, z in [0, a] x [0, b] x [0, c], solid elements).
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from functools import cached_property

import numpy as np
import sympy as sp

#: Local coordinates of every domain, in axis order.
x, y, z = sp.symbols("x y z", real=True)
LOCAL = (x, y, z)
#: Letters of the local axes in nodal vector names (``r_<letters>``).
AXIS_LETTERS = "xyz"
#: Rules of reduced integration of a subdomain axis: name -> (points, weights) on [-1, 1].
AXIS_RULES = {"gauss2": ((-1 / sp.sqrt(3), 1 / sp.sqrt(3)), (1, 1)),
              "lobatto2": ((-1, 1), (1, 1))}


@dataclass(frozen=True)
class Axis:
    """One axis of a box: ``coordinate`` in ``[low * scale, high * scale]``."""

    coordinate: sp.Symbol
    scale: sp.Symbol
    low: sp.Rational
    high: sp.Rational

    @property
    def extent(self) -> sp.Rational:
        """``high - low``: the length of the axis in units of ``scale``."""
        return self.high - self.low


@dataclass(frozen=True)
class Domain:
    """A box domain (see the module docstring).

    name: ``beam`` or ``plate`` (or any new one); axes: one ``Axis`` per dimension;
    parameters: the geometric parameters in the order the runtime passes them (``Element``'s
    ``length, height, width``: the sizes along local x, y, z, or the thickness in 2D), with
    ``labels`` for messages; thickness: 2D only, the parameter that scales areas;
    subdomains: ``{name: ((axis, unit value), ...)}`` of the axes each one fixes (``volume``,
    fixing none, is always there); a value naming a rule of ``AXIS_RULES`` integrates that
    axis by that rule instead.
    """

    name: str
    axes: tuple[Axis, ...]
    parameters: tuple[sp.Symbol, ...]
    labels: tuple[str, ...]
    thickness: sp.Symbol | None = None
    subdomains: tuple = ()

    def __post_init__(self) -> None:
        if len(self.axes) not in (2, 3):
            raise ValueError(f"domain {self.name!r}: expected 2 or 3 axes")
        if (self.thickness is not None) != (len(self.axes) == 2):
            raise ValueError(f"domain {self.name!r}: a thickness exactly when 2D")
        used = {a.scale for a in self.axes} | ({self.thickness} - {None})
        if used != set(self.parameters) or len(self.parameters) != 3:
            raise ValueError(f"domain {self.name!r}: the 3 parameters must be the axis scales "
                             "(and the thickness in 2D)")
        subdomains = dict(self.subdomains)
        for name, fixed in subdomains.items():
            for axis, value in fixed:
                a = self.axes[axis]
                if value not in AXIS_RULES and not a.low <= value <= a.high:
                    raise ValueError(f"domain {self.name!r}, subdomain {name!r}: unit value "
                                     f"{value} outside axis {axis}")
        subdomains = {"volume": (), **subdomains}
        object.__setattr__(self, "subdomains", tuple(subdomains.items()))

    @property
    def subdomain_names(self) -> tuple[str, ...]:
        return tuple(name for name, _ in self.subdomains)

    def fixed(self, subdomain: str) -> tuple:
        """((axis, unit value), ...) of the axes ``subdomain`` fixes."""
        return tuple((axis, value) for axis, value in dict(self.subdomains)[subdomain]
                     if value not in AXIS_RULES)

    def reduced_axes(self, subdomain: str) -> dict[int, str]:
        """{axis: rule name} of the axes ``subdomain`` integrates by a rule of ``AXIS_RULES``."""
        return {axis: value for axis, value in dict(self.subdomains)[subdomain]
                if value in AXIS_RULES}

    def rule_moment(self, axis: int, rule: str, power: int) -> sp.Rational:
        """The ``rule`` of ``AXIS_RULES`` on the unit ``axis`` applied to ``u^power``:
        ``sum_i w_i (high - low) / 2 u_i^power`` at the mapped points, exactly (rational)."""
        a = self.axes[axis]
        points, weights = AXIS_RULES[rule]
        return sp.nsimplify(sp.expand(sum(
            w * a.extent / 2 * (a.low + (t + 1) * a.extent / 2) ** power
            for t, w in zip(points, weights, strict=True))), rational=True)

    @property
    def dim(self) -> int:
        return len(self.axes)

    @property
    def coordinates(self) -> tuple[sp.Symbol, ...]:
        return tuple(a.coordinate for a in self.axes)

    def bounds(self) -> list[tuple[sp.Symbol, sp.Expr, sp.Expr]]:
        """(coordinate, low, high) of every axis, in the parameters."""
        return [(a.coordinate, a.low * a.scale, a.high * a.scale) for a in self.axes]

    def unit_substitution(self, unit: tuple[sp.Symbol, ...]) -> dict:
        """{coordinate: scale * unit coordinate}."""
        return {a.coordinate: a.scale * u for a, u in zip(self.axes, unit, strict=False)}

    def fixed_factor(self, subdomain: str) -> sp.Expr:
        """Extent of the fixed axes of ``subdomain`` (times the thickness in 2D)."""
        factor = sp.Integer(1) if self.thickness is None else self.thickness
        for axis, _ in self.fixed(subdomain):
            factor *= self.axes[axis].scale * self.axes[axis].extent
        return factor

    # --- exact integration of polynomials ------------------------------------------------

    def integrate(self, expr, subdomain: str = "volume") -> sp.Expr:
        """Exact integral of a polynomial in the local coordinates over ``subdomain``, as a
        canonical sum of terms (rational times a monomial in the parameters)."""
        return self.integrate_poly(sp.Poly(sp.expand(expr), *self.coordinates), subdomain)

    def integrate_poly(self, poly: sp.Poly, subdomain: str = "volume") -> sp.Expr:
        """As ``integrate`` for a ``Poly`` in the local coordinates."""
        fixed = dict(self.fixed(subdomain))
        reduced = self.reduced_axes(subdomain)
        total = sp.Integer(0)
        for powers, coeff in poly.terms():
            term = coeff
            for axis, (a, power) in enumerate(zip(self.axes, powers, strict=True)):
                if axis in reduced:
                    term *= self.rule_moment(axis, reduced[axis], power) * a.scale ** (power + 1)
                    continue
                if axis in fixed:
                    value = fixed[axis]
                    if power and value == 0:
                        term = 0
                        break
                    term *= (value * a.scale) ** power * a.scale * a.extent
                    continue
                moment = (a.high ** (power + 1) - a.low ** (power + 1)) / (power + 1)
                if moment == 0:
                    term = 0
                    break
                term *= moment * a.scale ** (power + 1)
            if term != 0 and self.thickness is not None:
                term *= self.thickness
            total += term
        return total

    def unit_moment(self, powers: tuple[int, ...], subdomain: str = "volume") -> Fraction:
        """Integral of the unit-box monomial ``u^powers`` over ``subdomain`` of the unit box
        (fixed axes at their unit value, free axes integrated; no extents)."""
        fixed = dict(self.fixed(subdomain))
        reduced = self.reduced_axes(subdomain)
        value = Fraction(1)
        for axis, (a, power) in enumerate(zip(self.axes, powers, strict=True)):
            if axis in reduced:
                moment = sp.Rational(self.rule_moment(axis, reduced[axis], power))
                value *= Fraction(int(moment.p), int(moment.q))
            elif axis in fixed:
                value *= Fraction(fixed[axis]) ** power
            else:
                low, high = Fraction(a.low), Fraction(a.high)
                value *= (high ** (power + 1) - low ** (power + 1)) / (power + 1)
        return value

    def measure_monomial(self, subdomain: str = "volume") -> dict[sp.Symbol, int]:
        """Exponents of the parameters in dV of ``subdomain`` for the unit box: the free axes'
        scales (dx = s du), the fixed axes' scales (their extent) and the thickness."""
        exponents = dict.fromkeys(self.parameters, 0)
        for a in self.axes:
            exponents[a.scale] += 1
        if self.thickness is not None:
            exponents[self.thickness] += 1
        return exponents

    def fixed_extent(self, subdomain: str) -> Fraction:
        """The rational part of the fixed axes' extents of ``subdomain``."""
        value = Fraction(1)
        for axis, _ in self.fixed(subdomain):
            value *= Fraction(self.axes[axis].extent)
        return value

    # --- Gauss rules (numeric, for the runtime and the exactness check) --------------------

    def exact_orders(self, degrees: tuple[int, ...]) -> tuple[int, ...]:
        """Gauss-Legendre orders that integrate polynomials of per-axis ``degrees`` exactly."""
        return tuple(d // 2 + 1 for d in degrees)

    def gauss_rule(self, parameters, orders, subdomain: str = "volume"):
        """Tensor Gauss-Legendre points (p, dim) and weights (p,) over ``subdomain`` for
        numeric ``parameters`` (in ``self.parameters`` order); weights include the fixed
        extents and the thickness."""
        values = dict(zip(self.parameters, (float(v) for v in parameters), strict=True))
        fixed = dict(self.fixed(subdomain))
        reduced = self.reduced_axes(subdomain)
        axes, weights = [], []
        factor = values[self.thickness] if self.thickness is not None else 1.0
        for i, (a, order) in enumerate(zip(self.axes, orders, strict=True)):
            scale = values[a.scale]
            if i in fixed:
                axes.append(np.array([float(fixed[i]) * scale]))
                weights.append(np.array([1.0]))
                factor *= float(a.extent) * scale
                continue
            t, w = (np.array(AXIS_RULES[reduced[i]], dtype=float) if i in reduced
                    else np.polynomial.legendre.leggauss(order))
            low, high = float(a.low) * scale, float(a.high) * scale
            axes.append(low + (t + 1) * (high - low) / 2)
            weights.append(w * (high - low) / 2)
        points = np.stack([g.ravel() for g in np.meshgrid(*axes, indexing="ij")], axis=1)
        weight = np.prod([g.ravel() for g in np.meshgrid(*weights, indexing="ij")], axis=0)
        return points, weight * factor

    @cached_property
    def metadata(self) -> dict:
        """What element.json records about the domain (the runtime never rebuilds it)."""
        return {
            "name": self.name,
            "parameters": [str(p) for p in self.parameters],
            "labels": list(self.labels),
            "axes": [{"coordinate": str(a.coordinate), "scale": str(a.scale),
                      "low": [int(a.low.p), int(a.low.q)],
                      "high": [int(a.high.p), int(a.high.q)]} for a in self.axes],
            "thickness": None if self.thickness is None else str(self.thickness),
            "subdomains": {name: [[axis, v if v in AXIS_RULES else
                                   [int(sp.Rational(v).p), int(sp.Rational(v).q)]]
                                  for axis, v in fixed]
                           for name, fixed in self.subdomains},
        }


# --- shipped domains ---------------------------------------------------------------------------

#: Beam box parameters: length (x), height (y), width (z; the thickness in 2D).
length, height, width = sp.symbols("l h w", positive=True)
#: Plate box parameters: sides a (x) and b (y), thickness t (z).
side_a, side_b, thickness = sp.symbols("a b t", positive=True)

#: Box parameters of solid elements: sides a (x), b (y) and c (z).
side_c = sp.symbols("c", positive=True)

HALF = sp.Rational(1, 2)


def beam(dim: int) -> Domain:
    """x in [0, l], y in [-h/2, h/2] (, z in [-w/2, w/2]; in 2D w is the thickness); the
    ``axis`` subdomain is y = z = 0 (measure: h w times the length); the reduced ones of
    ``beam_reduced`` integrate x by 2-point rules."""
    axes = [Axis(x, length, sp.Integer(0), sp.Integer(1)), Axis(y, height, -HALF, HALF)]
    if dim == 3:
        axes.append(Axis(z, width, -HALF, HALF))
    fixed = tuple((axis, sp.Integer(0)) for axis in range(1, dim))
    return Domain("beam", tuple(axes), (length, height, width), ("length", "height", "width"),
                  width if dim == 2 else None, (("axis", fixed), *beam_reduced(fixed)))


def beam_reduced(axis_fixed: tuple) -> tuple:
    """The beam subdomains with x integrated by a 2-point rule: ``volume_gauss2`` (Gauss-
    Legendre), ``volume_lobatto2`` and ``axis_lobatto2`` (Gauss-Lobatto: the ends x = 0, l;
    the axis fixes ``axis_fixed``, y = z = 0)."""
    return (("volume_gauss2", ((0, "gauss2"),)), ("volume_lobatto2", ((0, "lobatto2"),)),
            ("axis_lobatto2", ((0, "lobatto2"), *axis_fixed)))


def plate() -> Domain:
    """x in [0, a], y in [0, b], z in [-t/2, t/2]; the ``midsurface`` subdomain is z = 0, the
    ``volume_gauss2x2`` one the volume with x and y (the surface) by the 2-point Gauss rule
    and z by the volume's order (the reduced surface integration of shells)."""
    axes = (Axis(x, side_a, sp.Integer(0), sp.Integer(1)),
            Axis(y, side_b, sp.Integer(0), sp.Integer(1)),
            Axis(z, thickness, -HALF, HALF))
    return Domain("plate", axes, (side_a, side_b, thickness), ("length", "height", "width"),
                  None, (("midsurface", ((2, sp.Integer(0)),)),
                         ("volume_gauss2x2", ((0, "gauss2"), (1, "gauss2")))))


def box() -> Domain:
    """x in [0, a], y in [0, b], z in [0, c] (a solid: no lower-dimensional subdomain)."""
    axes = tuple(Axis(coordinate, scale, sp.Integer(0), sp.Integer(1))
                 for coordinate, scale in zip(LOCAL, (side_a, side_b, side_c), strict=True))
    return Domain("box", axes, (side_a, side_b, side_c), ("length", "height", "width"))
