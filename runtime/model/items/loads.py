"""External loads of scenes (``[[load]]`` tables): a typed registry, ``LOADS``.

A load is a constant generalised force vector (``nominal``, N per coordinate, at a time-law
value of 1) scaled by its ``time_law`` (default: constant 1), or, when it ``follows`` the
deformation (``follower = true``, ``pressure``), a generalised force f(q) with its exact
Jacobian (``state_force``, ``runtime.model.items.follower``) scaled by its time law; its
``nominal`` is then zero.  Each class declares its TOML keys as fields
(``runtime.model.schema.Record``); adding one is one class here and one entry in ``LOADS``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from runtime.kernels.kind import element_kind
from runtime.model.errors import SceneError, show
from runtime.model.items import load_points
from runtime.model.items.base import ModelView
from runtime.model.items.body_joints import angle_forms
from runtime.model.items.body_vectors import (
    check_frame_node,
    exclusive_sides,
    frame_deflection,
    side_of,
)
from runtime.model.items.follower import FrameLoad, Patches, PressureLoad
from runtime.model.items.force_elements import (
    BodyTorqueForce,
    BushingForce,
    SpringDamperForce,
    TorsionalSpringForce,
)
from runtime.model.items.python_loads import PythonForce, PythonFunction
from runtime.model.items.rigid import check_rigid_bodies, planar_defaults, rigid_key
from runtime.model.schema import (
    Context,
    EdgeRef,
    NodeRef,
    Record,
    boolean,
    choice,
    edge_key,
    key,
    law_key,
    node_key,
    number,
    registry,
    rotation_vector,
    unit_axis,
    vector,
)
from runtime.model.time_laws import Constant, Law

__all__ = ["LOADS", "BodyForce", "BodyTorque", "Bushing", "DistributedForce", "End", "FaceForce",
           "Gravity", "LineForce", "LineMoment", "Load", "NodeLoad", "PointForce", "PointMoment",
           "Pressure", "PythonLoad", "SpringDamper", "TorsionalSpring"]

StateForce = Callable[[np.ndarray, bool], Patches]


@dataclass(frozen=True)
class Load(Record):
    """Base of the loads: ``nominal(model)`` times ``time_law.value(t)``; ``potential``: its
    work is the potential energy of the ``potential_energy`` sensor (gravity)."""

    potential: ClassVar[bool] = False
    #: whether the static analyses scale it by their load factor (the load stepping's
    #: fraction, the arc length's lambda): every load, not the force elements (springs,
    #: dampers, bushings are part of the structure)
    load_factor: ClassVar[bool] = True
    time_law: Law | dict = key(law_key, Constant(), kw_only=True)

    def nominal(self, model: ModelView) -> np.ndarray:
        """Generalised force (size,) in N (per coordinate) at a time-law value of 1."""
        raise NotImplementedError

    #: the key that names its nodes ("node", "edge"; none for a field such as gravity)
    target_key: ClassVar[str] = ""

    def targets(self) -> list[NodeRef]:
        """The nodes it acts on (none for a field such as gravity)."""
        return []

    @property
    def follows(self) -> bool:
        """Whether it depends on the coordinates (then ``state_force``, and ``nominal`` is 0)."""
        return False

    def state_force(self, model: ModelView) -> StateForce:
        """The function (q (size,), jacobian) -> ``Patches`` of its generalised force at a
        time-law value of 1 (loads that ``follow``)."""
        raise NotImplementedError


def _boolean_key(value: Any, path: str, context: Context) -> bool:
    return boolean(value, path)


def _no_frame(path: str, body: str, context: Context) -> None:
    """SceneError when the nodes of ``body`` carry no frame for a follower load."""
    kind = element_kind(context.node.bodies[body].element)
    if load_points.frame_gradients(kind) is None:
        raise SceneError(f"{path}: body {show(body)} ({kind.name}) carries only "
                         f"{', '.join(kind.vectors)}: a follower load needs the frame of its "
                         "gradients (r_x and r_y, or r_y and r_z, in 3D); use follower = false")


@dataclass(frozen=True)
class NodeLoad(Load):
    """A load on one ``node``; ``on_gradients``: it acts on the node's gradients (a moment),
    else on its position (a force); ``noun`` names it in messages."""

    on_gradients: ClassVar[bool] = False
    noun: ClassVar[str] = "force"
    target_key: ClassVar[str] = "node"
    node: NodeRef | str = key(node_key)

    def targets(self) -> list[NodeRef]:
        return [self.node]


def _vector_key(value: Any, path: str, context: Context) -> tuple[float, ...]:
    return vector(value, path, context.dim, f"the scene is {context.dim}D")


@dataclass(frozen=True)
class PointForce(NodeLoad):
    """A force ``force`` (dim,) in N on the position of ``node``: fixed in direction, or with
    ``follower = true`` turning with the node's frame (its gradients, as ``frame =``
    sensors): ``force`` is given at the reference, its components in the node's reference
    frame are kept in the deformed frame."""

    type: ClassVar[str] = "point_force"
    force: tuple[float, ...] = key(_vector_key)
    follower: bool = key(_boolean_key, False)

    def resolved(self, context: Context) -> Load:
        if self.follower:
            _no_frame("follower", self.node.body, context)
        return self

    @property
    def follows(self) -> bool:
        return self.follower

    def nominal(self, model: ModelView) -> np.ndarray:
        out = np.zeros(model.size)
        if not self.follower:
            out[model.node_dofs(model.node_index(self.node), "r")] = self.force
        return out

    def state_force(self, model: ModelView) -> StateForce:
        maps = _node_maps(model, self.node)
        return FrameLoad(maps, force=maps.local(model.reference, self.force))


def _node_maps(model: ModelView, ref: NodeRef, section: bool = False):
    return load_points.node_maps(model, model.node_index(ref), model.bodies[ref.body].kind,
                                 section)


def _moment_key(value: Any, path: str, context: Context) -> float | tuple[float, ...]:
    return rotation_vector(value, path, context.dim, "the moment in N m")


def _section_node_key(value: Any, path: str, context: Context) -> NodeRef:
    """A node a moment can act on: one whose gradients define a frame
    (``ElementKind.frame_gap``: r_y, or in 2D r_x of a cable node); a 3D cable node's r_x or a
    shell node's r_z fixes one direction only."""
    ref = node_key(value, path, context)
    kind = element_kind(context.node.bodies[ref.body].element)
    gap = kind.frame_gap()
    if gap is not None or "r_y" not in kind.vectors and context.dim == 3:
        raise SceneError(f"{path}: node {show(value)} of body {show(ref.body)} ({kind.name}) "
                         f"cannot take a moment: {gap or 'a moment in 3D acts on r_y and r_z'}; "
                         "a moment needs the node's frame")
    return ref


