"""Time laws (eqs. 42 and 45) and TOML scenes: valid scenes parse to the expected dataclasses,
every invalid input is a SceneError naming its key path."""

from __future__ import annotations

import copy
import math
import tomllib
from pathlib import Path

import pytest

from runtime import (
    Arc,
    Body,
    Clamp,
    ConstraintViolation,
    Displacement,
    Dynamic,
    Gravity,
    Hub,
    KineticEnergy,
    Material,
    Modal,
    NodeRef,
    Pin,
    PointForce,
    Scene,
    Solver,
    Static,
    StrainEnergy,
    load_scene,
)
from runtime.catalog import generated_kinds
from runtime.model.errors import SceneError
from runtime.model.scene import parse_scene
from runtime.model.time_laws import (
    Constant,
    ConstantRate,
    CosineRamp,
    LinearRamp,
    Sine,
    SpinUp,
    Table,
    parse_law,
)

# --------------------------------------------------------------------------- laws

LAWS = {
    "constant": Constant(2.5),
    "cosine_ramp": CosineRamp(duration=3.5, scale=300.0),
    "linear_ramp": LinearRamp(duration=2.0, scale=-4.0),
    "sine": Sine(amplitude=1.5, frequency_hz=0.7, phase_deg=30.0, offset=0.2),
    "table": Table(((0.0, 0.0), (1.0, 2.0), (3.0, -1.0))),
    "spin_up": SpinUp(omega=4.0, t_ramp=15.0),
    "constant_rate": ConstantRate(omega=-1.3),
}
# sample times away from kinks (ramp ends at 3.5, 2, 15; table breakpoints 0, 1, 3), on both
# sides of every ramp end
TIMES = [0.31, 0.9, 1.7, 2.6, 3.2, 3.8, 7.1, 14.6, 15.4, 21.0]


@pytest.mark.parametrize("name", LAWS)
def test_law_derivatives_match_finite_differences(name):
    law = LAWS[name]
    h = 1e-6
    for t in TIMES:
        fd_rate = (law.value(t + h) - law.value(t - h)) / (2 * h)
        fd_acc = (law.rate(t + h) - law.rate(t - h)) / (2 * h)
        scale = 1.0 + abs(law.value(t)) + abs(law.rate(t))
        assert law.rate(t) == pytest.approx(fd_rate, abs=1e-6 * scale), (name, t)
        assert law.acceleration(t) == pytest.approx(fd_acc, abs=1e-6 * scale), (name, t)


@pytest.mark.parametrize("name", LAWS)
def test_law_round_trips_through_its_table(name):
    law = LAWS[name]
    assert parse_law(law.to_dict(), "law") == law


def test_cosine_ramp_is_eq_42():
    law = CosineRamp(duration=3.5)
    assert law.value(3.5 / 2) == pytest.approx(0.5, abs=1e-15)
    assert law.value(0.0) == 0.0
    assert law.value(3.5) == pytest.approx(1.0, abs=1e-15)
    assert law.value(4.0) == 1.0
    assert law.rate(3.5) == pytest.approx(0.0, abs=1e-15)
    assert law.rate(4.0) == 0.0
    f = 300.0
    scaled = CosineRamp(duration=3.5, scale=f)
    for t in (0.4, 1.0, 2.9):
        assert scaled.value(t) == pytest.approx(f / 2 * (1 - math.cos(math.pi * t / 3.5)))


def test_spin_up_is_eq_45_and_continuous_at_t_ramp():
    omega, T = 4.0, 15.0
    law = SpinUp(omega, T)
    for t in (0.5, 3.0, 7.5, 12.0):
        expected = omega / T * (t * t / 2 + (T / (2 * math.pi)) ** 2
                                * (math.cos(2 * math.pi * t / T) - 1))
        assert law.value(t) == pytest.approx(expected, rel=1e-12)
    eps = 1e-9
    assert law.value(T - eps) == pytest.approx(law.value(T + eps), abs=1e-7)
    assert law.value(T) == pytest.approx(omega * T / 2, rel=1e-14)
    assert law.rate(T - eps) == pytest.approx(law.rate(T + eps), abs=1e-7)
    assert law.rate(T) == pytest.approx(omega, rel=1e-14)
    assert law.acceleration(T) == pytest.approx(0.0, abs=1e-14)
    assert law.value(20.0) == pytest.approx(omega * (20.0 - T / 2))
    assert law.acceleration(T / 2) == pytest.approx(2 * omega / T)
    assert law.value(0.0) == law.rate(0.0) == law.acceleration(0.0) == 0.0


