"""The reference configuration of a mesh given by node positions and cells (a mesh file,
``runtime.model.mesh_file``): node frames and element references for any kind, from its node
layout.

* **Lines** (beam and cable kinds): the elements form one chain; the tangent at a node is
  that of the circle through it and its neighbours along the chain (the three nearest at an
  end; a straight chain gives the chord), so an arc gives the exact tangent at every node.
  An element's length (its local x extent) is the arc length between its end nodes on the
  circle their tangents define, ``c phi / (2 sin(phi / 2))`` for the chord c and the angle
  phi between the end tangents (c on a straight element).  Node frames: r_x the unit tangent,
  r_y perpendicular in the x-y plane (``z x t``, as a straight line's, or ``x x t`` for a
  near-vertical tangent), r_z completing the frame (as ``runtime.element.reference``).
* **Surfaces** (plate and shell kinds): r_z is the unit normal at the node, the normalised
  mean over the elements sharing it of the normal of each element's interpolated surface
  (the kind's position shape functions at the node, z = 0), or the normals a file gives;
  higher derivatives (r_zz) are zero (straight fibres).  The element sides a, b (local x and
  y extents) are the chords from the first corner to its neighbours.  Kinds whose nodes
  carry in-plane gradients (r_x, r_y: plate3d) share them between elements, which needs a
  flat mesh of rectangles with one common frame (else the slope discontinuity of Shabana and
  Mikkola).

* **Solids** (brick kinds): every element a box whose edges from its first corner run along
  the three axes of element 0's (a right-handed orthogonal triple), the nodes' r_x, r_y, r_z
  those unit directions (shared by every element, as a ``box =`` body's); the sides a, b, c
  are those edges' lengths.

Errors are ``MeshGeometryError`` (a message without the key path; the reader adds it).
"""

from __future__ import annotations

import numpy as np

from runtime.element import invariants
from runtime.element.reference import curved_reference_check, frame_reference
from runtime.kernels.kind import ElementKind, vector_axes
from runtime.kernels.loader import kernel_family

#: largest angle (deg) between the normals two elements give a shared node: beyond it the
#: surface has a crease there, which one shared r_z cannot carry
CREASE_DEG = 20.0
#: relative tolerance of "the same shape" (congruent elements) and of "flat and aligned"
SAME = 1e-10


class MeshGeometryError(ValueError):
    """A mesh whose geometry the kind cannot take (the message says why)."""


def carries_in_plane_gradients(kind: ElementKind) -> bool:
    """Whether the kind's nodes carry a derivative along a meshed axis (r_x of a beam, r_x and
    r_y of plate3d) besides the position."""
    return any(set(vector_axes(name)) & set(kind.mesh_axes) for name in kind.vectors)


# --------------------------------------------------------------------------- lines

def line_chain(connectivity: np.ndarray, kind: ElementKind
               ) -> tuple[np.ndarray, np.ndarray, bool]:
    """The elements of a line mesh ordered along their chain and oriented along it
    (connectivity (elements, n_nodes) in the kind's order), the chain of all nodes (element
    ends and interior nodes, in order along the line) and whether it is a closed loop.
    MeshGeometryError for a branching or broken chain."""
    fractions = kind.node_fractions[:, 0]
    first, last = int(np.argmin(fractions)), int(np.argmax(fractions))
    inner = [int(i) for i in np.argsort(fractions) if i not in (first, last)]
    ends = connectivity[:, [first, last]]
    touching: dict[int, list[int]] = {}
    for e, (a, b) in enumerate(ends.tolist()):
        if a == b:
            raise MeshGeometryError(f"element {e} starts and ends at node {a}")
        touching.setdefault(a, []).append(e)
        touching.setdefault(b, []).append(e)
    branch = [n for n, elements in touching.items() if len(elements) > 2]
    if branch:
        raise MeshGeometryError(f"node {branch[0]} joins {len(touching[branch[0]])} elements; "
                                "a line body is one chain of elements (split it into bodies "
                                "joined at that node)")
    free = sorted(n for n, elements in touching.items() if len(elements) == 1)
    start = free[0] if free else int(ends[0, 0])
    order, oriented, used, node = [], [], set(), start
    while True:
        following = [e for e in touching[node] if e not in used]
        if not following:
            break
        e = following[0]
        used.add(e)
        a, b = ends[e]
        row = connectivity[e].copy()
        if a != node:   # reversed along the chain: flip it (its interior nodes too)
            row[[first, last]] = row[[last, first]]
            row[inner] = row[inner[::-1]]
        order.append(e)
        oriented.append(row)
        node = int(row[last])
    if len(order) != len(connectivity):
        raise MeshGeometryError(f"the elements form {len(connectivity) - len(order) and 2} or "
                                "more separate chains; a line body is one chain of elements "
                                "(one body per chain)")
    rows = np.array(oriented)
    chain = [int(rows[0, first])]
    for row in rows:
        chain += [int(row[i]) for i in inner] + [int(row[last])]
    if not free:   # a closed loop: the first node is not repeated
        chain = chain[:-1]
    return rows, np.array(chain), not free


