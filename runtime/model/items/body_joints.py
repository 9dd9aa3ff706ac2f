"""Joints of rigid bodies (``[[constraint]]`` tables ``body_spherical``, ``body_revolute``):
a point of a rigid ``body`` (body coordinates ``point``) joined to the ground (where the
point is at t = 0), to a ``node`` of a meshed body, or to the point ``other_point`` of another
rigid body ``other``, at the same place at t = 0.

In natural coordinates a body point is linear in the coordinates (``natural_map``), so the
spherical rows ``r_P - r_Q = 0`` are linear joint rows (``A q = 0``) between bodies and nodes,
and quadratic blocks (``runtime.model.holonomic``) with a constant to the ground.  The
revolute joint adds two rows ``a . b_k = 0``: the joint axis ``a`` (the body's ``axis``,
body coordinates, its direction at t = 0 shared by the other side) on one side, two unit
vectors b_1, b_2 normal to it at t = 0 on the other: on the ground (constants: linear rows),
on another body (bilinear: quadratic rows), or on a node, whose axis is a fixed combination
of its gradient vectors (``G c = a`` at the reference; bilinear rows with the body's normals).

A revolute joint's ``angle`` law theta(t) adds the rheonomic row sin(theta - phi) = 0 on the
body's rotation phi about the axis relative to the other side (``angle_forms``), a
prismatic joint's ``displacement`` law d(t) the row a . (r_P - r_Q) - d(t) = 0; their time
coefficients are driver coordinates of the model (``runtime.model.holonomic.DrivenBlock``).
The prismatic joint slides on the ground or, with ``other``, on another rigid body, or,
with ``node``, on a node's frame (``runtime.model.items.body_vectors``).

In 2D scenes (planar natural coordinates, ``runtime.model.items.rigid``) the same rows are
written for two components: a spherical joint and a revolute joint are the same pin (2
rows; the axis is z), the revolute's ``angle`` drives the rotation about z by the rows
[u . u', u . v'] = [cos phi, sin phi], a prismatic joint has one row across its axis and,
for a rigid body, one rotation lock, a weld ties each of the node's gradients to a fixed
combination of the body's u and v = perp(u) (2 rows per gradient).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from runtime.model.errors import SceneError, show
from runtime.model.holonomic import DrivenBlock, Driver, QuadraticBlock
from runtime.model.items import body_vectors as vectors
from runtime.model.items.base import ModelView
from runtime.model.items.constraints import Built, Constraint, NodeSide, normals_of
from runtime.model.items.rigid import PERP, RigidBody, planar_defaults, rigid_key
from runtime.model.schema import (
    Context,
    NodeRef,
    Record,
    key,
    law_key,
    node_key,
    unit_axis,
    vector,
)
from runtime.model.time_laws import Law

__all__ = ["BodyPrismatic", "BodyRevolute", "BodySpherical", "BodyWeld", "angle_forms",
           "driven_travel", "motion_key"]

#: the joined points must coincide at t = 0 to this, relative to the scene's size
COINCIDENT = 1e-9
#: a prescribed joint motion starts at 0 to this (rad or m)
MOTION_START = 1e-12


def _point_key(value: Any, path: str, context: Context) -> tuple[float, ...]:
    return vector(value, path, context.dim, f"a point in body coordinates, m, {context.dim}D")


def _axis_key(value: Any, path: str, context: Context) -> tuple[float, ...]:
    return unit_axis(value, path)


def _world_point(context: Context, name: str, point: tuple[float, ...]) -> np.ndarray:
    item = context.rigid[name]
    if isinstance(item, RigidBody):
        return item.frame @ np.asarray(point, float) + np.asarray(item.position)
    if item.node is not None:
        return np.asarray(context.node.bodies[item.node.body].node_position(item.node.index))
    return np.asarray(item.position, float)


@dataclass(frozen=True)
class BodySpherical(NodeSide, Constraint):
    """A point of a rigid ``body`` held at a point (module docstring): shared position."""

    type: ClassVar[str] = "body_spherical"
    body: str = key(rigid_key)
    point: tuple[float, ...] = key(_point_key, (0.0, 0.0, 0.0))
    node: NodeRef | str | None = key(node_key, None)
    other: str | None = key(rigid_key, None)
    other_point: tuple[float, ...] = key(_point_key, (0.0, 0.0, 0.0))

    @classmethod
    def parse(cls, data: dict, path: str, context: Context) -> Record:
        vectors.exclusive_sides(data, path)
        if "other_point" in data and "other" not in data:
            raise SceneError(f"{path}.other_point: a point of another body needs other")
        joint = super().parse(data, path, context)
        if joint.other == joint.body:
            raise SceneError(f"{path}.other: expected another body than {show(joint.body)}")
        here = _world_point(context, joint.body, joint.point)
        there = joint.target_point(context)
        scale = max(1.0, float(np.abs(here).max()), float(np.abs(there).max()))
        if np.abs(here - there).max() > COINCIDENT * scale:
            raise SceneError(f"{path}.point: the joined points must coincide at t = 0; "
                             f"the body point is at {tuple(round(x, 12) for x in here)}, the "
                             f"other at {tuple(round(x, 12) for x in there)}")
        if isinstance(joint, BodyRevolute) and not isinstance(context.rigid[joint.body],
                                                             RigidBody):
            raise SceneError(f"{path}.body: a revolute joint needs a rigid body (type = "
                             f"\"rigid\"), got the point mass {show(joint.body)}")
        return joint

    def resolved(self, context: Context) -> Record:
        return planar_defaults(self, context, ("point",) if self.other is None
                               else ("point", "other_point"))

    @property
    def target_key(self) -> str:
        return "node"

    def target_point(self, context: Context) -> np.ndarray | None:
        """Where the other side is at t = 0 (the ground: where the body point is)."""
        if self.node is not None:
            body = context.node.bodies[self.node.body]
            return np.asarray(body.node_position(self.node.index), float)
        if self.other is not None:
            return _world_point(context, self.other, self.other_point)
        return _world_point(context, self.body, self.point)

    def _side(self, model: ModelView) -> tuple[np.ndarray, np.ndarray]:
        return model.rigid_point(self.body, self.point)

    def _other_side(self, model: ModelView) -> tuple[np.ndarray, np.ndarray] | None:
        """(coordinates, map (dim, k)) of the other point, None for the ground."""
        if self.node is not None:
            return model.node_dofs(model.node_index(self.node), "r"), np.eye(model.dim)
        if self.other is not None:
            return model.rigid_point(self.other, self.other_point)
        return None

    def apply(self, model: ModelView, built: Built) -> None:
        dofs, point = self._side(model)
        other = self._other_side(model)
        if other is None:      # r_P = its place at t = 0: linear rows with a constant
            place = point @ model.reference[dofs]
            built.blocks.append(QuadraticBlock(f"{self.type} of {self.body}", dofs,
                                               np.zeros((point.shape[0], dofs.size,
                                                         dofs.size)), point, -place))
            return
        other_dofs, other_point = other
        for c in range(point.shape[0]):
            row: dict[int, float] = {}
            for index, value in zip(dofs, point[c], strict=True):
                if value != 0.0:
                    row[int(index)] = row.get(int(index), 0.0) + float(value)
            for index, value in zip(other_dofs, other_point[c], strict=True):
                if value != 0.0:
                    row[int(index)] = row.get(int(index), 0.0) - float(value)
            built.rows.append(row)


def motion_key(what: str) -> Callable[[Any, str, Context], Law]:
    """A time law of prescribed joint motion (``what``: its unit), zero at t = 0: the
    motion is measured from the joint's pose at t = 0."""
    def parse(value: Any, path: str, context: Context) -> Law:
        law = law_key(value, path, context)
        start = law.value(0.0)
        if abs(start) > MOTION_START:
            raise SceneError(f"{path}: expected a law that is 0 at t = 0 ({what}, measured "
                             f"from the joint's pose at t = 0), got {start:.6g} at t = 0")
        return law
    return parse