def test_table_interpolates_linearly_and_holds_the_ends():
    law = Table(((0.0, 0.0), (1.0, 2.0), (3.0, -1.0)))
    assert law.value(-1.0) == 0.0
    assert law.value(0.5) == pytest.approx(1.0)
    assert law.value(1.0) == pytest.approx(2.0)
    assert law.value(2.0) == pytest.approx(0.5)
    assert law.value(10.0) == -1.0
    assert law.rate(0.5) == pytest.approx(2.0)
    assert law.rate(2.0) == pytest.approx(-1.5)
    assert law.rate(10.0) == 0.0 and law.rate(-1.0) == 0.0
    assert law.acceleration(0.5) == 0.0


def test_simple_laws():
    assert Constant().value(3.0) == 1.0
    assert LinearRamp(2.0).value(1.0) == pytest.approx(0.5)
    assert LinearRamp(2.0).value(5.0) == 1.0
    assert Sine(2.0, 1.0, phase_deg=90.0).value(0.0) == pytest.approx(2.0)
    assert ConstantRate(2.0).value(3.0) == pytest.approx(6.0)


@pytest.mark.parametrize("data, message", [
    ({"type": "cosine_ramp", "duration": -1}, "x.duration: expected a positive number, got -1"),
    ({"type": "cosine_ramp"}, "x.duration: missing"),
    ({"type": "cosine_ramp", "duration": 1, "t_c": 1}, "x.t_c: unknown key"),
    ({"type": "ramp"}, "x.type: unknown time law \"ramp\"; expected one of constant, cosine"),
    ({"duration": 1.0}, "x.type: missing"),
    ("spin_up", "x: expected a table"),
    ({"type": "spin_up", "omega": True, "t_ramp": 1.0}, "x.omega: expected a finite number"),
    ({"type": "sine", "amplitude": 1.0, "frequency_hz": 0}, "x.frequency_hz"),
    ({"type": "table", "points": [[0, 1], [0, 2]]}, "x.points[1]: times must be strictly"),
    ({"type": "table", "points": [[0, 1, 2]]}, "x.points[0]: expected a pair"),
    ({"type": "table", "points": []}, "x.points: expected a non-empty list"),
])
def test_bad_laws(data, message):
    with pytest.raises(SceneError) as info:
        parse_law(data, "x")
    assert message in str(info.value)


# --------------------------------------------------------------------------- scenes

CANTILEVER = """
title = "Cantilever with tip load (paper, Table I)"

[material.steel]
E = 132e9
nu = 0.0
rho = 8245.2

[[body]]
name = "beam"
element = "beam3d"            # any registered element kind
material = "steel"
section = { height = 0.1, width = 0.1 }
elements = 10
start = [0.0, 0.0, 0.0]       # straight line from start to end, or
end = [5.0, 0.0, 0.0]         # arc = { center = [...], radius = R, angle_deg = A, ... }

[[constraint]]
type = "clamp"                # clamp | pin | prescribed_rotation | spherical | ...
node = "beam:0"

[[load]]
type = "point_force"
node = "beam:-1"
force = [0.0, -300.0, 0.0]
time_law = { type = "cosine_ramp", duration = 3.5 }   # eq. 42

[[sensor]]
name = "tip_y"
type = "displacement"         # displacement | position | strain_energy | kinetic_energy | ...
node = "beam:-1"
component = "y"               # x | y | z | norm
# frame = "beam:0"            # optional: components in the frame of that node

[analysis.static]             # each analysis is optional
[analysis.modal]
modes = 4
[analysis.dynamic]
t_end = 4.0
step = 1e-3
integrator = "trapezoidal"    # trapezoidal (paper) | generalized_alpha
output_every = 0.01
"""

