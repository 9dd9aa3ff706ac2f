"""Constraints that hold linear combinations of a node's coordinates: ``symmetry`` (a mirror
plane) and ``fix`` (chosen components of the position).

Both give every target node rows ``a . (q_node - q0_node) = 0`` over its coordinates (q0 the
reference): a row on a single coordinate holds that coordinate (a fixed coordinate, as a
clamp's, eliminated from the unknowns), any other row is a joint row ``a . q = a . q0``
with a Lagrange multiplier (``Built.rows`` and ``Built.offsets``).

Symmetry about the plane with unit normal n through the nodes (mirror S = I - 2 n n^T):
the full model is its half and the half's mirror image, r(S X) = S r(X).  The mirror half's
element coordinates are those of the half mapped by the linear map C with S G0 = G0 C (G0
(dim, k): the node's reference first gradients, columns r_a), so at a node on the plane,
shared by both halves,

* position: n . (r - r0) = 0 (1 row);
* first gradients G = [r_a]: S G = G C, the derivative along the mirrored direction is the
  mirror of the derivative (S r_d = r_{S d}).  With u an eigenvector of C (C^2 = I): G u
  lies in the plane for C u = u (n . G u = 0, 1 row) and along n for C u = -u (t . G u = 0
  for the dim - 1 tangents t, dim - 1 rows).  The mirror of the carried directions must be
  carried (SceneError else): a full frame always is, a shell's director r_z must lie in
  the plane (then n . r_z = 0) or along n, a cable's tangent r_x too;
* higher derivatives r_ab..., along directions a, b, ... that C maps to +- themselves
  (signs s_a): S r_ab = s_a s_b r_ab, so n . r_ab = 0 when the product is +1 (a shell's
  r_zz, always: n . r_zz = 0), t . r_ab = 0 when it is -1.

Rows whose coefficients are all on one coordinate (a normal along a coordinate axis, a node
frame aligned with it) become fixed coordinates.  docs/design.md, "Symmetry".
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from runtime.kernels.kind import ElementKind, is_first_gradient, vector_axes
from runtime.model.errors import SceneError, show
from runtime.model.items.base import ModelView
from runtime.model.items.constraints import Built, HeldNodes
from runtime.model.schema import Context, key, vector

__all__ = ["Fix", "Symmetry", "hold_rows", "symmetry_rows"]

#: coefficients below this times a row's largest are round-off of axis-aligned planes: 0
ZERO = 1e-12
#: how far (relative) the reference may be from symmetric: nodes off the plane (to the
#: model's extent), gradients whose mirror is not carried, rows already held
TOLERANCE = 1e-6


def _cleaned(rows: np.ndarray) -> np.ndarray:
    """Rows (m, k) with the entries below ZERO times their row's largest set to 0."""
    rows = np.array(rows, float)
    rows[np.abs(rows) < ZERO * np.abs(rows).max(axis=1, keepdims=True)] = 0.0
    return rows


def _span(columns: np.ndarray) -> np.ndarray:
    """Independent columns (k, r) of ``columns`` (k, m) of entries of order 1 (projections,
    unit vectors) spanning its range, taken in order (so that unit columns stay unit:
    coordinate axes stay single coordinates); parts below TOLERANCE are round-off."""
    picked: list[np.ndarray] = []
    basis: list[np.ndarray] = []
    for column in columns.T:
        rest = column.copy()
        for unit in basis:
            rest -= (unit @ rest) * unit
        size = float(np.linalg.norm(rest))
        if size > TOLERANCE:
            picked.append(np.where(np.abs(column) < ZERO, 0.0, column))
            basis.append(rest / size)
    return np.array(picked).T.reshape(columns.shape[0], len(picked))