def angle_forms(model: ModelView, body: str, axis: tuple[float, ...], side: vectors.Side,
                owner: str) -> QuadraticBlock:
    """The rotation phi of the rigid ``body`` about its ``axis`` (body coordinates)
    relative to the other ``side`` since t = 0, as two quadratic rows [e . e', e . f'] =
    [cos phi, sin phi] (times the lengths of the vectors): e a body vector normal to the
    axis, e' and f' = a x e' the side's vectors that are e and a x e at t = 0: fixed on the
    ground (linear rows), fixed combinations of another body's axes or of a node's
    gradients (bilinear rows; ``body_vectors.direction``).  In 2D (axis z) e = u, and e',
    f' are the body's u and v at t = 0."""
    frame = model.rigid[body].item.frame
    reference = (normals_of(frame @ np.asarray(axis)) if model.dim == 3
                 else frame.T)                                       # e', f' at t = 0
    mine = vectors.direction(model, body, reference[0])
    return vectors.dot_rows(owner, [(mine, vectors.direction(
        model, side, vector, f"{owner}: the reference direction")) for vector in reference])


def _row(block: QuadraticBlock, row: int, sign: float) -> QuadraticBlock:
    """Row ``row`` of ``block`` times ``sign``, as a block of its own."""
    pick = slice(row, row + 1)
    return QuadraticBlock(block.owner, block.dofs, sign * block.hessians[pick],
                          sign * block.linear[pick], sign * block.constant[pick])