ROTATING = """
title = "Rotating beam (paper, Fig. 7)"

[material.aluminium]
E = 68.95e9
nu = 0.0
rho = 2766.67

[[body]]
name = "beam"
element = "beam2d"
material = "aluminium"
section = { height = 0.0367505, width = 0.0019861 }
elements = 10
start = [0.0, 0.0]
end = [8.0, 0.0]
quadrature = [5, 3]

[[constraint]]
type = "prescribed_rotation"
node = "beam:0"
angle = { type = "spin_up", omega = 4.0, t_ramp = 15.0 }   # eq. 45

[[sensor]]
name = "tip_v"
type = "displacement"
node = "beam:-1"
frame = "beam:0"
component = "y"

[[sensor]]
name = "strain_energy"
type = "strain_energy"

[[sensor]]
name = "kinetic_energy"
type = "kinetic_energy"
body = "beam"

[[sensor]]
name = "violation"
type = "constraint_violation"

[analysis.dynamic]
t_end = 20.0
step = 2e-3
integrator = "generalized_alpha"
rho_inf = 0.9

[solver]
method = "cij"
backend = "numpy"
"""

PENDULUM = """
[material.steel]
E = 2.1e11
nu = 0.3
rho = 7800

[[body]]
name = "arm"
element = "beam3d"
material = "steel"
section = { height = 0.02, width = 0.01 }
elements = 4
arc = { center = [0.0, 0.0, 0.0], radius = 1.0, start_angle_deg = -90, angle_deg = 90 }

[[body]]
name = "link"
element = "beam3d"
material = "steel"
section = { height = 0.02, width = 0.01 }
elements = 2
start = [1.0, 0.0, 0.0]
end = [2.0, 0.0, 0.0]

[[constraint]]
type = "pin"
node = "arm:0"

[[constraint]]
type = "spherical"
nodes = ["arm:-1", "link:0"]

[[constraint]]
type = "prescribed_rotation"
node = "link:-1"
angle = { type = "constant_rate", omega = 0.5 }
axis = [0.0, 2.0, 0.0]

[[load]]
type = "gravity"
acceleration = [0.0, -9.81, 0.0]

[[sensor]]
name = "tip"
type = "position"
node = "link:-1"
component = "norm"

[[sensor]]
name = "V"
type = "potential_energy"

[[sensor]]
name = "total"
type = "total_energy"
"""


def toml(text: str) -> dict:
    return tomllib.loads(text)


def test_cantilever_scene_parses():
    scene = parse_scene(toml(CANTILEVER), "cantilever.toml")
    assert scene == Scene(
        title="Cantilever with tip load (paper, Table I)",
        materials={"steel": Material("steel", 132e9, 0.0, 8245.2)},
        bodies=(Body("beam", "beam3d", "steel", 0.1, 0.1, 10, (0.0, 0.0, 0.0), (5.0, 0.0, 0.0),
                     None, None),),
        constraints=(Clamp(NodeRef("beam", 0)),),
        loads=(PointForce(NodeRef("beam", 10), (0.0, -300.0, 0.0),
                          time_law=CosineRamp(duration=3.5)),),
        sensors=(Displacement("tip_y", NodeRef("beam", 10), "y"),),
        static=Static(),
        modal=Modal(modes=4),
        dynamic=Dynamic(t_end=4.0, step=1e-3, output_every=0.01),
        solver=Solver(),
        source="cantilever.toml",
    )
    assert scene.dim == 3
    assert scene.bodies[0].n_nodes == 11
    assert scene.material_of("beam").E == 132e9


def test_rotating_beam_scene_parses():
    scene = parse_scene(toml(ROTATING))
    assert scene.dim == 2
    assert scene.bodies[0].quadrature == (5, 3)
    assert scene.constraints == (Hub(NodeRef("beam", 0), SpinUp(4.0, 15.0)),)
    assert scene.sensors == (
        Displacement("tip_v", NodeRef("beam", 10), "y", NodeRef("beam", 0)),
        StrainEnergy("strain_energy"),
        KineticEnergy("kinetic_energy", "beam"),
        ConstraintViolation("violation"),
    )
    assert scene.loads == ()
    assert scene.static is None and scene.modal is None
    assert scene.dynamic == Dynamic(20.0, 2e-3, "generalized_alpha", None, 0.9)
    assert scene.solver == Solver("cij", "numpy")
    assert scene.title == "Rotating beam (paper, Fig. 7)"


