"""The public Python API of scenes: the scene dataclasses validate as TOML files do (one
validation path, the same key-path messages), ``Scene.to_toml()`` and ``load_scene`` round-trip
exactly (a seeded property test over random valid scenes), and constraints, loads and sensors
are typed registries."""

from __future__ import annotations

import copy
import dataclasses
import math
import random
import tomllib

import numpy as np
import pytest

import scenes
from runtime import (
    Arc,
    Body,
    BodyAngle,
    BodyAngularVelocity,
    BodyCylindrical,
    BodyForce,
    BodyPosition,
    BodyPrismatic,
    BodyReaction,
    BodyRevolute,
    BodySpherical,
    BodyTorque,
    BodyUniversal,
    BodyVelocity,
    BodyWeld,
    Bushing,
    Clamp,
    Constant,
    ConstantRate,
    ConstraintViolation,
    CosineRamp,
    Cylindrical,
    Displacement,
    DissipatedEnergy,
    DistributedForce,
    Dynamic,
    End,
    FaceForce,
    Fix,
    Gravity,
    Hub,
    KineticEnergy,
    LinearRamp,
    LineForce,
    LineMoment,
    Material,
    Modal,
    NodeRef,
    Output,
    Pin,
    PointForce,
    PointMass,
    PointMoment,
    Position,
    PotentialEnergy,
    Pressure,
    Prismatic,
    Rectangle,
    Revolute,
    RigidBody,
    Scene,
    SceneError,
    Sine,
    Slide,
    Sliding,
    Solver,
    Spherical,
    Spin,
    SpinUp,
    SpringAngle,
    SpringDamper,
    Static,
    StrainEnergy,
    Symmetry,
    Table,
    TorsionalSpring,
    TotalEnergy,
    Universal,
    Velocity,
    Weld,
    load_scene,
)
from runtime.catalog import generated_kinds
from runtime.kernels.kind import element_kind
from runtime.model.items.constraint_types import CONSTRAINTS
from runtime.model.items.load_points import frame_gradients
from runtime.model.items.loads import LOADS
from runtime.model.items.rigid import RIGID_BODIES
from runtime.model.items.sensors import (
    SENSORS,
    Acceleration,
    Reaction,
    SectionForce,
    Strain,
    Stress,
)
from runtime.model.placements import Box
from runtime.model.scene import parse_scene

STEEL = Material("steel", E=2.1e11, nu=0.3, rho=7800.0)


def cantilever(**changes) -> Scene:
    """A 3D cantilever of 4 elements with a tip force, as the API builds it."""
    values = dict(title="api", materials=[STEEL],
                  bodies=[Body("beam", "beam3d", "steel", 0.1, 0.1, 4, (0, 0, 0), (1, 0, 0))],
                  constraints=[Clamp("beam:0")],
                  loads=[PointForce("beam:-1", (0, -100, 0), time_law=CosineRamp(0.5))],
                  sensors=[Displacement("tip_y", "beam:-1", "y")],
                  static=Static(), dynamic=Dynamic(t_end=0.01, step=1e-3))
    return Scene(**{**values, **changes})


# --------------------------------------------------------------------------- one validation

def test_a_python_scene_equals_its_toml_twin():
    scene = cantilever()
    assert scene == parse_scene(tomllib.loads(scene.to_toml()))
    # parsed values: resolved node references, floats, tuples, materials by name
    assert scene.constraints == (Clamp(NodeRef("beam", 0)),)
    assert scene.loads[0].node == NodeRef("beam", 4)
    assert scene.loads[0].force == (0.0, -100.0, 0.0)
    assert scene.bodies[0].start == (0.0, 0.0, 0.0)
    assert scene.materials == {"steel": STEEL}
    assert scene.source == "<scene>"


def test_the_brief_example_names_the_key_path():
    with pytest.raises(SceneError, match=r"^body\[0\]\.elements: expected a positive integer, "
                                         r"got 0$"):
        cantilever(bodies=[Body("beam", "beam3d", "steel", 0.1, 0.1, 0, (0, 0, 0), (1, 0, 0))])


def _message(build) -> str:
    with pytest.raises(SceneError) as info:
        build()
    return str(info.value)


