"""Sensors: named scalar outputs of a model state (``[[sensor]]`` tables), a typed registry
``SENSORS``.

Each class declares its TOML keys as fields (``runtime.model.schema.Record``), its ``unit`` and
whether it is an ``energy`` (plotted together), and computes its values over a block of
``Samples`` (k output times at once, vectorised: one output time is a block of one); adding
one is one class here and one entry in ``SENSORS``.  ``Sensors`` evaluates all the sensors of
a model's scene, at one state or over a block.
"""

from __future__ import annotations

import dataclasses
import re
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from runtime.kernels.kind import element_kind
from runtime.model.errors import SceneError, show
from runtime.model.items import material_points as material
from runtime.model.items.base import ModelView
from runtime.model.items.rigid import check_rigid_bodies, planar_defaults, rigid_key
from runtime.model.schema import (
    NAME_LENGTH,
    Context,
    EdgeRef,
    NodeRef,
    Record,
    choice,
    edge_key,
    key,
    node_key,
    number,
    registry,
    string,
    vector,
)

__all__ = ["ENERGY_TYPES", "SENSORS", "Acceleration", "ConstraintViolation", "DissipatedEnergy",
           "Displacement", "KineticEnergy", "Position", "PotentialEnergy", "Reaction", "Samples",
           "SectionForce", "Sensor", "Sensors", "StrainEnergy", "Strain", "Stress",
           "Slide", "SpringAngle", "TotalEnergy", "Velocity", "check_reactions"]

# names of sensors become CSV columns and PNG file names: ASCII letters, digits, "_", "." and
# "-", not starting with "." or "-", at most NAME_LENGTH characters, unique ignoring case (file
# systems that ignore case); "t" is the time column, "energies" the energy plot, the others
# are device names on Windows
SENSOR_NAME = re.compile(r"[A-Za-z0-9_][A-Za-z0-9_.\-]*")
RESERVED_SENSOR_NAMES = ("t", "energies", "con", "prn", "aux", "nul",
                         *(f"com{i}" for i in range(1, 10)), *(f"lpt{i}" for i in range(1, 10)))


def _name_key(value: Any, path: str, context: Context) -> str:
    name = string(value, path)
    if not SENSOR_NAME.fullmatch(name) or len(name) > NAME_LENGTH:
        raise SceneError(f"{path}: expected letters, digits, _ . and - starting with a "
                         f"letter, digit or _, at most {NAME_LENGTH} characters (it names a "
                         f"CSV column and a PNG file), got {show(name)}")
    if name.split(".")[0].lower() in RESERVED_SENSOR_NAMES:
        raise SceneError(f"{path}: expected a name other than the reserved "
                         f"{', '.join(RESERVED_SENSOR_NAMES)} (in any case, also before a "
                         f'"."), got {show(name)}')
    return name


@dataclass(frozen=True)
class Samples:
    """States at k output times: ``t`` (k,) in s (None: a static state, loads at their
    nominal value), coordinates ``q`` and velocities ``v`` (k, size), and the energy
    ``dissipated`` (k,) in J by damping since the start of the dynamic run, and
    ``spring_angles`` (k, loads): the joint angle phi (rad) of every torsional spring, turns
    counted (``runtime.model.dae.StateLoads.spring_angles``), by scene load index (None:
    each within half a turn of 0).

    For the sensors that need them (``Sensor.dynamics``), the equations of motion at these
    states: accelerations ``a`` (k, size) in m/s^2 (fixed coordinates zero, prescribed ones
    their prescribed accelerations; zero in a static state), joint ``multipliers``
    (k, joints) and the applied force ``force`` (k, size): elastic, damping and external
    generalised forces F(q, v, t), so that ``M a + A^T multipliers = F`` on the free
    coordinates; None when no sensor needs them."""

    t: np.ndarray | None
    q: np.ndarray
    v: np.ndarray
    dissipated: np.ndarray
    a: np.ndarray | None = None
    multipliers: np.ndarray | None = None
    force: np.ndarray | None = None
    spring_angles: np.ndarray | None = None


@dataclass(frozen=True)
class Sensor(Record):
    """Base of the sensors: ``name`` names a CSV column and a PNG plot; ``unit`` of the value;
    ``energy``: plotted with the other energies."""

    unit: ClassVar[str] = "J"
    energy: ClassVar[bool] = True
    #: needs the accelerations, multipliers and forces of ``Samples``
    dynamics: ClassVar[bool] = False
    name: str = key(_name_key)

    def values(self, model: ModelView, samples: Samples) -> np.ndarray:
        """The sensor at every state of ``samples``, (k,)."""
        raise NotImplementedError

    def to_dict(self) -> dict[str, Any]:
        return {"name": self.name, **super().to_dict()}


def _component_key(value: Any, path: str, context: Context) -> str:
    components = ("x", "y", "z", "norm") if context.dim == 3 else ("x", "y", "norm")
    return choice(value, path, components, "component")


