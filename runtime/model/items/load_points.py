"""Points at which loads act, with the linear maps of the position and of the frame's
gradients there (``runtime.model.items.follower.PointMaps``): a node, the element sides of a
plate's grid line, the element faces of a box's lattice plane, the axis of a beam body, the
mid-surface of a plate body.

Shape functions come from each kind's generated ``invariants`` family; a map (dim, n) of a
field ``sum_k s_k q_k`` is ``s^T (x) I_dim`` in the node-major element coordinates."""

from __future__ import annotations

import numpy as np

from runtime.element import invariants
from runtime.kernels.kind import ElementKind
from runtime.kernels.loader import kernel_family
from runtime.model.items.base import BodyView, ModelView
from runtime.model.items.follower import PointMaps
from runtime.model.schema import EdgeRef

#: Gauss points along an element side for line loads, and per direction over an element face
#: for face loads (exact for the shape functions times the length or area element up to
#: degree 15)
EDGE_GAUSS_ORDER = 8
#: Gauss points per direction over a plate element (pressure) and along a beam element
SURFACE_GAUSS_ORDER = 5
AXIS_GAUSS_ORDER = 5


def shape_tables(body: BodyView, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Shape values (p, n_shape) and local gradients (p, n_shape, dim) at local points."""
    kind, element = body.kind, body.element
    family = kernel_family(kind.name, "invariants", element.backend)
    data = {"point": points, "geometry": np.asarray(element.geometry, float)}
    values = family("shape_values", data)["values"]
    grads = invariants.full_gradients(kind, invariants.shape_gradient_table(
        kind, family, element.geometry, points))
    return values, grads


def field_map(values: np.ndarray, dim: int) -> np.ndarray:
    """Map (p, dim, n_shape * dim) of the field with shape values (p, n_shape)."""
    p, n = values.shape
    return np.einsum("pk,de->pdke", values, np.eye(dim)).reshape(p, dim, n * dim)


def _element_sides(kind: ElementKind, on_edge: np.ndarray, edge: EdgeRef
                   ) -> list[tuple[int, float]]:
    """The sides (local axis held fixed, its fraction) of an element whose nodes
    ``on_edge`` (n_nodes,) bool lie on ``edge``: on a grid line, the side at fixed local x
    (``x=I``) or y; on a node set of a mesh file, every side all of whose nodes are in it."""
    fractions = kind.node_fractions
    if edge.set is None:
        axis = "xy".index(edge.axis)
        return [(axis, float(fractions[np.flatnonzero(on_edge)[0], axis]))]
    return [(axis, value) for axis in (0, 1) for value in (0.0, 1.0)
            if on_edge[np.isclose(fractions[:, axis], value)].all()]


def edge_sides(body: BodyView, edge: EdgeRef):
    """The element sides on a grid line or a node set (each once: an interior line's sides
    belong to two elements): per side (element index, local points (p, dim) on the
    mid-surface, length elements ds (p,) in m: Gauss weight times |dr0/ds|)."""
    kind, element = body.kind, body.element
    t, w = np.polynomial.legendre.leggauss(EDGE_GAUSS_ORDER)
    on_edge = np.isin(body.mesh.connectivity, edge.nodes)
    sides: set[frozenset] = set()
    for e in np.flatnonzero(on_edge.sum(axis=1) > 1):
        for axis, fraction in _element_sides(kind, on_edge[e], edge):
            along = 1 - axis          # the side lies at fixed local x (or y), along y (or x)
            local = np.isclose(kind.node_fractions[:, axis], fraction)
            side = frozenset(body.mesh.connectivity[e][local & on_edge[e]].tolist())
            if side in sides:
                continue
            sides.add(side)
            size = element.geometry[along]
            points = np.zeros((t.size, kind.dim))   # mid-surface (z = 0) of the side
            points[:, axis] = fraction * element.geometry[axis]
            points[:, along] = (t + 1) / 2 * size
            values, grads = shape_tables(body, points)
            q0 = body.element_e0[e].reshape(kind.n_shape, kind.dim)
            ds = np.linalg.norm(grads[:, :, along] @ q0, axis=1) * w * size / 2
            yield e, points, ds, values, grads


def face_sides(body: BodyView, face: EdgeRef):
    """The element faces on a lattice plane ``"BODY:x=I"`` (``y=J``, ``z=K``) of a box body,
    each once (an interior plane's faces belong to two elements): per face (element index,
    shape values (p, n_shape) at its Gauss points, area elements dA (p,) in m^2: Gauss weight
    times |dr0/du x dr0/dv|)."""
    kind, element = body.kind, body.element
    axis = "xyz".index(face.axis)
    along = [a for a in range(3) if a != axis]
    t, w = np.polynomial.legendre.leggauss(EDGE_GAUSS_ORDER)
    on_face = np.isin(body.mesh.connectivity, face.nodes)
    done: set[frozenset] = set()
    for e in np.flatnonzero(on_face.sum(axis=1) > 0):
        local = on_face[e]
        fractions = np.unique(np.round(kind.node_fractions[local, axis], 12))
        if fractions.size != 1:
            continue
        plane = np.isclose(kind.node_fractions[:, axis], fractions[0])
        side = frozenset(body.mesh.connectivity[e][plane].tolist())
        if not local[plane].all() or side in done:
            continue
        done.add(side)
        sizes = [element.geometry[a] for a in along]
        u, v = np.meshgrid((t + 1) / 2 * sizes[0], (t + 1) / 2 * sizes[1], indexing="ij")
        points = np.zeros((u.size, kind.dim))
        points[:, axis] = fractions[0] * element.geometry[axis]
        points[:, along[0]], points[:, along[1]] = u.ravel(), v.ravel()
        values, grads = shape_tables(body, points)
        q0 = body.element_e0[e].reshape(kind.n_shape, kind.dim)
        normal = np.cross(grads[:, :, along[0]] @ q0, grads[:, :, along[1]] @ q0)
        weights = np.outer(w * sizes[0] / 2, w * sizes[1] / 2).ravel()
        yield e, values, np.linalg.norm(normal, axis=1) * weights


def _frame_maps(grads: np.ndarray, dim: int,
                order: str = "xy") -> tuple[np.ndarray, np.ndarray | None]:
    """Maps of the field gradients that define a point's frame: the pair ``order`` in 3D
    (default r_x and r_y), r_x in 2D."""
    if dim == 2:
        return field_map(grads[:, :, 0], dim), None
    a, b = ("xyz".index(axis) for axis in order)
    return field_map(grads[:, :, a], dim), field_map(grads[:, :, b], dim)


def edge_maps(body: BodyView, edge: EdgeRef, section: bool = False) -> PointMaps:
    """The Gauss points of the sides of a plate grid line (weights: ds in m), with the
    frame of the mid-surface (r_x, r_y), or with ``section`` that of the section across the
    line ((r_y, r_z) on x = const, (r_z, r_x) on y = const)."""
    sides = list(edge_sides(body, edge))
    dim = body.kind.dim
    order = ("yz" if edge.axis == "x" else "zx") if section else "xy"
    position = np.stack([field_map(s[3], dim) for s in sides])
    a, b = zip(*(_frame_maps(s[4], dim, order) for s in sides), strict=True)
    return PointMaps(body.element_dofs[[s[0] for s in sides]], position, np.stack(a),
                     np.stack(b), order, np.stack([s[2] for s in sides]))


def _box_rule(body: BodyView, axes: tuple[int, ...], order: int):
    """Tensor Gauss points (p, dim) over the local box's ``axes`` (others at 0), weights (p,)."""
    t, w = np.polynomial.legendre.leggauss(order)
    geometry = body.element.geometry
    grids = np.meshgrid(*[(t + 1) / 2 * geometry[a] for a in axes], indexing="ij")
    weights = np.ones(1)
    for a in axes:
        weights = np.multiply.outer(weights, w * geometry[a] / 2)
    points = np.zeros((grids[0].size, body.kind.dim))
    for a, grid in zip(axes, grids, strict=True):
        points[:, a] = grid.ravel()
    return points, weights.ravel()


def axis_maps(body: BodyView) -> PointMaps:
    """Gauss points along the axis of every element of a beam body (weights: ds in m)."""
    dim = body.kind.dim
    points, weights = _box_rule(body, (0,), AXIS_GAUSS_ORDER)
    values, grads = shape_tables(body, points)
    a, b = _frame_maps(grads, dim)
    q0 = body.element_e0.reshape(-1, body.kind.n_shape, dim)
    ds = np.linalg.norm(np.einsum("pk,ekd->epd", grads[:, :, 0], q0), axis=-1) * weights
    return PointMaps(body.element_dofs, field_map(values, dim)[None], a[None],
                     None if b is None else b[None], "xy" if dim == 3 else "", ds)


def surface_maps(body: BodyView) -> PointMaps:
    """Gauss points over the mid-surface of every element of a plate body (weights: dA0 in
    m^2, |dr0/dx x dr0/dy| times the Gauss weight)."""
    dim = body.kind.dim
    points, weights = _box_rule(body, (0, 1), SURFACE_GAUSS_ORDER)
    values, grads = shape_tables(body, points)
    a, b = _frame_maps(grads, dim)
    q0 = body.element_e0.reshape(-1, body.kind.n_shape, dim)
    tangents = [np.einsum("pk,ekd->epd", grads[:, :, c], q0) for c in (0, 1)]
    area = np.linalg.norm(np.cross(*tangents), axis=-1) * weights
    return PointMaps(body.element_dofs, field_map(values, dim)[None], a[None], b[None], "xy",
                     area)


def frame_gradients(kind: ElementKind) -> str | None:
    """How a node of ``kind`` defines its frame (as ``frame =`` sensors): "xy" (r_x, r_y),
    "yz" (r_y, r_z; 3D nodes without r_x), "x" or "y" (2D: r_x, or r_y); None when it
    cannot (a 3D cable node carries r_x only)."""
    vectors = kind.vectors
    if kind.dim == 2:
        return "x" if "r_x" in vectors else ("y" if "r_y" in vectors else None)
    if "r_x" in vectors and "r_y" in vectors:
        return "xy"
    return "yz" if "r_y" in vectors and "r_z" in vectors else None


def node_maps(model: ModelView, node: int, kind: ElementKind,
              section: bool = False) -> PointMaps:
    """One point at a node: its own coordinates (1, per_node), the selections of its
    position and of the gradients of its frame (``frame_gradients``; with ``section`` those
    of its section: r_y and r_z in 3D, r_y in 2D, r_x on a 2D cable), weight 1."""
    dim, vectors = model.dim, model.node_vectors(node)
    n = len(vectors) * dim

    def select(name: str) -> np.ndarray:
        out = np.zeros((dim, n))
        k = vectors.index(name)
        out[:, k * dim:(k + 1) * dim] = np.eye(dim)
        return out

    rule = frame_gradients(kind)
    if section and "r_y" in vectors:
        rule = "yz" if dim == 3 else "section"
    if rule == "section":   # 2D: the angle of r_y
        a, b = select("r_y"), None
    elif rule == "y":      # 2D, r_x completed from r_y turned by -90 degrees
        a, b = np.array([[0.0, 1.0], [-1.0, 0.0]]) @ select("r_y"), None
    elif rule in ("x", None):
        a, b = select("r_x"), None
    else:
        a, b = select(f"r_{rule[0]}"), select(f"r_{rule[1]}")
    order = rule if dim == 3 else ""
    return PointMaps(model.node_dofs(node)[None], select("r")[None, None], a[None, None],
                     None if b is None else b[None, None], order, np.ones((1, 1)))