BODY = Body("beam", "beam3d", "steel", 0.1, 0.1, 4, (0, 0, 0), (1, 0, 0))
# (Python change, the same change made to the TOML table)
SAME_ERRORS = [
    ({"bodies": [dataclasses.replace(BODY, height=-0.1)]},
     lambda d: d["body"][0]["section"].update(height=-0.1)),
    ({"bodies": [dataclasses.replace(BODY, element="beam9d")]},
     lambda d: d["body"][0].update(element="beam9d")),
    ({"bodies": [dataclasses.replace(BODY, end=(1.0, 0.0))]},
     lambda d: d["body"][0].update(end=[1.0, 0.0])),
    ({"bodies": [dataclasses.replace(BODY, initial_velocity=(1.0, 0.0))]},
     lambda d: d["body"][0].update(initial_velocity=[1.0, 0.0])),
    ({"bodies": [dataclasses.replace(BODY, initial_angular_velocity=Spin(2.0, (0, 0, 0)))]},
     lambda d: d["body"][0].update(initial_angular_velocity={"omega": 2.0,
                                                             "about": [0, 0, 0]})),
    ({"materials": [dataclasses.replace(STEEL, nu=0.5)]},
     lambda d: d["material"]["steel"].update(nu=0.5)),
    ({"constraints": [Clamp("beam:11")]}, lambda d: d["constraint"][0].update(node="beam:11")),
    ({"constraints": [Clamp("bem:0")]}, lambda d: d["constraint"][0].update(node="bem:0")),
    ({"constraints": [Clamp(NodeRef("beam", -6))]},
     lambda d: d["constraint"][0].update(node="beam:-6")),
    ({"constraints": [Clamp("beam:0"), Pin("beam:0")]},
     lambda d: d["constraint"].append({"type": "pin", "node": "beam:0"})),
    ({"constraints": [Clamp("beam:0"), Revolute(("beam:1", "beam:2"))]},
     lambda d: d["constraint"].append({"type": "revolute", "nodes": ["beam:1", "beam:2"]})),
    ({"constraints": [Clamp("beam:0"), Weld(("beam:1", "beam:1"))]},
     lambda d: d["constraint"].append({"type": "weld", "nodes": ["beam:1", "beam:1"]})),
    ({"constraints": [Clamp("beam:0"), Hub("beam:2", SpinUp(1.0, 1.0), (0, 0, 0))]},
     lambda d: d["constraint"].append({"type": "prescribed_rotation", "node": "beam:2",
                                       "angle": {"type": "spin_up", "omega": 1.0,
                                                 "t_ramp": 1.0}, "axis": [0, 0, 0]})),
    ({"loads": [PointForce("beam:0", (0, 1, 0))]},
     lambda d: d["load"][0].update(node="beam:0")),
    ({"loads": [PointMoment("beam:0", (0, 0, 1))]},
     lambda d: d["load"].__setitem__(0, {"type": "point_moment", "node": "beam:0",
                                         "moment": [0, 0, 1]})),
    ({"loads": [PointMoment("beam:-1", 1.0)]},
     lambda d: d["load"].__setitem__(0, {"type": "point_moment", "node": "beam:-1",
                                         "moment": 1.0})),
    ({"loads": [Gravity((0, -9.81, 0), time_law=CosineRamp(-1.0))]},
     lambda d: d["load"].__setitem__(0, {"type": "gravity", "acceleration": [0, -9.81, 0],
                                         "time_law": {"type": "cosine_ramp",
                                                      "duration": -1.0, "value": 1.0}})),
    ({"sensors": [Displacement("t", "beam:-1", "y")]},
     lambda d: d["sensor"][0].update(name="t")),
    ({"sensors": [Displacement("tip", "beam:-1", "w")]},
     lambda d: d["sensor"][0].update(name="tip", component="w")),
    ({"sensors": [StrainEnergy("U", "bem")]},
     lambda d: d["sensor"].__setitem__(0, {"name": "U", "type": "strain_energy",
                                           "body": "bem"})),
    ({"dynamic": Dynamic(t_end=0.0105, step=1e-3)},
     lambda d: d["analysis"]["dynamic"].update(t_end=0.0105)),
    ({"static": Static(load_steps=0)},
     lambda d: d["analysis"]["static"].update(load_steps=0)),
    ({"modal": Modal(about="deformed")}, lambda d: d["analysis"].update(modal={
        "about": "deformed"})),
    ({"solver": Solver(method="fast")}, lambda d: d.update(solver={"method": "fast"})),
    ({"output": Output(vtk="yes")}, lambda d: d.update(output={"vtk": "yes"})),
    ({"title": "a\nb"}, lambda d: d.update(title="a\nb")),
]


@pytest.mark.parametrize("changes, mutate", SAME_ERRORS,
                         ids=[",".join(c) + str(i) for i, (c, _) in enumerate(SAME_ERRORS)])
def test_python_and_toml_fail_with_the_same_message(changes, mutate):
    data = cantilever().to_dict()
    mutate(data)
    toml_message = _message(lambda: parse_scene(copy.deepcopy(data)))
    assert _message(lambda: cantilever(**changes)) == toml_message
    path = toml_message.split(":")[0]
    assert path and " " not in path.split(".")[0], toml_message


def test_replace_revalidates():
    scene = cantilever()
    longer = dataclasses.replace(scene, dynamic=Dynamic(t_end=0.02, step=1e-3))
    assert longer.dynamic.t_end == 0.02 and longer.bodies == scene.bodies
    with pytest.raises(SceneError, match=r"^analysis\.dynamic\.step: expected a step of at"):
        dataclasses.replace(scene, dynamic=Dynamic(t_end=0.01, step=1.0))


def test_node_references_from_the_end_follow_a_remeshed_body():
    scene = cantilever()
    assert scene.loads[0].node == NodeRef("beam", 4) and str(scene.loads[0].node) == "beam:4"
    finer = dataclasses.replace(scene, bodies=[dataclasses.replace(BODY, elements=8)])
    assert finer.loads[0].node == NodeRef("beam", 8)
    assert finer.sensors[0].node == NodeRef("beam", 8)
    # an index written from the start stays where it was
    fixed = dataclasses.replace(scene, loads=[PointForce(NodeRef("beam", 4), (0, -1, 0))])
    finer = dataclasses.replace(fixed, bodies=[dataclasses.replace(BODY, elements=8)])
    assert finer.loads[0].node == NodeRef("beam", 4)