def _frame_key(value: Any, path: str, context: Context) -> NodeRef:
    """A node whose gradients define a frame (``ElementKind.frame_gap``: at least dim - 1 of
    them; a 3D cable node's r_x or a shell node's r_z fixes one direction only)."""
    ref = node_key(value, path, context)
    kind = element_kind(context.node.bodies[ref.body].element)
    gap = kind.frame_gap()
    if gap is not None:
        raise SceneError(f"{path}: node {show(value)} of body {show(ref.body)} ({kind.name}) "
                         f"has no frame: {gap}; expected a node of a kind with a frame")
    return ref


@dataclass(frozen=True)
class NodeSensor(Sensor):
    """A vector of ``node`` (m): one ``component`` (x | y | z | norm), in global axes or, with
    ``frame``, in the frame of that node (its gradients orthonormalised, r_x first) relative
    to its position."""

    unit: ClassVar[str] = "m"
    energy: ClassVar[bool] = False
    node: NodeRef | str = key(node_key)
    component: str = key(_component_key)
    frame: NodeRef | str | None = key(_frame_key, None)

    def _vector(self, position: np.ndarray, reference: np.ndarray) -> np.ndarray:
        """The vectors (k, dim) this sensor reports from the node's positions (k, dim) and
        reference (dim,) (m)."""
        raise NotImplementedError

    def values(self, model: ModelView, samples: Samples) -> np.ndarray:
        q = samples.q
        node = model.node_index(self.node)
        position = q[:, model.node_dofs(node, "r")]
        reference = model.reference[model.node_dofs(node, "r")]
        if self.frame is not None:
            frame_node = model.node_index(self.frame)
            origin = q[:, model.node_dofs(frame_node, "r")]
            origin0 = model.reference[model.node_dofs(frame_node, "r")]
            position = np.einsum("kji,kj->ki", model.node_frame(q, frame_node),
                                 position - origin)
            reference = model.node_frame(model.reference, frame_node).T @ (reference - origin0)
        return _component(self._vector(position, reference), self.component)


def _component(vectors: np.ndarray, component: str) -> np.ndarray:
    """One component (x, y, z) or the norm of vectors (k, dim), (k,)."""
    if component == "norm":
        return np.linalg.norm(vectors, axis=1)
    return vectors[:, "xyz".index(component)].copy()


@dataclass(frozen=True)
class Displacement(NodeSensor):
    """Displacement of the node from its reference position (m)."""

    type: ClassVar[str] = "displacement"

    def _vector(self, position: np.ndarray, reference: np.ndarray) -> np.ndarray:
        return position - reference


@dataclass(frozen=True)
class Position(NodeSensor):
    """Position of the node (m)."""

    type: ClassVar[str] = "position"

    def _vector(self, position: np.ndarray, reference: np.ndarray) -> np.ndarray:
        return position


@dataclass(frozen=True)
class Velocity(Sensor):
    """Velocity of ``node`` (m/s): one ``component`` (x | y | z | norm) in global axes."""

    type: ClassVar[str] = "velocity"
    unit: ClassVar[str] = "m/s"
    energy: ClassVar[bool] = False
    node: NodeRef | str = key(node_key)
    component: str = key(_component_key)

    def values(self, model: ModelView, samples: Samples) -> np.ndarray:
        velocity = samples.v[:, model.node_dofs(model.node_index(self.node), "r")]
        return _component(velocity, self.component)


def _body_point_key(value: Any, path: str, context: Context) -> tuple[float, ...]:
    return vector(value, path, context.dim, f"a point in body coordinates, m, {context.dim}D")


@dataclass(frozen=True)
class BodyPosition(Sensor):
    """Position (m) of the point ``point`` (body coordinates) of the rigid body or point mass
    ``body``: one ``component`` (x | y | z | norm) in global axes."""

    type: ClassVar[str] = "body_position"
    unit: ClassVar[str] = "m"
    energy: ClassVar[bool] = False
    body: str = key(rigid_key)
    component: str = key(_component_key)
    point: tuple[float, ...] = key(_body_point_key, (0.0, 0.0, 0.0))

    def resolved(self, context: Context) -> Record:
        return planar_defaults(self, context, ("point",))

    def _of(self, model: ModelView, states: np.ndarray) -> np.ndarray:
        dofs, point = model.rigid_point(self.body, self.point)
        return _component(states[:, dofs] @ point.T, self.component)

    def values(self, model: ModelView, samples: Samples) -> np.ndarray:
        return self._of(model, samples.q)


@dataclass(frozen=True)
class BodyVelocity(BodyPosition):
    """Velocity (m/s) of a point of a rigid body (as ``body_position``)."""

    type: ClassVar[str] = "body_velocity"
    unit: ClassVar[str] = "m/s"

    def values(self, model: ModelView, samples: Samples) -> np.ndarray:
        return self._of(model, samples.v)


