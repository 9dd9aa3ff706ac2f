"""High-precision reference: direct Gauss quadrature of the St. Venant-Kirchhoff energy in mpmath
(and of the cable energy of Berzeri and Shabana for cable kinds).

Shares no code with the generator or the kernels: the shape functions of every shipped kind
are typed here from the literature (``LITERATURE``: docs/design.md section 4 for the 2-node
beams, Project Chrono's ANCF-3333 beam, ANCF-3443 plate and ANCF-3833 shell in their
normalised coordinates for the others), differentiated once by SymPy into mpmath functions,
and the energy is integrated by Gauss quadrature in 50-digit arithmetic.  What an element
states as data is read from its metadata (``generated/<kind>/element.json``): the dimension,
the domain (the span of each local axis in the geometry parameters, the thickness of a planar
element) and the Gauss orders that integrate the straight element exactly.

A kind without literature shape functions (a new element file) is integrated with the element
file's own (``symgen/elements``): the arithmetic stays independent of the invariants and the
kernels, the shape functions do not; ``shape_functions`` says which are used.
"""

from __future__ import annotations

import functools
import itertools

import mpmath as mp
import numpy as np
import sympy as sp

from runtime.kernels.kind import element_kind

mp.mp.dps = 50

#: Local coordinates and the three geometry parameters (length, height, width: a beam's
#: l, h, w, a plate's a, b, t), in which the shape functions below are written.
X, Y, Z, L, H, W = sp.symbols("x y z L H W")


def _beam_2node(dim: int) -> list[sp.Expr]:
    """docs/design.md section 4 (Shabana & Yakoub; the planar beam drops the z ones)."""
    xi = X / L
    s = [1 - 3 * xi**2 + 2 * xi**3, L * (xi - 2 * xi**2 + xi**3), Y * (1 - xi), Z * (1 - xi),
         3 * xi**2 - 2 * xi**3, L * (-(xi**2) + xi**3), Y * xi, Z * xi]
    return s if dim == 3 else [s[k] for k in (0, 1, 2, 4, 5, 6)]


def _beam_3node(dim: int) -> list[sp.Expr]:
    """Chrono 3333: nodes at xi = -1, 0, 1 (here ordered x = 0, L/2, L): N, y N, z N."""
    xi = 2 * X / L - 1
    n_end0 = (xi**2 - xi) / 2
    n_mid = 1 - xi**2
    n_end1 = (xi**2 + xi) / 2
    per = (1, Y) if dim == 2 else (1, Y, Z)
    return [f * n for n in (n_end0, n_mid, n_end1) for f in per]


def _plate() -> list[sp.Expr]:
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


def _shell_8node() -> list[sp.Expr]:
    """Chrono 3833 without r_zz (lenX = L, lenY = H, thickness W): Calc_Sxi_compact's node
    functions of corners A, B, C, D and mid-sides E, F, G, H, each carrying r and
    z r_z = (W zeta / 2) r_z."""
    u, v = 2 * X / L - 1, 2 * Y / H - 1
    z = W * (2 * Z / W) / 2
    n = [-(u - 1) * (v - 1) * (u + v + 1) / 4, (u + 1) * (v - 1) * (v - u + 1) / 4,
         (u + 1) * (v + 1) * (u + v - 1) / 4, -(u - 1) * (v + 1) * (v - u - 1) / 4,
         (u**2 - 1) * (v - 1) / 2, -(u + 1) * (v**2 - 1) / 2,
         -(u**2 - 1) * (v + 1) / 2, (u - 1) * (v**2 - 1) / 2]
    return [f for node in n for f in (node, z * node)]


def _cable() -> list[sp.Expr]:
    """Cubic Hermite functions of the ANCF cable (Berzeri and Shabana; Gerstmayr and
    Irschik): s = [1 - 3xi^2 + 2xi^3, L (xi - 2xi^2 + xi^3), 3xi^2 - 2xi^3, L (xi^3 - xi^2)]."""
    xi = X / L
    return [1 - 3 * xi**2 + 2 * xi**3, L * (xi - 2 * xi**2 + xi**3), 3 * xi**2 - 2 * xi**3,
            L * (xi**3 - xi**2)]