def test_materials_as_a_sequence_or_by_name():
    by_name = cantilever(materials={"steel": STEEL})
    assert by_name == cantilever()
    with pytest.raises(SceneError, match=r"^material\.steel: duplicate material name"):
        cantilever(materials=[STEEL, STEEL])
    with pytest.raises(SceneError, match=r'^material\.iron: the material under this key is '
                                         r'called "steel"'):
        cantilever(materials={"iron": STEEL})
    with pytest.raises(SceneError, match=r"^material: expected Material objects"):
        cantilever(materials=[{"E": 1.0}])


def test_raw_tables_and_numpy_values_are_accepted():
    scene = cantilever(constraints=[{"type": "clamp", "node": "beam:0"}],
                       loads=[PointForce("beam:-1", np.array([0.0, -100.0, 0.0]),
                                         time_law=CosineRamp(np.float64(0.5)))],
                       bodies=[dataclasses.replace(BODY, elements=np.int64(4))])
    assert scene == cantilever()
    assert type(scene.bodies[0].elements) is int


def test_unknown_types_are_errors_listing_the_registry():
    data = cantilever().to_dict()
    data["load"][0]["type"] = "moment"
    message = _message(lambda: parse_scene(data))
    assert message == ('load[0].type: unknown load type "moment"; expected one of '
                       'point_force, point_moment, gravity, line_force, line_moment, '
                       'face_force, pressure, distributed_force, python, body_force, '
                       'spring_damper, body_torque, torsional_spring, bushing')
    data["load"][0] = {"acceleration": [0, -9.81, 0]}
    assert _message(lambda: parse_scene(data)).startswith("load[0].type: missing required key")


def test_registries_are_keyed_by_type():
    for registry in (CONSTRAINTS, LOADS, SENSORS):
        assert all(cls.type == name for name, cls in registry.items())
    assert list(CONSTRAINTS) == ["clamp", "pin", "symmetry", "fix", "prescribed_rotation",
                                 "spherical", "revolute", "weld", "prismatic",
                                 "cylindrical", "universal", "body_spherical",
                                 "body_revolute",
                                 "body_prismatic", "body_weld", "body_cylindrical",
                                 "body_universal", "sliding"]
    assert list(LOADS) == ["point_force", "point_moment", "gravity", "line_force",
                           "line_moment", "face_force", "pressure", "distributed_force",
                           "python",
                           "body_force", "spring_damper", "body_torque", "torsional_spring",
                           "bushing"]
    assert list(SENSORS) == ["displacement", "position", "strain_energy", "kinetic_energy",
                             "potential_energy", "total_energy", "dissipated_energy",
                             "constraint_violation", "velocity", "acceleration", "reaction",
                             "strain", "stress", "section", "body_position", "body_velocity",
                             "body_angle", "body_angular_velocity", "body_reaction", "slide",
                             "spring_angle"]
    assert list(RIGID_BODIES) == ["rigid", "point_mass"]


def test_output_table():
    scene = cantilever(output=Output(vtk=True, states=True))
    assert scene.output == Output(vtk=True, animation=False, states=True)
    assert "[output]\nvtk = true\nstates = true\n" in scene.to_toml()
    assert cantilever().output == Output()
    data = cantilever().to_dict()
    data["output"] = {"gif": True}
    assert _message(lambda: parse_scene(data)).startswith(
        "output.gif: unknown key; expected one of vtk, animation, states")
    data["output"] = {"animation": 1}
    assert _message(lambda: parse_scene(data)) == \
        "output.animation: expected true or false, got 1"


def test_initial_conditions_parse_per_dimension():
    spin = Spin((0.0, 0.0, 2.0), (0.5, 0.0, 0.0))
    scene = cantilever(bodies=[dataclasses.replace(BODY, initial_velocity=[1, 0, 0],
                                                   initial_angular_velocity=spin)])
    assert scene.bodies[0].initial_velocity == (1.0, 0.0, 0.0)
    assert scene.bodies[0].initial_angular_velocity == spin
    data = scene.to_dict()
    assert data["body"][0]["initial_angular_velocity"] == {"omega": [0.0, 0.0, 2.0],
                                                           "about": [0.5, 0.0, 0.0]}
    del data["body"][0]["initial_angular_velocity"]["about"]
    assert _message(lambda: parse_scene(data)).startswith(
        "body[0].initial_angular_velocity.about: missing required key; expected the point")
    message = _message(lambda: cantilever(bodies=[dataclasses.replace(
        BODY, initial_angular_velocity=Spin(2.0, (0, 0, 0)))]))
    assert message == ("body[0].initial_angular_velocity.omega: expected a list of 3 numbers "
                       "(the scene is 3D), got 2.0")


# --------------------------------------------------------------------------- round trip

NAMES = ["beam", "link", "arm ü", "b-2", "x.y", "Bar_3"]
MATERIAL_NAMES = ["steel", "alu 2", 'q"uote', "ü-mat", "a.b", "back\\slash"]
TITLES = ["untitled", 'a "quoted" title', "back \\ slash", "ünïcode — dash", "x" * 200]


def _number(rng: random.Random, low: float, high: float) -> float:
    """A float with all its digits (round trips must keep every bit)."""
    return rng.uniform(low, high)