@dataclass(frozen=True)
class RigidBodySensor(Sensor):
    """Base of the sensors of a rigid body ``body`` (not a point mass: it has no axes)."""

    energy: ClassVar[bool] = False
    body: str = key(rigid_key)

    @classmethod
    def parse(cls, data: dict, path: str, context: Context) -> Record:
        sensor = super().parse(data, path, context)
        check_rigid_bodies(sensor, path, context, f"a {cls.type} reads a rigid body")
        return sensor


@dataclass(frozen=True)
class BodyAngle(RigidBodySensor):
    """The angle (rad, in (-pi, pi]) of the 2D rigid body ``body``'s x axis u from the
    global x axis, atan2(u_y, u_x)."""

    type: ClassVar[str] = "body_angle"
    unit: ClassVar[str] = "rad"
    dims: ClassVar[tuple[int, ...]] = (2,)
    dims_message: ClassVar[str] = ("a 3D body's orientation is no single angle; in 3D read "
                                   "body_position of two of its points")

    def values(self, model: ModelView, samples: Samples) -> np.ndarray:
        u = samples.q[:, model.rigid[self.body].dofs[2:4]]
        return np.arctan2(u[:, 1], u[:, 0])


def _rotation_component_key(value: Any, path: str, context: Context) -> str:
    return choice(value, path, ("x", "y", "z", "norm") if context.dim == 3 else ("z", "norm"),
                  "component (a 2D rotation is about z)" if context.dim == 2 else "component")


@dataclass(frozen=True)
class BodyAngularVelocity(RigidBodySensor):
    """Angular velocity (rad/s) of the rigid body ``body``, w = sum_a e_a x e_a' / 2 over
    its axes e_a (u, v, w; in 2D u and v = perp(u)): exact for orthonormal axes (e_a' =
    w x e_a).  One ``component`` (x | y | z | norm, global axes; in 2D z, the default, or
    norm)."""

    type: ClassVar[str] = "body_angular_velocity"
    unit: ClassVar[str] = "rad/s"
    component: str = key(_rotation_component_key, "z")

    def values(self, model: ModelView, samples: Samples) -> np.ndarray:
        rigid = model.rigid[self.body]
        axes = rigid.item.axes(samples.q[:, rigid.dofs])
        rates = rigid.item.axes(samples.v[:, rigid.dofs])
        omega = sum(_cross3(axes[:, a], rates[:, a]) for a in range(axes.shape[1])) / 2
        return _component(omega, self.component)


def _body_key(value: Any, path: str, context: Context) -> str:
    return choice(value, path, context.body_names, "body")


@dataclass(frozen=True)
class Acceleration(Sensor):
    """Acceleration of ``node`` (m/s^2): one ``component`` (x | y | z | norm) in global axes,
    from the equations of motion at the output state (the consistent accelerations of its
    positions and velocities; zero in a static state)."""

    type: ClassVar[str] = "acceleration"
    unit: ClassVar[str] = "m/s^2"
    energy: ClassVar[bool] = False
    dynamics: ClassVar[bool] = True
    node: NodeRef | str = key(node_key)
    component: str = key(_component_key)

    def values(self, model: ModelView, samples: Samples) -> np.ndarray:
        acceleration = samples.a[:, model.node_dofs(model.node_index(self.node), "r")]
        return _component(acceleration, self.component)


def _quantity_key(value: Any, path: str, context: Context) -> str:
    return choice(value, path, ("force", "moment"), "quantity")


def _any_component_key(value: Any, path: str, context: Context) -> str:
    return choice(value, path, ("x", "y", "z", "norm"), "component")


