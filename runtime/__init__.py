"""Runtime of the ANCF toolchain: generated kernels, elements, models and the CLI.

The public Python API: ``Element``; scenes built from the dataclasses below (the same
validation and messages as TOML files, ``Scene.to_toml()``, ``load_scene(path)``); and
``run_scene(scene) -> Result`` (every analysis in memory, no file written).
"""

from runtime.app.result import Result
from runtime.app.simulation import run_scene
from runtime.element.element import Element
from runtime.model.bodies import Body, Material, Spin
from runtime.model.errors import SceneError
from runtime.model.items.axis_joints import BodyCylindrical, BodyUniversal
from runtime.model.items.body_joints import (
    BodyPrismatic,
    BodyRevolute,
    BodySpherical,
    BodyWeld,
)
from runtime.model.items.constraints import Clamp, Hub, Pin, Revolute, Spherical, Weld
from runtime.model.items.loads import (
    BodyForce,
    BodyTorque,
    Bushing,
    DistributedForce,
    End,
    FaceForce,
    Gravity,
    LineForce,
    LineMoment,
    PointForce,
    PointMoment,
    Pressure,
    PythonLoad,
    SpringDamper,
    TorsionalSpring,
)
from runtime.model.items.node_frame_joints import Cylindrical, Prismatic, Universal
from runtime.model.items.rigid import PointMass, RigidBody
from runtime.model.items.sensors import (
    Acceleration,
    BodyAngle,
    BodyAngularVelocity,
    BodyPosition,
    BodyReaction,
    BodyVelocity,
    ConstraintViolation,
    Displacement,
    DissipatedEnergy,
    KineticEnergy,
    Position,
    PotentialEnergy,
    Reaction,
    SectionForce,
    Sensor,
    Slide,
    SpringAngle,
    Strain,
    StrainEnergy,
    Stress,
    TotalEnergy,
    Velocity,
)
from runtime.model.items.sliding import Sliding
from runtime.model.items.symmetry import Fix, Symmetry
from runtime.model.placements import Arc, Rectangle
from runtime.model.scene import Scene, load_scene
from runtime.model.schema import NodeRef
from runtime.model.settings import Dynamic, Modal, Output, Solver, Static
from runtime.model.time_laws import (
    Constant,
    ConstantRate,
    CosineRamp,
    LinearRamp,
    PythonLaw,
    Sine,
    SpinUp,
    Table,
)

__all__ = [
    "Acceleration", "Arc", "Body", "BodyAngle", "BodyAngularVelocity", "BodyCylindrical",
    "BodyForce",
    "BodyPosition", "BodyPrismatic",
    "BodyReaction", "BodyRevolute", "BodySpherical", "BodyTorque", "BodyUniversal", "BodyVelocity",
    "BodyWeld", "Bushing", "Clamp", "Constant", "ConstantRate", "ConstraintViolation",
    "CosineRamp", "Cylindrical", "Displacement", "DissipatedEnergy", "DistributedForce",
    "Dynamic", "Element",
    "End", "FaceForce", "Fix", "Gravity", "Hub", "KineticEnergy", "LineForce", "LineMoment",
    "LinearRamp", "Material", "Modal", "NodeRef", "Output", "Pin", "PointForce", "PointMass",
    "PointMoment", "Position", "PotentialEnergy", "Pressure", "Prismatic", "PythonLaw",
    "PythonLoad",
    "Reaction", "Rectangle", "Result", "Revolute", "RigidBody", "Scene", "SceneError",
    "SectionForce", "Sensor", "Sine", "Slide", "Sliding", "Solver", "Spherical", "Spin",
    "SpinUp", "SpringAngle", "SpringDamper",
    "Static", "Strain", "StrainEnergy", "Stress", "Symmetry", "Table", "TorsionalSpring",
    "TotalEnergy", "Universal", "Velocity", "Weld", "load_scene", "run_scene"
]