@dataclass(frozen=True)
class PointMoment(NodeLoad):
    """A moment ``moment`` in N m on the section of ``node``: a number about +z in 2D, a
    vector (3,) in 3D; fixed in space.

    Consistent generalised force: the virtual work of M on the small rotation d theta of the
    node's section, read from its gradients r_y (and r_z) in the reference.  With (t1, t2,
    t3) the node's reference frame (its gradients r_x, r_y, r_z orthonormalised, r_x first)
    and a rotation d theta, d r_y = d theta x t2 and d r_z = d theta x t3, so
    d theta . t3 = -t1 . d r_y, d theta . t2 = t1 . d r_z and d theta . t1 = (t3 . d r_y -
    t2 . d r_z) / 2 (the twist read from both, averaged); M . d theta = Q_y . d r_y +
    Q_z . d r_z gives, with M_i = M . t_i,

        3D:  Q_y = (M_1 / 2) t3 - M_3 t1,   Q_z = M_2 t1 - (M_1 / 2) t2
        2D:  Q_y = -M t1                     (M about z)

    on the node's r_y and r_z coordinates (nothing on r and r_x).  It is also the work of a
    linear distribution of tractions over the section (the bending stress -M y / I) with
    resultant M.  Assumption: small rotations of the section; Q is constant, so a section
    turned by a finite angle theta receives the moment of those fixed tractions, M cos(theta)
    in bending, not M.  A 2D node without r_y (a cable's) takes the moment on its tangent:
    d r_x = d theta (-r_x,y, r_x,x), so Q_x = M (-r_x,y, r_x,x) / |r_x|^2 at the reference
    (a 3D cable node has no section orientation: refused).

    ``follower = true``: the moment turns with the node's frame (its components in the
    reference frame are kept) and does the virtual work M . d theta on the exact rotation of
    the frame built from the node's gradients (``runtime.model.items.follower``; in 2D the
    frame of r_x, so M d theta with theta the angle of r_x): exact for finite rotations.
    """

    type: ClassVar[str] = "point_moment"
    on_gradients: ClassVar[bool] = True
    noun: ClassVar[str] = "moment"
    node: NodeRef | str = key(_section_node_key)
    moment: float | tuple[float, ...] = key(_moment_key)
    follower: bool = key(_boolean_key, False)

    @property
    def follows(self) -> bool:
        return self.follower

    def state_force(self, model: ModelView) -> StateForce:
        maps = _node_maps(model, self.node, section=True)
        return FrameLoad(maps, moment=_moment_components(maps, model, self.moment))

    def nominal(self, model: ModelView) -> np.ndarray:
        node = model.node_index(self.node)
        out = np.zeros(model.size)
        if self.follower:
            return out
        if "r_y" not in model.node_vectors(node):  # a 2D cable node: on its tangent
            tangent = model.reference[model.node_dofs(node, "r_x")]
            out[model.node_dofs(node, "r_x")] = (self.moment * np.array([-tangent[1], tangent[0]])
                                                 / (tangent @ tangent))
            return out
        frame = model.node_frame(model.reference, node)
        if model.dim == 2:
            out[model.node_dofs(node, "r_y")] = -self.moment * frame[:, 0]
            return out
        t1, t2, t3 = frame.T
        m1, m2, m3 = frame.T @ np.asarray(self.moment, float)
        out[model.node_dofs(node, "r_y")] = 0.5 * m1 * t3 - m3 * t1
        out[model.node_dofs(node, "r_z")] = m2 * t1 - 0.5 * m1 * t2
        return out