@dataclass(frozen=True)
class Reaction(Sensor):
    """The ``quantity`` (force in N | moment in N m) that the constraints of ``node`` exert on
    it: its supports (clamp, pin, prescribed_rotation: the residual ``M a - F`` of the
    coordinates they hold or prescribe) and its joints (``-A^T lambda`` on its free
    coordinates).  The force acts on the position r; the moment about the node's position
    is ``sum_k r_k x f_k`` over its gradients r_k with their generalised forces f_k (the
    virtual work of a small rotation w: delta r_k = w x r_k).  With ``edge`` instead of
    ``node`` (a grid line of a rectangle body, ``"BODY:x=0"``): the resultant over its nodes,
    the moment about the edge's first node (``(r_n - r_0) x f_n`` added per node).  One
    ``component`` (x | y | z | norm, the default; a 2D moment is about z: z | norm) in global
    axes or, with ``frame``, in that node's frame; ``quantity`` defaults to force."""

    type: ClassVar[str] = "reaction"
    energy: ClassVar[bool] = False
    dynamics: ClassVar[bool] = True
    node: NodeRef | str | None = key(node_key, None)
    quantity: str = key(_quantity_key, "force")
    component: str = key(_any_component_key, "norm")
    frame: NodeRef | str | None = key(_frame_key, None)
    edge: EdgeRef | str | None = key(edge_key, None)

    @property
    def unit(self) -> str:   # type: ignore[override]
        return "N" if self.quantity == "force" else "N m"

    @classmethod
    def parse(cls, data: dict, path: str, context: Context) -> Record:
        given = [name for name in ("node", "edge") if name in data]
        if len(given) != 1:
            raise SceneError(f'{path}: expected either node = "BODY:INDEX" or edge = '
                             f'"BODY:x=I" (a grid line of a rectangle body), got '
                             f"{' and '.join(given) if given else 'neither'}")
        return _checked_component(super().parse(data, path, context), path, context)

    def targets(self) -> list[NodeRef]:
        """The nodes whose reactions it sums."""
        return [self.node] if self.edge is None else self.edge.refs()

    def values(self, model: ModelView, samples: Samples) -> np.ndarray:
        dim, k = model.dim, len(samples.q)
        nodes = [model.node_index(ref) for ref in self.targets()]
        vector = np.zeros((k, dim if self.quantity == "force" else 3))
        origin = samples.q[:, model.node_dofs(nodes[0], "r")]
        for node in nodes:
            names = model.node_vectors(node)
            per_vector = _constraint_force(model, samples, model.node_dofs(node)).reshape(
                k, len(names), dim)
            force = per_vector[:, names.index("r")]
            if self.quantity == "force":
                vector += force
                continue
            vector += _cross3(samples.q[:, model.node_dofs(node, "r")] - origin, force)
            for index, name in enumerate(names):
                if name != "r":
                    vector += _cross3(samples.q[:, model.node_dofs(node, name)],
                                      per_vector[:, index])
        if self.frame is not None and (self.quantity == "force" or dim == 3):
            frame = model.node_frame(samples.q, model.node_index(self.frame))
            vector = np.einsum("kji,kj->ki", frame, vector)
        return _component(vector, self.component)


def _constraint_force(model: ModelView, samples: Samples, dofs: np.ndarray) -> np.ndarray:
    """(k, dofs) generalised force of the constraints on coordinates ``dofs``: M a - F where
    they are held or prescribed, -A^T lambda where they are free."""
    held = samples.a @ model.mass[:, dofs] - samples.force[:, dofs]
    if not model.joints.shape[0] and not model.holonomic:
        return np.where(np.isin(dofs, model.free), 0.0, held)
    joints = _multiplier_force(model, samples, dofs)
    return np.where(np.isin(dofs, model.free), -joints, held)


def _multiplier_force(model: ModelView, samples: Samples, dofs: np.ndarray,
                      rows: list[int] | None = None) -> np.ndarray:
    """(k, dofs) C^T lambda on the coordinates ``dofs`` of the constraint rows ``rows``
    (indices into the multipliers [joints; quadratic rows]; None: all), C = [A; Phi_q(q)]."""
    nj = model.joints.shape[0]
    out = np.zeros((len(samples.q), dofs.size))
    for k, (q, lam) in enumerate(zip(samples.q, samples.multipliers, strict=True)):
        chosen = lam.copy() if rows is None else np.zeros_like(lam)
        if rows is not None:
            chosen[rows] = lam[rows]
        if nj:
            out[k] += model.joints[:, dofs].T @ chosen[:nj]
        if model.holonomic:
            out[k] += model.holonomic.jacobian(q)[:, dofs].T @ chosen[nj:]
    return out


def _cross3(arm: np.ndarray, force: np.ndarray) -> np.ndarray:
    """arm x force of (k, dim) vectors as (k, 3) (2D: the z part)."""
    if arm.shape[1] == 3:
        return np.cross(arm, force)
    out = np.zeros((arm.shape[0], 3))
    out[:, 2] = arm[:, 0] * force[:, 1] - arm[:, 1] * force[:, 0]
    return out


def _checked_component(sensor: Reaction | BodyReaction, path: str, context: Context) -> Record:
    """The reaction ``sensor``, SceneError unless its component exists for its quantity in
    the scene's dimension (a 2D force has x and y, a 2D moment z)."""
    allowed = ("x", "y", "z", "norm") if context.dim == 3 else \
        ("x", "y", "norm") if sensor.quantity == "force" else ("z", "norm")
    if sensor.component not in allowed:
        why = "a 2D moment is about z" if sensor.quantity == "moment" else \
            "a 2D force has x and y"
        raise SceneError(f"{path}.component: unknown component {show(sensor.component)} "
                         f"of a {context.dim}D {sensor.quantity} ({why}); expected one of "
                         f"{', '.join(allowed)}")
    return sensor


def _load_index_key(value: Any, path: str, context: Context) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < 0:
        raise SceneError(f"{path}: expected the index (0, 1, ...) of a [[load]] table, got "
                         f"{show(value)}")
    return value


def _constraint_index_key(value: Any, path: str, context: Context) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < 0:
        raise SceneError(f"{path}: expected the index (0, 1, ...) of a [[constraint]] of "
                         f"the body, got {show(value)}")
    return value