#: kind: its shape functions typed from the literature, node-major, in X, Y, Z, L, H, W.
LITERATURE = {
    "cable2d": _cable,
    "cable3d": _cable,
    "beam2d": lambda: _beam_2node(2),
    "beam3d": lambda: _beam_2node(3),
    "beam2d_3node": lambda: _beam_3node(2),
    "beam3d_3node": lambda: _beam_3node(3),
    "plate3d": _plate,
    "shell3d_8node": _shell_8node,
}


def shape_functions(kind: str, source: str | None = None) -> list[sp.Expr]:
    """Shape functions of ``kind`` in X, Y, Z, L, H, W: ``source`` "literature" (typed here),
    "element" (the element file's, renamed) or None (the literature's when typed)."""
    if source == "literature" or (source is None and kind in LITERATURE):
        return LITERATURE[kind]()
    from symgen.elements import get

    spec = get(kind)
    names = dict(zip(spec.coordinates, (X, Y, Z), strict=False))
    names.update(zip(spec.domain.parameters, (L, H, W), strict=True))
    return [s.xreplace(names) for s in spec.shape_functions]


def domain(kind: str, length, height, width) -> tuple[list[tuple], object]:
    """(low, high) of each local axis and the thickness of a planar element (1 otherwise) for
    the geometry parameters (length, height, width), from the element's metadata."""
    domain = element_kind(kind).domain
    geometry = (length, height, width)
    return domain.bounds(geometry), domain.thickness_of(geometry)


def volume(kind: str, length: float, height: float, width: float) -> float:
    """Volume (m^3) of the straight element: the product of the spans times the thickness."""
    spans, thickness = domain(kind, length, height, width)
    return float(np.prod([high - low for low, high in spans]) * thickness)


@functools.cache
def _gradient_function(kind: str, source: str | None):
    coords = (X, Y, Z)[: element_kind(kind).dim]
    grads = sp.Matrix([[sp.diff(s, c) for c in coords] for s in shape_functions(kind, source)])
    return sp.lambdify((X, Y, Z, L, H, W), grads, modules="mpmath")


@functools.cache
def _gauss(order: int):
    x, _ = np.polynomial.legendre.leggauss(order)
    # refine the nodes to 50 digits with mpmath's Legendre roots
    nodes = [mp.findroot(lambda t: mp.legendre(order, t), mp.mpf(xi)) for xi in x]
    weights = [2 / ((1 - t**2) * mp.diff(lambda s: mp.legendre(order, s), t) ** 2)
               for t in nodes]
    return nodes, weights


@functools.cache
def _cable_functions(kind: str, source: str | None):
    s = sp.Matrix(shape_functions(kind, source))
    return (sp.lambdify((X, L), s.diff(X), modules="mpmath"),
            sp.lambdify((X, L), s.diff(X, 2), modules="mpmath"))