def _moment_components(maps, model: ModelView, moment) -> np.ndarray:
    """A moment given in global components at the reference as components in the frames of
    the points of ``maps`` (m, p, 3); in 2D the moment about z (m, p, 1)."""
    if model.dim == 2:
        return np.full((*maps.weights.shape, 1), float(moment))
    return maps.local(model.reference, moment)


@dataclass(frozen=True)
class Gravity(Load):
    """A uniform acceleration field ``acceleration`` (dim,) in m/s^2 on every body: the
    consistent generalised force M u of the mass matrix M and the rigid translation u."""

    type: ClassVar[str] = "gravity"
    potential: ClassVar[bool] = True
    acceleration: tuple[float, ...] = key(_vector_key)

    def nominal(self, model: ModelView) -> np.ndarray:
        return model.mass @ model.rigid_field(translation=self.acceleration)


def _body_point_key(value: Any, path: str, context: Context) -> tuple[float, ...]:
    return vector(value, path, context.dim, f"a point in body coordinates, m, {context.dim}D")


@dataclass(frozen=True)
class BodyForce(Load):
    """A force ``force`` (dim,) in N, fixed in direction, at the point ``point`` (body
    coordinates, m) of the rigid body or point mass ``body``: the generalised force N^T f
    of the point's map (``runtime.model.items.rigid.natural_map``)."""

    type: ClassVar[str] = "body_force"
    body: str = key(rigid_key)
    force: tuple[float, ...] = key(_vector_key)
    point: tuple[float, ...] = key(_body_point_key, (0.0, 0.0, 0.0))

    def resolved(self, context: Context) -> Record:
        return planar_defaults(self, context, ("point",))

    def nominal(self, model: ModelView) -> np.ndarray:
        dofs, point = model.rigid_point(self.body, self.point)
        out = np.zeros(model.size)
        out[dofs] += point.T @ np.asarray(self.force)
        return out


def _finite_key(value: Any, path: str, context: Context) -> float:
    return number(value, path)


def _body_axis_key(value: Any, path: str, context: Context) -> tuple[float, ...]:
    return unit_axis(value, path)