@dataclass(frozen=True)
class BodyReaction(RigidBodySensor):
    """The ``quantity`` (force in N | moment in N m about the body's origin) that the
    constraints exert on the rigid body ``body``: all of them, or the one ``constraint``
    (its index among the [[constraint]] tables), from the multipliers: the generalised force
    Q = -C^T lambda on the natural coordinates [r0, u, v, w] gives the force Q_r0 and the
    moment sum_a e_a x Q_a (e_a = u, v, w; the body's own rigidity rows add none; in 2D,
    on [r0, u], the moment about z u x Q_u).  One ``component`` (x | y | z | norm, the
    default; a 2D moment is about z: z | norm) in global axes."""

    type: ClassVar[str] = "body_reaction"
    dynamics: ClassVar[bool] = True
    quantity: str = key(_quantity_key, "force")
    component: str = key(_any_component_key, "norm")
    constraint: int | None = key(_constraint_index_key, None)

    @property
    def unit(self) -> str:   # type: ignore[override]
        return "N" if self.quantity == "force" else "N m"

    @classmethod
    def parse(cls, data: dict, path: str, context: Context) -> Record:
        return _checked_component(super().parse(data, path, context), path, context)

    def values(self, model: ModelView, samples: Samples) -> np.ndarray:
        rigid = model.rigid[self.body]
        if self.constraint is not None and self.constraint >= len(model.constraint_multipliers):
            raise ValueError(f"sensor {self.name}: constraint {self.constraint} out of range")
        rows = None if self.constraint is None else model.constraint_multipliers[
            self.constraint]
        force = -_multiplier_force(model, samples, rigid.dofs, rows)
        dim = model.dim
        if self.quantity == "force":
            return _component(force[:, :dim], self.component)
        vectors = samples.q[:, rigid.dofs].reshape(len(samples.q), -1, dim)[:, 1:]
        moment = sum(_cross3(vectors[:, a], force[:, dim * (a + 1):dim * (a + 2)])
                     for a in range(vectors.shape[1]))
        return _component(moment, self.component)


def _slide_quantity_key(value: Any, path: str, context: Context) -> str:
    return choice(value, path, ("parameter", "rate", "reaction"), "quantity")


@dataclass(frozen=True)
class Slide(Sensor):
    """The sliding joint ``constraint`` (its index among the [[constraint]] tables, a
    ``sliding`` one): its point's curve parameter s along the body (``quantity``
    "parameter", m: element index times the element length plus the local coordinate, the
    reference arc length on straight elements), its rate ds/dt ("rate", m/s), or the force
    the joint applies to the point ("reaction", N: -(d phi / d r_P)^T lambda from the rows'
    multipliers, normal to the line), one ``component`` (x | y | z | norm)."""

    type: ClassVar[str] = "slide"
    energy: ClassVar[bool] = False
    constraint: int = key(_constraint_index_key)
    quantity: str = key(_slide_quantity_key, "parameter")
    component: str = key(_component_key, "norm")

    @property
    def unit(self) -> str:   # type: ignore[override]
        return {"parameter": "m", "rate": "m/s", "reaction": "N"}[self.quantity]

    @property
    def dynamics(self) -> bool:   # type: ignore[override]
        return self.quantity == "reaction"

    def values(self, model: ModelView, samples: Samples) -> np.ndarray:
        rows = model.constraint_multipliers[self.constraint]
        joints = model.joints.shape[0]
        block = next(b for b, first in _blocks(model) if first + joints == rows[0])
        out = []
        for k, q in enumerate(samples.q):
            x = q[block.dofs]
            if self.quantity == "parameter":
                out.append(block.parameter(x))
            elif self.quantity == "rate":
                out.append(block.rate(x, samples.v[k][block.dofs]))
            else:
                out.append(block.force(x, samples.multipliers[k][rows]))
        if self.quantity != "reaction":
            return np.array(out)
        return _component(np.array(out), self.component)


def _blocks(model: ModelView):
    """(block, its first row among the quadratic rows) of the model's constraint blocks."""
    first = 0
    for block in model.holonomic.blocks:
        yield block, first
        first += block.rows


def check_reactions(sensors: tuple[Sensor, ...], constraints: tuple) -> None:
    """SceneError naming a reaction sensor whose node no constraint holds or joins."""
    held = {ref for c in constraints for ref in c.targets()}
    for i, sensor in enumerate(sensors):
        if not isinstance(sensor, Reaction):
            continue
        free = [ref for ref in sensor.targets() if ref not in held]
        if free and sensor.edge is not None:
            raise SceneError(f"sensor[{i}].edge: node {free[0]} of edge {sensor.edge} is held "
                             f"by no clamp, pin or prescribed_rotation and in no joint; "
                             f"expected an edge held by a [[constraint]]")
        if free:
            raise SceneError(f"sensor[{i}].node: node {sensor.node} is held by no clamp, pin "
                             f"or prescribed_rotation and in no joint (no reaction to "
                             f"measure); expected a node of a [[constraint]]")