@dataclass(frozen=True)
class BodyRevolute(BodySpherical):
    """A spherical joint that also keeps the body's ``axis`` (body coordinates) aligned with
    the other side's (module docstring): one relative rotation, about the axis.  With an
    ``angle`` law theta(t) (rad) that rotation is prescribed (a rheonomic row, module
    docstring)."""

    type: ClassVar[str] = "body_revolute"
    axis: tuple[float, ...] = key(_axis_key, (0.0, 0.0, 1.0),
                                  only_3d="a 2D revolute joint turns about z")
    angle: Law | None = key(motion_key("an angle in rad"), None)

    def drivers(self) -> tuple[Driver, ...]:
        if self.angle is None:
            return ()
        return Driver(self.angle, "cos"), Driver(self.angle, "sin")

    def apply(self, model: ModelView, built: Built) -> None:
        self._align(model, built)
        if self.angle is not None:
            self._drive(model, built)

    def _drive(self, model: ModelView, built: Built) -> None:
        """The row sin(theta) cos(phi) - cos(theta) sin(phi) = sin(theta - phi), with
        cos(phi) and sin(phi) the bilinear forms of ``angle_forms``."""
        forms = angle_forms(model, self.body, self.axis, vectors.side_of(self),
                            f"{self.type} of {self.body} (angle)")
        cosine, sine = built.drivers
        built.blocks.append(DrivenBlock(forms.owner, (_row(forms, 0, 1.0),
                                                      _row(forms, 1, -1.0)),
                                        (int(sine), int(cosine))))

    def _align(self, model: ModelView, built: Built) -> None:
        super().apply(model, built)
        if model.dim == 2:      # a pin: the axis is z on both sides
            return
        body = model.rigid[self.body]
        dofs = body.dofs
        frame = body.item.frame
        axis_world = frame @ np.asarray(self.axis)
        normals = normals_of(axis_world)
        mine = vectors.direction(model, self.body, axis_world)      # the body's axis a
        if self.node is None and self.other is None:      # normals fixed: linear rows
            for normal in normals:
                coefficients = normal @ mine.map
                built.rows.append({int(i): float(v) for i, v in zip(dofs, coefficients,
                                                                   strict=True) if v != 0.0})
            return
        if self.other is not None:       # the other body's normals b_k
            pairs = [(mine, vectors.direction(model, self.other, n)) for n in normals]
        else:                           # the node's axis a = G c, the body's normals
            theirs = vectors.direction(model, self.node, axis_world, f"{self.type}: the axis")
            pairs = [(theirs, vectors.direction(model, self.body, n)) for n in normals]
        built.blocks.append(vectors.dot_rows(f"{self.type} of {self.body}", pairs))


