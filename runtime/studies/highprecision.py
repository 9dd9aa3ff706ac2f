"""High-precision reference: direct Gauss quadrature of the St. Venant-Kirchhoff energy in mpmath.

Shares no code with the generated kernels: shape functions are written out here from
DESIGN.md section 3, and every operation runs in 50-digit arithmetic.
"""

from __future__ import annotations

import mpmath as mp
import numpy as np

mp.mp.dps = 50


def shape_gradients(kind: str, x, y, z, length):
    """ds_k/d(x, y[, z]) for the beams of DESIGN.md section 3, as mpmath matrices."""
    xi = x / length
    d1 = [(-6 * xi + 6 * xi**2) / length, 1 - 4 * xi + 3 * xi**2, -y / length, -z / length,
          (6 * xi - 6 * xi**2) / length, -2 * xi + 3 * xi**2, y / length, z / length]
    dy = [0, 0, 1 - xi, 0, 0, 0, xi, 0]
    dz = [0, 0, 0, 1 - xi, 0, 0, 0, xi]
    if kind == "beam3d":
        return mp.matrix([[d1[k], dy[k], dz[k]] for k in range(8)])
    keep = [0, 1, 2, 4, 5, 6]
    return mp.matrix([[d1[k], dy[k]] for k in keep])


def _gauss(order):
    x, w = np.polynomial.legendre.leggauss(order)
    # refine the nodes to 50 digits with mpmath's Legendre roots
    nodes = [mp.findroot(lambda t: mp.legendre(order, t), mp.mpf(xi)) for xi in x]
    weights = [2 / ((1 - t**2) * mp.diff(lambda s: mp.legendre(order, s), t) ** 2)
               for t in nodes]
    return nodes, weights


def energy_and_force(kind, e, e0, length, height, width, E, nu, orders=None):
    """(U, force) of one element by 50-digit Gauss quadrature; force = -dU/de."""
    dim = 3 if kind == "beam3d" else 2
    orders = orders or ((5, 3, 3) if dim == 3 else (5, 3))
    E, nu = mp.mpf(E), mp.mpf(nu)
    lam = E * nu / ((1 + nu) * (1 - 2 * nu))
    shear = E / (2 * (1 + nu))
    length, height, width = mp.mpf(length), mp.mpf(height), mp.mpf(width)
    n = len(e) // dim
    q = mp.matrix([[mp.mpf(float(e[k * dim + c])) for c in range(dim)] for k in range(n)])
    q0 = mp.matrix([[mp.mpf(float(e0[k * dim + c])) for c in range(dim)] for k in range(n)])
    spans = [(0, length), (-height / 2, height / 2), (-width / 2, width / 2)][:dim]
    rules = [_gauss(o) for o in orders]
    energy = mp.mpf(0)
    grad = mp.matrix(n, dim)
    import itertools
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
        ds = shape_gradients(kind, coords[0], coords[1], coords[2], length)
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