def circle_tangent(a: np.ndarray, b: np.ndarray, c: np.ndarray, at: int) -> np.ndarray:
    """Unit tangent (3,) at point ``at`` (0, 1, 2: a, b or c) of the circle through the
    points a, b, c (3,), oriented from a towards c; the direction of c - a when they are
    collinear."""
    u, v = a - c, b - c
    normal = np.cross(u, v)
    area = float(normal @ normal)
    chord = c - a
    if area <= (1e-12 * np.linalg.norm(u) * np.linalg.norm(v)) ** 2:
        return chord / np.linalg.norm(chord)
    centre = c + np.cross(u @ u * v - v @ v * u, normal) / (2 * area)
    tangent = np.cross(normal, (a, b, c)[at] - centre)
    tangent /= np.linalg.norm(tangent)
    step = (b - a, c - a, c - b)[at]    # along the chain: from a through b to c
    return tangent if tangent @ step > 0 else -tangent


def chain_tangents(positions: np.ndarray, chain: np.ndarray, closed: bool) -> np.ndarray:
    """Unit tangents (nodes, 3) at the chain's nodes from circles through neighbours."""
    points = positions[chain]
    n = len(chain)
    steps = np.linalg.norm(np.diff(points, axis=0), axis=1)
    if not (steps > 1e-12 * np.ptp(points, axis=0).max()).all():
        k = int(np.argmin(steps))
        raise MeshGeometryError(f"nodes {int(chain[k])} and {int(chain[k + 1])} of the chain "
                                "lie at one point; expected distinct points along the line")
    tangents = np.zeros((len(positions), 3))
    if n == 2:
        tangents[chain] = (points[1] - points[0]) / np.linalg.norm(points[1] - points[0])
        return tangents
    for i in range(n):
        if closed:
            tangents[chain[i]] = circle_tangent(points[i - 1], points[i], points[(i + 1) % n],
                                                1)
        else:
            j = min(max(i - 1, 0), n - 3)
            tangents[chain[i]] = circle_tangent(points[j], points[j + 1], points[j + 2], i - j)
    return tangents


def line_frames(tangents: np.ndarray, dim: int) -> np.ndarray:
    """Node frames (nodes, dim, dim) with r_x the tangent: r_y = z x t in the x-y plane (x x t
    for a tangent within 25 degrees of z), r_z = t x r_y (``straight_reference``'s frames)."""
    if dim == 2:
        t = tangents[:, :2] / np.linalg.norm(tangents[:, :2], axis=1, keepdims=True)
        return np.stack([t, np.column_stack([-t[:, 1], t[:, 0]])], axis=-1)
    helper = np.where(np.abs(tangents[:, 2:3]) < 0.9, [[0.0, 0.0, 1.0]], [[1.0, 0.0, 0.0]])
    normal = np.cross(helper, tangents)
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    return np.stack([tangents, normal, np.cross(tangents, normal)], axis=-1)


