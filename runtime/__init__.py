"""Runtime of the ANCF toolchain: generated kernels, elements, models and the CLI.

The public Python API: ``Element``, and scenes built from the dataclasses below (the same
validation and messages as TOML files, ``Scene.to_toml()``, ``load_scene(path)``).
"""

from runtime.constraints import Clamp, Hub, Pin, Revolute, Spherical, Weld
from runtime.element import Element
from runtime.laws import (
    Constant,
    ConstantRate,
    CosineRamp,
    LinearRamp,
    SceneError,
    Sine,
    SpinUp,
    Table,
)
from runtime.loads import Gravity, PointForce, PointMoment
from runtime.scene import (
    Arc,
    Body,
    Dynamic,
    Material,
    Modal,
    NodeRef,
    Output,
    Scene,
    Solver,
    Spin,
    Static,
    load_scene,
)
from runtime.sensors import (
    ConstraintViolation,
    Displacement,
    KineticEnergy,
    Position,
    PotentialEnergy,
    Sensor,
    StrainEnergy,
    TotalEnergy,
)

# run_scene(scene) -> Result (runtime/run.py, in memory, no file I/O) joins this API here

__all__ = [
    "Arc", "Body", "Clamp", "Constant", "ConstantRate", "ConstraintViolation", "CosineRamp",
    "Displacement", "Dynamic", "Element", "Gravity", "Hub", "KineticEnergy", "LinearRamp",
    "Material", "Modal", "NodeRef", "Output", "Pin", "PointForce", "PointMoment", "Position",
    "PotentialEnergy", "Revolute", "Scene", "SceneError", "Sensor", "Sine", "Solver", "Spherical",
    "Spin", "SpinUp", "StrainEnergy", "Static", "Table", "TotalEnergy", "Weld", "load_scene",
]