def _law(rng: random.Random):
    kind = rng.randrange(7)
    if kind == 0:
        return Constant(_number(rng, -2, 2))
    if kind == 1:
        return CosineRamp(_number(rng, 0.1, 2), _number(rng, -2, 2))
    if kind == 2:
        return LinearRamp(_number(rng, 0.1, 2), _number(rng, -2, 2))
    if kind == 3:
        return Sine(_number(rng, -2, 2), _number(rng, 0.1, 5), _number(rng, -90, 90),
                    _number(rng, -1, 1))
    if kind == 4:
        times = sorted({round(_number(rng, 0, 5), 6) for _ in range(rng.randint(1, 4))})
        return Table(tuple((t, _number(rng, -1, 1)) for t in times))
    if kind == 5:
        return SpinUp(_number(rng, -5, 5), _number(rng, 0.1, 20))
    return ConstantRate(_number(rng, -5, 5))


def _vector(rng: random.Random, dim: int, scale: float = 1.0) -> tuple[float, ...]:
    return tuple(_number(rng, -scale, scale) for _ in range(dim))


def _rotation(rng: random.Random, dim: int):
    return _number(rng, -3, 3) if dim == 2 else _vector(rng, 3, 3)


def random_scene(rng: random.Random) -> Scene:
    """A random valid scene using every kind of body, constraint, load, sensor and table."""
    dim = rng.choice([2, 3])
    line_kinds = [k for k in generated_kinds() if element_kind(k).dim == dim
                  and len(element_kind(k).mesh_axes) == 1]
    materials = []
    for name in rng.sample(MATERIAL_NAMES, rng.randint(1, 3)):
        law = rng.choice(["svk", "ecm"])
        materials.append(Material(
            name, _number(rng, 1e9, 3e11), _number(rng, -0.5, 0.49), _number(rng, 100, 9000),
            law, _number(rng, 0.5, 1.0) if law == "ecm" and rng.random() < 0.5 else None,
            _number(rng, 0, 1e-3) if rng.random() < 0.3 else 0.0))
    # a chain of bodies, each starting where the previous one ends
    point = _vector(rng, dim, 2.0)
    bodies = []
    for name in rng.sample(NAMES, rng.randint(1, 3)):
        elements = rng.randint(1, 4)
        kind = rng.choice(line_kinds)        # with a material whose law applies to it
        usable = [m.name for m in materials if element_kind(kind).law_not_applicable(m.law)
                  is None]
        if not usable:
            materials.append(Material(f"m{len(materials)}", 2e11, 0.3, 7800.0))
            usable = [materials[-1].name]
        common = dict(name=name, element=kind, material=rng.choice(usable),
                      height=_number(rng, 0.01, 0.2), width=_number(rng, 0.01, 0.2),
                      elements=elements)
        if rng.random() < 0.3 and "general" in element_kind(kind).energy.variants:
            radius, start = _number(rng, 0.5, 2.0), _number(rng, -180, 180)
            angle = rng.choice([-1, 1]) * _number(rng, 10, 120)
            center = (point[0] - radius * math.cos(math.radians(start)),
                      point[1] - radius * math.sin(math.radians(start)), *point[2:])
            body = Body(**common, arc=Arc(center, radius, start, angle))
            end = math.radians(start + angle)
            point = (center[0] + radius * math.cos(end), center[1] + radius * math.sin(end),
                     *point[2:])
        else:
            end = tuple(p + d for p, d in zip(point, _vector(rng, dim, 1.5), strict=True))
            body = Body(**common, start=point, end=end)
            point = end
        if rng.random() < 0.4:
            body = dataclasses.replace(body, quadrature=tuple(rng.randint(1, 6)
                                                              for _ in range(dim)))
        if rng.random() < 0.4:
            body = dataclasses.replace(body, initial_velocity=_vector(rng, dim))
        if rng.random() < 0.4:
            body = dataclasses.replace(body, initial_angular_velocity=Spin(
                _rotation(rng, dim), _vector(rng, dim)))
        bodies.append(body)
    plate_kinds = [k for k in generated_kinds() if len(element_kind(k).mesh_axes) == 2]
    plate = None
    if dim == 3 and rng.random() < 0.4:   # a plate apart from the chain
        grid = (rng.randint(1, 3), rng.randint(1, 3))
        kind = rng.choice(plate_kinds)       # with a material whose law applies to it
        usable = [m.name for m in materials if element_kind(kind).law_not_applicable(m.law)
                  is None]
        if not usable:
            materials.append(Material("sheet_metal", 2e11, 0.0, 7800.0))
            usable = ["sheet_metal"]
        plate = Body("sheet", kind, rng.choice(usable),
                     rectangle=Rectangle(tuple(np.add(_vector(rng, 3, 2.0), (0, 0, 10.0))),
                                         (_number(rng, 0.1, 2), _number(rng, 0.1, 2)), grid),
                     thickness=_number(rng, 0.001, 0.05))
        bodies.append(plate)

    solid_kinds = [k for k in generated_kinds() if len(element_kind(k).mesh_axes) == 3]
    block = None
    if dim == 3 and solid_kinds and rng.random() < 0.3:   # a block apart from the chain
        grid = tuple(rng.randint(1, 2) for _ in range(3))
        block = Body("block", rng.choice(solid_kinds), "solid_steel",
                     box=Box(tuple(np.add(_vector(rng, 3, 2.0), (0, 0, -10.0))),
                             tuple(_number(rng, 0.1, 1) for _ in range(3)), grid))
        materials.append(Material("solid_steel", 2e11, 0.3, 7800.0))
        bodies.append(block)

    constraints, held = [], {}
    first = f"{bodies[0].name}:0"
    kind = rng.choice([Clamp, Pin, Hub, None])
    if kind is Hub:
        constraints.append(Hub(first, _law(rng), _vector(rng, 3) if dim == 3 and
                               rng.random() < 0.5 else None))
    elif kind is not None:
        constraints.append(kind(first))
    if kind is not None:
        held[(bodies[0].name, 0)] = kind
    chain = [b for b in bodies if b is not plate and b is not block]
    for a, b in zip(chain, chain[1:], strict=False):
        # nodes carrying r and every first gradient, nothing else (not r_xx of a quintic cable)
        full = all(element_kind(x.element).vectors == ("r", *element_kind(x.element)
                                                       .first_gradients)
                   and len(element_kind(x.element).first_gradients) == dim for x in (a, b))
        joints = ([Spherical] + ([Weld, Prismatic] if full else [])
                  + ([Revolute] if dim == 2 or full else [])
                  + ([Cylindrical, Universal] if full and dim == 3 else []))
        joint = rng.choice(joints)((f"{a.name}:-1", NodeRef(b.name, 0)))
        if isinstance(joint, Revolute | Cylindrical) and dim == 3 and rng.random() < 0.5:
            joint = dataclasses.replace(joint, axis=_vector(rng, 3))   # normalised
        if isinstance(joint, Prismatic) and rng.random() < 0.5:
            joint = dataclasses.replace(joint, axis=_vector(rng, dim), displacement=rng.choice(
                [None, CosineRamp(_number(rng, 0.1, 2), _number(rng, -1, 1))]))
        if isinstance(joint, Universal) and rng.random() < 0.5:     # the cross: normal axes
            axis = _vector(rng, 3)
            joint = dataclasses.replace(joint, axis=axis, other_axis=tuple(
                float(x) for x in np.cross(axis, _vector(rng, 3))))
        constraints.append(joint)
    if plate is not None:
        edge = rng.choice(["x=0", "x=-1", "y=0", "y=-1"])
        constraints.append(rng.choice([Clamp, Pin])(edge=f"sheet:{edge}"))
        axis, line = edge.split("=")
        a = "xy".index(axis)
        line = int(line) % plate.grid_shape[a]
        # the nodes on that lattice line (a layout with mid-side nodes has fewer than a
        # full grid: runtime/model/mesh.py)
        for node in plate.mesh.on_line(a, line):
            held[("sheet", int(node))] = type(constraints[-1])
        other = {"x=0": "x=-1", "x=-1": "x=0", "y=0": "y=-1", "y=-1": "y=0"}[edge]
        # follower loads and edge moments need a node frame (not r, r_z shells')
        framed = frame_gradients(element_kind(plate.element)) is not None
        loads_on_plate = [rng.choice([
            LineForce(edge=f"sheet:{other}", force_per_length=_vector(rng, 3),
                      follower=framed and rng.random() < 0.5),
            *([LineMoment(edge=f"sheet:{other}", moment_per_length=_vector(rng, 3),
                          follower=rng.random() < 0.5)] if framed else []),
            Pressure(body="sheet", pressure=_number(rng, -1e3, 1e3))])]
        if rng.random() < 0.5:    # the free edge on a mirror plane normal to its axis
            normal = tuple(float(i == a) * rng.choice([-1.0, 1.0]) for i in range(3))
            constraints.append(Symmetry(edge=f"sheet:{other}", normal=normal))
    for body in chain:            # pins and fixed components on interior nodes
        for index in range(1, body.n_nodes - 1):
            if rng.random() < 0.2:
                constraints.append(Pin(NodeRef(body.name, index)))
                held[(body.name, index)] = Pin
            elif rng.random() < 0.2:
                constraints.append(Fix(NodeRef(body.name, index), components=tuple(
                    rng.sample("xyz"[:dim], rng.randint(1, dim)))))

    loads = loads_on_plate if plate is not None else []
    if block is not None:
        face = f"block:{rng.choice('xyz')}={rng.choice([0, -1])}"
        loads.append(FaceForce(face, _vector(rng, 3)))
    for _ in range(rng.randint(0, 3)):
        body = rng.choice(bodies)
        index = rng.randrange(body.n_nodes)
        holder = held.get((body.name, index))
        law = _law(rng) if rng.random() < 0.5 else Constant()
        options = [Gravity(_vector(rng, dim, 10), time_law=law)]
        vectors = element_kind(body.element).vectors
        # a follower load needs a frame (not a 3D cable's, nor an r, r_z shell's)
        framed = frame_gradients(element_kind(body.element)) is not None
        if holder is None:
            options.append(PointForce(f"{body.name}:{index - body.n_nodes}",
                                      _vector(rng, dim, 100), time_law=law,
                                      follower=framed and rng.random() < 0.3))
        if body is not plate:
            options.append(DistributedForce(body=body.name, force_per_length=_vector(rng, dim),
                                            follower=framed and rng.random() < 0.5,
                                            time_law=law))
        if holder in (None, Pin) and ("r_y" in vectors or (dim == 2 and "r_x" in vectors)):
            options.append(PointMoment(NodeRef(body.name, index), _rotation(rng, dim),
                                       time_law=law))
        loads.append(rng.choice(options))

    sensors = []
    for i in range(rng.randint(0, 6)):
        body = rng.choice(bodies)
        node = NodeRef(body.name, rng.randrange(body.n_nodes))
        if body is plate and rng.random() < 0.5:       # by grid index, as written
            columns, _ = body.grid_shape
            column, row = body.mesh.lattice[node.index]  # where the node is on the lattice
            node = f"sheet:{column - columns * rng.randrange(2)},{row}"
        name = rng.choice(["s", "tip.x", "U-", "_v"]) + str(i)
        components = ("x", "y", "norm") if dim == 2 else ("x", "y", "z", "norm")
        # a frame needs gradients that span one (not a 3D cable's, nor an r, r_z shell's)
        framed = frame_gradients(element_kind(body.element)) is not None
        options = [
            Displacement(name, node, rng.choice(components),
                         NodeRef(body.name, 0) if framed and rng.random() < 0.5 else None),
            Position(name, node, rng.choice(components)),
            StrainEnergy(name, rng.choice([None, body.name])),
            KineticEnergy(name, rng.choice([None, body.name])),
            PotentialEnergy(name), TotalEnergy(name), DissipatedEnergy(name),
            ConstraintViolation(name), Velocity(name, node, rng.choice(components)),
            Acceleration(name, node, rng.choice(components)),
            *_point_sensors(rng, name, body, dim, plate)]
        supports = [f"{b}:{i}" for b, i in sorted(held)] + [
            n for c in constraints if hasattr(c, "nodes") for n in c.nodes]
        if supports:
            quantity = rng.choice(["force", "moment"])
            options.append(Reaction(name, rng.choice(supports), quantity,
                                    rng.choice(components if dim == 3 or quantity == "force"
                                               else ("z", "norm"))))
        sensors.append(rng.choice(options))

    rigid = [] if rng.random() < 0.5 else (
        _rigid_items(rng, chain, constraints, loads, sensors, held) if dim == 3
        else _planar_rigid_items(rng, chain, constraints, loads, sensors))
    static = Static(rng.randint(1, 100), _number(rng, 1e-12, 1e-4), rng.randint(1, 5)) \
        if rng.random() < 0.5 else None
    modal = Modal(rng.randint(1, 2), rng.choice(["reference", "static"])) \
        if rng.random() < 0.5 else None
    dynamic = None
    if rng.random() < 0.6:
        step = rng.choice([1e-3, 2.5e-3, 0.01, 1 / 3])
        steps = rng.randint(10, 40)
        frequency = rng.choice([s.name for s in sensors]) if sensors and rng.random() < 0.5 \
            else None
        # a frequency fit needs 8 outputs or more: at most every step then (>= 10 steps)
        every = rng.choice([None, step] if frequency else [None, step, 2 * step])
        dynamic = Dynamic(steps * step, step, rng.choice(["trapezoidal", "generalized_alpha"]),
                          every, _number(rng, 0, 1),
                          _number(rng, 1e-12, 1e-4), rng.randint(1, 50), frequency, 0.0,
                          rng.choice(["full", "modified"]))
    solver = Solver(rng.choice(["gram", "cij", "quadrature"]), rng.choice(["c", "numpy"]),
                    rng.choice([None, "python", "compiled"]))
    output = Output(*(rng.random() < 0.5 for _ in range(3)))
    return Scene(title=rng.choice(TITLES), materials=materials, bodies=bodies,
                 rigid_bodies=rigid,
                 constraints=constraints, loads=loads, sensors=sensors, static=static,
                 modal=modal, dynamic=dynamic, solver=solver, output=output)


