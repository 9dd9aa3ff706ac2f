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

A kind without literature shape functions (a new element file) takes shape functions
**derived from its node layout** (``derived``): the nodes and nodal vectors of its metadata
state the interpolation conditions (``r`` its value at a node, ``r_x`` its x-derivative,
``r_zz`` its second z-derivative, ...), and the functions that meet them are solved for in
the polynomial space the element file's functions span.  That confirms the element file's
coefficients (they must be those functions) without a second hand-typed entry; only the
space comes from the element file.  ``shape_functions`` says which are used.
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


def _shell_3833() -> list[sp.Expr]:
    """Chrono 3833 (lenX = L, lenY = H, one layer of thickness W on the mid-surface):
    Calc_Sxi_compact, whose node functions carry the factor f = T - 2 zoffset - t - t zeta
    (T = t = W, zoffset = 0) for r_z and f^2 for r_zz: per node n, -n f / 2, n f^2 / 8."""
    u, v = 2 * X / L - 1, 2 * Y / H - 1
    zeta = 2 * Z / W
    f = W - 2 * 0 - W - W * zeta
    n = [-(u - 1) * (v - 1) * (v + u + 1) / 4, (u + 1) * (v - 1) * (v - u + 1) / 4,
         (u + 1) * (v + 1) * (v + u - 1) / 4, -(u - 1) * (v + 1) * (v - u - 1) / 4,
         (u - 1) * (u + 1) * (v - 1) / 2, -(v - 1) * (v + 1) * (u + 1) / 2,
         -(u - 1) * (u + 1) * (v + 1) / 2, (v - 1) * (v + 1) * (u - 1) / 2]
    return [g for node in n for g in (node, -node * f / 2, node * f**2 / 8)]


def _cable() -> list[sp.Expr]:
    """Cubic Hermite functions of the ANCF cable (Berzeri and Shabana; Gerstmayr and
    Irschik): s = [1 - 3xi^2 + 2xi^3, L (xi - 2xi^2 + xi^3), 3xi^2 - 2xi^3, L (xi^3 - xi^2)]."""
    xi = X / L
    return [1 - 3 * xi**2 + 2 * xi**3, L * (xi - 2 * xi**2 + xi**3), 3 * xi**2 - 2 * xi**3,
            L * (xi**3 - xi**2)]


def _quintic_cable() -> list[sp.Expr]:
    """Quintic Hermite functions (r, r_x, r_xx at both ends) in their factored form:
    (1 - xi)^3 (1 + 3 xi + 6 xi^2), L xi (1 - xi)^3 (1 + 3 xi), L^2 xi^2 (1 - xi)^3 / 2 at
    x = 0 and xi^3 (10 - 15 xi + 6 xi^2), L xi^3 (1 - xi) (3 xi - 4), L^2 xi^3 (1 - xi)^2 / 2
    at x = L."""
    xi = X / L
    return [(1 - xi)**3 * (1 + 3 * xi + 6 * xi**2), L * xi * (1 - xi)**3 * (1 + 3 * xi),
            L**2 * xi**2 * (1 - xi)**3 / 2, xi**3 * (10 - 15 * xi + 6 * xi**2),
            L * xi**3 * (1 - xi) * (3 * xi - 4), L**2 * xi**3 * (1 - xi)**2 / 2]


#: kind: its shape functions typed from the literature, node-major, in X, Y, Z, L, H, W.
LITERATURE = {
    "cable2d": _cable,
    "cable3d": _cable,
    "cable2d_quintic": _quintic_cable,
    "cable3d_quintic": _quintic_cable,
    "beam2d": lambda: _beam_2node(2),
    "beam3d": lambda: _beam_2node(3),
    "beam2d_3node": lambda: _beam_3node(2),
    "beam3d_3node": lambda: _beam_3node(3),
    "plate3d": _plate,
    "shell3d_8node": _shell_8node,
    "shell3d_3833": _shell_3833,
}


def shape_functions(kind: str, source: str | None = None) -> list[sp.Expr]:
    """Shape functions of ``kind`` in X, Y, Z, L, H, W: ``source`` "literature" (typed here),
    "derived" (from the node layout, ``derived``), "element" (the element file's, renamed)
    or None (the literature's when typed, else the derived ones)."""
    if source == "literature" or (source is None and kind in LITERATURE):
        return LITERATURE[kind]()
    if source in (None, "derived"):
        return derived(kind)
    if source != "element":
        raise ValueError(f"source: expected 'literature', 'derived' or 'element', got "
                         f"{source!r}")
    return _element_functions(kind)