def _integer_key(value: Any, path: str, context: Context) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        raise SceneError(f"{path}: expected an integer element index (0 the first, -1 the "
                         f"last), got {show(value)}")
    return value


def _point_key(value: Any, path: str, context: Context) -> tuple[float, ...]:
    axes = "x, y, z" if context.dim == 3 else "x, y"
    return vector(value, path, context.dim, f"local coordinates {axes} in m")


def _element_of(sensor: Any, path: str, context: Context) -> tuple[Any, int]:
    """The scene body of ``sensor.body`` and its element index made non-negative (SceneError
    at ``path.element`` out of range)."""
    body = context.node.bodies[sensor.body]
    count = int(np.prod(body.counts))
    if not -count <= sensor.element < count:
        raise SceneError(f"{path}.element: element index {sensor.element} out of range for "
                         f"body {show(sensor.body)} with {count} elements (0..{count - 1} or "
                         f"-{count}..-1)")
    return body, sensor.element % count


def _check_point(point: tuple[float, ...], body: Any, path: str) -> None:
    """SceneError at ``path`` unless ``point`` lies in the element's local box (a cable's on
    its axis)."""
    kind = element_kind(body.element)
    bounds = kind.domain.bounds(body.geometry)
    names = "xyz"
    for a, ((low, high), value) in enumerate(zip(bounds, point, strict=True)):
        slack = 1e-12 * max(abs(low), abs(high), 1e-30)
        if not low - slack <= value <= high + slack:
            raise SceneError(f"{path}[{a}]: local {names[a]} = {value:g} m outside the element "
                             f"of body {show(body.name)} ({names[a]} in [{low:g}, {high:g}] "
                             f"m); expected a point of the element's local box")
    if kind.energy.structural and any(point[1:]):
        raise SceneError(f"{path}: a cable ({kind.name}) has no cross section (r, r_x only): "
                         f"its strain is the axial strain on the axis; expected y"
                         f"{' and z' if kind.dim == 3 else ''} = 0")


TENSOR_COMPONENTS = {2: ("xx", "yy", "xy"), 3: ("xx", "yy", "zz", "yz", "xz", "xy")}


def _tensor_component_key(value: Any, path: str, context: Context) -> str:
    return choice(value, path, (*TENSOR_COMPONENTS[context.dim], "von_mises"), "component")


@dataclass(frozen=True)
class MaterialPointSensor(Sensor):
    """A tensor field at the material point ``point`` (local coordinates x, y(, z) in m in
    the element's box: x along the axis from its first node) of element ``element`` (0-based
    along the body; negative from the end) of ``body``: one ``component`` xx | yy | zz | yz
    | xz | xy (2D: xx, yy, xy) in the element's local frame
    (``runtime.model.items.material_points``)."""

    energy: ClassVar[bool] = False
    body: str = key(_body_key)
    element: int = key(_integer_key)
    point: tuple[float, ...] = key(_point_key)
    component: str = key(_tensor_component_key)

    @classmethod
    def parse(cls, data: dict, path: str, context: Context) -> Record:
        sensor = super().parse(data, path, context)
        body, element = _element_of(sensor, path, context)
        _check_point(sensor.point, body, f"{path}.point")
        return dataclasses.replace(sensor, element=element)

    def _tensor(self, model: ModelView, samples: Samples) -> np.ndarray:
        """The (k, dim, dim) tensor this sensor reads."""
        raise NotImplementedError

    def _fields(self, model: ModelView, samples: Samples) -> material.Fields:
        return material.strain_stress(model.bodies[self.body], np.array([self.element]),
                                      np.array([self.point], float), samples.q)

    def values(self, model: ModelView, samples: Samples) -> np.ndarray:
        tensor = self._tensor(model, samples)
        if self.component == "von_mises":
            return material.von_mises(tensor)
        a, b = ("xyz".index(c) for c in self.component)
        return tensor[:, a, b].copy()


@dataclass(frozen=True)
class Strain(MaterialPointSensor):
    """Green-Lagrange strain (dimensionless) in the reference local frame."""

    type: ClassVar[str] = "strain"
    unit: ClassVar[str] = "1"

    @classmethod
    def parse(cls, data: dict, path: str, context: Context) -> Record:
        if data.get("component") == "von_mises":
            raise SceneError(f"{path}.component: von_mises is a stress; expected one of "
                             f"{', '.join(TENSOR_COMPONENTS[context.dim])}")
        return super().parse(data, path, context)

    def _tensor(self, model: ModelView, samples: Samples) -> np.ndarray:
        return self._fields(model, samples).strain[:, 0, 0]


def _measure_key(value: Any, path: str, context: Context) -> str:
    return choice(value, path, STRESS_MEASURES, "stress measure")


STRESS_MEASURES = ("cauchy", "pk2")