@dataclass(frozen=True)
class BodyTorque(Load):
    """A torque ``torque`` (N m) times its ``time_law`` about the ``axis`` (body
    coordinates, unit; default z; 2D: about z, no axis) of the rigid body ``body``, turning
    with the body: a motor on a body in a revolute joint about that axis
    (``runtime.model.items.force_elements``)."""

    type: ClassVar[str] = "body_torque"
    body: str = key(rigid_key)
    torque: float = key(_finite_key)
    axis: tuple[float, ...] = key(_body_axis_key, (0.0, 0.0, 1.0),
                                  only_3d="a 2D torque is about z")

    @classmethod
    def parse(cls, data: dict, path: str, context: Context) -> Record:
        load = super().parse(data, path, context)
        check_rigid_bodies(load, path, context, "a torque needs a rigid body")
        return load

    @property
    def follows(self) -> bool:
        return True

    def nominal(self, model: ModelView) -> np.ndarray:
        return np.zeros(model.size)

    def state_force(self, model: ModelView) -> BodyTorqueForce:
        return BodyTorqueForce(model.rigid[self.body].dofs, np.asarray(self.axis),
                               self.torque)


@dataclass(frozen=True)
class End:
    """An end of a force element: a ``node`` of a meshed body, the point ``point`` (body
    coordinates, m) of a rigid ``body``, or a fixed ``anchor`` (dim,) in m.  TOML:
    "BODY:INDEX", {body = "NAME", point = [x, y(, z)]} (point default the origin) or
    [x, y(, z)]."""

    node: NodeRef | None = None
    body: str | None = None
    point: tuple[float, ...] = (0.0, 0.0, 0.0)
    anchor: tuple[float, ...] | None = None

    @classmethod
    def parse(cls, value: Any, path: str, context: Context) -> End:
        if isinstance(value, str):
            return cls(node=node_key(value, path, context))
        if isinstance(value, list):
            return cls(anchor=vector(value, path, context.dim,
                                     f"an anchor point in m, {context.dim}D"))
        if isinstance(value, dict) and set(value) <= {"body", "point"} and "body" in value:
            point = _body_point_key(value.get("point", [0.0] * context.dim), f"{path}.point",
                                    context)
            return cls(body=rigid_key(value["body"], f"{path}.body", context), point=point)
        raise SceneError(f'{path}: expected a node "BODY:INDEX", a rigid body\'s point '
                         f'{{body = "NAME", point = [x, y, z]}} or an anchor [x, y, z], got '
                         f"{show(value)}")

    def to_dict(self) -> Any:
        if self.node is not None:
            return self.node.spelled()
        if self.anchor is not None:
            return list(self.anchor)
        if not any(self.point):     # the origin, in the scene's dimension
            return {"body": self.body}
        return {"body": self.body, "point": list(self.point)}

    def position(self, model: ModelView) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(coordinates (k,), map (dim, k), constant (dim,)) of its position."""
        dim = model.dim
        if self.node is not None:
            return (model.node_dofs(model.node_index(self.node), "r"), np.eye(dim),
                    np.zeros(dim))
        if self.anchor is not None:
            return np.zeros(0, int), np.zeros((dim, 0)), np.asarray(self.anchor, float)
        dofs, point = model.rigid_point(self.body, self.point)
        return dofs, point, np.zeros(dim)


def _end_key(value: Any, path: str, context: Context) -> End:
    return End.parse(value, path, context)


def _non_negative_key(value: Any, path: str, context: Context) -> float:
    number_ = number(value, path)
    if number_ < 0:
        raise SceneError(f"{path}: expected a number >= 0, got {show(value)}")
    return number_


@dataclass(frozen=True)
class ForceElement(Load):
    """A force element: a state load with no nominal part, whose exact Jacobians
    (``state_force``, ``runtime.model.items.force_elements``) couple its coordinates in the
    model's pattern."""

    load_factor: ClassVar[bool] = False

    @property
    def follows(self) -> bool:
        return True

    def nominal(self, model: ModelView) -> np.ndarray:
        return np.zeros(model.size)

    def coupled_dofs(self, model: ModelView) -> np.ndarray:
        """The coordinates its Jacobian couples (they join the model's pattern)."""
        return self.state_force(model).dofs[0]


@dataclass(frozen=True)
class RigidForceElement(ForceElement):
    """A force element on the rigid ``body`` and the rigid body ``other`` (or the ground):
    both must be rigid bodies (``joins``: what the message says it joins) and distinct."""

    dims: ClassVar[tuple[int, ...]] = (3,)
    dims_message: ClassVar[str] = ("torsional springs and bushings are 3D (3D scenes only); "
                                   "in 2D a spring_damper")
    joins: ClassVar[str] = "joins rigid bodies"

    @classmethod
    def parse(cls, data: dict, path: str, context: Context) -> Record:
        load = super().parse(data, path, context)
        check_rigid_bodies(load, path, context, f"a {cls.type.replace('_', ' ')} {cls.joins}")
        return load