def _rigid_items(rng: random.Random, chain: list, constraints: list, loads: list,
                 sensors: list, held: dict) -> list:
    """Rigid bodies and point masses (3D) with their joints, loads and sensors, appended to
    ``constraints``, ``loads`` and ``sensors``: a body on the chain's last node, a body
    turning about a ground axis, a particle and a mass on a node; the joints and the
    bushing take the chain's last node as their other side where it carries a frame."""
    frame, _ = np.linalg.qr(np.array([_vector(rng, 3) for _ in range(3)]))
    if np.linalg.det(frame) < 0:
        frame[:, 0] *= -1
    end = chain[-1]
    tip = end.node_position(end.n_nodes - 1)
    sides = [_number(rng, 0.1, 1.0) for _ in range(3)]
    shape = rng.choice([{"box": {"size": sides}}, {"cylinder": {"radius": sides[0],
                                                               "length": sides[1]}}])
    crank = RigidBody("crank", position=tip, rotation=tuple(map(tuple, frame)),
                      velocity=_vector(rng, 3) if rng.random() < 0.5 else None,
                      angular_velocity=_vector(rng, 3) if rng.random() < 0.5 else None,
                      centre_of_mass=_vector(rng, 3, 0.2), density=_number(rng, 100, 9000),
                      **shape)
    moments = sorted(_number(rng, 0.5, 1.0) for _ in range(3))
    wheel = RigidBody("wheel", mass=_number(rng, 0.1, 10), inertia=tuple(moments),
                      position=_vector(rng, 3, 5.0))
    bob = PointMass("bob", _number(rng, 0.1, 5), position=_vector(rng, 3, 5.0),
                    velocity=_vector(rng, 3))
    on_node = PointMass("lump", _number(rng, 0.1, 5), node=NodeRef(chain[0].name, 0))
    joint = len(constraints)
    constraints.append(BodySpherical(body="crank", node=f"{end.name}:-1"))
    constraints.append(BodyRevolute(body="wheel", point=_vector(rng, 3), axis=_vector(rng, 3),
                                    angle=rng.choice([None, SpinUp(_number(rng, -9, 9),
                                                                   _number(rng, 0.1, 2))])))
    # the chain's last node as the other side where its gradients carry a frame
    framed = len(element_kind(end.element).first_gradients) == 3
    node = [{"node": f"{end.name}:-1"}] if framed else []
    constraints.append(BodyPrismatic(body="bob", axis=_vector(rng, 3), displacement=rng.choice(
        [None, CosineRamp(_number(rng, 0.1, 2), _number(rng, -1, 1))]),
        **rng.choice([{}, {"other": "wheel"}, *node])))
    constraints.append(BodyCylindrical(body="wheel", point=_vector(rng, 3),
                                       axis=_vector(rng, 3),
                                       **rng.choice([{}, {"other": "crank"}, *node])))
    constraints.append(BodyUniversal(body="wheel", point=_vector(rng, 3), axis=(0.0, 0.0, 1.0),
                                     other_axis=rng.choice([(1.0, 0.0, 0.0), (0.6, 0.8, 0.0)]),
                                     **rng.choice([{}, *node])))
    loads.append(BodyForce(body="crank", force=_vector(rng, 3, 10), point=_vector(rng, 3)))
    loads.append(SpringDamper(End(body="bob"), rng.choice([
        End(anchor=_vector(rng, 3, 9.0)), End(node=NodeRef(chain[0].name, 0)),
        End(body="wheel", point=_vector(rng, 3))]), _number(rng, 0, 1e4),
        _number(rng, 0, 10), rng.choice([None, _number(rng, 0.1, 2)])))
    loads.append(Bushing(body="crank", stiffness=tuple(_number(rng, 0, 1e3) for _ in range(6)),
                         point=_vector(rng, 3), **rng.choice([{}, {"other": "wheel"}, *node]),
                         damping=rng.choice([None, tuple(_number(rng, 0, 5) for _ in range(6))])))
    sensors.append(SpringAngle(f"sa{len(sensors)}", len(loads)))
    loads.append(TorsionalSpring(body="wheel", stiffness=_number(rng, 0, 100),
                                 other=rng.choice([None, "crank"]), axis=_vector(rng, 3),
                                 damping=_number(rng, 0, 10), angle=_number(rng, -1, 1)))
    sensors.append(rng.choice([BodyPosition, BodyVelocity])(
        f"rb{len(sensors)}", rng.choice(["crank", "wheel", "bob", "lump"]),
        rng.choice(["x", "y", "z", "norm"]), _vector(rng, 3)))
    sensors.append(BodyAngularVelocity(f"rw{len(sensors)}", rng.choice(["crank", "wheel"]),
                                       rng.choice(["x", "y", "z", "norm"])))
    sensors.append(BodyReaction(f"rr{len(sensors)}", "crank", rng.choice(["force", "moment"]),
                                rng.choice(["x", "y", "z", "norm"]),
                                rng.choice([None, joint])))
    # a bead on the chain's first body, sliding along its centre line from its node 1
    bead = PointMass("bead", _number(rng, 0.1, 5), position=chain[0].node_position(1))
    slider = len(constraints)
    constraints.append(Sliding(beam=chain[0].name, body="bead"))
    sensors.append(Slide(f"sl{len(sensors)}", slider, rng.choice(["parameter", "rate",
                                                                  "reaction"]),
                         rng.choice(["x", "y", "z", "norm"])))
    if held.get((chain[0].name, 0)) is None:    # a hub welded to the chain's free start
        hub = RigidBody("hub", mass=_number(rng, 0.1, 10), inertia=tuple(moments),
                        position=chain[0].node_position(0))
        constraints.append(BodyWeld(body="hub", node=f"{chain[0].name}:0"))
        loads.append(BodyTorque(body="hub", torque=_number(rng, -10, 10),
                                axis=_vector(rng, 3), time_law=_law(rng)))
        return [crank, wheel, bob, on_node, bead, hub]
    return [crank, wheel, bob, on_node, bead]