def line_references(kind: ElementKind, positions: np.ndarray, connectivity: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(connectivity oriented along the chain, element references (elements, ndof), element
    lengths (elements,) in m) of a line mesh (positions (nodes, dim) in m)."""
    curved_reference_check(kind, "file mesh")
    rows, chain, closed = line_chain(connectivity, kind)
    points = np.zeros((len(positions), 3))
    points[:, :kind.dim] = positions
    tangents = chain_tangents(points, chain, closed)
    frames = line_frames(tangents, kind.dim)
    first = int(np.argmin(kind.node_fractions[:, 0]))
    last = int(np.argmax(kind.node_fractions[:, 0]))
    a, b = rows[:, first], rows[:, last]
    chord = np.linalg.norm(points[b] - points[a], axis=1)
    phi = np.arccos(np.clip(np.sum(tangents[a] * tangents[b], axis=1), -1.0, 1.0))
    small = phi < 1e-8
    lengths = np.where(small, chord, chord * phi / (2 * np.sin(np.where(small, 1.0, phi) / 2)))
    e0s = np.array([frame_reference(kind, positions[row], frames[row]) for row in rows])
    return rows, e0s, lengths


# --------------------------------------------------------------------------- surfaces

def _corners(kind: ElementKind) -> tuple[int, int, int]:
    """Local indices of the corners at (0, 0), (1, 0) and (0, 1) of the meshed axes."""
    fractions = kind.node_fractions[:, :2]
    return tuple(int(np.flatnonzero(np.all(np.isclose(fractions, p), axis=1))[0])
                 for p in ((0, 0), (1, 0), (0, 1)))


def element_sides(kind: ElementKind, positions: np.ndarray, connectivity: np.ndarray
                  ) -> np.ndarray:
    """Sides (elements, 2) in m of surface elements: the chords from the first corner to the
    corners along local x and y."""
    o, x, y = _corners(kind)
    rows = positions[connectivity]
    return np.stack([np.linalg.norm(rows[:, x] - rows[:, o], axis=1),
                     np.linalg.norm(rows[:, y] - rows[:, o], axis=1)], axis=1)


def surface_normals(kind: ElementKind, positions: np.ndarray, connectivity: np.ndarray
                    ) -> np.ndarray:
    """Unit normals (elements, n_nodes, 3) of each element's interpolated surface at its
    nodes: r0_x x r0_y from the position shape functions (kinds without in-plane gradients;
    with them, the normal of the corners' plane).  The direction does not depend on the
    element's parameter extents, so one table of shape gradients serves every element."""
    o, x, y = _corners(kind)
    rows = positions[connectivity]                         # (elements, n, 3)
    if carries_in_plane_gradients(kind):
        normal = np.cross(rows[:, x] - rows[:, o], rows[:, y] - rows[:, o])
        normal /= np.linalg.norm(normal, axis=1, keepdims=True)
        return np.repeat(normal[:, None, :], kind.n_nodes, axis=1)
    family = kernel_family(kind.name, "invariants", "numpy")
    unit = (1.0, 1.0, 1.0)
    points = kind.node_points(*unit).copy()
    points[:, 2] = 0.0
    grads = invariants.full_gradients(kind, invariants.shape_gradient_table(
        kind, family, unit, points))                       # (n, n_shape, 3)
    q0 = np.zeros((len(rows), kind.n_shape, 3))
    q0[:, list(kind.position_vectors)] = rows - rows[:, :1]
    j0 = np.einsum("eka,pkb->epab", q0, grads)             # (elements, n, 3, 3)
    normal = np.cross(j0[..., 0], j0[..., 1])
    length = np.linalg.norm(normal, axis=-1, keepdims=True)
    _check_degenerate(length[..., 0], np.linalg.norm(j0[..., :2], axis=-2).prod(axis=-1))
    return normal / length


def _check_degenerate(measure: np.ndarray, scale: np.ndarray) -> None:
    """MeshGeometryError where an element's surface (or line) degenerates at a node: a
    ``measure`` (elements, n) below 1e-12 of its ``scale``, or not finite."""
    bad = ~(measure > 1e-12 * scale)
    if bad.any():
        e, k = (int(i) for i in np.argwhere(bad)[0])
        raise MeshGeometryError(f"element {e} degenerates at its node {k} (its sides there "
                                "are parallel or of zero length); expected cells of positive "
                                "area with distinct points")


def node_normals(normals: np.ndarray, connectivity: np.ndarray, nodes: int) -> np.ndarray:
    """Unit normals (nodes, 3): the normalised sum of the element normals (elements, n, 3)
    at each node.  MeshGeometryError where two elements' normals at a node point opposite
    ways (cells of opposite orientation) or differ by more than CREASE_DEG (a crease)."""
    total = np.zeros((nodes, 3))
    np.add.at(total, connectivity.ravel(), normals.reshape(-1, 3))
    length = np.linalg.norm(total, axis=1, keepdims=True)
    mean = total / np.where(length > 0, length, 1.0)
    cosine = np.sum(normals * mean[connectivity], axis=2)   # (elements, n)
    worst = np.unravel_index(np.argmin(cosine), cosine.shape)
    if cosine[worst] < np.cos(np.radians(CREASE_DEG)):
        node = int(connectivity[worst])
        sharing = sorted({int(e) for e in np.argwhere(connectivity == node)[:, 0]})
        angles = [float(np.degrees(np.arccos(np.clip(normals[e][connectivity[e] == node][0]
                                                      @ normals[worst[0]][worst[1]], -1, 1))))
                  for e in sharing]
        if max(angles) > 90:
            raise MeshGeometryError(
                f"elements {', '.join(map(str, sharing))} meet at node {node} with opposite "
                "orientations (their normals point opposite ways); expected every cell "
                "numbered the same way round (counter-clockwise seen from one side)")
        raise MeshGeometryError(
            f"elements {', '.join(map(str, sharing))} meet at node {node} at a crease (their "
            f"normals differ by up to {max(angles):.3g} degrees, more than {CREASE_DEG:g}); "
            "one shared normal r_z needs a smooth surface: split the body at the crease")
    return mean


def surface_references(kind: ElementKind, positions: np.ndarray, connectivity: np.ndarray,
                       normals: np.ndarray | None = None
                       ) -> tuple[np.ndarray, np.ndarray]:
    """(element references (elements, ndof), sides (elements, 2) in m) of a surface mesh
    (positions (nodes, 3) in m; ``normals`` (nodes, 3) to use instead of the surface's,
    unit vectors oriented as the cells)."""
    curved_reference_check(kind, "file mesh")
    sides = element_sides(kind, positions, connectivity)
    element_normals = surface_normals(kind, positions, connectivity)
    computed = node_normals(element_normals, connectivity, len(positions))
    if normals is not None:
        against = np.flatnonzero(np.sum(normals * computed, axis=1) <= 0)
        if against.size:
            raise MeshGeometryError(f"the normal given at node {int(against[0])} points "
                                    "against the orientation of its cells; expected normals "
                                    "on the side the cells' numbering turns towards")
        computed = normals
    if carries_in_plane_gradients(kind):
        frames = _aligned_frames(kind, positions, connectivity, computed)
    else:
        frames = _normal_frames(computed)
    e0s = np.array([frame_reference(kind, positions[row], frames[row])
                    for row in connectivity])
    return e0s, sides


def _normal_frames(normals: np.ndarray) -> np.ndarray:
    """Orthonormal frames (nodes, 3, 3) whose third column is the normal (the first two, any
    tangent pair, are not used by kinds that carry r_z only)."""
    helper = np.where(np.abs(normals[:, 0:1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    t1 = helper - np.sum(helper * normals, axis=1, keepdims=True) * normals
    t1 /= np.linalg.norm(t1, axis=1, keepdims=True)
    return np.stack([t1, np.cross(normals, t1), normals], axis=-1)


def _aligned_frames(kind: ElementKind, positions: np.ndarray, connectivity: np.ndarray,
                    normals: np.ndarray) -> np.ndarray:
    """The common frame (nodes, 3, 3) of a flat mesh of rectangles with parallel sides, the
    only surface mesh whose nodes can share in-plane gradients; MeshGeometryError else."""
    o, x, y = _corners(kind)
    rows = positions[connectivity]
    ex, ey = rows[:, x] - rows[:, o], rows[:, y] - rows[:, o]
    ex /= np.linalg.norm(ex, axis=1, keepdims=True)
    ey /= np.linalg.norm(ey, axis=1, keepdims=True)
    frame = np.column_stack([ex[0], ey[0], np.cross(ex[0], ey[0])])
    scale = np.ptp(positions, axis=0).max()
    height = (positions - positions[0]) @ frame[:, 2]
    rectangle = np.abs(np.sum(ex * ey, axis=1)) <= SAME
    opposite = np.all(np.isclose(rows[:, x] - rows[:, o], rows[:, _far(kind)]
                                 - rows[:, y], rtol=0, atol=SAME * scale), axis=1)
    aligned = (np.abs(ex - ex[0]).max(axis=1) <= SAME) & (np.abs(ey - ey[0]).max(axis=1) <= SAME)
    bad = np.flatnonzero(~(rectangle & opposite & aligned))
    if np.abs(height).max() > SAME * scale or bad.size:
        what = ("the mesh is not flat" if np.abs(height).max() > SAME * scale else
                f"element {int(bad[0])} is not a rectangle with sides parallel to element 0's")
        raise MeshGeometryError(
            f"{kind.name} nodes carry r_x and r_y, which every element sharing a node uses as "
            f"its own: elements meeting at a slope or with turned sides would need a "
            f"transformation of the gradients between them (the slope discontinuity of "
            f"Shabana and Mikkola), so a {kind.name} mesh must be flat rectangles with one "
            f"common frame, and {what}; for curved or unstructured meshes use shell3d_3833 "
            f"(r, r_z, r_zz: only the normal is shared)")
    return np.broadcast_to(frame, (len(positions), 3, 3))


def solid_references(kind: ElementKind, positions: np.ndarray, connectivity: np.ndarray
                     ) -> tuple[np.ndarray, np.ndarray]:
    """(element references (elements, ndof), sides (elements, 3) in m) of a solid mesh of
    boxes with one common, right-handed frame (the module docstring); MeshGeometryError
    naming the first element that is not such a box."""
    points = kind.node_fractions
    rows = positions[connectivity]                              # (elements, nodes, 3)
    corner = [int(np.flatnonzero(np.all(np.isclose(points, p), axis=1))[0])
              for p in ((0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1))]
    edges = np.stack([rows[:, c] - rows[:, corner[0]] for c in corner[1:]], axis=-1)
    sides = np.linalg.norm(edges, axis=1)                       # (elements, 3)
    scale = np.ptp(positions, axis=0).max()
    flat = np.flatnonzero(~(sides.min(axis=1) > 1e-12 * scale))
    if flat.size:
        raise MeshGeometryError(f"element {int(flat[0])} has an edge of zero length from its "
                                "first corner; expected cells of positive volume")
    frames = edges / sides[:, None, :]
    frame = frames[0]
    expected = rows[:, corner[0], None, :] + np.einsum("nk,eak->ena", points, edges)
    box = np.all(np.abs(expected - rows) <= SAME * scale, axis=(1, 2))
    aligned = np.abs(frames - frame).max(axis=(1, 2)) <= SAME
    bad = np.flatnonzero(~(box & aligned))
    if np.abs(frame.T @ frame - np.eye(3)).max() > SAME or np.linalg.det(frame) <= 0:
        bad = np.array([0])
    if bad.size:
        raise MeshGeometryError(
            f"element {int(bad[0])} is not a box with edges along element 0's axes (a "
            f"right-handed orthogonal triple from its first corner); {kind.name} nodes carry "
            f"r_x, r_y and r_z, which every element sharing a node uses as its own, so its "
            f"mesh must be boxes of one common frame")
    e0s = np.array([frame_reference(kind, positions[row],
                                    np.broadcast_to(frame, (len(row), 3, 3)))
                    for row in connectivity])
    return e0s, sides


def _far(kind: ElementKind) -> int:
    """Local index of the corner at (1, 1)."""
    fractions = kind.node_fractions[:, :2]
    return int(np.flatnonzero(np.all(np.isclose(fractions, (1, 1)), axis=1))[0])


# --------------------------------------------------------------------------- shapes

def shape_groups(kind: ElementKind, e0s: np.ndarray) -> np.ndarray:
    """Index (elements,) of each element's shape, numbered in order of first appearance:
    elements of one index are congruent (their references are rigid placements of one
    another), so they share one set of invariants.  Compared by the Gram matrices Q0 Q0^T
    relative to the first node, on a grid of ``SAME`` times the largest entry (two elements
    in one cell differ by less; congruent elements either side of a cell's edge only make
    one group more)."""
    q = e0s.reshape(len(e0s), kind.n_shape, kind.dim).copy()
    positions = list(kind.position_vectors)
    q[:, positions] -= q[:, positions[:1]]
    grams = np.einsum("eka,ela->ekl", q, q)
    cells = np.round(grams / (SAME * np.abs(grams).max())).astype(np.int64)
    _, first, inverse = np.unique(cells.reshape(len(e0s), -1), axis=0, return_index=True,
                                  return_inverse=True)
    return np.argsort(np.argsort(first))[inverse.ravel()]