def _element_functions(kind: str) -> list[sp.Expr]:
    from symgen.elements import get

    spec = get(kind)
    names = dict(zip(spec.coordinates, (X, Y, Z), strict=False))
    names.update(zip(spec.domain.parameters, (L, H, W), strict=True))
    return [s.xreplace(names) for s in spec.shape_functions]


def _derivative_orders(vector: str, dim: int) -> tuple[int, ...]:
    """Derivative orders per axis that a nodal vector names: r -> (0, 0, 0), r_x -> (1, 0,
    0), r_zz -> (0, 0, 2), r_xy -> (1, 1, 0)."""
    letters = vector[2:] if vector.startswith("r_") else ""
    if vector != "r" and (not letters or set(letters) - set("xyz"[:dim])):
        raise ValueError(f"nodal vector {vector!r}: expected r or r_ followed by axes of "
                         f"{'xyz'[:dim]}")
    return tuple(letters.count(axis) for axis in "xyz"[:dim])


@functools.cache
def _derived(kind: str) -> tuple[sp.Expr, ...]:
    info = element_kind(kind)
    dim = info.dim
    unit = sp.symbols("u0:3")[:dim]          # x / L, y / H, z / W
    scales = (L, H, W)[:dim]
    physical = dict(zip((X, Y, Z)[:dim], [u * p for u, p in zip(unit, scales, strict=True)],
                        strict=True))
    space = sorted({m for s in _element_functions(kind)
                    for m in sp.Poly(sp.expand(s.xreplace(physical)), *unit).monoms()})
    points = []
    for node in info.nodes:                  # each coordinate [a_L, a_H, a_W, b]
        point = []
        for axis, coefficients in enumerate(node[:dim]):
            own = [float(c) for i, c in enumerate(coefficients) if i != axis]
            if any(own):
                raise ValueError(f"{kind}: node coordinate {coefficients} is not a multiple "
                                 f"of the {'xyz'[axis]} axis' parameter alone")
            point.append(sp.nsimplify(coefficients[axis]))
        points.append(point)
    conditions = [(point, _derivative_orders(vector, dim)) for point in points
                  for vector in info.vectors]
    if len(space) != len(conditions):
        raise ValueError(f"{kind}: its shape functions span {len(space)} monomials but its "
                         f"nodes state {len(conditions)} interpolation conditions")
    monomials = [sp.Mul(*[u**p for u, p in zip(unit, powers, strict=True)])
                 for powers in space]

    def condition(monomial, point, orders):
        for u, order in zip(unit, orders, strict=True):
            monomial = sp.diff(monomial, u, order)
        return monomial.subs(dict(zip(unit, point, strict=True)))

    values = sp.Matrix([[condition(m, point, orders) for m in monomials]
                        for point, orders in conditions])
    if values.rank() < len(conditions):
        raise ValueError(f"{kind}: its nodes' interpolation conditions are not independent "
                         "in the space its shape functions span")
    coefficients = values.T.inv()            # row j: shape function j in the monomials
    functions = []
    for j, (_, orders) in enumerate(conditions):
        scale = sp.Mul(*[p**o for p, o in zip(scales, orders, strict=True)])
        combination = sum(c * m for c, m in zip(coefficients.row(j), monomials, strict=True))
        normal = dict(zip(unit, [c / p for c, p in zip((X, Y, Z), scales, strict=False)],
                          strict=True))
        functions.append(sp.expand(scale * combination.xreplace(normal)))
    return tuple(functions)


def derived(kind: str) -> list[sp.Expr]:
    """Shape functions of ``kind`` derived from its node layout (element.json ``nodes``,
    ``vectors``): the functions s_j of the polynomial space the element file's functions
    span with D_i s_j(node of i) = delta_ij for every coordinate i (D_i its nodal vector's
    derivative: value, r_x, r_zz, ...), in X, Y, Z, L, H, W.  ValueError when the layout
    does not determine them (conditions and space of different sizes, or dependent)."""
    return list(_derived(kind))


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
