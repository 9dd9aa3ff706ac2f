"""Points and directions of the sides of joints as affine functions of the model's
coordinates, and constraint rows that are their dot products (quadratic blocks,
``runtime.model.holonomic``).

A side is the ground (None), a rigid body (its name) or a node of a meshed body (a
``NodeRef``).  In natural coordinates a body point and a body direction are linear in the
body's 12 coordinates (``runtime.model.items.rigid.natural_map``; in 2D its 4); a node's point and
direction are fixed combinations r + G c and G c of its position r and its gradients G
(r_x, r_y (, r_z): its section's frame, ``gradient_map``), c fixed at t = 0; a point or
direction of the ground is a constant.  So ``a . b`` of two of them is a quadratic form
with a constant Hessian: the rows of the joints whose axes are fixed in both sides
(cylindrical, universal, prismatic off the ground) and the deflection of a bushing.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from runtime.kernels.kind import element_kind
from runtime.model.errors import SceneError, show
from runtime.model.holonomic import QuadraticBlock
from runtime.model.items.base import ModelView
from runtime.model.items.constraints import gradient_map
from runtime.model.items.rigid import natural_map
from runtime.model.schema import Context, NodeRef

__all__ = ["Affine", "Side", "body_point", "check_frame_node", "combined", "direction", "dot_rows",
           "exclusive_sides", "frame_deflection", "frame_rows", "point", "side_axes",
           "side_axis", "side_of"]

#: the other side of a joint: the ground (None), a rigid body (its name) or a node
Side = str | NodeRef | None

#: an axis given in the frame of a node with one gradient lies along it to this (cosine)
ALONG = 1e-12


@dataclass(frozen=True)
class Affine:
    """A vector ``map @ q[dofs] + constant`` (dim,) of the coordinates ``dofs`` (k,), map
    (dim, k)."""

    dofs: np.ndarray
    map: np.ndarray
    constant: np.ndarray

    def __sub__(self, other: Affine) -> Affine:
        return Affine(np.concatenate([self.dofs, other.dofs]),
                      np.hstack([self.map, -other.map]), self.constant - other.constant)

    def at(self, q: np.ndarray) -> np.ndarray:
        """Its value (dim,) at the coordinates q (size,)."""
        return self.map @ q[self.dofs] + self.constant


def side_of(item) -> Side:
    """The other side of a joint or force element ``item``: its ``node``, else its rigid
    body ``other`` (None: the ground)."""
    node = getattr(item, "node", None)
    return node if node is not None else getattr(item, "other", None)


def exclusive_sides(data: dict, path: str) -> None:
    """SceneError when the table ``data`` names both a ``node`` and another body
    ``other`` as the other side."""
    if "node" in data and "other" in data:
        raise SceneError(f"{path}.other: expected a node or another body (or neither: "
                         "the ground), got both")


def check_frame_node(node: NodeRef | None, where: str, context: Context, needs: str) -> None:
    """SceneError at the key path ``where`` when the ``node`` (None: no node side) lacks the
    gradients of a frame fixed in it (r_x, r_y (, r_z) spanning the scene's space; a cable
    node's r_x fixes one direction only); ``needs`` says what needs the frame, as "a
    body_prismatic holds"."""
    if node is None:
        return
    kind = element_kind(context.node.bodies[node.body].element)
    if len(kind.first_gradients) < context.dim:
        raise SceneError(f"{where}: {needs} the node's frame, which needs its "
                         f"{('two', 'three')[context.dim - 2]} gradients "
                         f"{', '.join(('r_x', 'r_y', 'r_z')[:context.dim])} (a "
                         f"{'beam2d' if context.dim == 2 else 'beam3d or plate3d'} node); node "
                         f"{show(node.spelled())} of body {show(node.body)} ({kind.name}) "
                         f"carries only {', '.join(kind.vectors)}: enough for an axis along "
                         "a gradient (body_revolute, body_universal), not for a frame")


def side_axis(model: ModelView, side: Side, local: tuple[float, ...], what: str) -> np.ndarray:
    """The direction (3,) at t = 0 of the unit vector ``local`` given in the ``side``'s axes:
    global for the ground, a rigid body's axes, a node's reference frame (its gradients
    orthonormalised, ``ModelView.node_frame``).  A node whose one gradient fixes a single
    axis (a 3D cable's r_x) has that axis only: SceneError naming ``what`` unless ``local``
    lies along it."""
    local = np.asarray(local, float)
    if side is None:
        return local
    if not isinstance(side, NodeRef):
        return np.asarray(model.rigid[side].item.frame, float) @ local
    node = model.node_index(side)
    kind = model.bodies[side.body].kind
    if kind.frame_gap() is None:
        return model.node_frame(model.reference, node) @ local
    gradient = kind.first_gradients[0]
    axis = "xyz".index(gradient[-1])
    if abs(local[axis]) < 1.0 - ALONG:
        raise SceneError(f"{what}: node {show(side.spelled())} of body {show(side.body)} "
                         f"({kind.name}) has only {gradient} of a frame: expected an axis "
                         f"along its local {gradient[-1]}, got {tuple(float(x) for x in local)}")
    tangent = model.reference[model.node_dofs(node, gradient)]
    return np.sign(local[axis]) * tangent / np.linalg.norm(tangent)


def point(model: ModelView, side: Side, world: np.ndarray,
          what: str = "the joint's point") -> Affine:
    """The point of the ``side`` (module docstring) that is at ``world`` (dim,) at t = 0; on a
    node r + G c with G c the offset from the node at t = 0 (SceneError naming ``what``
    when the offset is not in the span of the node's gradients)."""
    world = np.asarray(world, float)
    dim = world.size
    if side is None:
        return Affine(np.zeros(0, np.int64), np.zeros((dim, 0)), world)
    if isinstance(side, NodeRef):
        node = model.node_index(side)
        offset = world - model.reference[model.node_dofs(node, "r")]
        dofs, mapping = gradient_map(model, node, offset, f"{what}: its offset from the node")
        start = dim * model.node_vectors(node).index("r")
        mapping[:, start:start + dim] += np.eye(dim)
        return Affine(dofs, mapping, np.zeros(dim))
    rigid = model.rigid[side]
    local = rigid.item.frame.T @ (world - np.asarray(rigid.item.position))
    return Affine(rigid.dofs, natural_map(local), np.zeros(dim))


def body_point(model: ModelView, body: str, local: tuple[float, ...]) -> Affine:
    """The point at body coordinates ``local`` of the rigid body or point mass ``body``."""
    dofs, mapping = model.rigid_point(body, local)
    return Affine(dofs, mapping, np.zeros(mapping.shape[0]))


def direction(model: ModelView, side: Side, world: np.ndarray,
              what: str = "the joint's direction") -> Affine:
    """The direction fixed in the ``side`` (module docstring) that is ``world`` (dim,) at
    t = 0; on a node a fixed combination G c of its gradients (SceneError naming ``what``
    when ``world`` is not in their span)."""
    world = np.asarray(world, float)
    dim = world.size
    if side is None:
        return Affine(np.zeros(0, np.int64), np.zeros((dim, 0)), world)
    if isinstance(side, NodeRef):
        dofs, mapping = gradient_map(model, model.node_index(side), world, what)
        return Affine(dofs, mapping, np.zeros(dim))
    rigid = model.rigid[side]
    local = rigid.item.frame.T @ world
    return Affine(rigid.dofs, natural_map(local) - natural_map(np.zeros(dim)), np.zeros(dim))


def dot_rows(owner: str, pairs: list[tuple[Affine, Affine]],
             constants: list[float] | None = None) -> QuadraticBlock:
    """The rows ``a . b + constant`` of the ``pairs`` (a, b) over the union of their
    coordinates (each once): H = A^T B + B^T A, g = A^T b0 + B^T a0, c = a0 . b0."""
    dofs = np.unique(np.concatenate([x.dofs for pair in pairs for x in pair]))
    k = dofs.size

    def spread(x: Affine) -> np.ndarray:
        full = np.zeros((x.map.shape[0], k))
        np.add.at(full.T, np.searchsorted(dofs, x.dofs), x.map.T)
        return full

    hessians, linear, constant = [], [], []
    for a, b in pairs:
        first, second = spread(a), spread(b)
        hessians.append(first.T @ second + second.T @ first)
        linear.append(first.T @ b.constant + second.T @ a.constant)
        constant.append(float(a.constant @ b.constant))
    if constants is not None:
        constant = [c + extra for c, extra in zip(constant, constants, strict=True)]
    return QuadraticBlock(owner, dofs, np.array(hessians).reshape(len(pairs), k, k),
                          np.array(linear).reshape(len(pairs), k), np.array(constant))


def combined(block: QuadraticBlock, matrix: np.ndarray) -> QuadraticBlock:
    """The rows ``matrix @ phi`` (matrix (n, rows)) of ``block``'s rows phi."""
    return QuadraticBlock(block.owner, block.dofs, np.tensordot(matrix, block.hessians, 1),
                          matrix @ block.linear, matrix @ block.constant)


def side_axes(model: ModelView, side: Side) -> np.ndarray:
    """The axes (rows, (dim, dim)) at t = 0 of the frame of a rigid body or of a node's
    reference frame (its gradients orthonormalised, ``ModelView.node_frame``)."""
    if isinstance(side, NodeRef):
        return model.node_frame(model.reference, model.node_index(side)).T
    return np.asarray(model.rigid[side].item.frame, float).T


def frame_rows(model: ModelView, here: Affine, side: Side, along: np.ndarray, owner: str,
               turning: Side = None) -> QuadraticBlock:
    """The displacement (m) of the point ``here`` (dim: a rigid body's point, a node's
    position) from the ``side``'s point Q that is there at t = 0, along the side's
    directions b_k that are the rows of ``along`` (n, dim) at t = 0: n rows
    (r_P - r_Q) . b_k; with ``turning`` (the side of P: a rigid body or a node with a
    frame) three more, the small rotation of its axes a_k (``side_axes``) relative to the
    side's directions b_k that are a_k at t = 0 (rad, the axial vector of the skew part of
    [a_i . b_j]: theta_1 = (a_2 . b_3 - a_3 . b_2) / 2, ...; it changes sign when the
    sides swap; in 2D one, the rotation about z, theta_3).  All 0 at t = 0, bilinear
    (linear to the ground)."""
    slide = here - point(model, side, here.at(model.reference), f"{owner}: the point")
    pairs = [(slide, direction(model, side, d, f"{owner}: the direction")) for d in along]
    n = len(pairs)
    if turning is None:
        return dot_rows(owner, pairs)
    axes = side_axes(model, turning)                      # a_k at t = 0 (rows)
    mine = [direction(model, turning, a) for a in axes]
    theirs = [direction(model, side, a, f"{owner}: the axis") for a in axes]
    planes = ((1, 2), (2, 0), (0, 1)) if len(axes) == 3 else ((0, 1),)
    for i, j in planes:                                   # a_i . b_j and a_j . b_i
        pairs += [(mine[i], theirs[j]), (mine[j], theirs[i])]
    matrix = np.zeros((n + len(planes), n + 2 * len(planes)))
    matrix[:n, :n] = np.eye(n)
    for k in range(len(planes)):
        matrix[n + k, n + 2 * k], matrix[n + k, n + 1 + 2 * k] = 0.5, -0.5
    return combined(dot_rows(owner, pairs), matrix)


def frame_deflection(model: ModelView, body: str, local: tuple[float, ...], side: Side,
                     owner: str) -> QuadraticBlock:
    """Six rows (``frame_rows``): the displacement of the point ``local`` of the rigid
    ``body`` from the ``side``'s point there at t = 0 along the side's directions that are
    the body's axes at t = 0 (m), and the small rotation of the body's axes relative to
    them (rad); all 0 at t = 0."""
    return frame_rows(model, body_point(model, body, local), side, side_axes(model, body),
                      owner, body)