def _cross(a, b) -> list:
    """a x b of mpmath vectors: one entry in 2D, three in 3D."""
    if len(a) == 2:
        return [a[0] * b[1] - a[1] * b[0]]
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def cable_energy_and_force(kind, e, length, height, width, E, orders=None, source=None,
                           bending="simple"):
    """(U, force) of a cable (a straight reference parameterised by arc length) by 50-digit
    Gauss quadrature along its length: the structural energy
    U = EA/2 int ((r_x.r_x - 1)/2)^2 dx + EI/2 int b dx, with A = h w and I = w h^3 / 12 in
    2D, h w (h^2 + w^2) / 24 in 3D (the mean of the principal moments), and ``bending``
    b = r_xx.r_xx (``simple``, Berzeri and Shabana) or |r_x x r_xx|^2 / |r_x|^4
    (``exact_curvature``, Gerstmayr and Irschik)."""
    info = element_kind(kind)
    dim = info.dim
    order = (orders or info.exact_orders)[0]
    first, second = _cable_functions(kind, source)
    E, length, height, width = (mp.mpf(v) for v in (E, length, height, width))
    area = height * width
    moment = (width * height**3 / 12 if dim == 2
              else height * width * (height**2 + width**2) / 24)
    n = len(e) // dim
    q = mp.matrix([[mp.mpf(float(e[k * dim + c])) for c in range(dim)] for k in range(n)])
    nodes, weights = _gauss(order)
    energy, grad = mp.mpf(0), mp.matrix(n, dim)
    unit = [[mp.mpf(int(i == c)) for c in range(dim)] for i in range(dim)]
    for t, w in zip(nodes, weights, strict=True):
        x, weight = (t + 1) * length / 2, w * length / 2
        s1, s2 = mp.matrix(first(x, length)), mp.matrix(second(x, length))
        r_x, r_xx = q.T * s1, q.T * s2
        eps = (sum(c**2 for c in r_x) - 1) / 2
        energy += weight * E * area * eps**2 / 2
        grad += weight * E * area * eps * s1 * r_x.T
        if bending == "simple":
            energy += weight * E * moment * sum(c**2 for c in r_xx) / 2
            grad += weight * E * moment * s2 * r_xx.T
            continue
        rx, rxx = list(r_x), list(r_xx)
        norm2 = sum(c**2 for c in rx)
        cross = _cross(rx, rxx)
        squared = sum(c**2 for c in cross)
        energy += weight * E * moment * squared / norm2**2 / 2
        for k in range(n):
            for i in range(dim):
                d_cross = [s1[k] * a + s2[k] * b for a, b in
                           zip(_cross(unit[i], rxx), _cross(rx, unit[i]), strict=True)]
                d_squared = 2 * sum(a * b for a, b in zip(cross, d_cross, strict=True))
                d_norm2 = 2 * s1[k] * rx[i]
                grad[k, i] += weight * E * moment * (d_squared / norm2**2
                                                     - 2 * squared * d_norm2 / norm2**3) / 2
    force = np.array([-float(grad[k, c]) for k in range(n) for c in range(dim)])
    return float(energy), force


def energy_and_force(kind, e, e0, length, height, width, E, nu, orders=None, source=None):
    """(U, force) of one element by 50-digit Gauss quadrature; force = -dU/de.  ``orders``:
    Gauss orders per local axis (default: the element's exact orders for a straight
    reference); ``source``: which shape functions (see ``shape_functions``).  Cables
    (element.json ``energy``) take their structural energy (``cable_energy_and_force``)."""
    info = element_kind(kind)
    if info.energy.name == "cable":
        return cable_energy_and_force(kind, e, length, height, width, E, orders, source)
    dim = info.dim
    orders = orders or info.exact_orders
    gradients = _gradient_function(kind, source)
    E, nu = mp.mpf(E), mp.mpf(nu)
    lam = E * nu / ((1 + nu) * (1 - 2 * nu))
    shear = E / (2 * (1 + nu))
    length, height, width = mp.mpf(length), mp.mpf(height), mp.mpf(width)
    n = len(e) // dim
    q = mp.matrix([[mp.mpf(float(e[k * dim + c])) for c in range(dim)] for k in range(n)])
    q0 = mp.matrix([[mp.mpf(float(e0[k * dim + c])) for c in range(dim)] for k in range(n)])
    spans, thickness = domain(kind, length, height, width)
    rules = [_gauss(o) for o in orders]
    energy = mp.mpf(0)
    grad = mp.matrix(n, dim)
    for combo in itertools.product(*[range(o) for o in orders]):
        coords, weight = [], thickness
        for axis, i in enumerate(combo):
            low, high = spans[axis]
            t, w = rules[axis][0][i], rules[axis][1][i]
            coords.append(low + (t + 1) * (high - low) / 2)
            weight *= w * (high - low) / 2
        coords += [mp.mpf(0)] * (3 - dim)
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