@dataclass(frozen=True)
class SpringDamper(ForceElement):
    """A linear spring-damper between ``end_a`` and ``end_b`` (``End``): ``stiffness`` (N/m),
    ``damping`` (N s/m), rest ``length`` (m; default the distance at t = 0); the force
    k (L - L0) + c L' along the line of the ends, with exact Jacobians
    (``runtime.model.items.force_elements``), times its ``time_law``."""

    type: ClassVar[str] = "spring_damper"
    end_a: End = key(_end_key)
    end_b: End = key(_end_key)
    stiffness: float = key(_non_negative_key)
    damping: float = key(_non_negative_key, 0.0)
    length: float | None = key(_non_negative_key, None)

    def state_force(self, model: ModelView) -> SpringDamperForce:
        dofs_a, map_a, const_a = self.end_a.position(model)
        dofs_b, map_b, const_b = self.end_b.position(model)
        dofs = np.concatenate([dofs_b, dofs_a])
        difference = np.hstack([map_b, -map_a])
        offset = const_b - const_a
        unique, inverse = np.unique(dofs, return_inverse=True)
        merged = np.zeros((model.dim, unique.size))
        np.add.at(merged.T, inverse, difference.T)
        rest = float(np.linalg.norm(merged @ model.reference[unique] + offset))
        return SpringDamperForce(unique, merged, offset, self.stiffness, self.damping,
                                 rest if self.length is None else self.length)


@dataclass(frozen=True)
class TorsionalSpring(RigidForceElement):
    """A torsional spring-damper about the ``axis`` (body coordinates, default z) of a
    revolute joint of the rigid ``body``: on its rotation relative to the ground, to the
    rigid body ``other`` or to a ``node`` of a meshed body (``angle_forms``), the moment
    k (phi - phi_0) + c phi' with ``stiffness`` k (N m/rad), ``damping`` c (N m s/rad) and
    free ``angle`` phi_0 (rad, from the pose at t = 0; default 0), phi counting turns (no
    jump past half a turn), with exact Jacobians (``runtime.model.items.force_elements``),
    times its ``time_law``."""

    type: ClassVar[str] = "torsional_spring"
    joins: ClassVar[str] = "needs a rigid body"
    body: str = key(rigid_key)
    stiffness: float = key(_non_negative_key)
    other: str | None = key(rigid_key, None)
    node: NodeRef | str | None = key(node_key, None)
    axis: tuple[float, ...] = key(_body_axis_key, (0.0, 0.0, 1.0))
    damping: float = key(_non_negative_key, 0.0)
    angle: float = key(_finite_key, 0.0)

    @classmethod
    def parse(cls, data: dict, path: str, context: Context) -> Record:
        exclusive_sides(data, path)
        return super().parse(data, path, context)

    def state_force(self, model: ModelView) -> TorsionalSpringForce:
        forms = angle_forms(model, self.body, self.axis, side_of(self),
                            f"{self.type} of {self.body}")
        return TorsionalSpringForce(forms, self.stiffness, self.damping, self.angle)


def _bushing_matrix_key(value: Any, path: str, context: Context) -> tuple[tuple[float, ...], ...]:
    """A symmetric positive semi-definite 6 x 6 matrix (rows: the displacements along the
    frame's axes, then the small rotations about them), or its six diagonal entries."""
    if isinstance(value, list) and len(value) == 6 and not any(isinstance(x, list)
                                                                for x in value):
        matrix = np.diag(vector(value, path, 6, "six diagonal entries"))
    elif isinstance(value, list) and len(value) == 6:
        matrix = np.array([vector(row, f"{path}[{i}]", 6, "a row of a 6 x 6 matrix")
                           for i, row in enumerate(value)])
    else:
        raise SceneError(f"{path}: expected six diagonal entries or a 6 x 6 matrix, got "
                         f"{show(value)}")
    if not np.allclose(matrix, matrix.T, rtol=1e-12, atol=0.0):
        raise SceneError(f"{path}: expected a symmetric matrix, got {show(value)}")
    lowest = float(np.linalg.eigvalsh(matrix)[0])
    if lowest < -1e-12 * float(np.abs(matrix).max(initial=0.0)):
        raise SceneError(f"{path}: expected a positive semi-definite matrix, got an "
                         f"eigenvalue {lowest:.6g}")
    return tuple(tuple(float(x) for x in row) for row in matrix)


