"""Sensors: named scalar outputs of a model state (``[[sensor]]`` tables), a typed registry
``SENSORS``.

Each class declares its TOML keys as fields (``runtime.model.schema.Record``), its ``unit`` and
whether it is an ``energy`` (plotted together), and computes its values over a block of
``Samples`` (k output times at once, vectorised: one output time is a block of one); adding
one is one class here and one entry in ``SENSORS``.  ``Sensors`` evaluates all the sensors of
a model's scene, at one state or over a block.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from runtime.kernels.kind import element_kind
from runtime.model.errors import SceneError, show
from runtime.model.items.base import ModelView
from runtime.model.schema import (
    NAME_LENGTH,
    Context,
    NodeRef,
    Record,
    choice,
    key,
    node_key,
    registry,
    string,
)

__all__ = ["ENERGY_TYPES", "SENSORS", "ConstraintViolation", "DissipatedEnergy", "Displacement",
           "KineticEnergy", "Position", "PotentialEnergy", "Samples", "Sensor", "Sensors",
           "StrainEnergy", "TotalEnergy", "Velocity"]

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
    ``dissipated`` (k,) in J by damping since the start of the dynamic run."""

    t: np.ndarray | None
    q: np.ndarray
    v: np.ndarray
    dissipated: np.ndarray


@dataclass(frozen=True)
class Sensor(Record):
    """Base of the sensors: ``name`` names a CSV column and a PNG plot; ``unit`` of the value;
    ``energy``: plotted with the other energies."""

    unit: ClassVar[str] = "J"
    energy: ClassVar[bool] = True
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


def _body_key(value: Any, path: str, context: Context) -> str:
    return choice(value, path, context.body_names, "body")


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
    """Potential energy (J) of the gravity loads relative to the reference."""

    type: ClassVar[str] = "potential_energy"

    def values(self, model: ModelView, samples: Samples) -> np.ndarray:
        return model.gravity_potential(samples.q, samples.t)


@dataclass(frozen=True)
class TotalEnergy(Sensor):
    """Strain + kinetic + gravity potential energy (J) of the whole model."""

    type: ClassVar[str] = "total_energy"

    def values(self, model: ModelView, samples: Samples) -> np.ndarray:
        return (model.strain_energy(samples.q) + model.kinetic_energy(samples.v)
                + model.gravity_potential(samples.q, samples.t))


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
class ConstraintViolation(Sensor):
    """max |A q| of the joint rows (m; 0 without joints)."""

    type: ClassVar[str] = "constraint_violation"
    unit: ClassVar[str] = "m"
    energy: ClassVar[bool] = False

    def values(self, model: ModelView, samples: Samples) -> np.ndarray:
        if model.joints.shape[0] == 0:
            return np.zeros(len(samples.q))
        return np.abs(model.joints @ samples.q.T).max(axis=0)


SENSORS: dict[str, type[Sensor]] = registry(
    Displacement, Position, StrainEnergy, KineticEnergy, PotentialEnergy, TotalEnergy,
    DissipatedEnergy, ConstraintViolation, Velocity)
ENERGY_TYPES = tuple(name for name, cls in SENSORS.items() if cls.energy)


class Sensors:
    """Evaluates every sensor of a model's scene on global states (q, v)."""

    def __init__(self, model: ModelView) -> None:
        self.model = model
        self.sensors = model.scene.sensors
        self.names = [s.name for s in self.sensors]
        self.energy_names = [s.name for s in self.sensors if s.energy]

    def values(self, q: np.ndarray, v: np.ndarray | None = None,
               t: float | None = 0.0) -> dict[str, float]:
        """{sensor name: value} at coordinates q (and velocities v, zero if None), time t
        (None: loads at their nominal value, as in the static analysis); the energy
        dissipated so far is the model's ``dissipated_energy``."""
        v = np.zeros_like(q) if v is None else v
        samples = Samples(None if t is None else np.array([t], float), q[None, :], v[None, :],
                          np.array([self.model.dissipated_energy]))
        return {name: float(value[0]) for name, value in self.block(samples).items()}

    def block(self, samples: Samples) -> dict[str, np.ndarray]:
        """{sensor name: values (k,)} over a block of output states."""
        return {s.name: s.values(self.model, samples) for s in self.sensors}
