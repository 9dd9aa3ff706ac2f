"""The exact large deflection of a cantilever under a fixed-direction tip load (the
inextensible, unshearable elastica), computed two independent ways, and Mattiasson's table.

A cantilever of length L along x, clamped at s = 0, with a tip force P perpendicular to the
undeformed beam; the tangent angle theta(s) obeys EI theta'' + P cos(theta) = 0,
theta(0) = 0, theta'(L) = 0.  With alpha = P L^2 / EI and lengths in units of L:

* ``by_quadrature``: the first integral theta'^2 = 2 alpha (sin theta_L - sin theta) gives
  sqrt(2 alpha) = int_0^theta_L dtheta / sqrt(sin theta_L - sin theta) for the tip angle
  theta_L (found by root bracketing), x_L = sqrt(2 sin theta_L / alpha) and
  y_L = int_0^theta_L sin theta dtheta / sqrt(2 alpha (sin theta_L - sin theta)), the square-root
  singularity integrated exactly by QUADPACK's algebraic weight;
* ``by_bvp``: the boundary-value problem x' = cos theta, y' = sin theta, theta' = kappa,
  kappa' = -alpha cos theta solved by collocation (``scipy.integrate.solve_bvp``).

Both give (u, w): the tip's horizontal shortening and its deflection along the load, over L.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import quad, solve_bvp
from scipy.optimize import brentq

#: Mattiasson (1981), Int. J. Numer. Meth. Eng. 17, table of the cantilever under a tip load:
#: P L^2 / EI -> (u / L horizontal shortening, w / L deflection), 5 decimals.
MATTIASSON = {1.0: (0.05643, 0.30172), 2.0: (0.16064, 0.49346), 5.0: (0.38763, 0.71379),
              10.0: (0.55500, 0.81061)}


def _singular(theta_l: float, numerator) -> float:
    """int_0^theta_L numerator(theta) / sqrt(sin theta_L - sin theta) dtheta, the factor
    (theta_L - theta)^(-1/2) taken by the quadrature weight."""
    def smooth(theta: float) -> float:
        d = theta_l - theta
        # sin theta_L - sin theta = 2 cos((theta_L + theta) / 2) sin(d / 2) = d * this
        rest = math.cos(0.5 * (theta_l + theta)) * np.sinc(d / (2.0 * math.pi))
        return numerator(theta) / math.sqrt(rest)

    value, _ = quad(smooth, 0.0, theta_l, weight="alg", wvar=(0.0, -0.5), epsabs=0.0,
                    epsrel=1e-12, limit=200)
    return value


def by_quadrature(alpha: float) -> tuple[float, float]:
    """(u / L, w / L) of the elastica for alpha = P L^2 / EI > 0, from its first integral."""
    if alpha <= 0:
        raise ValueError(f"alpha: expected P L^2 / EI > 0, got {alpha!r}")
    target = math.sqrt(2.0 * alpha)
    theta_l = brentq(lambda t: _singular(t, lambda _: 1.0) - target, 1e-8,
                     0.5 * math.pi - 1e-6, xtol=1e-15, rtol=1e-15)
    x_l = math.sqrt(2.0 * math.sin(theta_l) / alpha)
    y_l = _singular(theta_l, math.sin) / target
    return 1.0 - x_l, y_l


def by_bvp(alpha: float, nodes: int = 200) -> tuple[float, float]:
    """(u / L, w / L) of the elastica for alpha = P L^2 / EI > 0, by collocation."""
    def rhs(s, z):
        return np.vstack([np.cos(z[2]), np.sin(z[2]), z[3], -alpha * np.cos(z[2])])

    def ends(a, b):
        return np.array([a[0], a[1], a[2], b[3]])

    s = np.linspace(0.0, 1.0, nodes)
    guess = np.zeros((4, s.size))
    guess[0] = s
    solution = solve_bvp(rhs, ends, s, guess, tol=1e-10, max_nodes=100_000)
    if not solution.success:
        raise RuntimeError(f"elastica BVP for alpha = {alpha:g}: {solution.message}")
    x_l, y_l = solution.sol(1.0)[:2]
    return 1.0 - float(x_l), float(y_l)