@dataclass(frozen=True)
class Bushing(RigidForceElement):
    """A linear bushing between the frame of the rigid ``body`` at its ``point`` (body
    coordinates) and the other side's frame there at t = 0: the rigid body ``other``, the
    frame of a ``node`` (its gradients r_x, r_y, r_z: a node with the three) or the ground.
    Its deflection delta (6,) is the displacement (m) along and the small rotation (rad)
    about the body's axes at t = 0 fixed in the other side
    (``body_vectors.frame_deflection``), its force and moment K delta + C delta' with the
    6 x 6 ``stiffness`` K and ``damping`` C (default 0), exact Jacobians
    (``runtime.model.items.force_elements``), times its ``time_law``.  The rotations are
    those of small relative rotations."""

    type: ClassVar[str] = "bushing"
    body: str = key(rigid_key)
    stiffness: tuple[tuple[float, ...], ...] = key(_bushing_matrix_key)
    point: tuple[float, ...] = key(_body_point_key, (0.0, 0.0, 0.0))
    other: str | None = key(rigid_key, None)
    node: NodeRef | str | None = key(node_key, None)
    damping: tuple[tuple[float, ...], ...] | None = key(_bushing_matrix_key, None)

    @classmethod
    def parse(cls, data: dict, path: str, context: Context) -> Record:
        exclusive_sides(data, path)
        load = super().parse(data, path, context)
        check_frame_node(load.node, f"{path}.node", context, "a bushing turns with")
        return load

    def state_force(self, model: ModelView) -> BushingForce:
        forms = frame_deflection(model, self.body, self.point, side_of(self),
                                 f"{self.type} of {self.body}")
        damping = np.zeros((6, 6)) if self.damping is None else np.array(self.damping)
        return BushingForce(forms, np.array(self.stiffness), damping)


@dataclass(frozen=True)
class EdgeLoad(Load):
    """A load per unit (reference) length along the ``edge`` of a rectangle body
    (``"BODY:x=-1"``: its last grid column), integrated over the element sides on that grid
    line, each once (Gauss rule along each side, ds from the reference)."""

    on_gradients: ClassVar[bool] = False
    target_key: ClassVar[str] = "edge"
    edge: EdgeRef | str = key(edge_key)

    def targets(self) -> list[NodeRef]:
        return self.edge.refs()

    def _maps(self, model: ModelView):
        return load_points.edge_maps(model.bodies[self.edge.body], self.edge,
                                     self.on_gradients)


@dataclass(frozen=True)
class LineForce(EdgeLoad):
    """A uniform force per unit length ``force_per_length`` (dim,) in N/m along an edge
    (``EdgeLoad``): fixed in direction, the consistent generalised force int S^T f ds; or
    with ``follower = true`` turning with the frame of the mid-surface at each point (its
    gradients r_x, r_y; components in the reference frame kept), per unit reference length.
    Its resultant is f times the edge length (a tip line load on a plate strip: P = f b)."""

    type: ClassVar[str] = "line_force"
    noun: ClassVar[str] = "line force"
    force_per_length: tuple[float, ...] = key(_vector_key)
    follower: bool = key(_boolean_key, False)

    @property
    def follows(self) -> bool:
        return self.follower

    def nominal(self, model: ModelView) -> np.ndarray:
        out = np.zeros(model.size)
        if self.follower:
            return out
        body = model.bodies[self.edge.body]
        for e, _, ds, values, _ in load_points.edge_sides(body, self.edge):
            out[body.element_dofs[e]] += np.outer(values.T @ ds,
                                                  self.force_per_length).ravel()
        return out

    def state_force(self, model: ModelView) -> StateForce:
        maps = self._maps(model)
        return FrameLoad(maps, force=maps.local(model.reference, self.force_per_length))