def driven_travel(travel: QuadraticBlock, driver: int) -> DrivenBlock:
    """The rheonomic row ``travel - d(t) = 0`` of the one-row block ``travel`` (a slide
    along a prismatic joint's axis from t = 0, m) and the driver coordinate ``driver`` of
    the ``displacement`` law d(t)."""
    k = travel.dofs.size
    unit = QuadraticBlock(travel.owner, travel.dofs, np.zeros((1, k, k)), np.zeros((1, k)),
                          -np.ones(1))
    return DrivenBlock(travel.owner, (travel, unit), (-1, int(driver)))


def _global_axis_key(value: Any, path: str, context: Context) -> tuple[float, ...]:
    return unit_axis(value, path, context.dim)


@dataclass(frozen=True)
class BodyPrismatic(NodeSide, Constraint):
    """A slider on the ground: the point ``point`` (body coordinates) of the rigid body or
    point mass ``body`` moves along the global ``axis`` through where it is at t = 0 (two
    rows n_k . (r_P - r_P0) = 0 with n_k normal to the axis: linear rows with a constant),
    and a rigid body keeps its orientation (three linear rows u . v0 = v . w0 = w . u0 = 0,
    the infinitesimal rotations about w0, u0 and v0).  With ``other`` (a rigid body) or
    ``node`` (a node with the three gradients of a frame) the axis and the line are fixed in
    that side (their place at t = 0) and the orientation is kept relative to it: the rows
    of ``body_vectors.frame_rows``, the slide along the side's normals of the axis and the
    small relative rotation (bilinear, symmetric in the two sides).  With a
    ``displacement`` law d(t) (m), the travel along the axis from t = 0 is prescribed (a
    rheonomic row)."""

    type: ClassVar[str] = "body_prismatic"
    body: str = key(rigid_key)
    point: tuple[float, ...] = key(_point_key, (0.0, 0.0, 0.0))
    axis: tuple[float, ...] = key(_global_axis_key, (1.0, 0.0, 0.0))
    displacement: Law | None = key(motion_key("a displacement in m"), None)
    other: str | None = key(rigid_key, None)
    node: NodeRef | str | None = key(node_key, None)

    @classmethod
    def parse(cls, data: dict, path: str, context: Context) -> Record:
        vectors.exclusive_sides(data, path)
        joint = super().parse(data, path, context)
        vectors.check_frame_node(joint.node, f"{path}.node", context, f"a {cls.type} holds")
        if joint.other is not None:
            if joint.other == joint.body:
                raise SceneError(f"{path}.other: expected another body than "
                                 f"{show(joint.body)}")
            if not isinstance(context.rigid[joint.other], RigidBody):
                raise SceneError(f"{path}.other: the slide's axis turns with a rigid body "
                                 f"(type = \"rigid\"), got the point mass "
                                 f"{show(joint.other)}")
        return joint

    def drivers(self) -> tuple[Driver, ...]:
        return () if self.displacement is None else (Driver(self.displacement),)

    def resolved(self, context: Context) -> Record:
        return planar_defaults(self, context, ("point", "axis"))

    @property
    def target_key(self) -> str:
        return "body"

    def apply(self, model: ModelView, built: Built) -> None:
        if self.other is not None or self.node is not None:
            self._between(model, built)
            return
        dofs, position = model.rigid_point(self.body, self.point)
        normals = normals_of(np.asarray(self.axis))
        rows = normals @ position                                   # (dim - 1, k)
        built.blocks.append(QuadraticBlock(f"{self.type} of {self.body}", dofs,
                                           np.zeros((len(rows), dofs.size, dofs.size)), rows,
                                           -rows @ model.reference[dofs]))
        if self.displacement is not None:   # a . (r_P - r_P0) - d(t) = 0
            along = np.asarray(self.axis) @ position
            built.blocks.append(driven_travel(QuadraticBlock(
                f"{self.type} of {self.body} (displacement)", dofs,
                np.zeros((1, dofs.size, dofs.size)), along[None, :],
                np.array([-along @ model.reference[dofs]])), built.drivers[0]))
        rigid = model.rigid[self.body]
        if not isinstance(rigid.item, RigidBody):
            return
        if model.dim == 2:                                       # u . v0 = 0
            v0 = PERP @ model.reference[rigid.dofs[2:]]
            built.rows.append({int(rigid.dofs[2 + c]): float(v0[c]) for c in range(2)
                               if v0[c] != 0.0})
            return
        axes = model.reference[rigid.dofs[3:]].reshape(3, 3)     # u0, v0, w0
        for a, b in ((0, 1), (1, 2), (2, 0)):                   # e_a . e_b0 = 0
            built.rows.append({int(rigid.dofs[3 + 3 * a + c]): float(axes[b, c])
                               for c in range(3) if axes[b, c] != 0.0})

    def _between(self, model: ModelView, built: Built) -> None:
        """The slide on the ``other`` body or the ``node`` (class docstring)."""
        side = vectors.side_of(self)
        owner = f"{self.type} of {self.body} on {side}"
        axis = np.asarray(self.axis)
        turns = isinstance(model.rigid[self.body].item, RigidBody)    # not a point mass
        here = vectors.body_point(model, self.body, self.point)
        built.blocks.append(vectors.frame_rows(model, here, side, normals_of(axis), owner,
                                               self.body if turns else None))
        if self.displacement is not None:   # a . (r_P - r_Q) - d(t) = 0
            built.blocks.append(driven_travel(vectors.frame_rows(
                model, here, side, axis[None, :], f"{owner} (displacement)"),
                built.drivers[0]))


