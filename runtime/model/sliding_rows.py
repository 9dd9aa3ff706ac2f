"""Constraint rows of a point sliding along the centre line of an ANCF line body, with the
curve parameter eliminated (docs/design.md section 15, "The sliding joint").

The centre line of element e is ``c(xi) = N(xi) q_e`` (``xi`` in 0 .. l, m, the element's
local axis; N the position map of its shape functions on the axis, polynomials in xi:
``CentreLine``).  The point is ``r_P = P x_P`` (a node, a point mass or a rigid body's point:
linear in its coordinates).  Its offset from the line is ``d(x, xi) = r_P - c(xi)``; the
parameter of the point is eliminated by the closest-point condition

    g(x, xi) = t . d = 0,      t = c_xi (the tangent, r_x at xi),

which defines ``xi*(x)`` (implicit function: xi*_x = -g_x / g_xi), and the rows are the
components of d along dim - 1 directions normal to the tangent,

    phi_k(x) = n_k . d (x, xi*(x)),      n_k = L_k N_j(xi) q_e + b_k

(2D: n = the tangent turned by 90 degrees; 3D: e x t and e for the joint's ``normal`` e):
with d normal to t, phi = 0 holds exactly when d = 0.  Every form F = n . d is bilinear in
the coordinates at a fixed xi and polynomial in xi, so its value, gradient and Hessian over
(x, xi) are exact (``_form``), and the rows' total Jacobian and Hessian follow from the
implicit function theorem exactly:

    phi_x  = F_x + F_xi s_x,       s_x = -g_x / g_xi,
    phi_xx = F_xx + F_xxi s_x^T + s_x F_xxi^T + F_xixi s_x s_x^T + F_xi s_xx,
    s_xx   = -(g_xx + g_xxi s_x^T + s_x g_xxi^T + g_xixi s_x s_x^T) / g_xi.

The rows are scleronomic: the acceleration constraint's velocity terms are v^T phi_xx v.
The block covers every element of the body: its Jacobian row spans the point's and the
body's coordinates (zero but on the element the point is on), its coupling pattern is the
union of (point, element) pairs (``coupled``), fixed when the model is built.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

__all__ = ["CentreLine", "SlideError", "SlidingBlock"]

#: polynomial degree of the fit of the shape functions on the axis (exact up to this: the
#: quintic cables are degree 5)
DEGREE = 7
#: the fit must reproduce the shape values to this at points off the fit's
FIT_TOLERANCE = 1e-10
#: Newton on the closest-point condition stops at corrections below this times l
PARAMETER_TOLERANCE = 1e-14
PARAMETER_ITERATIONS = 50


class SlideError(ValueError):
    """A sliding joint that cannot go on: its point left the body's centre line (beyond an
    end) or no closest point was found; the message names the joint."""


def left_the_body(owner: str, end: str, parameter: float, line: CentreLine) -> str:
    """The cause of a point that left its body at its ``end`` ("start" | "end") at the
    curve ``parameter`` (m), worded identically by both engines."""
    return (f"{owner}: the point left the body at its {end} (curve parameter "
            f"{parameter:.6g} m, the body is {line.elements * line.length:.6g} m long)")


def no_closest_point(owner: str) -> str:
    """The cause of a closest-point search that did not converge (both engines)."""
    return (f"{owner}: no closest point of the body's centre line to the point (Newton on "
            f"the curve parameter did not converge)")


class CentreLine:
    """The centre line of a line body's elements (all of one shape): ``derivatives(xi)``
    gives the position maps N_j (4, dim, ndof) of d^j c / d xi^j, j = 0..3, at a local
    ``xi`` (m, 0 .. ``length``), from a polynomial fit (degree ``DEGREE``) of the kind's
    shape functions on the axis, checked off the fit's points."""

    def __init__(self, kind, element, element_dofs: np.ndarray, shape_values) -> None:
        self.dim, self.n_shape = kind.dim, kind.n_shape
        self.length = float(element.geometry[0])
        self.elements = element_dofs.shape[0]
        self.ndof = element_dofs.shape[1]
        u = (1 - np.cos(np.pi * (np.arange(DEGREE + 1) + 0.5) / (DEGREE + 1))) / 2
        values = shape_values(u * self.length)                        # (D + 1, n_shape)
        vandermonde = np.vander(u, DEGREE + 1, increasing=True)
        #: (D + 1, n_shape) coefficients of the shape values in u = xi / l
        self.coefficients = np.linalg.solve(vandermonde, values)
        check = np.array([0.0, 0.137, 0.5, 0.911, 1.0])
        fitted = np.vander(check, DEGREE + 1, increasing=True) @ self.coefficients
        error = np.abs(fitted - shape_values(check * self.length)).max()
        if error > FIT_TOLERANCE * max(1.0, float(np.abs(values).max())):
            raise ValueError(f"the shape functions of {kind.name} on the axis are not "
                             f"polynomials of degree {DEGREE} (fit error {error:.3g})")
        powers = np.arange(DEGREE + 1)
        #: coefficients of the j-th xi-derivative (4, D + 1, n_shape)
        self._derived = np.zeros((4, DEGREE + 1, self.n_shape))
        current = self.coefficients.copy()
        for j in range(4):
            self._derived[j] = current / self.length**j
            current = np.vstack([(powers[1:, None] * current[1:]), np.zeros((1, self.n_shape))])

    @property
    def polynomials(self) -> np.ndarray:
        """(4, D + 1, n_shape) coefficients in u = xi / l of the xi-derivatives 0..3 of the
        shape functions on the axis (the compiled step's data)."""
        return self._derived

    def derivatives(self, xi: float) -> np.ndarray:
        """N_j (4, dim, ndof) at xi: d^j c / d xi^j = N_j q_e (node-major coordinates)."""
        u = xi / self.length
        basis = u ** np.arange(DEGREE + 1)
        values = np.einsum("jpk,p->jk", self._derived, basis)          # (4, n_shape)
        return np.einsum("jk,de->jdke", values, np.eye(self.dim)).reshape(
            4, self.dim, self.n_shape * self.dim)