@dataclass(frozen=True)
class FaceForce(Load):
    """A uniform force per unit (reference) area ``force_per_area`` (3,) in N/m^2 on a face
    ``"BODY:x=I"`` (``y=J``, ``z=K``) of a box body, fixed in direction: the consistent
    generalised force int S^T f dA over the element faces on that lattice plane (a pressure
    p on the face x = -1 is ``[-p, 0, 0]``; a tip shear P over a section A,
    ``[0, 0, -P / A]``).  Its resultant is f times the face's area."""

    type: ClassVar[str] = "face_force"
    dims: ClassVar[tuple[int, ...]] = (3,)
    dims_message: ClassVar[str] = "face_force acts on faces of box bodies (3D scenes)"
    noun: ClassVar[str] = "face force"
    target_key: ClassVar[str] = "face"
    face: EdgeRef | str = key(edge_key)
    force_per_area: tuple[float, ...] = key(_vector_key)

    def targets(self) -> list[NodeRef]:
        return self.face.refs()

    def nominal(self, model: ModelView) -> np.ndarray:
        out = np.zeros(model.size)
        body = model.bodies[self.face.body]
        for e, values, area in load_points.face_sides(body, self.face):
            out[body.element_dofs[e]] += np.outer(values.T @ area, self.force_per_area).ravel()
        return out


@dataclass(frozen=True)
class LineMoment(EdgeLoad):
    """A uniform moment per unit length ``moment_per_length`` (3,) in N m/m along an edge
    (``EdgeLoad``), e.g. ``[0, -m, 0]`` bends a strip along x about y: the virtual work of m
    on the rotation of the mid-surface frame (r_x, r_y) at each point
    (``runtime.model.items.follower``).  Fixed (the default): the constant generalised force
    of that work at the reference (small rotations, as ``point_moment``); with
    ``follower = true`` the moment turns with the frame and the force is exact for finite
    rotations.  Its resultant moment is m times the edge length."""

    type: ClassVar[str] = "line_moment"
    dims: ClassVar[tuple[int, ...]] = (3,)
    dims_message: ClassVar[str] = "line_moment acts on plate edges (3D scenes)"
    on_gradients: ClassVar[bool] = True
    noun: ClassVar[str] = "line moment"
    moment_per_length: tuple[float, ...] = key(_vector_key)
    follower: bool = key(_boolean_key, False)

    @property
    def follows(self) -> bool:
        return self.follower

    def state_force(self, model: ModelView) -> StateForce:
        maps = self._maps(model)
        return FrameLoad(maps, moment=_moment_components(maps, model, self.moment_per_length))

    def nominal(self, model: ModelView) -> np.ndarray:
        out = np.zeros(model.size)
        if not self.follower:     # the follower's force at the reference, held constant
            patches = self.state_force(model)(model.reference, False)
            np.add.at(out, patches.dofs, patches.force)
        return out


def _body_of_kind(value: Any, path: str, context: Context, plates: bool) -> str:
    """A body name whose kind is a plate kind (``plates``) or a beam kind."""
    name = choice(value, path, context.body_names, "body")
    kind = element_kind(context.node.bodies[name].element)
    if (len(kind.mesh_axes) == 2) != plates:
        raise SceneError(f"{path}: body {show(name)} is made of {kind.name} elements; "
                         f"expected a {'plate (rectangle)' if plates else 'beam (line)'} body")
    return name


def _plate_key(value: Any, path: str, context: Context) -> str:
    return _body_of_kind(value, path, context, True)


def _beam_key(value: Any, path: str, context: Context) -> str:
    return _body_of_kind(value, path, context, False)


@dataclass(frozen=True)
class Pressure(Load):
    """A uniform pressure ``pressure`` in Pa on the mid-surface of the plate ``body``, along
    its deformed unit normal r_x x r_y (+z of a plate in the x-y plane at the reference), per
    unit reference area (a follower load: its resultant on a flat plate is p times the plate's
    area; the deformed area does not scale it)."""

    type: ClassVar[str] = "pressure"
    dims: ClassVar[tuple[int, ...]] = (3,)
    dims_message: ClassVar[str] = "pressure acts on plates (3D scenes)"
    body: str = key(_plate_key)
    pressure: float = key(lambda value, path, context: number(value, path))

    @property
    def follows(self) -> bool:
        return True

    def nominal(self, model: ModelView) -> np.ndarray:
        return np.zeros(model.size)

    def state_force(self, model: ModelView) -> StateForce:
        return PressureLoad(load_points.surface_maps(model.bodies[self.body]), self.pressure)


