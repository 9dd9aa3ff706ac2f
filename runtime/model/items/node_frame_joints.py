"""Joints between two ANCF nodes about axes fixed in their sections (``[[constraint]]``
types ``prismatic``, ``cylindrical`` and ``universal``, ``nodes = ["A:i", "B:j"]``, the
``axis`` global at t = 0).  A node's points and directions are fixed combinations of its
position and gradients that are those points and directions at t = 0
(``runtime.model.items.body_vectors``), so every row is a dot product of two affine maps
of the coordinates: a quadratic block with constant Hessians, bilinear in the two nodes'
coordinates (``runtime.model.holonomic``), as the rows of the rigid bodies' joints.

* prismatic (A carries the line): B's position keeps on the line through A's point at B's
  place at t = 0 along the axis fixed in A's section ((r_B - r_Q) . n_k(A) = 0 for two
  normals n_k of the axis: 1 row in 2D), and B's frame keeps its orientation relative to
  A's (the small rotation of ``body_vectors.frame_rows``: 3 rows, 1 in 2D): 5 rows, the
  slide along the axis left, or prescribed by a ``displacement`` law d(t) (m, from t = 0:
  the rheonomic row a . (r_B - r_Q) - d(t) = 0, as a ``body_prismatic``'s);
* cylindrical (the axis a fixed in A, the line and its normals n_k in B): a . n_k(B) = 0
  and (r_A - r_Q) . n_k(B) = 0 with Q B's point at A's place at t = 0: 4 rows, a rotation
  about and a slide along the axis left;
* universal (the nodes at one place): the position is shared (3 linear rows) and A's
  ``axis`` stays normal to B's ``other_axis`` (1 row, the cross of a Cardan joint): two
  rotations left.

The nodes of a prismatic or cylindrical joint may be apart at t = 0, B's position on the
axis through A's.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from runtime.model.errors import SceneError
from runtime.model.holonomic import Driver
from runtime.model.items import body_vectors as vectors
from runtime.model.items.axis_joints import check_normal
from runtime.model.items.base import ModelView
from runtime.model.items.body_joints import driven_travel, motion_key
from runtime.model.items.constraints import Built, Joint, NodePair, normals_of
from runtime.model.schema import Context, NodeRef, Record, key, unit_axis
from runtime.model.time_laws import Law

__all__ = ["Cylindrical", "Prismatic", "Universal"]

#: the second node lies on the axis through the first at t = 0 to this, relative to the
#: scene's size
ON_AXIS = 1e-9


def _axis_key(value: Any, path: str, context: Context) -> tuple[float, ...]:
    return unit_axis(value, path, context.dim)


def _place(context: Context, node: NodeRef) -> np.ndarray:
    """The position (dim,) of ``node`` at t = 0 (m)."""
    return np.asarray(context.node.bodies[node.body].node_position(node.index), float)


def _reference_position(model: ModelView, node: NodeRef) -> np.ndarray:
    return model.reference[model.node_dofs(model.node_index(node), "r")]


@dataclass(frozen=True)
class NodeLine(NodePair):
    """Base of the prismatic and cylindrical joints: the second node on the line along the
    global ``axis`` through the first at t = 0 (SceneError at ``nodes`` otherwise)."""

    @classmethod
    def parse(cls, data: dict, path: str, context: Context) -> Record:
        joint = super().parse(data, path, context)
        first, second = (_place(context, node) for node in joint.nodes)
        offset = second - first
        axis = np.asarray(joint.axis)
        across = offset - (offset @ axis) * axis
        scale = max(1.0, float(np.abs(first).max()), float(np.abs(second).max()))
        if np.linalg.norm(across) > ON_AXIS * scale:
            raise SceneError(f"{path}.nodes: the second node must lie on the axis through "
                             f"the first at t = 0 (its offset is the slide's rest value); "
                             f"{joint.nodes[1]} is {np.linalg.norm(across):.6g} m off the "
                             f"line through {joint.nodes[0]} along "
                             f"{tuple(float(x) for x in axis)}")
        return joint


@dataclass(frozen=True)
class Prismatic(NodeLine):
    """A slide along the ``axis`` (global at t = 0, default z; x in 2D), fixed in the first
    node's section, of the second node, whose frame keeps its orientation relative to the
    first's (module docstring): 5 rows in 3D, 2 in 2D, and one more with a
    ``displacement`` law.  Both nodes carry a frame."""

    type: ClassVar[str] = "prismatic"
    axis: tuple[float, ...] | None = key(_axis_key, None)
    displacement: Law | None = key(motion_key("a displacement in m"), None)

    def drivers(self) -> tuple[Driver, ...]:
        return () if self.displacement is None else (Driver(self.displacement),)

    @classmethod
    def parse(cls, data: dict, path: str, context: Context) -> Record:
        joint = super().parse(data, path, context)
        for k, node in enumerate(joint.nodes):
            vectors.check_frame_node(node, f"{path}.nodes[{k}]", context,
                                     "a prismatic joint holds")
        return joint

    def resolved(self, context: Context) -> Prismatic:
        if self.axis is None:
            return dataclasses.replace(self, axis=(0.0, 0.0, 1.0) if context.dim == 3
                                       else (1.0, 0.0))
        return self

    def rows(self, dim: int, per_node: int) -> int:
        return (5 if dim == 3 else 2) + (self.displacement is not None)

    def apply(self, model: ModelView, built: Built) -> None:
        first, second = self.nodes
        owner = f"{self.type} of {first} and {second}"
        axis = np.asarray(self.axis)
        here = vectors.point(model, second, _reference_position(model, second))
        built.blocks.append(vectors.frame_rows(model, here, first, normals_of(axis), owner,
                                               second))
        if self.displacement is not None:   # a . (r_B - r_Q) - d(t) = 0
            built.blocks.append(driven_travel(vectors.frame_rows(
                model, here, first, axis[None, :], f"{owner} (displacement)"),
                built.drivers[0]))


@dataclass(frozen=True)
class Cylindrical(NodeLine):
    """A rotation about and a slide along the ``axis`` (global at t = 0, default z), a
    fixed combination of the first node's gradients (it must lie in their span), the line
    and two normals of the axis fixed in the second node's section (module docstring):
    4 rows.  The second node carries a frame."""

    type: ClassVar[str] = "cylindrical"
    dims: ClassVar[tuple[int, ...]] = (3,)
    dims_message: ClassVar[str] = ("a cylindrical joint is 3D (3D scenes only); in 2D a "
                                   "prismatic")
    axis: tuple[float, ...] = key(_axis_key, (0.0, 0.0, 1.0))

    @classmethod
    def parse(cls, data: dict, path: str, context: Context) -> Record:
        joint = super().parse(data, path, context)
        vectors.check_frame_node(joint.nodes[1], f"{path}.nodes[1]", context,
                                 "a cylindrical joint's line and the normals of its axis "
                                 "turn with")
        return joint

    def rows(self, dim: int, per_node: int) -> int:
        return 4

    def apply(self, model: ModelView, built: Built) -> None:
        first, second = self.nodes
        owner = f"{self.type} of {first} and {second}"
        axis = np.asarray(self.axis)
        mine = vectors.direction(model, first, axis, f"{self.type}: axis")
        place = _reference_position(model, first)
        slide = vectors.point(model, first, place) - vectors.point(
            model, second, place, f"{owner}: the first node's offset")
        normals = [vectors.direction(model, second, n, f"{owner}: the normal of the axis")
                   for n in normals_of(axis)]
        built.blocks.append(vectors.dot_rows(owner, [(mine, n) for n in normals]
                                             + [(slide, n) for n in normals]))


@dataclass(frozen=True)
class Universal(Joint):
    """A Cardan joint: the nodes (at one place) share their position, and the first node's
    ``axis`` stays normal to the second's ``other_axis`` (both global at t = 0, normal to
    each other, each a fixed combination of its node's gradients; module docstring):
    4 rows, the rotations about both axes left."""

    type: ClassVar[str] = "universal"
    dims: ClassVar[tuple[int, ...]] = (3,)
    dims_message: ClassVar[str] = ("a universal joint is 3D (3D scenes only); in 2D a "
                                   "spherical joint")
    axis: tuple[float, ...] = key(_axis_key, (0.0, 0.0, 1.0))
    other_axis: tuple[float, ...] = key(_axis_key, (1.0, 0.0, 0.0))

    @classmethod
    def parse(cls, data: dict, path: str, context: Context) -> Record:
        joint = super().parse(data, path, context)
        check_normal(np.asarray(joint.axis), np.asarray(joint.other_axis),
                     f"{path}.other_axis", "axis")
        return joint

    def rows(self, dim: int, per_node: int) -> int:
        return 4

    def apply(self, model: ModelView, built: Built) -> None:
        super().apply(model, built)
        first, second = self.nodes
        built.blocks.append(vectors.dot_rows(f"{self.type} of {first} and {second}", [(
            vectors.direction(model, first, np.asarray(self.axis), f"{self.type}: axis"),
            vectors.direction(model, second, np.asarray(self.other_axis),
                              f"{self.type}: other_axis"))]))
