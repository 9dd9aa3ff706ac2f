"""Strain, stress and section forces at material points of elements, through the element's
shape functions (the ``shape_values``, ``shape_gradients`` and, for cables,
``shape_curvatures`` point tables of the kind's ``invariants`` kernel family), vectorised
over a block of k states, m elements and p local points.

Frames (docs/laws.md, "Strain and Voigt notation"): with ``J0 = dr0/dx`` at a local point,
``J0 = R0 U`` (R0 the Gram-Schmidt frame of dr0/dx, dr0/dy[, dr0/dz], U upper triangular)
and ``F = (dr/dx) U^-1``:

* Green-Lagrange ``E = (F^T F - I) / 2`` and second Piola-Kirchhoff ``S`` are components in
  the *reference local frame* R0 (the frame of the material law; axis 1 the beam axis);
* ``S`` is the law's: each part ``D`` of the law (``Element.law_coefficients``) times the
  Voigt strain at the point, a part on a lower-dimensional domain (ecm's Poisson part on the
  beam axis) taking the strain on that domain at the same axial position (constant over the
  section, as the element's energy integrates it);
* Cauchy ``sigma = F S F^T / det F`` is given in the *current local frame*: the Gram-Schmidt
  frame of the current dr/dx, dr/dy[, dr/dz] (axis 1 along the deformed dr/dx, the rule of the
  node frames);
* von Mises from sigma (3D: the full tensor; 2D: plane stress, sigma_33 = 0).

Cables (the ``cable`` energy: r, r_x only, no section) have the axial strain only, on the
axis: ``E11 = (r_x . r_x - 1) / 2``, ``S11 = E E11``, ``sigma11 = |r_x| S11``.

Section forces at an axial position: the force and moment that the part of the beam beyond
the section exerts on the part before it (the stress resultant on the face with outward
normal +x): ``f = int F S N0 dA0`` and ``m = int (r - r_c) x F S N0 dA0`` over the reference
cross section (Gauss rule, ``N0 dA0 = det U U^-T e1 dy dz``; r_c the axis point), with
components in the current local frame at the axis point: N = f.t1, Q2 = f.t2, Q3 = f.t3,
T = m.t1, M2 = m.t2, M3 = m.t3 (2D: N, Q2, M3).  For cables ``N = |r_x| E A E11`` and
``m = E I r_x x r_xx / |r_x|^3`` (EI kappa).
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass

import numpy as np

from runtime.element.invariants import full_gradients, shape_gradient_table
from runtime.kernels.kind import ElementKind
from runtime.kernels.loader import kernel_family
from runtime.model.items.base import BodyView

__all__ = ["SECTION_ORDER", "Fields", "Section", "section_forces", "shear_pairs_of",
           "strain_stress", "von_mises"]

#: Gauss points per cross-section axis of the section resultants (exact for the quartic
#: integrands of the linear-section kinds)
SECTION_ORDER = 4
_SECTION_RULE = np.polynomial.legendre.leggauss(SECTION_ORDER)


@dataclass(frozen=True)
class Fields:
    """At k states, m elements, p points: Green-Lagrange ``strain`` and second
    Piola-Kirchhoff ``pk2`` (k, m, p, dim, dim) in the reference local frame, in Pa for pk2;
    Cauchy ``cauchy`` (k, m, p, dim, dim) in Pa in the current local frame; ``frame`` the
    current local frame (k, m, p, dim, dim) (columns t1, t2(, t3) in global axes)."""

    strain: np.ndarray
    pk2: np.ndarray
    cauchy: np.ndarray
    frame: np.ndarray


def shear_pairs_of(dim: int) -> list[tuple[int, int]]:
    """Local axes of the Voigt shear strains (3D: 23, 13, 12; 2D: 12)."""
    return [(0, 1)] if dim == 2 else [(1, 2), (0, 2), (0, 1)]


def _voigt(dim: int, coefficient: np.ndarray) -> np.ndarray:
    """The Voigt matrix of a law part from its coefficients (upper triangle of the normal
    block row-major, then the shear diagonal)."""
    shears = len(shear_pairs_of(dim))
    matrix = np.zeros((dim + shears, dim + shears))
    rows, cols = np.triu_indices(dim)
    matrix[rows, cols] = matrix[cols, rows] = coefficient[:rows.size]
    matrix[np.arange(dim, dim + shears), np.arange(dim, dim + shears)] = coefficient[rows.size:]
    return matrix


def _to_voigt(strain: np.ndarray) -> np.ndarray:
    """Voigt strains (..., dim + shears) with engineering shears 2 E_ab."""
    dim = strain.shape[-1]
    normal = [strain[..., a, a] for a in range(dim)]
    shear = [2 * strain[..., a, b] for a, b in shear_pairs_of(dim)]
    return np.stack(normal + shear, axis=-1)


def _from_voigt(stress: np.ndarray, dim: int) -> np.ndarray:
    """Symmetric tensors (..., dim, dim) of Voigt stresses (..., dim + shears)."""
    out = np.zeros((*stress.shape[:-1], dim, dim))
    for a in range(dim):
        out[..., a, a] = stress[..., a]
    for s, (a, b) in enumerate(shear_pairs_of(dim)):
        out[..., a, b] = out[..., b, a] = stress[..., dim + s]
    return out


def orthonormal_columns(matrix: np.ndarray) -> np.ndarray:
    """Modified Gram-Schmidt of the columns of (..., dim, dim), column 1 kept in direction."""
    basis: list[np.ndarray] = []
    for a in range(matrix.shape[-1]):
        column = matrix[..., a]
        for unit in basis:
            column = column - np.sum(column * unit, axis=-1, keepdims=True) * unit
        basis.append(column / np.linalg.norm(column, axis=-1, keepdims=True))
    return np.stack(basis, axis=-1)


def von_mises(cauchy: np.ndarray) -> np.ndarray:
    """Von Mises stress (...) of Cauchy tensors (..., dim, dim) (2D: plane stress)."""
    s = cauchy
    if s.shape[-1] == 2:
        return np.sqrt(s[..., 0, 0] ** 2 - s[..., 0, 0] * s[..., 1, 1] + s[..., 1, 1] ** 2
                       + 3 * s[..., 0, 1] ** 2)
    return np.sqrt(0.5 * ((s[..., 0, 0] - s[..., 1, 1]) ** 2 + (s[..., 1, 1] - s[..., 2, 2]) ** 2
                          + (s[..., 2, 2] - s[..., 0, 0]) ** 2)
                   + 3 * (s[..., 0, 1] ** 2 + s[..., 1, 2] ** 2 + s[..., 0, 2] ** 2))


class _Tables:
    """Shape-function tables of one body's kind at local points, each computed once per
    set of points (``tables`` keeps them with the body's element), and the law's
    coefficients."""

    def __init__(self, body: BodyView) -> None:
        self.body = body
        self.kind: ElementKind = body.kind
        self.element = body.element
        self.geometry = np.asarray(self.element.geometry, float)
        self.family = kernel_family(self.kind.name, "invariants", self.element.backend)
        self.coefficients = {domain: np.asarray(value, float) for domain, value in
                             self.element.law_coefficients().items()}
        self._memo: dict[tuple[str, bytes], np.ndarray] = {}

    def _table(self, name: str, points: np.ndarray, compute) -> np.ndarray:
        key = (name, np.ascontiguousarray(points, float).tobytes())
        if key not in self._memo:
            self._memo[key] = compute()
        return self._memo[key]

    def values(self, points: np.ndarray) -> np.ndarray:
        """Shape values (p, n) at local points (p, dim)."""
        return self._table("values", points, lambda: self.family(
            "shape_values", {"point": points, "geometry": self.geometry})["values"])

    def gradients(self, points: np.ndarray) -> np.ndarray:
        """Local shape gradients ds/dx (p, n, dim)."""
        return self._table("gradients", points, lambda: full_gradients(
            self.kind, shape_gradient_table(self.kind, self.family, self.geometry, points)))

    def curvatures(self, points: np.ndarray) -> np.ndarray:
        """d2s/dx2 (p, n) along the axis (cable kinds)."""
        return self._table("curvatures", points, lambda: self.family(
            "shape_curvatures", {"point": points, "geometry": self.geometry})["curvatures"])

    def section(self) -> tuple[float, float]:
        """Area (m^2) and second moment (m^4) of a cable's section."""
        area, inertia = self._table("section", np.zeros(0), lambda: self.family(
            "section", {"geometry": self.geometry[None, :]})["section"][0])
        return float(area), float(inertia)

    def nodal(self, q: np.ndarray, elements: np.ndarray) -> np.ndarray:
        """Nodal vectors (k, m, n, dim) of ``elements`` at coordinates q (k, size)."""
        return _relative(self.kind, q[:, self.body.element_dofs[elements]])


_TABLES: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _tables_of(body: BodyView) -> _Tables:
    """The tables of ``body`` (kept while its element lives)."""
    found = _TABLES.get(body.element)
    if found is None or found.body is not body:
        found = _TABLES[body.element] = _Tables(body)
    return found


def _relative(kind: ElementKind, coordinates: np.ndarray) -> np.ndarray:
    """Element coordinates (..., ndof) as nodal vectors (..., n, dim), positions relative to
    the element's first position (they keep the digits of the element's size, not of its
    distance from the origin; the gradients of the position shape functions sum to zero)."""
    nodal = coordinates.reshape(*coordinates.shape[:-1], kind.n_shape, kind.dim).copy()
    positions = list(kind.position_vectors)
    nodal[..., positions, :] -= nodal[..., positions[:1], :]
    return nodal


def _mapping(tables: _Tables, q: np.ndarray, elements: np.ndarray, points: np.ndarray):
    """(F (k, m, p, dim, dim) = dr/dx U^-1, dr/dx (k, m, p, dim, dim), U^-1 (m, p, dim, dim))
    at local points (p, dim) of ``elements``."""
    grads = tables.gradients(points)
    e0 = _relative(tables.kind, tables.body.element_e0[elements])
    j0 = np.einsum("mna,pnb->mpab", e0, grads)
    upper = np.swapaxes(np.linalg.cholesky(np.einsum("mpab,mpac->mpbc", j0, j0)), -1, -2)
    u_inv = np.linalg.inv(upper)
    current = np.einsum("kmna,pnb->kmpab", tables.nodal(q, elements), grads)
    return current @ u_inv, current, u_inv


def _green_lagrange(deformation: np.ndarray) -> np.ndarray:
    dim = deformation.shape[-1]
    return (np.swapaxes(deformation, -1, -2) @ deformation - np.eye(dim)) / 2


def _law_points(kind: ElementKind, geometry: np.ndarray, domain: str,
                points: np.ndarray) -> np.ndarray:
    """``points`` (p, dim) moved onto a law domain: its fixed axes (the beam axis y = z = 0,
    a plate's mid-surface) at their values, the others kept."""
    moved = points.copy()
    values = kind.domain.values(tuple(geometry))
    for axis, fraction in kind.domain.fixed_axes(domain).items():
        moved[:, axis] = fraction * values[kind.domain.axes[axis].scale]
    return moved


def strain_stress(body: BodyView, elements: np.ndarray, points: np.ndarray,
                  q: np.ndarray) -> Fields:
    """Strain and stresses (``Fields``) of ``body``'s ``elements`` (m,) at local points
    (p, dim) (m; inside the element's box) for coordinates q (k, size)."""
    tables = _tables_of(body)
    kind, dim = tables.kind, tables.kind.dim
    elements = np.asarray(elements, int)
    if kind.energy.structural:
        return _cable_fields(tables, elements, points, q)
    deformation, current, _ = _mapping(tables, q, elements, points)
    strain = _green_lagrange(deformation)
    voigt = np.zeros((*strain.shape[:-2], dim + len(shear_pairs_of(dim))))
    for domain, coefficient in tables.coefficients.items():
        if not np.any(coefficient):
            continue
        moved = _law_points(kind, tables.geometry, domain, points)
        local = strain if np.array_equal(moved, points) else \
            _green_lagrange(_mapping(tables, q, elements, moved)[0])
        voigt = voigt + _to_voigt(local) @ _voigt(dim, np.asarray(coefficient, float)).T
    pk2 = _from_voigt(voigt, dim)
    cauchy = deformation @ pk2 @ np.swapaxes(deformation, -1, -2) / \
        np.linalg.det(deformation)[..., None, None]
    frame = orthonormal_columns(current)
    return Fields(strain, pk2, np.swapaxes(frame, -1, -2) @ cauchy @ frame, frame)


def _axial_modulus(tables: _Tables) -> float:
    """E of a cable (the E11 coefficient of its axis law, Pa)."""
    return float(tables.coefficients["axis"][0])


def _cable_metric(tables: _Tables, elements: np.ndarray, points: np.ndarray) -> np.ndarray:
    """|r0_x| (m, p) of the reference of a curved cable's ``elements`` at ``points`` (ones
    for straight references, parameterised by arc length)."""
    if tables.element.straight:
        return np.ones((elements.size, points.shape[0]))
    reference = _relative(tables.kind, tables.body.element_e0[elements])
    return np.linalg.norm(np.einsum("mna,pn->mpa", reference,
                                    tables.gradients(points)[:, :, 0]), axis=-1)


def _cable_fields(tables: _Tables, elements: np.ndarray, points: np.ndarray,
                  q: np.ndarray) -> Fields:
    """A cable's axial strain and stresses on its axis (the other components zero): E11 =
    (|r_x|^2 - a0^2) / (2 a0^2) per reference arc length (a0 = |r0_x|, 1 when straight)."""
    dim = tables.kind.dim
    tangent = np.einsum("kmna,pn->kmpa", tables.nodal(q, elements),
                        tables.gradients(points)[:, :, 0])
    stretch = np.linalg.norm(tangent, axis=-1)
    metric = _cable_metric(tables, elements, points)
    axial = (stretch ** 2 - metric ** 2) / (2 * metric ** 2)
    strain, pk2, cauchy = (np.zeros((*axial.shape, dim, dim)) for _ in range(3))
    strain[..., 0, 0] = axial
    pk2[..., 0, 0] = _axial_modulus(tables) * axial
    cauchy[..., 0, 0] = stretch / metric * pk2[..., 0, 0]
    frame = np.zeros_like(strain)
    frame[..., 0] = tangent / stretch[..., None]
    if dim == 2:
        frame[..., 0, 1], frame[..., 1, 1] = -frame[..., 1, 0], frame[..., 0, 0]
    else:   # no section orientation: the axis, then any right-handed completion
        helper = np.where(np.abs(frame[..., 0, :1]) < 0.9, [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
        second = np.cross(frame[..., 0], helper)
        frame[..., 1] = second / np.linalg.norm(second, axis=-1, keepdims=True)
        frame[..., 2] = np.cross(frame[..., 0], frame[..., 1])
    return Fields(strain, pk2, cauchy, frame)


@dataclass(frozen=True)
class Section:
    """Section forces at k states: ``force`` (k, dim) N and ``moment`` (k, 3) N m (2D: only
    the z component) in global axes, and the current local ``frame`` (k, dim, dim) at the axis
    point (columns t1, t2(, t3))."""

    force: np.ndarray
    moment: np.ndarray
    frame: np.ndarray

    def components(self) -> dict[str, np.ndarray]:
        """{N, Q2, Q3, T, M2, M3, M: (k,)} in the local frame (2D: N, Q2, M3, M; M the
        magnitude of the bending moment)."""
        dim = self.force.shape[1]
        force = np.einsum("kab,ka->kb", self.frame, self.force)
        if dim == 2:
            return {"N": force[:, 0], "Q2": force[:, 1], "M3": self.moment[:, 2],
                    "M": np.abs(self.moment[:, 2])}
        moment = np.einsum("kab,ka->kb", self.frame, self.moment)
        return {"N": force[:, 0], "Q2": force[:, 1], "Q3": force[:, 2], "T": moment[:, 0],
                "M2": moment[:, 1], "M3": moment[:, 2], "M": np.hypot(moment[:, 1], moment[:, 2])}


def _cross(arm: np.ndarray, force: np.ndarray) -> np.ndarray:
    """arm x force for (..., dim) vectors, as (..., 3) (2D: (0, 0, z))."""
    if arm.shape[-1] == 3:
        return np.cross(arm, force)
    z = arm[..., 0] * force[..., 1] - arm[..., 1] * force[..., 0]
    return np.stack([np.zeros_like(z), np.zeros_like(z), z], axis=-1)


def section_forces(body: BodyView, element: int, x: float, q: np.ndarray) -> Section:
    """Section forces (``Section``) of a beam ``body`` at local axial position ``x`` (m) of
    ``element``, for coordinates q (k, size)."""
    tables = _tables_of(body)
    kind, dim = tables.kind, tables.kind.dim
    elements = np.array([element])
    if kind.energy.structural:
        return _cable_section(tables, elements, x, q)
    bounds = kind.domain.bounds(tuple(tables.geometry))
    t, w = _SECTION_RULE
    across = [low + (t + 1) * (high - low) / 2 for low, high in bounds[1:]]
    weights = [w * (high - low) / 2 for low, high in bounds[1:]]
    grid = np.meshgrid(*across, indexing="ij")
    points = np.column_stack([np.full(grid[0].size, x), *(g.ravel() for g in grid)])
    weight = np.prod([g.ravel() for g in np.meshgrid(*weights, indexing="ij")], axis=0) * \
        float(kind.domain.thickness_of(tuple(tables.geometry)))
    fields = strain_stress(body, elements, points, q)
    deformation, _, u_inv = _mapping(tables, q, elements, points)
    normal = np.linalg.det(np.linalg.inv(u_inv))[..., None] * np.swapaxes(u_inv, -1, -2)[..., 0]
    traction = np.einsum("kmpab,kmpbc,mpc->kmpa", deformation, fields.pk2, normal)[:, 0]
    axis = np.zeros((1, dim))
    axis[0, 0] = x
    values, centre = tables.values(points), tables.values(axis)
    nodal = tables.nodal(q, elements)[:, 0]
    arm = np.einsum("pn,kna->kpa", values - centre, nodal)
    force = np.einsum("p,kpa->ka", weight, traction)
    moment = np.einsum("p,kpa->ka", weight, _cross(arm, traction))
    frame = orthonormal_columns(_mapping(tables, q, elements, axis)[1])[:, 0, 0]
    return Section(force, moment, frame)


def _cable_section(tables: _Tables, elements: np.ndarray, x: float, q: np.ndarray) -> Section:
    """N = (|r_x| / a0) E A E11 along the axis (``_cable_fields``); the bending moment
    m = E I r_x x r_xx / |r_x|^3 of the simple bending, and the law's own E I (kappa - kappa0)
    / a0 of the exact curvature, kappa = r_x x r_xx / |r_x|^2 and kappa0 the reference's."""
    point = np.zeros((1, tables.kind.dim))
    point[0, 0] = x
    nodal = tables.nodal(q, elements)[:, 0]
    tangent = np.einsum("kna,n->ka", nodal, tables.gradients(point)[0, :, 0])
    second = np.einsum("kna,n->ka", nodal, tables.curvatures(point)[0])
    area, inertia = tables.section()
    modulus = _axial_modulus(tables)
    stretch = np.linalg.norm(tangent, axis=1)
    metric = _cable_metric(tables, elements, point)[0, 0]
    unit = tangent / stretch[:, None]
    axial = (stretch ** 2 - metric ** 2) / (2 * metric ** 2)
    force = (stretch / metric * modulus * area * axial)[:, None] * unit
    if tables.element.bending == "exact_curvature":
        reference = _relative(tables.kind, tables.body.element_e0[elements])[0]
        r0x = reference.T @ tables.gradients(point)[0, :, 0]
        r0xx = reference.T @ tables.curvatures(point)[0]
        kappa0 = _cross(r0x[None], r0xx[None]) / metric ** 2
        kappa = _cross(tangent, second) / stretch[:, None] ** 2
        moment = modulus * inertia * (kappa - kappa0) / metric
    else:
        moment = modulus * inertia * _cross(tangent, second) / stretch[:, None] ** 3
    frame = _cable_fields(tables, elements, point, q).frame[:, 0, 0]
    return Section(force, moment, frame)