@dataclass(frozen=True)
class DistributedForce(Load):
    """A uniform force per unit reference length ``force_per_length`` (dim,) in N/m along the
    axis of every element of the beam ``body``: fixed in direction (the consistent force
    int S^T f ds), or with ``follower = true`` turning with the frame of the axis at each
    point (gradients dr/dx, dr/dy in 3D, dr/dx in 2D; components in the reference frame
    kept).  Its resultant is f times the body's length."""

    type: ClassVar[str] = "distributed_force"
    body: str = key(_beam_key)
    force_per_length: tuple[float, ...] = key(_vector_key)
    follower: bool = key(_boolean_key, False)

    def resolved(self, context: Context) -> Load:
        kind = element_kind(context.node.bodies[self.body].element)
        if self.follower and context.dim == 3 and "r_y" not in kind.vectors:
            raise SceneError(f"follower: body {show(self.body)} ({kind.name}) carries only "
                             f"{', '.join(kind.vectors)}: no section frame along its axis "
                             "for a follower load; use follower = false")
        return self

    @property
    def follows(self) -> bool:
        return self.follower

    def _maps(self, model: ModelView):
        return load_points.axis_maps(model.bodies[self.body])

    def nominal(self, model: ModelView) -> np.ndarray:
        out = np.zeros(model.size)
        if not self.follower:
            maps = self._maps(model)
            force = np.einsum("mp,pdn,d->mn", maps.weights, maps.position[0],
                              np.asarray(self.force_per_length, float))
            np.add.at(out, maps.dofs, force)
        return out

    def state_force(self, model: ModelView) -> StateForce:
        maps = self._maps(model)
        return FrameLoad(maps, force=maps.local(model.reference, self.force_per_length))


def _function_key(value: Any, path: str, context: Context) -> PythonFunction:
    return PythonFunction.parse(value, path, context.folder)


def _nodes_key(value: Any, path: str, context: Context) -> tuple[NodeRef, ...]:
    if not isinstance(value, list | tuple) or not value:
        raise SceneError(f'{path}: expected a non-empty list of nodes ["BODY:INDEX", ...], '
                         f"got {show(value)}")
    refs = tuple(node_key(item, f"{path}[{i}]", context) for i, item in enumerate(value))
    for i, ref in enumerate(refs):
        if ref in refs[:i]:
            raise SceneError(f"{path}[{i}]: node {show(value[i])} is listed twice")
    return refs


@dataclass(frozen=True)
class PythonLoad(Load):
    """A generalised force written as a Python function ``function(t, q, v) -> (size,)``
    (N per coordinate) of the time and the full coordinates and velocities, for controllers
    (``runtime.model.items.python_loads``), times its ``time_law``.  ``nodes``: the nodes
    whose coordinates it acts on and reads (default: every coordinate), which must share an
    element (the Jacobian stays inside the model's pattern); ``jacobian(t, q, v) -> (df/dq,
    df/dv)``, else central finite differences over those coordinates.  TOML names the
    functions "module:function"; the Python API takes the callables."""

    type: ClassVar[str] = "python"
    noun: ClassVar[str] = "Python load"
    function: PythonFunction | str | Callable = key(_function_key)
    jacobian: PythonFunction | str | Callable | None = key(_function_key, None)
    nodes: tuple[NodeRef, ...] | None = key(_nodes_key, None)

    @classmethod
    def parse(cls, data: dict, path: str, context: Context) -> Load:
        record = super().parse(data, path, context)
        object.__setattr__(record, "_where", path)   # names it in errors at run time
        return record

    @property
    def follows(self) -> bool:
        return True

    def nominal(self, model: ModelView) -> np.ndarray:
        return np.zeros(model.size)

    def state_force(self, model: ModelView) -> PythonForce:
        dofs = (np.arange(model.size) if self.nodes is None else np.concatenate(
            [model.node_dofs(model.node_index(ref)) for ref in self.nodes]))
        return PythonForce(self.function, self.jacobian, dofs, model.size,
                           getattr(self, "_where", "load"))


LOADS: dict[str, type[Load]] = registry(PointForce, PointMoment, Gravity, LineForce, LineMoment,
                                        FaceForce, Pressure, DistributedForce, PythonLoad,
                                        BodyForce, SpringDamper, BodyTorque, TorsionalSpring,
                                        Bushing)