@dataclass(frozen=True)
class Normal:
    """A direction n = L N_j(xi) q_e + b of the rows (``L`` (dim, dim) constant, ``order`` j
    the derivative of the centre line it turns, ``offset`` b (dim,) constant)."""

    turn: np.ndarray
    order: int
    offset: np.ndarray


class Local(NamedTuple):
    """The rows on the element the point is on: element ``e``, ``xi`` (m), ``columns`` (kl,)
    of the block's coordinates they read, values (m,), Jacobian (m, kl), Hessian
    (m, kl, kl), the parameter's gradient s_x (kl,), and d phi / d r_P (m, dim)."""

    element: int
    xi: float
    columns: np.ndarray
    value: np.ndarray
    jacobian: np.ndarray
    hessian: np.ndarray
    slope: np.ndarray
    point: np.ndarray


@dataclass(frozen=True)
class SlidingBlock:
    """The rows of a point sliding on a line body (module docstring), over ``dofs`` (k,):
    first the point's ``point_size`` coordinates (its position ``point_map`` (dim, p) times
    them), then the body's coordinates; ``element_columns`` (elements, ndof) the columns of
    each element's coordinates among them; ``start`` the element and xi of the point at
    t = 0 (where the closest-point search starts, then from the last point found)."""

    owner: str
    dofs: np.ndarray
    point_size: int
    point_map: np.ndarray
    line: CentreLine
    element_columns: np.ndarray
    normals: tuple[Normal, ...]
    start: tuple[int, float]
    _last: list = field(default_factory=list, repr=False, compare=False)
    _cache: dict = field(default_factory=dict, repr=False, compare=False)

    def __post_init__(self) -> None:
        self._last[:] = list(self.start)

    @property
    def rows(self) -> int:
        return len(self.normals)

    @property
    def terms(self) -> tuple:
        """No quadratic terms (the compiled step evaluates these rows from their own data:
        ``sliding_rows`` in templates/stepper.c.j2)."""
        return ()

    @property
    def start_found(self) -> tuple[int, float]:
        """The element and xi of the last point of the line found (``local``)."""
        return int(self._last[0]), float(self._last[1])

    @property
    def coupled(self) -> np.ndarray:
        """The coordinate sets its Hessian couples (elements, p + ndof): the point's with
        each element's."""
        point = np.broadcast_to(self.dofs[:self.point_size], (self.line.elements,
                                                              self.point_size))
        return np.hstack([point, self.dofs[self.element_columns]])

    def element_coordinates(self, element: int) -> np.ndarray:
        """The block's columns (p + ndof,) of the point and of element ``element``."""
        return np.concatenate([np.arange(self.point_size), self.element_columns[element]])

    def _maps(self, element: int, xi: float):
        """(D_i, A_i per normal, T_i, columns): the maps (dim, kl) of d, of the normals and
        of the tangent and their xi-derivatives (i = 0..2), on the coordinates
        y = x[columns] of the point and the element: d = D_0 y, n = A_0 y + b, t = T_0 y."""
        columns = self.element_coordinates(element)
        n = self.line.derivatives(xi)                              # (4, dim, ndof)
        p, dim = self.point_size, self.line.dim
        zeros = np.zeros((dim, p))
        d_maps = [np.hstack([self.point_map, -n[0]])] + [np.hstack([zeros, -n[i]])
                                                          for i in (1, 2)]
        normal_maps = [[np.hstack([zeros, normal.turn @ n[normal.order + i]])
                        if normal.order + i <= 3 else np.zeros((dim, p + self.line.ndof))
                        for i in range(3)] for normal in self.normals]
        tangent = [np.hstack([zeros, n[1 + i]]) for i in range(3)]
        return d_maps, normal_maps, tangent, columns

    def _locate(self, x: np.ndarray) -> tuple[int, float]:
        """The element and xi of the point of the line closest to the point (Newton on
        g = t . d = 0 from the last point found, crossing into the neighbouring elements).
        SlideError beyond the body's ends or without convergence."""
        element, xi = int(self._last[0]), float(self._last[1])
        line = self.line
        for _ in range(PARAMETER_ITERATIONS):
            d_maps, _, tangent, columns = self._maps(element, xi)
            y = x[columns]
            d, t, t_xi = d_maps[0] @ y, tangent[0] @ y, tangent[1] @ y
            slope = t_xi @ d - t @ t
            step = -(t @ d) / slope if slope != 0.0 else np.inf
            if not np.isfinite(step):
                break
            xi += step
            while xi > line.length and element < line.elements - 1:
                xi -= line.length
                element += 1
            while xi < 0.0 and element > 0:
                xi += line.length
                element -= 1
            if xi > line.length * (1 + 1e-12) or xi < -line.length * 1e-12:
                raise SlideError(left_the_body(self.owner, "end" if xi > 0 else "start",
                                               element * line.length + xi, line))
            if abs(step) <= PARAMETER_TOLERANCE * line.length:
                self._last[:] = [element, xi]
                return element, xi
        raise SlideError(no_closest_point(self.owner))

    def local(self, x: np.ndarray) -> Local:
        """The rows at x = q[dofs] (k,) on the element the point is on (``Local``)."""
        key = x.tobytes()
        if key in self._cache:
            return self._cache[key]
        element, xi = self._locate(x)
        d_maps, normal_maps, tangent, columns = self._maps(element, xi)
        y = x[columns]
        g = _form(tangent, np.zeros(self.line.dim), d_maps, y)
        s_x = -g[1] / g[2]
        s_xx = -(g[3] + np.outer(g[4], s_x) + np.outer(s_x, g[4]) + g[5] * np.outer(s_x, s_x)
                 ) / g[2]
        values, jacobians, hessians, points = [], [], [], []
        t = tangent[0] @ y
        for normal, maps in zip(self.normals, normal_maps, strict=True):
            f = _form(maps, normal.offset, d_maps, y)
            values.append(f[0])
            jacobians.append(f[1] + f[2] * s_x)
            hessians.append(f[3] + np.outer(f[4], s_x) + np.outer(s_x, f[4])
                            + f[5] * np.outer(s_x, s_x) + f[2] * s_xx)
            n = maps[0] @ y + normal.offset
            points.append(n - f[2] * t / g[2])       # d phi / d r_P (s moves with r_P)
        out = Local(element, xi, columns, np.array(values), np.array(jacobians),
                    np.array(hessians), s_x, np.array(points))
        self._cache.clear()
        self._cache[key] = out
        return out

    def _scatter(self, local: Local, part: np.ndarray, axes: int) -> np.ndarray:
        shape = (self.rows,) + (self.dofs.size,) * axes
        out = np.zeros(shape)
        index = (slice(None),) + np.ix_(*([local.columns] * axes))
        out[index] = part
        return out

    def value(self, x: np.ndarray) -> np.ndarray:
        """phi (m,) at x = q[dofs] (k,), m."""
        return self.local(x).value.copy()

    def jacobian(self, x: np.ndarray) -> np.ndarray:
        """d phi / dx (m, k) (total: through the parameter too)."""
        local = self.local(x)
        return self._scatter(local, local.jacobian, 1)

    def curvature(self, x: np.ndarray, v: np.ndarray) -> np.ndarray:
        """v^T phi_xx v (m,) at the velocities v = q'[dofs] (k,)."""
        local = self.local(x)
        w = v[local.columns]
        return np.einsum("mij,i,j->m", local.hessian, w, w)

    def hessian(self, x: np.ndarray) -> np.ndarray:
        """d2 phi / dx2 (m, k, k)."""
        local = self.local(x)
        return self._scatter(local, local.hessian, 2)

    def parameter(self, x: np.ndarray) -> float:
        """The curve parameter s (m) of the point: element index times l plus xi (the
        reference arc length on straight elements)."""
        local = self.local(x)
        return local.element * self.line.length + local.xi

    def rate(self, x: np.ndarray, v: np.ndarray) -> float:
        """ds/dt (m/s) = s_x . v at the velocities v (k,)."""
        local = self.local(x)
        return float(local.slope @ v[local.columns])

    def force(self, x: np.ndarray, multipliers: np.ndarray) -> np.ndarray:
        """The force (dim,) in N the joint applies to the point for the rows' multipliers
        (m,): -(d phi / d r_P)^T lambda (the equations are M a + Phi_q^T lambda = F)."""
        return -(self.local(x).point.T @ multipliers)


def _form(normal_maps, offset: np.ndarray, d_maps, y: np.ndarray):
    """(F, F_y, F_xi, F_yy, F_yxi, F_xixi) of F = n . d with n = A_0 y + b, d = D_0 y and
    their xi-derivatives A_i y, D_i y (``normal_maps`` A_0..A_2, ``d_maps`` D_0..D_2, each
    (dim, kl)) at the coordinates y (kl,)."""
    a0, a1, a2 = normal_maps[:3]
    d0, d1, d2 = d_maps[:3]
    n, n_xi, n_xixi = a0 @ y + offset, a1 @ y, a2 @ y
    d, d_xi, d_xixi = d0 @ y, d1 @ y, d2 @ y
    return (n @ d, a0.T @ d + d0.T @ n, n_xi @ d + n @ d_xi, a0.T @ d0 + d0.T @ a0,
            a1.T @ d + a0.T @ d_xi + d1.T @ n + d0.T @ n_xi,
            n_xixi @ d + 2 * n_xi @ d_xi + n @ d_xixi)