def test_arc_joints_and_gravity_parse():
    scene = parse_scene(toml(PENDULUM), "pendulum.toml")
    assert scene.title == "pendulum"
    assert scene.bodies[0].arc == Arc((0.0, 0.0, 0.0), 1.0, -90.0, 90.0)
    assert scene.bodies[0].start is None
    pin, spherical, hub = scene.constraints
    assert pin == Pin(NodeRef("arm", 0))
    assert spherical.nodes == (NodeRef("arm", 4), NodeRef("link", 0))
    assert hub.node == NodeRef("link", 2)
    assert hub.axis == (0.0, 1.0, 0.0)
    assert scene.loads == (Gravity((0.0, -9.81, 0.0)),)
    assert [(s.name, s.type) for s in scene.sensors] == [
        ("tip", "position"), ("V", "potential_energy"), ("total", "total_energy")]


SHIPPED = sorted((Path(__file__).resolve().parents[1] / "scenes").glob("*.toml"))


@pytest.mark.parametrize("path", SHIPPED, ids=[p.name for p in SHIPPED])
def test_shipped_scenes_parse(path):
    assert load_scene(path).bodies


def test_prescribed_rotation_axis_defaults_to_z_in_3d():
    data = toml(CANTILEVER)
    data["constraint"] = [{"type": "prescribed_rotation", "node": "beam:0",
                           "angle": {"type": "constant_rate", "omega": 1.0}}]
    assert parse_scene(data).constraints[0].axis == (0.0, 0.0, 1.0)


def _set(*path_and_value):
    """A mutation setting data[k1][k2]... = value (a missing final key is created)."""
    *path, value = path_and_value

    def mutate(data: dict) -> None:
        target = data
        for key in path[:-1]:
            target = target[key]
        target[path[-1]] = value
    return mutate


def _delete(*path):
    def mutate(data: dict) -> None:
        target = data
        for key in path[:-1]:
            target = target[key]
        del target[path[-1]]
    return mutate


def _append(key, item):
    def mutate(data: dict) -> None:
        data.setdefault(key, []).append(item)
    return mutate


def _second_body(**changes):
    def mutate(data: dict) -> None:
        body = dict(copy.deepcopy(data["body"][0]), **changes)
        data["body"].append(body)
    return mutate


BODY = ("body", 0)
LOAD_LAW = ("load", 0, "time_law")
DYN = ("analysis", "dynamic")