@dataclass(frozen=True)
class BodyWeld(BodySpherical):
    """A rigid connection of a rigid body and a ``node`` of a meshed body (the node's
    section turns with the body, as a clamp on a hub that moves): shared position, and each
    of the node's gradient vectors a fixed combination of the body's axes,
    ``r_k = sum_a c_ka e_a`` with c_ka = e_a0 . r_k0 at t = 0 (linear rows: dim per vector;
    the body direction of ``body_vectors.direction``).  The node keeps its reference
    section's shape and size (its gradients do not stretch)."""

    type: ClassVar[str] = "body_weld"

    @classmethod
    def parse(cls, data: dict, path: str, context: Context) -> Record:
        joint = super().parse(data, path, context)
        if joint.node is None:
            raise SceneError(f"{path}.node: a body_weld joins a rigid body to a node of a "
                             "meshed body; expected node = \"BODY:INDEX\"")
        if not isinstance(context.rigid[joint.body], RigidBody):
            raise SceneError(f"{path}.body: a weld needs a rigid body (type = \"rigid\"), "
                             f"got the point mass {show(joint.body)}")
        return joint

    def apply(self, model: ModelView, built: Built) -> None:
        super().apply(model, built)
        node = model.node_index(self.node)
        for name in model.node_vectors(node):
            if name == "r":
                continue
            gradient = model.node_dofs(node, name)
            mine = vectors.direction(model, self.body, model.reference[gradient])
            for c, coefficients in enumerate(mine.map):             # sum_a c_a e_a - r_k
                row = {int(i): float(v) for i, v in zip(mine.dofs, coefficients, strict=True)
                       if v != 0.0}
                row[int(gradient[c])] = -1.0
                built.rows.append(row)
