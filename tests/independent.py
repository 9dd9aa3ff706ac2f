"""Independent 50-digit reference for the element kinds beyond the 2-node beams.

Shares no code with the generator or the kernels: the shape functions are typed here from
the literature (Project Chrono's ANCF-3333 beam and ANCF-3443 plate, written in their
normalised coordinates xi, eta, zeta in [-1, 1]), differentiated once by SymPy into mpmath
functions, and the St. Venant-Kirchhoff energy is integrated by Gauss quadrature in 50-digit
arithmetic (orders exact for straight references: 5 x 3 x 3 for the 3-node beams, 7 x 7 x 3
for the plate).
"""

from __future__ import annotations

import functools
import itertools

import mpmath as mp
import numpy as np
import sympy as sp

mp.mp.dps = 50

X, Y, Z, L, H, W = sp.symbols("x y z L H W")


def _beam_3node(dim: int):
    """Chrono 3333: nodes at xi = -1, 0, 1 (here ordered x = 0, L/2, L): N, y N, z N."""
    xi = 2 * X / L - 1
    n_end0 = (xi**2 - xi) / 2
    n_mid = 1 - xi**2
    n_end1 = (xi**2 + xi) / 2
    per = (1, Y) if dim == 2 else (1, Y, Z)
    return [f * n for n in (n_end0, n_mid, n_end1) for f in per]


def _plate():
    """Chrono 3443 (lenX = L, lenY = H, thickness W), corners A, B, C, D counter-clockwise."""
    u, v = 2 * X / L - 1, 2 * Y / H - 1
    zeta = 2 * Z / W  # z = W zeta / 2
    t = W
    return [
        -sp.Rational(1, 8) * (u - 1) * (v - 1) * (v**2 + v + u**2 + u - 2),
        -sp.Rational(1, 16) * L * (u + 1) * (u - 1) ** 2 * (v - 1),
        -sp.Rational(1, 16) * H * (v + 1) * (v - 1) ** 2 * (u - 1),
        -sp.Rational(1, 8) * (u - 1) * (v - 1) * (t - t - t * zeta),
        sp.Rational(1, 8) * (u + 1) * (v - 1) * (v**2 + v + u**2 - u - 2),
        -sp.Rational(1, 16) * L * (u - 1) * (u + 1) ** 2 * (v - 1),
        sp.Rational(1, 16) * H * (v + 1) * (v - 1) ** 2 * (u + 1),
        sp.Rational(1, 8) * (u + 1) * (v - 1) * (t - t - t * zeta),
        -sp.Rational(1, 8) * (u + 1) * (v + 1) * (v**2 - v + u**2 - u - 2),
        sp.Rational(1, 16) * L * (u - 1) * (u + 1) ** 2 * (v + 1),
        sp.Rational(1, 16) * H * (v - 1) * (v + 1) ** 2 * (u + 1),
        -sp.Rational(1, 8) * (u + 1) * (v + 1) * (t - t - t * zeta),
        sp.Rational(1, 8) * (u - 1) * (v + 1) * (v**2 - v + u**2 + u - 2),
        sp.Rational(1, 16) * L * (u + 1) * (u - 1) ** 2 * (v + 1),
        -sp.Rational(1, 16) * H * (v - 1) * (v + 1) ** 2 * (u - 1),
        sp.Rational(1, 8) * (u - 1) * (v + 1) * (t - t - t * zeta),
    ]


#: kind: (dim, shape functions, Gauss orders, domain spans as functions of L, H, W)
KINDS = {
    "beam2d_3node": (2, lambda: _beam_3node(2), (5, 3),
                     lambda l_, h, w: [(0, l_), (-h / 2, h / 2)]),
    "beam3d_3node": (3, lambda: _beam_3node(3), (5, 3, 3),
                     lambda l_, h, w: [(0, l_), (-h / 2, h / 2), (-w / 2, w / 2)]),
    "plate3d": (3, _plate, (7, 7, 3),
                lambda l_, h, w: [(0, l_), (0, h), (-w / 2, w / 2)]),
}


@functools.cache
def _gradient_function(kind: str):
    dim, shapes, _, _ = KINDS[kind]
    coords = (X, Y, Z)[:dim]
    grads = sp.Matrix([[sp.diff(s, c) for c in coords] for s in shapes()])
    return sp.lambdify((X, Y, Z, L, H, W), grads, modules="mpmath")


@functools.cache
def _gauss(order: int):
    x, _ = np.polynomial.legendre.leggauss(order)
    nodes = [mp.findroot(lambda t: mp.legendre(order, t), mp.mpf(xi)) for xi in x]
    weights = [2 / ((1 - t**2) * mp.diff(lambda s: mp.legendre(order, s), t) ** 2)
               for t in nodes]
    return nodes, weights


def energy_and_force(kind, e, e0, length, height, width, E, nu):
    """(U, force) of one element by 50-digit Gauss quadrature; force = -dU/de."""
    dim, _, orders, spans_of = KINDS[kind]
    gradients = _gradient_function(kind)
    E, nu = mp.mpf(E), mp.mpf(nu)
    lam = E * nu / ((1 + nu) * (1 - 2 * nu))
    shear = E / (2 * (1 + nu))
    length, height, width = mp.mpf(length), mp.mpf(height), mp.mpf(width)
    n = len(e) // dim
    q = mp.matrix([[mp.mpf(float(e[k * dim + c])) for c in range(dim)] for k in range(n)])
    q0 = mp.matrix([[mp.mpf(float(e0[k * dim + c])) for c in range(dim)] for k in range(n)])
    spans = spans_of(length, height, width)
    rules = [_gauss(o) for o in orders]
    energy = mp.mpf(0)
    grad = mp.matrix(n, dim)
    for combo in itertools.product(*[range(o) for o in orders]):
        coords, weight = [], mp.mpf(1)
        for axis, i in enumerate(combo):
            low, high = spans[axis]
            t, w = rules[axis][0][i], rules[axis][1][i]
            coords.append(low + (t + 1) * (high - low) / 2)
            weight *= w * (high - low) / 2
        if dim == 2:
            weight *= width
            coords.append(mp.mpf(0))
        ds = mp.matrix(gradients(*coords, length, height, width))
        j0 = q0.T * ds
        b = ds * mp.inverse(j0)
        f = q.T * b
        strain = (f.T * f - mp.eye(dim)) / 2
        trace = sum(strain[i, i] for i in range(dim))
        wdet = weight * mp.det(j0)
        energy += wdet * (lam / 2 * trace**2 + shear * sum(x**2 for x in strain))
        stress = lam * trace * mp.eye(dim) + 2 * shear * strain
        grad += wdet * (b * stress * f.T)
    force = np.array([-float(grad[k, c]) for k in range(n) for c in range(dim)])
    return float(energy), force