def _planar_rigid_items(rng: random.Random, chain: list, constraints: list, loads: list,
                        sensors: list) -> list:
    """The rigid items of a 2D scene: a crank (a shape or mass and inertia about z; an
    angle or a rotation) pinned to the chain's last node, a wheel on a pin to the ground
    (its angle driven, or not), a particle sliding on the ground or the wheel, a point mass
    on a node; a body force, a motor torque and a spring-damper; the body sensors."""
    end = chain[-1]
    tip = end.node_position(end.n_nodes - 1)
    angle = _number(rng, -3, 3)
    pose = rng.choice([{"angle": angle}, {"rotation": (
        (math.cos(angle), -math.sin(angle)), (math.sin(angle), math.cos(angle)))}])
    shape = rng.choice([{"box": {"size": [_number(rng, 0.1, 1.0) for _ in range(3)]},
                         "density": _number(rng, 100, 9000)},
                        {"mass": _number(rng, 0.1, 10), "inertia": _number(rng, 0.01, 1)}])
    crank = RigidBody("crank", position=tip, centre_of_mass=_vector(rng, 2, 0.2),
                      velocity=_vector(rng, 2) if rng.random() < 0.5 else None,
                      angular_velocity=_number(rng, -5, 5) if rng.random() < 0.5 else None,
                      **pose, **shape)
    wheel = RigidBody("wheel", mass=_number(rng, 0.1, 10), inertia=_number(rng, 0.01, 1),
                      position=_vector(rng, 2, 5.0))
    bob = PointMass("bob", _number(rng, 0.1, 5), position=_vector(rng, 2, 5.0),
                    velocity=_vector(rng, 2))
    on_node = PointMass("lump", _number(rng, 0.1, 5), node=NodeRef(chain[0].name, 0))
    joint = len(constraints)
    constraints.append(rng.choice([BodySpherical, BodyRevolute])(
        body="crank", node=f"{end.name}:-1"))
    constraints.append(BodyRevolute(body="wheel", point=_vector(rng, 2), angle=rng.choice(
        [None, SpinUp(_number(rng, -9, 9), _number(rng, 0.1, 2))])))
    constraints.append(BodyPrismatic(body="bob", axis=_vector(rng, 2), displacement=rng.choice(
        [None, CosineRamp(_number(rng, 0.1, 2), _number(rng, -1, 1))]),
        **rng.choice([{}, {"other": "wheel"}])))
    loads.append(BodyForce(body="crank", force=_vector(rng, 2, 10), point=_vector(rng, 2)))
    loads.append(BodyTorque(body="wheel", torque=_number(rng, -10, 10), time_law=_law(rng)))
    loads.append(SpringDamper(End(body="bob"), rng.choice([
        End(anchor=_vector(rng, 2, 9.0)), End(node=NodeRef(chain[0].name, 0)),
        End(body="wheel", point=_vector(rng, 2))]), _number(rng, 0, 1e4),
        _number(rng, 0, 10), rng.choice([None, _number(rng, 0.1, 2)])))
    sensors.append(rng.choice([BodyPosition, BodyVelocity])(
        f"rb{len(sensors)}", rng.choice(["crank", "wheel", "bob", "lump"]),
        rng.choice(["x", "y", "norm"]), _vector(rng, 2)))
    sensors.append(BodyAngle(f"ra{len(sensors)}", rng.choice(["crank", "wheel"])))
    sensors.append(BodyAngularVelocity(f"rw{len(sensors)}", rng.choice(["crank", "wheel"]),
                                       rng.choice(["z", "norm"])))
    quantity = rng.choice(["force", "moment"])
    sensors.append(BodyReaction(f"rr{len(sensors)}", "crank", quantity, rng.choice(
        ["x", "y", "norm"] if quantity == "force" else ["z", "norm"]), rng.choice([None, joint])))
    return [crank, wheel, bob, on_node]