# (base scene, mutation, expected substring of the SceneError message)
BAD = [
    # unknown keys
    ("3d", _set("titel", "x"), "titel: unknown key; expected one of title, material"),
    ("3d", _set(*BODY, "sectoin", {}), "body[0].sectoin: unknown key; expected one of name"),
    ("3d", _second_body(name="b2", sectoin=1), "body[1].sectoin: unknown key"),
    ("3d", _set(*BODY, "section", "depth", 0.1), "body[0].section.depth: unknown key"),
    ("3d", _set("load", 0, "direction", 1), "load[0].direction: unknown key"),
    ("3d", _set(*LOAD_LAW, "t_c", 1.0), "load[0].time_law.t_c: unknown key"),
    ("3d", _set("sensor", 0, "body", "beam"), "sensor[0].body: unknown key"),
    ("3d", _set("constraint", 0, "angle", {"type": "constant"}), "constraint[0].angle: unknown"),
    ("3d", _set("analysis", "transient", {}), "analysis.transient: unknown key"),
    ("3d", _set(*DYN, "dt", 0.1), "analysis.dynamic.dt: unknown key"),
    ("3d", _set("solver", {"workers": 2}), "solver.workers: unknown key"),
    ("3d", _set("material", "steel", "G", 1.0), "material.steel.G: unknown key"),
    # missing keys
    ("3d", _delete(*BODY, "material"), "body[0].material: missing required key"),
    ("3d", _delete(*BODY, "section", "width"), "body[0].section.width: missing"),
    ("3d", _delete(*BODY, "end"), "body[0].end: missing required key"),
    ("3d", _delete("load", 0, "force"), "load[0].force: missing"),
    ("3d", _delete(*LOAD_LAW, "duration"), "load[0].time_law.duration: missing"),
    ("3d", _delete("sensor", 0, "component"), "sensor[0].component: missing"),
    ("3d", _delete("sensor", 0, "name"), "sensor[0].name: missing"),
    ("3d", _delete("constraint", 0, "type"), "constraint[0].type: missing"),
    ("3d", _delete(*DYN, "t_end"), "analysis.dynamic.t_end: missing"),
    ("3d", _delete("material", "steel", "rho"), "material.steel.rho: missing"),
    ("2d", _delete("constraint", 0, "angle"), "constraint[0].angle: missing"),
    # wrong types and values
    ("3d", _set(*BODY, "elements", True), "body[0].elements: expected a positive integer, got "
                                          "true"),
    ("3d", _set(*BODY, "elements", 0), "body[0].elements: expected a positive integer, got 0"),
    ("3d", _set(*BODY, "elements", 2.5), "body[0].elements: expected an integer, got 2.5"),
    ("3d", _set(*BODY, "section", "height", -0.1), "body[0].section.height: expected a positive"),
    ("3d", _set(*BODY, "section", "height", True), "body[0].section.height: expected a positive"),
    ("3d", _set(*BODY, "section", 0.1), "body[0].section: expected a table"),
    ("3d", _set("material", "steel", "E", "132e9"),
     'material.steel.E: expected a positive number, got "132e9"'),
    ("3d", _set("material", "steel", "E", -1.0), "material.steel.E: expected a positive"),
    ("3d", _set("material", "steel", "nu", 0.5), "material.steel.nu: expected a Poisson ratio"),
    ("3d", _set("material", "steel", "rho", False), "material.steel.rho: expected a positive"),
    ("3d", _set(*BODY, "material", "wood"),
     'body[0].material: material "wood" is not defined; defined materials: steel'),
    ("3d", _set(*BODY, "element", "beam9d"),
     'body[0].element: unknown element kind "beam9d"; expected one of '
     + ", ".join(generated_kinds())),
    ("3d", _set(*BODY, "start", [0.0, 0.0]), "body[0].start: expected a list of 3 numbers"),
    ("3d", _set(*BODY, "end", [5.0, 0.0, "0"]), "body[0].end: expected a list of 3 numbers"),
    ("2d", _set(*BODY, "end", [8.0, 0.0, 0.0]), "body[0].end: expected a list of 2 numbers"),
    ("3d", _set(*BODY, "end", [0.0, 0.0, 0.0]), "body[0].end: expected a point different"),
    ("3d", _set(*BODY, "arc", {"center": [0, 0, 0], "radius": 1.0, "angle_deg": 90}),
     "body[0]: expected either start and end or arc, got both"),
    ("3d", lambda d: (d["body"][0].pop("start"), d["body"][0].pop("end")),
     "body[0]: expected start and end (straight) or arc, got neither"),
    ("pendulum", _set(*BODY, "arc", "radius", 0.0), "body[0].arc.radius: expected a positive"),
    ("pendulum", _set(*BODY, "arc", "angle_deg", 0), "body[0].arc.angle_deg: expected a non-zero"),
    ("pendulum", _set(*BODY, "arc", "center", [0, 0]), "body[0].arc.center: expected a list of 3"),
    ("3d", _set(*BODY, "quadrature", [5, 3]), "body[0].quadrature: expected a list of 3 positive"),
    ("3d", _set(*BODY, "name", "a:b"), 'body[0].name: expected a name without ":"'),
    ("3d", _second_body(), 'body[1].name: duplicate body name "beam"'),
    ("3d", _second_body(name="b2", element="beam2d", start=[0, 0], end=[1, 0]),
     "body[1].element: expected a 3D element kind like body[0], got beam2d (2D)"),
    ("3d", _set("body", []), "body: a scene needs at least one [[body]]"),
    ("3d", _delete("body"), "body: a scene needs at least one [[body]]"),
    ("3d", lambda d: d.__setitem__("body", d["body"][0]), "body: expected an array of tables"),
    # node references
    ("3d", _set("constraint", 0, "node", "bem:0"), 'constraint[0].node: unknown body "bem"'),
    ("3d", _set("constraint", 0, "node", "beam:11"),
     'constraint[0].node: node index 11 out of range for body "beam" with 11 nodes'),
    ("3d", _set("load", 0, "node", "beam:-12"), "load[0].node: node index -12 out of range"),
    ("3d", _set("constraint", 0, "node", "beam"), 'constraint[0].node: expected a node reference'),
    ("3d", _set("constraint", 0, "node", "beam:x"), "constraint[0].node: expected an integer"),
    ("3d", _set("constraint", 0, "node", 0), "constraint[0].node: expected a node reference"),
    ("3d", _set("sensor", 0, "frame", "beam:20"), "sensor[0].frame: node index 20 out of range"),
    ("pendulum", _set("constraint", 1, "nodes", ["arm:-1", "arm:4"]),
     "constraint[1].nodes: expected two different nodes"),
    ("pendulum", _set("constraint", 1, "nodes", ["arm:-1"]), "constraint[1].nodes: expected two"),
    ("pendulum", _set("constraint", 1, "nodes", ["arm:-1", "lnk:0"]),
     'constraint[1].nodes[1]: unknown body "lnk"'),
    # constraints
    ("3d", _set("constraint", 0, "type", "glue"),
     'constraint[0].type: unknown constraint type "glue"; expected one of clamp, pin'),
    ("2d", _set("constraint", 0, "axis", [0.0, 0.0, 1.0]),
     "constraint[0].axis: only allowed in 3D"),
    ("pendulum", _set("constraint", 2, "axis", [0.0, 0.0, 0.0]),
     "constraint[2].axis: expected a non-zero axis"),
    ("pendulum", _set("constraint", 2, "axis", [0.0, 1.0]), "constraint[2].axis: expected a list"),
    ("2d", _set("constraint", 0, "angle", "t_ramp", 0), "constraint[0].angle.t_ramp: expected a "
                                                        "positive number, got 0"),
    ("2d", _set("constraint", 0, "angle", "type", "spin"),
     'constraint[0].angle.type: unknown time law "spin"'),
    # loads
    ("3d", _set("load", 0, "force", [0.0, -300.0]), "load[0].force: expected a list of 3 numbers"),
    ("3d", _set(*LOAD_LAW, "duration", -1),
     "load[0].time_law.duration: expected a positive number, got -1"),
    ("3d", _set(*LOAD_LAW, "type", "ramp"),
     'load[0].time_law.type: unknown time law "ramp"; expected one of constant, cosine_ramp'),
    ("3d", _set("load", 0, "type", "moment"), 'load[0].type: unknown load type "moment"'),
    ("3d", _append("load", {"type": "gravity", "acceleration": [0.0, -9.81]}),
     "load[1].acceleration: expected a list of 3 numbers"),
    ("3d", _append("load", {"type": "gravity", "node": "beam:0", "acceleration": [0, 0, 1]}),
     "load[1].node: unknown key"),
    # sensors
    ("3d", _set("sensor", 0, "component", "w"),
     'sensor[0].component: unknown component "w"; expected one of x, y, z, norm'),
    ("2d", _set("sensor", 0, "component", "z"),
     'sensor[0].component: unknown component "z"; expected one of x, y, norm'),
    ("3d", _set("sensor", 0, "type", "strains"), 'sensor[0].type: unknown sensor type "strains"'),
    ("3d", _append("sensor", {"name": "tip_y", "type": "constraint_violation"}),
     'sensor[1].name: duplicate sensor name "tip_y"'),
    ("3d", _append("sensor", {"name": "U", "type": "strain_energy", "body": "bem"}),
     'sensor[1].body: unknown body "bem"; expected one of beam'),
    ("3d", _set("sensor", 0, "name", "t"), "sensor[0].name: expected a name other than"),
    ("3d", _set("sensor", 0, "name", "tip y"), "sensor[0].name: expected letters"),
    ("2d", _set("sensor", 3, "node", "beam:0"), "sensor[3].node: unknown key"),
    ("pendulum", _set("sensor", 1, "body", "arm"), "sensor[1].body: unknown key"),
    # analyses and solver
    ("3d", _set(*DYN, "t_end", -4.0), "analysis.dynamic.t_end: expected a positive number"),
    ("3d", _set(*DYN, "t_end", math.nan), "analysis.dynamic.t_end: expected a positive number"),
    ("3d", _set(*DYN, "step", 0.0), "analysis.dynamic.step: expected a positive number, got 0.0"),
    ("3d", _set(*DYN, "step", 5.0), "analysis.dynamic.step: expected a step of at most t_end"),
    ("3d", _set(*DYN, "output_every", 1e-4), "analysis.dynamic.output_every: expected an interval"),
    ("3d", _set(*DYN, "integrator", "euler"),
     'analysis.dynamic.integrator: unknown integrator "euler"; expected one of trapezoidal, '
     "generalized_alpha"),
    ("2d", _set(*DYN, "rho_inf", 1.5), "analysis.dynamic.rho_inf: expected a number in [0, 1]"),
    ("2d", _set(*DYN, "rho_inf", -0.1), "analysis.dynamic.rho_inf: expected a number in [0, 1]"),
    ("3d", _set(*DYN, "max_iterations", 0), "analysis.dynamic.max_iterations: expected a pos"),
    ("3d", _set("analysis", "modal", "modes", 0), "analysis.modal.modes: expected a positive int"),
    ("3d", _set("analysis", "modal", "modes", True), "analysis.modal.modes: expected a positive"),
    ("3d", _set("analysis", "modal", "about", "deformed"), "analysis.modal.about: unknown value"),
    ("3d", _set("analysis", "static", "tolerance", True), "analysis.static.tolerance: expected"),
    ("3d", _set("analysis", "static", "load_steps", -2), "analysis.static.load_steps: expected"),
    ("3d", _set("analysis", "dynamic", 4.0), "analysis.dynamic: expected a table"),
    ("2d", _set("solver", "method", "fast"),
     'solver.method: unknown method "fast"; expected one of gram, cij, quadrature'),
    ("2d", _set("solver", "backend", "cuda"), 'solver.backend: unknown backend "cuda"'),
    ("3d", _set("title", 3), "title: expected a non-empty string, got 3"),
]
BASES = {"3d": CANTILEVER, "2d": ROTATING, "pendulum": PENDULUM}