def symmetry_rows(model: ModelView, node: int, normal: np.ndarray) -> np.ndarray:
    """The rows (m, per_node) over the coordinates of ``node`` (``model.node_dofs(node)``)
    that mirror symmetry about the plane of unit ``normal`` (dim,) through it imposes on the
    node's displacement (module docstring).  SceneError when the node's reference is not
    symmetric or the mirror of a carried direction is not carried."""
    dim = model.dim
    vectors = model.node_vectors(node)
    reference = model.reference[model.node_dofs(node)].reshape(len(vectors), dim)
    mirror = np.eye(dim) - 2.0 * np.outer(normal, normal)
    first = [k for k, name in enumerate(vectors) if is_first_gradient(name)]
    axes = [vector_axes(vectors[k])[0] for k in first]
    frame = reference[first].T                             # G0 (dim, k)
    mapping = np.zeros((len(first), len(first)))           # C with S G0 = G0 C
    if first:
        mapping = np.linalg.lstsq(frame, mirror @ frame, rcond=None)[0]
        if np.abs(frame @ mapping - mirror @ frame).max() > TOLERANCE * np.abs(frame).max():
            names = ", ".join(vectors[k] for k in first)
            raise SceneError(
                f"the mirror image of its gradients {names} is not a combination of them "
                f"(at the reference: {show(frame.T.round(6).tolist())}); expected gradients "
                f"in the symmetry plane or along its normal {show(normal.tolist())}")
        mapping = _cleaned(mapping.T).T
    tangents = _span(np.eye(dim) - np.outer(normal, normal)).T    # (dim - 1, dim)
    rows = []

    def row(parts: dict[int, np.ndarray]) -> np.ndarray:
        out = np.zeros((len(vectors), dim))
        for k, direction in parts.items():
            out[k] = direction
        return out.ravel()

    rows.append(row({vectors.index("r"): normal}))
    identity = np.eye(len(first))
    for sign in (1.0, -1.0):
        for u in _span((identity + sign * mapping) / 2.0).T:
            for direction in ([normal] if sign > 0 else tangents):
                rows.append(row({k: u[a] * direction for a, k in enumerate(first)}))
    for k, name in enumerate(vectors):
        if name == "r" or is_first_gradient(name):
            continue
        sign = 1.0
        for axis in vector_axes(name):
            a = axes.index(axis) if axis in axes else -1
            column = mapping[:, a] if a >= 0 else None
            if column is None or abs(abs(column[a]) - 1.0) > TOLERANCE or np.abs(
                    np.delete(column, a)).max(initial=0.0) > TOLERANCE:
                raise SceneError(
                    f"it carries {name}, along a direction that the symmetry plane "
                    f"of normal {show(normal.tolist())} does not map to itself or its "
                    f"opposite; expected its gradients in the plane or along the normal")
            sign *= column[a]
        held = [normal] if sign > 0 else list(tangents)
        scale = float(np.linalg.norm(reference[k]))
        if any(abs(direction @ reference[k]) > TOLERANCE * scale for direction in held):
            raise SceneError(f"its reference {name} is not symmetric about the plane of "
                             f"normal {show(normal.tolist())}")
        rows.extend(row({k: direction}) for direction in held)
    return _cleaned(np.array(rows))


def hold_rows(model: ModelView, built: Built, node: int, rows: np.ndarray) -> None:
    """Hold ``rows`` (m, per_node) of the displacement of ``node``'s coordinates: a row on
    one coordinate fixes it, any other joins the joint rows ``a . q = a . q0`` (offset
    ``a . q0``, the reference) unless the coordinates fixed and the rows already on this
    node hold it (a node on two planes, two constraints on one node)."""
    dofs = model.node_dofs(node)
    single = np.count_nonzero(rows, axis=1) == 1
    for r in rows[single]:
        built.fixed[dofs[np.flatnonzero(r)[0]]] = True
    position = {int(d): i for i, d in enumerate(dofs)}
    basis: list[np.ndarray] = []

    def add(vector: np.ndarray) -> bool:       # whether it holds something new
        rest = vector * ~built.fixed[dofs]
        for unit in basis:
            rest -= (unit @ rest) * unit
        size = float(np.linalg.norm(rest))
        if size <= TOLERANCE * float(np.linalg.norm(vector)):
            return False
        basis.append(rest / size)
        return True

    for existing in built.rows:
        if existing and all(i in position for i in existing):
            vector = np.zeros(dofs.size)
            for i, value in existing.items():
                vector[position[i]] = value
            add(vector)
    for r in rows[~single]:
        if add(r):
            offset = float(r @ model.reference[dofs])
            if offset != 0.0:
                built.offsets[len(built.rows)] = offset
            built.rows.append({int(dofs[i]): float(r[i]) for i in np.flatnonzero(r)})