def _point_sensors(rng: random.Random, name: str, body: Body, dim: int, plate) -> list:
    """A strain or stress sensor at a random point of a random element of ``body`` (on the
    axis of a cable) and, on a beam, a section sensor."""
    kind = element_kind(body.element)
    bounds = kind.domain.bounds(body.geometry)
    point = [rng.uniform(low, high) for low, high in bounds]
    if kind.energy.structural:
        point[1:] = [0.0] * (dim - 1)
    element = rng.randrange(int(np.prod(body.counts)))
    tensors = ("xx", "yy", "xy") if dim == 2 else ("xx", "yy", "zz", "yz", "xz", "xy")
    out = [Strain(name, body.name, element, tuple(point), rng.choice(tensors)),
           Stress(name, body.name, element, tuple(point),
                  rng.choice([*tensors, "von_mises"]), rng.choice(["cauchy", "pk2"]))]
    if len(kind.mesh_axes) == 1:     # a beam or a cable: a line of elements
        sections = (("N", "M3", "M") if dim == 2 else ("N", "M")) if kind.energy.structural \
            else (("N", "Q2", "M3", "M") if dim == 2 else ("N", "Q2", "Q3", "T", "M2", "M3"))
        out.append(SectionForce(name, body.name, element, point[0], rng.choice(sections)))
    return out


