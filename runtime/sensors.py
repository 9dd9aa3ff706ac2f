"""Sensors: scalar quantities of a model state, as declared in a scene (DESIGN.md section 7)."""

from __future__ import annotations

import numpy as np

from runtime.model import Model

ENERGY_TYPES = ("strain_energy", "kinetic_energy", "potential_energy", "total_energy")


def node_frame(model: Model, q: np.ndarray, node: int) -> np.ndarray:
    """Orthonormal frame (dim, dim) of a node: its gradient vectors, orthonormalised with r_x
    kept as the first axis (exact for a rigidly rotated node such as a hub)."""
    gradients = np.column_stack([q[model.node_dofs(node, name)]
                                 for name in model.vectors if name != "r"])
    basis, upper = np.linalg.qr(gradients)
    return basis * np.sign(np.diag(upper))


class Sensors:
    """Evaluates every sensor of a scene on global states (q, v)."""

    def __init__(self, model: Model) -> None:
        self.model = model
        self.sensors = model.scene.sensors
        self.names = [s.name for s in self.sensors]
        self.energy_names = [s.name for s in self.sensors if s.type in ENERGY_TYPES]

    def values(self, q: np.ndarray, v: np.ndarray | None = None,
               t: float | None = 0.0) -> dict[str, float]:
        """{sensor name: value} at coordinates q (and velocities v, zero if None), time t
        (None: loads at their nominal value, as in the static analysis)."""
        v = np.zeros_like(q) if v is None else v
        return {s.name: self._value(s, q, v, t) for s in self.sensors}

    def _value(self, sensor, q: np.ndarray, v: np.ndarray, t: float | None) -> float:
        model = self.model
        if sensor.type == "strain_energy":
            return model.strain_energy(q, sensor.body)
        if sensor.type == "kinetic_energy":
            return model.kinetic_energy(v, sensor.body)
        if sensor.type == "potential_energy":
            return model.gravity_potential(q, t)
        if sensor.type == "total_energy":
            return (model.strain_energy(q) + model.kinetic_energy(v)
                    + model.gravity_potential(q, t))
        if sensor.type == "constraint_violation":
            if model.joints.shape[0] == 0:
                return 0.0
            return float(np.abs(model.joints @ q).max())
        node = model.node_index(sensor.node)
        position = q[model.node_dofs(node, "r")]
        reference = model.reference[model.node_dofs(node, "r")]
        if sensor.frame is not None:
            frame_node = model.node_index(sensor.frame)
            origin = q[model.node_dofs(frame_node, "r")]
            origin0 = model.reference[model.node_dofs(frame_node, "r")]
            position = node_frame(model, q, frame_node).T @ (position - origin)
            reference = node_frame(model, model.reference, frame_node).T @ (reference - origin0)
        vector = position - reference if sensor.type == "displacement" else position
        if sensor.component == "norm":
            return float(np.linalg.norm(vector))
        return float(vector["xyz".index(sensor.component)])