def _normal_key(value: Any, path: str, context: Context) -> tuple[float, ...]:
    normal = vector(value, path, context.dim, f"the scene is {context.dim}D")
    norm = float(np.linalg.norm(normal))
    if norm == 0.0:
        raise SceneError(f"{path}: expected a non-zero normal of the symmetry plane, got "
                         f"{show(value)}")
    return normal if abs(norm - 1.0) <= 1e-12 else tuple(x / norm for x in normal)


def _components_key(value: Any, path: str, context: Context) -> tuple[str, ...]:
    names = "xyz"[:context.dim]
    expected = f"a list of distinct components among {', '.join(names)}"
    if not isinstance(value, list) or not value or any(c not in names or not isinstance(
            c, str) for c in value) or len(set(value)) != len(value):
        raise SceneError(f"{path}: expected {expected}, got {show(value)}")
    return tuple(value)


@dataclass(frozen=True)
class Symmetry(HeldNodes):
    """Mirror symmetry about the plane of unit ``normal`` (dim,) through the target nodes
    (``node`` or ``edge``, a grid line or a node set of a mesh file): the rows of
    ``symmetry_rows`` on each node."""

    type: ClassVar[str] = "symmetry"
    holds_position: ClassVar[bool] = False
    normal: tuple[float, ...] = key(_normal_key, kw_only=True)

    def held(self, kind: ElementKind) -> int:
        return len(kind.vectors)         # at least one row per nodal vector

    def apply(self, model: ModelView, built: Built) -> None:
        normal = np.asarray(self.normal, float)
        nodes = [model.node_index(ref) for ref in self.targets()]
        levels = [float(normal @ model.reference[model.node_dofs(n, "r")]) for n in nodes]
        extent = float(max(np.ptp(model.reference), 1.0))
        for ref, level in zip(self.targets(), levels, strict=True):
            if abs(level - levels[0]) > TOLERANCE * extent:
                raise SceneError(
                    f"{self.target_key}: node {ref} is {abs(level - levels[0]):.3g} m off the "
                    f"symmetry plane of normal {show(list(self.normal))} through "
                    f"{self.targets()[0]}; expected nodes on one plane normal to it")
        for ref, node in zip(self.targets(), nodes, strict=True):
            try:
                rows = symmetry_rows(model, node, normal)
            except SceneError as error:
                raise SceneError(f"{self.target_key}: {ref}: {error}") from None
            hold_rows(model, built, node, rows)


@dataclass(frozen=True)
class Fix(HeldNodes):
    """Holds the position components ``components`` (global axes, e.g. ["x", "z"]) of the
    target nodes at their reference values; the rest of the node moves freely."""

    type: ClassVar[str] = "fix"
    holds_position: ClassVar[bool] = False
    components: tuple[str, ...] = key(_components_key, kw_only=True)

    def held(self, kind: ElementKind) -> int:
        return len(self.components)

    def apply(self, model: ModelView, built: Built) -> None:
        dim = model.dim
        for ref in self.targets():
            node = model.node_index(ref)
            vectors = model.node_vectors(node)
            rows = np.zeros((len(self.components), len(vectors) * dim))
            start = vectors.index("r") * dim
            for i, component in enumerate(self.components):
                rows[i, start + "xyz".index(component)] = 1.0
            hold_rows(model, built, node, rows)