@pytest.mark.parametrize("base, mutate, message", BAD, ids=[m for _, _, m in BAD])
def test_bad_scene_raises_scene_error_naming_the_key_path(base, mutate, message):
    data = toml(BASES[base])
    parse_scene(copy.deepcopy(data))  # the base is valid
    mutate(data)
    with pytest.raises(SceneError) as info:
        parse_scene(data)
    text = str(info.value)
    assert message in text
    path = message.split(":")[0]
    assert text.startswith(path), text
    assert "\n" not in text


def test_load_scene_reads_files_and_reports_toml_syntax_errors(tmp_path):
    good = tmp_path / "cantilever.toml"
    good.write_text(CANTILEVER)
    assert load_scene(good).source == str(good)
    bad = tmp_path / "broken.toml"
    bad.write_text(CANTILEVER.replace("elements = 10", "elements = = 10"))
    with pytest.raises(SceneError) as info:
        load_scene(bad)
    line = CANTILEVER.splitlines().index("elements = 10") + 1
    assert str(bad) in str(info.value) and f"line {line}," in str(info.value)
    with pytest.raises(SceneError, match="cannot read"):
        load_scene(tmp_path / "missing.toml")


def test_scene_error_is_a_value_error():
    assert issubclass(SceneError, ValueError)
