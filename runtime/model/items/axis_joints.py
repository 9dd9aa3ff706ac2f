"""Joints of rigid bodies about axes fixed in both sides (``[[constraint]]`` tables
``body_cylindrical`` and ``body_universal``): a rigid ``body`` joined at its point ``point``
(body coordinates) to another rigid body ``other``, to a ``node`` of a meshed body (its
points and directions fixed combinations of its position and gradients) or, without
either, to the ground.  Their rows are dot products of the sides' points and directions
(``runtime.model.items.body_vectors``: quadratic blocks with constant Hessians, linear rows
to the ground):

* cylindrical: the body's ``axis`` a stays normal to two directions n_1, n_2 of the other
  side that are normal to it at t = 0, and the point stays on the line through its place at
  t = 0 along the axis, (r_P - r_Q) . n_k = 0 (Q the other side's point at P at t = 0):
  4 rows, a rotation about and a slide along the axis left (on a node, the normals n_k
  and the point's offset from the node must lie in the span of its gradients);
* universal: the point is shared (3 rows) and the body's ``axis`` stays normal to the
  other side's ``other_axis`` (1 row a . b = 0, the cross of a Cardan joint; in the other
  body's coordinates, the node's reference frame or global for the ground): two rotations
  left.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from runtime.model.errors import SceneError
from runtime.model.items import body_vectors as vectors
from runtime.model.items.base import ModelView
from runtime.model.items.constraints import Built, Constraint, NodeSide, normals_of
from runtime.model.items.rigid import check_rigid_bodies, rigid_key
from runtime.model.schema import Context, NodeRef, Record, key, node_key, unit_axis, vector

__all__ = ["BodyCylindrical", "BodyUniversal", "check_normal"]

#: the two axes of a universal joint are normal at t = 0 to this (cosine of their angle)
NORMAL = 1e-9


def _point_key(value: Any, path: str, context: Context) -> tuple[float, ...]:
    return vector(value, path, 3, "a point in body coordinates, m")


def _axis_key(value: Any, path: str, context: Context) -> tuple[float, ...]:
    return unit_axis(value, path)


@dataclass(frozen=True)
class AxisJoint(NodeSide, Constraint):
    """Base of the joints of this module (module docstring): the rigid ``body``, its
    ``point`` and ``axis`` (body coordinates), the other side: the rigid body ``other`` or
    the ``node`` (neither: the ground)."""

    dims: ClassVar[tuple[int, ...]] = (3,)
    dims_message: ClassVar[str] = ("cylindrical and universal joints are 3D (3D scenes only); "
                                   "in 2D a body_revolute or a body_prismatic")
    body: str = key(rigid_key)
    point: tuple[float, ...] = key(_point_key, (0.0, 0.0, 0.0))
    axis: tuple[float, ...] = key(_axis_key, (0.0, 0.0, 1.0))
    other: str | None = key(rigid_key, None)
    node: NodeRef | str | None = key(node_key, None)

    @classmethod
    def parse(cls, data: dict, path: str, context: Context) -> Record:
        vectors.exclusive_sides(data, path)
        joint = super().parse(data, path, context)
        check_rigid_bodies(joint, path, context, f"a {cls.type} joint needs a rigid body")
        return joint


    @property
    def target_key(self) -> str:
        return "body"

    def _frame(self, model: ModelView) -> tuple[vectors.Affine, np.ndarray]:
        """(r_P - r_Q (Q: the other side's point at P at t = 0), the axis at t = 0 (3,))."""
        here = vectors.body_point(model, self.body, self.point)
        frame = model.rigid[self.body].item.frame
        there = vectors.point(model, vectors.side_of(self), here.at(model.reference),
                              f"{self.type} of {self.body}: the point")
        return here - there, frame @ np.asarray(self.axis)


@dataclass(frozen=True)
class BodyCylindrical(AxisJoint):
    """A rotation about and a slide along the ``axis`` (module docstring)."""

    type: ClassVar[str] = "body_cylindrical"

    def apply(self, model: ModelView, built: Built) -> None:
        slide, axis = self._frame(model)
        mine = vectors.direction(model, self.body, axis)
        normals = [vectors.direction(model, vectors.side_of(self), n,
                                     f"{self.type} of {self.body}: the normal of the axis")
                   for n in normals_of(axis)]
        built.blocks.append(vectors.dot_rows(
            f"{self.type} of {self.body}", [(mine, n) for n in normals]
            + [(slide, n) for n in normals]))


def _other_axis_key(value: Any, path: str, context: Context) -> tuple[float, ...]:
    return unit_axis(value, path)


@dataclass(frozen=True)
class BodyUniversal(AxisJoint):
    """A shared point and the ``axis`` normal to ``other_axis`` (the other body's
    coordinates, the node's reference frame; global for the ground), normal to each other
    at t = 0 (module docstring)."""

    type: ClassVar[str] = "body_universal"
    other_axis: tuple[float, ...] = key(_other_axis_key, (1.0, 0.0, 0.0))

    @classmethod
    def parse(cls, data: dict, path: str, context: Context) -> Record:
        joint = super().parse(data, path, context)
        if joint.node is None:     # a node's frame is known with the model (``apply``)
            mine = np.array(context.rigid[joint.body].frame) @ np.asarray(joint.axis)
            theirs = np.asarray(joint.other_axis) if joint.other is None else (
                np.array(context.rigid[joint.other].frame) @ np.asarray(joint.other_axis))
            check_normal(mine, theirs, f"{path}.other_axis")
        return joint

    def apply(self, model: ModelView, built: Built) -> None:
        slide, axis = self._frame(model)
        side = vectors.side_of(self)
        owner = f"{self.type} of {self.body}"
        theirs = vectors.side_axis(model, side, self.other_axis, f"{owner}: other_axis")
        if self.node is not None:
            check_normal(axis, theirs, f"{owner}: other_axis (the node's reference frame)")
        unit = [vectors.direction(model, None, e) for e in np.eye(3)]
        built.blocks.append(vectors.dot_rows(
            owner, [(slide, e) for e in unit]
            + [(vectors.direction(model, self.body, axis),
                vectors.direction(model, side, theirs, f"{owner}: other_axis"))]))


def check_normal(mine: np.ndarray, theirs: np.ndarray, where: str,
                 first: str = "the body's axis") -> None:
    """SceneError at ``where`` unless the axes ``mine`` and ``theirs`` (3,; unit, global
    at t = 0) are normal to each other (``NORMAL``); ``first`` names ``mine``."""
    if abs(float(mine @ theirs)) > NORMAL:
        raise SceneError(f"{where}: expected an axis normal to {first} at t = 0 "
                         f"(the cross of the joint), got an angle of "
                         f"{np.degrees(np.arccos(np.clip(mine @ theirs, -1, 1))):.6g} degrees")