@dataclass(frozen=True)
class Stress(MaterialPointSensor):
    """Stress (Pa) of the element's material law: ``measure`` cauchy (default; in the current
    local frame) | pk2 (second Piola-Kirchhoff, in the reference local frame); component
    ``von_mises`` is that of the Cauchy stress whatever the measure."""

    type: ClassVar[str] = "stress"
    unit: ClassVar[str] = "Pa"
    measure: str = key(_measure_key, "cauchy")

    def _tensor(self, model: ModelView, samples: Samples) -> np.ndarray:
        fields = self._fields(model, samples)
        chosen = fields.pk2 if self.measure == "pk2" and self.component != "von_mises" \
            else fields.cauchy
        return chosen[:, 0, 0]


SECTION_COMPONENTS = {2: ("N", "Q2", "M3", "M"), 3: ("N", "Q2", "Q3", "T", "M2", "M3", "M")}
CABLE_SECTION_COMPONENTS = {2: ("N", "M3", "M"), 3: ("N", "M")}


def _section_component_key(value: Any, path: str, context: Context) -> str:
    return choice(value, path, SECTION_COMPONENTS[context.dim], "section force")


def _position_key(value: Any, path: str, context: Context) -> float:
    return number(value, path)


@dataclass(frozen=True)
class SectionForce(Sensor):
    """A section force of a beam ``body`` at local axial position ``x`` (m, from the element's
    first node) of element ``element``: ``component`` N (axial), Q2, Q3 (shears), T
    (torsion), M2, M3 (bending), M (the bending moment's magnitude) in the current local
    frame (2D: N, Q2, M3, M; cables: N, M3 (2D), M), the force and moment that the part
    beyond the section exerts on the part before it (``runtime.model.items.material_points``)."""

    type: ClassVar[str] = "section"
    energy: ClassVar[bool] = False
    body: str = key(_body_key)
    element: int = key(_integer_key)
    x: float = key(_position_key)
    component: str = key(_section_component_key)

    @property
    def unit(self) -> str:   # type: ignore[override]
        return "N" if self.component.startswith(("N", "Q")) else "N m"

    @classmethod
    def parse(cls, data: dict, path: str, context: Context) -> Record:
        sensor = super().parse(data, path, context)
        body, element = _element_of(sensor, path, context)
        kind = element_kind(body.element)
        if kind.mesh_axes != [0]:
            what = "surface" if len(kind.mesh_axes) == 2 else "solid"
            raise SceneError(f"{path}.body: body {show(body.name)} is a {kind.name} {what}; "
                             f"section forces are those of beams (a line of elements)")
        point = (sensor.x,) + (0.0,) * (context.dim - 1)
        _check_point(point, body, f"{path}.x")
        if kind.energy.structural and sensor.component not in \
                CABLE_SECTION_COMPONENTS[context.dim]:
            allowed = CABLE_SECTION_COMPONENTS[context.dim]
            raise SceneError(f"{path}.component: a cable ({kind.name}) carries no shear, "
                             f"torsion{' or section orientation' if context.dim == 3 else ''}"
                             f"; expected one of {', '.join(allowed)}")
        return dataclasses.replace(sensor, element=element)

    def values(self, model: ModelView, samples: Samples) -> np.ndarray:
        section = material.section_forces(model.bodies[self.body], self.element, self.x,
                                          samples.q)
        return section.components()[self.component].copy()


@dataclass(frozen=True)
class StrainEnergy(Sensor):
    """Strain energy (J) of ``body`` (None: the whole model)."""

    type: ClassVar[str] = "strain_energy"
    body: str | None = key(_body_key, None)

    def values(self, model: ModelView, samples: Samples) -> np.ndarray:
        return model.strain_energy(samples.q, self.body)


@dataclass(frozen=True)
class KineticEnergy(Sensor):
    """Kinetic energy 1/2 v^T M v (J) of ``body`` (None: the whole model)."""

    type: ClassVar[str] = "kinetic_energy"
    body: str | None = key(_body_key, None)

    def values(self, model: ModelView, samples: Samples) -> np.ndarray:
        return model.kinetic_energy(samples.v, self.body)


@dataclass(frozen=True)
class PotentialEnergy(Sensor):
    """Potential energy (J) of the gravity loads relative to the reference, plus the
    energy stored in the springs of spring-dampers."""

    type: ClassVar[str] = "potential_energy"

    def values(self, model: ModelView, samples: Samples) -> np.ndarray:
        return (model.gravity_potential(samples.q, samples.t)
                + model.spring_energy(samples.q, samples.t, samples.spring_angles))


@dataclass(frozen=True)
class TotalEnergy(Sensor):
    """Strain + kinetic + potential energy (J: gravity and springs) of the whole model."""

    type: ClassVar[str] = "total_energy"

    def values(self, model: ModelView, samples: Samples) -> np.ndarray:
        return (model.strain_energy(samples.q) + model.kinetic_energy(samples.v)
                + model.gravity_potential(samples.q, samples.t)
                + model.spring_energy(samples.q, samples.t, samples.spring_angles))