def test_random_scenes_round_trip_through_toml(tmp_path):
    rng = random.Random(9)
    kinds = set()
    for i in range(300):
        scene = random_scene(rng)
        text = scene.to_toml()
        again = parse_scene(tomllib.loads(text))
        assert again == scene, text
        assert again.to_toml() == text
        if i % 30 == 0:
            path = tmp_path / f"scene{i}.toml"
            path.write_text(text, encoding="utf-8")
            assert load_scene(path) == scene
        kinds.update(type(x).__name__ for x in (*scene.constraints, *scene.loads,
                                                 *scene.sensors, *scene.rigid_bodies))
        kinds.update(k for k in ("arc", "initial_angular_velocity", "quadrature", "rectangle")
                     if any(getattr(b, k) is not None for b in scene.bodies))
        kinds.update(b.element for b in scene.bodies)
    # every class of every registry and every element kind was exercised
    # (a Python load names a function of a module: tests/test_python_loads.py round-trips it)
    expected = {cls.__name__ for r in (CONSTRAINTS, LOADS, SENSORS, RIGID_BODIES)
                for cls in r.values() if cls.type != "python"}
    assert expected | {"arc", "initial_angular_velocity", "quadrature", "rectangle",
                       *generated_kinds()} <= kinds


@pytest.mark.parametrize("name", scenes.names())
def test_shipped_scenes_round_trip(name):
    scene = load_scene(scenes.path(name))
    text = scene.to_toml()
    again = parse_scene(tomllib.loads(text), str(scenes.path(name)))
    assert again == scene
    assert again.to_toml() == text