@dataclass(frozen=True)
class DissipatedEnergy(Sensor):
    """Energy (J) dissipated by Kelvin-Voigt damping since the start of the dynamic run (the
    engines integrate the dissipated power step by step; 0 in static analysis and without
    damping).  total_energy + dissipated_energy is conserved in a free motion."""

    type: ClassVar[str] = "dissipated_energy"

    def values(self, model: ModelView, samples: Samples) -> np.ndarray:
        return samples.dissipated.copy() if samples.t is not None else \
            np.zeros(len(samples.q))


@dataclass(frozen=True)
class SpringAngle(Sensor):
    """The deflection phi - phi_0 (rad) of the torsional spring ``load`` (its index among
    the [[load]] tables, a ``torsional_spring`` one), turns counted: past half a turn it
    goes on growing (``runtime.model.items.force_elements``)."""

    type: ClassVar[str] = "spring_angle"
    unit: ClassVar[str] = "rad"
    energy: ClassVar[bool] = False
    load: int = key(_load_index_key)

    def values(self, model: ModelView, samples: Samples) -> np.ndarray:
        spring = model.scene.loads[self.load].state_force(model)
        if samples.spring_angles is None:
            return np.array([spring.deflection(q) for q in samples.q])
        return np.array([spring.deflection(q, float(near)) for q, near in
                         zip(samples.q, samples.spring_angles[:, self.load], strict=True)])


@dataclass(frozen=True)
class ConstraintViolation(Sensor):
    """max |A q| of the joint rows and |Phi(q)| of the quadratic constraint rows (rigid
    bodies, 3D joints) (m, or 1 for the unit-length rows; 0 without joints)."""

    type: ClassVar[str] = "constraint_violation"
    unit: ClassVar[str] = "m"
    energy: ClassVar[bool] = False

    def values(self, model: ModelView, samples: Samples) -> np.ndarray:
        violation = np.zeros(len(samples.q))
        if model.joints.shape[0]:
            violation = np.abs(model.joints @ samples.q.T
                               - model.joint_offsets[:, None]).max(axis=0)
        if model.holonomic:
            violation = np.maximum(violation, [np.abs(model.holonomic.value(q)).max()
                                               for q in samples.q])
        return violation


SENSORS: dict[str, type[Sensor]] = registry(
    Displacement, Position, StrainEnergy, KineticEnergy, PotentialEnergy, TotalEnergy,
    DissipatedEnergy, ConstraintViolation, Velocity, Acceleration, Reaction, Strain, Stress,
    SectionForce, BodyPosition, BodyVelocity, BodyAngle, BodyAngularVelocity, BodyReaction,
    Slide, SpringAngle)
ENERGY_TYPES = tuple(name for name, cls in SENSORS.items() if cls.energy)


class Sensors:
    """Evaluates every sensor of a model's scene on global states (q, v)."""

    def __init__(self, model: ModelView) -> None:
        self.model = model
        self.sensors = model.scene.sensors
        self.names = [s.name for s in self.sensors]
        self.energy_names = [s.name for s in self.sensors if s.energy]
        #: some sensor needs the accelerations, multipliers and forces of the samples
        self.dynamics = any(s.dynamics for s in self.sensors)

    def values(self, q: np.ndarray, v: np.ndarray | None = None,
               t: float | None = 0.0, *, a: np.ndarray | None = None,
               multipliers: np.ndarray | None = None,
               force: np.ndarray | None = None,
               spring_angles: np.ndarray | None = None) -> dict[str, float]:
        """{sensor name: value} at coordinates q (and velocities v, zero if None), time t
        (None: loads at their nominal value, as in the static analysis), with the
        accelerations a (size,), joint multipliers and applied force (size,) of
        ``Samples`` where a sensor needs them; the energy dissipated so far is the model's
        ``dissipated_energy``, the torsional springs' angles (loads,) ``spring_angles`` or
        else the model's."""
        v = np.zeros_like(q) if v is None else v

        def row(x):
            return None if x is None else np.asarray(x, float)[None, :]

        samples = Samples(None if t is None else np.array([t], float), q[None, :], v[None, :],
                          np.array([self.model.dissipated_energy]), row(a), row(multipliers),
                          row(force), row(self.model.spring_angles if spring_angles is None
                                          else spring_angles))
        return {name: float(value[0]) for name, value in self.block(samples).items()}

    def block(self, samples: Samples) -> dict[str, np.ndarray]:
        """{sensor name: values (k,)} over a block of output states (ValueError when a
        sensor needs the accelerations, multipliers and forces and they are not given)."""
        if self.dynamics and (samples.a is None or samples.force is None
                              or samples.multipliers is None):
            names = ", ".join(s.name for s in self.sensors if s.dynamics)
            raise ValueError(f"sensors {names}: need the accelerations, multipliers and "
                             f"forces of the states (Samples.a, multipliers, force: "
                             f"runtime.solve.python_engine.OutputDynamics)")
        return {s.name: s.values(self.model, samples) for s in self.sensors}
