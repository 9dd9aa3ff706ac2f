"""The sliding joint (``[[constraint]] type = "sliding"``, docs/multibody.md): a point held
on the centre line of a line body, free to slide along it across the elements.  Checked
against what does not share its code: a bead on a stiff inclined rail slides as
s0 + g sin(alpha) t^2 / 2 and presses on it with m g cos(alpha); a bead on a stiff circular
arc swings with the pendulum's elliptic-integral period; a bead on a free flexible cable
keeps the energy; the rows' Jacobian, Hessian and curvature match finite differences on
every line kind; the engines agree to round-off; the scene round-trips; bad input names
its key; a point that leaves its body ends the run with its time and cause."""

from __future__ import annotations

import dataclasses
import math
import tomllib

import numpy as np
import pytest
import scipy.special
from test_multibody import scene_of

from runtime.model.errors import SceneError
from runtime.model.model import Model
from runtime.model.scene import load_scene, parse_scene
from runtime.model.sliding_rows import SlidingBlock
from runtime.solve import engines
from runtime.solve.linear import single_threaded_blas
from runtime.solve.python_engine import Divergence
from scenes import path as scene_path

G = 9.81

RAIL = """
[material.steel]
E = {E}
nu = 0.3
rho = {rho}
[[body]]
name = "rail"
element = "cable3d"
material = "steel"
section = {{height = 0.02, width = 0.02}}
elements = 6
start = [0, 0, 0]
end = [0.8, 0, -0.6]
[[body]]
type = "point_mass"
name = "bead"
mass = 0.5
position = [0.08, 0.0, -0.06]
[[constraint]]
type = "clamp"
node = "rail:0"
[[constraint]]
type = "clamp"
node = "rail:-1"
[[constraint]]
type = "sliding"
beam = "rail"
body = "bead"
[[load]]
type = "gravity"
acceleration = [0, 0, -9.81]
[[sensor]]
name = "s"
type = "slide"
constraint = 2
[[sensor]]
name = "rate"
type = "slide"
constraint = 2
quantity = "rate"
[[sensor]]
name = "push"
type = "slide"
constraint = 2
quantity = "reaction"
{held}
[analysis.dynamic]
t_end = {t_end}
step = 2e-3
integrator = "{integrator}"
"""


#: clamps on the rail's inner nodes (a rigid rail: its coordinates are the reference's)
RIGID = "".join(f'[[constraint]]\ntype = "clamp"\nnode = "rail:{k}"\n' for k in range(1, 6))


def _run(scene, engine: str = "python", **settings):
    """(times, sensor values {name: (k,)}, stepper, q (k, size)) of a dynamic run of
    ``scene`` (BLAS on one thread: the banded factorisations of building the engines and
    the output dynamics, outside the run's own single-threaded section, cost 0.5 s each
    with OpenBLAS threads on the loaded machine)."""
    with single_threaded_blas():
        return _run_threads(scene, engine, **settings)


def _run_threads(scene, engine: str, **settings):
    from runtime.model.items.sensors import Samples, Sensors
    from runtime.solve.python_engine import OutputDynamics

    dynamic = dataclasses.replace(scene.dynamic, **settings)
    model = Model(scene)
    stepper = engines.make(engine, model, dynamic, model.reference.copy())
    states = []
    stepper.run(dynamic.t_end, dynamic.step,
                lambda t, q, v: states.append((t, q.copy(), v.copy())))
    t = np.array([s[0] for s in states])
    q, v = np.array([s[1] for s in states]), np.array([s[2] for s in states])
    sensors = Sensors(model)
    a = lam = force = None
    if sensors.dynamics:
        from runtime.model.dae import DAESystem
        a, lam, force = OutputDynamics(DAESystem(model, model.reference.copy()))(t, q, v)
    values = sensors.block(Samples(t, q, v, np.zeros(t.size), a, lam, force))
    return t, values, stepper, q


@pytest.mark.parametrize("integrator", ["trapezoidal", "generalized_alpha"])
def test_a_bead_on_a_rigid_inclined_rail_slides_as_the_closed_form(integrator):
    """Every node of the rail held (its line is the reference's), sin(alpha) = 0.6:
    s = 0.1 + g 0.6 t^2 / 2 over three element boundaries (1/6 m long), ds/dt = g 0.6 t,
    the normal force m g cos(alpha) = 0.5 g 0.8 N."""
    scene = scene_of(RAIL.format(E=2.1e11, rho=7800.0, t_end=0.4, integrator=integrator,
                                 held=RIGID))
    t, values, _, _ = _run(scene)
    assert values["s"][-1] > 0.5 + 0.01        # past the boundaries at 1/6, 1/3 and 1/2
    assert np.abs(values["s"] - (0.1 + G * 0.6 * t**2 / 2)).max() < 1e-12
    assert np.abs(values["rate"] - G * 0.6 * t).max() < 1e-11
    assert np.abs(values["push"] - 0.5 * G * 0.8).max() < 1e-11


def test_a_bead_on_a_stiff_inclined_rail_slides_nearly_as_on_a_rigid_one():
    """The rail held at its ends only, 1000 times stiffer than steel: it bends and
    vibrates under the bead by less than a micrometre, and the bead slides as on the rigid
    rail to that."""
    scene = scene_of(RAIL.format(E=2.1e14, rho=7800.0, t_end=0.4,
                                 integrator="generalized_alpha", held=""))
    t, values, _, _ = _run(scene)
    error = np.abs(values["s"] - (0.1 + G * 0.6 * t**2 / 2)).max()
    assert 1e-10 < error < 1e-7


ARC = """
[material.stiff]
E = 2.1e14
nu = 0.3
rho = 100.0
[[body]]
name = "arc"
element = "beam3d"
material = "stiff"
section = {height = 0.02, width = 0.02}
elements = 12
arc = {center = [0.0, 0.0, 0.0], radius = 1.0, start_angle_deg = -150.0, angle_deg = 120.0}
[[body]]
type = "point_mass"
name = "bead"
mass = 1.0
position = [-0.5, -0.8660254037844386, 0.0]
[[constraint]]
type = "clamp"
node = "arc:0"
[[constraint]]
type = "clamp"
node = "arc:1"
[[constraint]]
type = "clamp"
node = "arc:2"
[[constraint]]
type = "clamp"
node = "arc:3"
[[constraint]]
type = "clamp"
node = "arc:4"
[[constraint]]
type = "clamp"
node = "arc:5"
[[constraint]]
type = "clamp"
node = "arc:6"
[[constraint]]
type = "clamp"
node = "arc:7"
[[constraint]]
type = "clamp"
node = "arc:8"
[[constraint]]
type = "clamp"
node = "arc:9"
[[constraint]]
type = "clamp"
node = "arc:10"
[[constraint]]
type = "clamp"
node = "arc:11"
[[constraint]]
type = "clamp"
node = "arc:12"
[[constraint]]
type = "sliding"
beam = "arc"
body = "bead"
[[load]]
type = "gravity"
acceleration = [0, -9.81, 0]
[[sensor]]
name = "x"
type = "body_position"
body = "bead"
component = "x"
[analysis.dynamic]
t_end = 0.56
step = 4e-3
integrator = "generalized_alpha"
rho_inf = 0.9
"""


def test_a_bead_on_a_stiff_circular_arc_swings_as_a_pendulum():
    """Released 30 degrees from the bottom of a 1 m arc of beam3d elements held at every
    node (at its node 3: on the line), it passes the bottom at T/4, T = 4 sqrt(R / g)
    K(sin^2 15 deg) (the elements' cubic interpolation of the circle is within 1e-6 of
    it)."""
    t, values, _, _ = _run(scene_of(ARC))
    x = values["x"]
    k = int(np.flatnonzero((x[:-1] < 0) & (x[1:] >= 0))[0])
    passing = t[k] + (t[k + 1] - t[k]) * -x[k] / (x[k + 1] - x[k])
    period = 4 * math.sqrt(1.0 / G) * scipy.special.ellipk(math.sin(math.radians(15)) ** 2)
    assert abs(passing - period / 4) < 2e-3 * period / 4


FREE = """
[material.steel]
E = 2.1e9
nu = 0.3
rho = 7800.0
[[body]]
name = "rail"
element = "cable3d"
material = "steel"
section = {height = 0.01, width = 0.01}
elements = 5
start = [0, 0, 0]
end = [1.0, 0, 0]
[[body]]
type = "point_mass"
name = "bead"
mass = 0.3
position = [0.3, 0.0, 0.0]
velocity = [2.0, 0.5, 0.0]
[[constraint]]
type = "sliding"
beam = "rail"
body = "bead"
normal = [0.0, 0.0, 1.0]
[[sensor]]
name = "s"
type = "slide"
constraint = 0
[[sensor]]
name = "energy"
type = "total_energy"
[analysis.dynamic]
t_end = 0.15
step = 1e-3
integrator = "trapezoidal"
"""


def test_a_bead_on_a_free_flexible_cable_keeps_the_energy():
    """No gravity, no damping: the bead (launched obliquely: it bends the cable) slides
    across an element boundary, and kinetic plus strain energy stays what it was after the
    start's projection of the velocities onto the joint, to the trapezoidal scheme's
    projection error: below 1e-4 of it, and four times smaller at half the step."""
    drifts = []
    for step in (1e-3, 5e-4):
        t, values, _, _ = _run(scene_of(FREE), step=step)
        energy = values["energy"]
        assert values["s"][-1] > 0.4 + 0.1
        drifts.append(np.abs(energy - energy[0]).max() / energy[0])
    assert drifts[1] < 1e-4
    assert drifts[1] < drifts[0] / 4


KINDS_3D = ("cable3d", "cable3d_quintic", "beam3d", "beam3d_3node")
KINDS_2D = ("cable2d", "cable2d_quintic", "beam2d", "beam2d_3node")


def _kind_scene(kind: str):
    """A curved body of ``kind`` (an arc) and a point on its line at t = 0: a point mass
    (3D) or the end node of another body (2D)."""
    straight = kind in ("cable3d", "cable3d_quintic")     # curved references: not these
    angle = math.radians(-60.0 + 40.0)        # on element 1 of 3, not at a node
    point = [0.5, 0.5] if straight else [math.cos(angle), math.sin(angle)]
    if kind in KINDS_3D:
        other = (f'[[body]]\ntype = "point_mass"\nname = "p"\nmass = 1.0\n'
                 f'position = [{point[0]!r}, {point[1]!r}, 0.0]\n')
        side = 'body = "p"'
    else:
        other = (f'[[body]]\nname = "p"\nelement = "{kind}"\nmaterial = "m"\n'
                 'section = {height = 0.01, width = 0.01}\nelements = 1\n'
                 f'start = [{point[0]!r}, {point[1]!r}]\nend = [1.5, 0.5]\n')
        side = 'node = "p:0"'
    centre = "[0.0, 0.0, 0.0]" if kind in KINDS_3D else "[0.0, 0.0]"
    shape = ("start = [0.0, 0.0, 0.0]\nend = [1.0, 1.0, 0.0]" if straight else
             f"arc = {{center = {centre}, radius = 1.0, start_angle_deg = -60.0, "
             f"angle_deg = 120.0}}")
    law = 'law = "svk_exact_curvature"' if kind.startswith("cable2d") else ""
    return scene_of(f"""
[material.m]
E = 1e9
nu = 0.3
rho = 1000.0
{law}
[[body]]
name = "line"
element = "{kind}"
material = "m"
section = {{height = 0.02, width = 0.02}}
elements = 3
{shape}
{other}
[[constraint]]
type = "sliding"
beam = "line"
{side}
""")


@pytest.mark.parametrize("kind", KINDS_3D + KINDS_2D)
def test_the_rows_match_finite_differences_on_every_line_kind(kind):
    """Phi_q, the geometric stiffness (Phi_q^T lambda)_q and v^T Phi_qq v of the rows
    (through the eliminated parameter) against central differences, near the start (the
    point off the line and the line moved by 1e-3); the rows vanish at t = 0."""
    model = Model(_kind_scene(kind))
    block = next(b for b in model.holonomic.blocks if isinstance(b, SlidingBlock))
    assert block.rows == model.dim - 1
    x0 = model.reference[block.dofs]
    assert np.abs(block.value(x0)).max() < 1e-9
    rng = np.random.default_rng(len(kind))
    x = x0 + 1e-3 * rng.normal(size=x0.size)
    lam = rng.normal(size=block.rows)
    step = 1e-6
    identity = np.eye(x.size)
    numeric = np.array([(block.value(x + step * e) - block.value(x - step * e)) / (2 * step)
                        for e in identity]).T
    assert np.abs(block.jacobian(x) - numeric).max() <= 1e-8
    stiffness = np.tensordot(lam, block.hessian(x), 1)
    numeric = np.array([(block.jacobian(x + step * e).T @ lam
                         - block.jacobian(x - step * e).T @ lam) / (2 * step)
                        for e in identity]).T
    assert np.abs(stiffness - numeric).max() <= 1e-7 * max(1.0, np.abs(stiffness).max())
    velocity = rng.normal(size=x.size)
    numeric = (block.jacobian(x + step * velocity) @ velocity
               - block.jacobian(x - step * velocity) @ velocity) / (2 * step)
    assert np.abs(block.curvature(x, velocity) - numeric).max() <= 1e-7
    rate = (block.parameter(x + step * velocity) - block.parameter(x - step * velocity)) / (
        2 * step)
    assert abs(block.rate(x, velocity) - rate) <= 1e-8


ROD = """
[material.steel]
E = 2.1e11
nu = 0.3
rho = 7800.0
[[body]]
name = "rail"
element = "beam3d"
material = "steel"
section = {height = 0.02, width = 0.02}
elements = 4
start = [0, 0, 0]
end = [1.0, 0, 0]
[[body]]
type = "rigid"
name = "ring"
mass = 0.4
inertia = [0.002, 0.003, 0.004]
centre_of_mass = [0.0, 0.0, -0.05]
position = [0.3, -0.1, 0.0]
[[constraint]]
type = "clamp"
node = "rail:0"
[[constraint]]
type = "sliding"
beam = "rail"
body = "ring"
point = [0.0, 0.1, 0.0]
normal = [0.0, 0.0, 1.0]
[[load]]
type = "gravity"
acceleration = [2.0, 0.0, -9.81]
[analysis.dynamic]
t_end = 0.05
step = 1e-3
integrator = "generalized_alpha"
"""


def test_a_rigid_body_point_slides_with_exact_rows_in_both_engines():
    """A rigid ring's point (body coordinates, 0.1 m from its origin) on a cantilever:
    the rows on its 12 natural coordinates match central differences, and the engines
    agree on a run in which the ring slides, swings and bends the beam."""
    scene = scene_of(ROD)
    model = Model(scene)
    block = next(b for b in model.holonomic.blocks if isinstance(b, SlidingBlock))
    assert block.point_size == 12
    x = model.reference[block.dofs] + 1e-3 * np.random.default_rng(3).normal(
        size=block.dofs.size)
    step = 1e-6
    numeric = np.array([(block.value(x + step * e) - block.value(x - step * e)) / (2 * step)
                        for e in np.eye(x.size)]).T
    assert np.abs(block.jacobian(x) - numeric).max() <= 1e-8
    (_, _, first, q_python), (_, _, second, q_compiled) = (
        _run(scene, engine) for engine in ("python", "compiled"))
    assert first.counters == second.counters
    assert np.abs(q_python - q_compiled).max() < 1e-12
    slid = block.parameter(q_python[-1][block.dofs]) - block.parameter(
        model.reference[block.dofs])
    assert slid > 0.5 * 2.0 * 0.05**2 / 2     # pulled along the rail by the 2 m/s^2


@pytest.mark.parametrize("integrator", ["trapezoidal", "generalized_alpha"])
def test_the_engines_agree_on_the_shipped_scene(integrator):
    scene = load_scene(scene_path("sliding_bead"))
    runs = [_run(scene, engine, integrator=integrator, t_end=0.1) for engine in
            ("python", "compiled")]
    (_, python, first, q_python), (_, compiled, second, q_compiled) = runs
    assert first.counters == second.counters
    difference = np.abs(q_python - q_compiled).max()
    assert difference < 1e-12
    for name in ("s", "s_rate"):
        assert np.abs(python[name] - compiled[name]).max() < 1e-11
    # the reaction balances the rail's elastic force: the states' difference times the
    # rail's stiffness EA / l = 2.1e11 * 4e-4 * 8 N/m
    reaction = np.abs(python["normal_force"] - compiled["normal_force"]).max()
    assert reaction < 10 * max(difference, 1e-16) * 2.1e11 * 4e-4 * 8


def test_two_beads_on_one_rail_move_alike_in_both_engines():
    """Two sliding joints (the compiled step's data of each joint at its own offsets): a
    second bead further down the same flexible rail, and a rigid body's point on a beam
    beside it, in one model."""
    text = RAIL.format(E=2.1e11, rho=7800.0, t_end=0.05, integrator="generalized_alpha",
                       held="")
    text = text.replace("[[constraint]]", '[[body]]\ntype = "point_mass"\nname = "bead2"\n'
                        'mass = 0.2\nposition = [0.48, 0.0, -0.36]\n[[constraint]]', 1)
    text += ('[[constraint]]\ntype = "sliding"\nbeam = "rail"\nbody = "bead2"\n'
             + ROD[ROD.index("[[body]]"):ROD.index("[[load]]")].replace('"rail"', '"rod"'))
    scene = scene_of(text)
    model = Model(scene)
    assert sum(isinstance(b, SlidingBlock) for b in model.holonomic.blocks) == 3
    (_, _, first, q_python), (_, _, second, q_compiled) = (
        _run(scene, engine) for engine in ("python", "compiled"))
    assert first.counters == second.counters
    assert np.abs(q_python - q_compiled).max() < 1e-12


def test_the_kkt_path_of_many_rows_and_the_schur_path_agree():
    """With eight free rigid bodies beside the bead (50 rows) the joints go through the
    sparse KKT system (``linear.KKT_ROWS``): its run matches the banded solver's Schur
    complement, in both engines."""
    bodies = "".join(f'[[body]]\ntype = "rigid"\nname = "b{k}"\nmass = 1.0\n'
                     f'inertia = [0.1, 0.2, 0.25]\nposition = [{k}.0, 5.0, 0.0]\n'
                     for k in range(8))
    text = RAIL.format(E=2.1e11, rho=7800.0, t_end=0.02, integrator="generalized_alpha",
                       held="")
    scene = scene_of(text.replace("[[constraint]]", bodies + "[[constraint]]", 1))
    banded = dataclasses.replace(scene, solver=dataclasses.replace(scene.solver,
                                                                   linear_solver="banded"))
    *_, schur, q_schur = _run(banded)
    assert schur.kkt is None
    for engine in ("python", "compiled"):
        *_, stepper, q = _run(scene, engine)
        assert stepper.kkt
        assert np.abs(q - q_schur).max() < 1e-12


def test_a_sliding_joint_that_repeats_a_joint_is_named():
    """The bead held at its place by a body_spherical, then put on a rail held at every
    node: the sliding rows repeat what the spherical joint holds (singular multipliers; on
    a flexible rail they would hold the rail to the bead instead)."""
    rigid = RAIL.format(E=2.1e11, rho=7800.0, t_end=0.1, integrator="generalized_alpha",
                        held=RIGID)
    scene = scene_of(rigid.replace('[[constraint]]\ntype = "sliding"',
                                 '[[constraint]]\ntype = "body_spherical"\nbody = "bead"\n'
                                 '[[constraint]]\ntype = "sliding"').replace(
                                     "constraint = 2\n", "constraint = 3\n"))
    with pytest.raises(SceneError, match=r"constraint\[3\]: redundant: a row of this sliding"):
        Model(scene)


def test_the_scenes_round_trip_through_toml():
    """The shipped scene (a point mass, a normal) and a node on a rail (2D)."""
    for scene in (load_scene(scene_path("sliding_bead")),
                  scene_of(ROLLER.replace("ENGINE", "python"))):
        assert parse_scene(tomllib.loads(scene.to_toml())) == scene


def test_a_point_that_leaves_its_body_ends_the_run_with_its_time():
    """On a rail of 0.2 m the bead runs off its lower end at t = sqrt(2 0.1 / (0.6 g)):
    the run stops there with the cause, after the outputs before it."""
    scene = scene_of(RAIL.format(E=2.1e11, rho=7800.0, t_end=0.4, integrator="generalized_alpha",
                                 held=RIGID).replace("end = [0.8, 0, -0.6]",
                                                     "end = [0.16, 0, -0.12]"))
    for engine in ("python", "compiled"):
        model = Model(scene)
        stepper = engines.make(engine, model, scene.dynamic, model.reference.copy())
        times = []
        with pytest.raises(Divergence, match="left the body at its end") as failure:
            stepper.run(0.4, 2e-3, lambda t, q, v, seen=times: seen.append(t))
        leaves = math.sqrt(2 * 0.1 / (0.6 * G))
        assert abs(failure.value.time - leaves) < 4e-3
        assert times[-1] > leaves - 4e-3


ROLLER = """[material.steel]
E = 2.1e11
nu = 0.0
rho = 7800.0
[[body]]
name = "arm"
element = "beam2d"
material = "steel"
section = {height = 0.02, width = 0.02}
elements = 4
start = [0, 0]
end = [1, 0]
[[body]]
name = "rail"
element = "cable2d"
material = "steel"
section = {height = 0.02, width = 0.02}
elements = 3
start = [1, -0.3]
end = [1, 0.3]
[[constraint]]
type = "clamp"
node = "arm:0"
[[constraint]]
type = "clamp"
node = "rail:0"
[[constraint]]
type = "clamp"
node = "rail:1"
[[constraint]]
type = "clamp"
node = "rail:2"
[[constraint]]
type = "clamp"
node = "rail:3"
[[constraint]]
type = "sliding"
beam = "rail"
node = "arm:-1"
[[load]]
type = "point_force"
node = "arm:-1"
force = [0.0, -200.0]
[[sensor]]
name = "tip_y"
type = "displacement"
node = "arm:-1"
component = "y"
[[sensor]]
name = "tip_x"
type = "displacement"
node = "arm:-1"
component = "x"
[[sensor]]
name = "s"
type = "slide"
constraint = 5
[analysis.static]
load_steps = 2
[solver]
engine = "ENGINE"
"""


def test_a_cantilever_on_a_rail_settles_alike_in_both_static_solves(tmp_path):
    """A 2D cantilever whose tip node slides on a vertical rail (a roller): the static
    solutions of both engines agree to round-off; the tip stays on the rail (x held) and
    the slide sensor reads the rail's parameter of the tip (0.3 m + its deflection)."""
    import json

    from runtime.cli import main

    results = []
    for engine in ("python", "compiled"):
        path = tmp_path / f"{engine}.toml"
        path.write_text(ROLLER.replace("ENGINE", engine))
        assert main(["run", str(path), "--out", str(tmp_path / engine)]) == 0
        results.append(json.loads((tmp_path / engine / "summary.json").read_text())
                       ["static"]["sensors"])
    python, compiled = results
    assert abs(python["tip_x"]) < 1e-9
    assert python["tip_y"] < -1e-3
    assert abs(python["s"] - (0.3 + python["tip_y"])) < 1e-12
    for name in python:
        assert abs(python[name] - compiled[name]) < 1e-12


BAD = RAIL.format(E=2.1e11, rho=7800.0, t_end=0.1, integrator="generalized_alpha", held="")


@pytest.mark.parametrize("change, culprit", [
    (('beam = "rail"', 'beam = "nope"'), r"constraint\[2\]\.beam: expected the name of a "
                                         r"meshed body"),
    (('body = "bead"\n[[load]]', 'node = "rail:2"\nbody = "bead"\n[[load]]'),
     r"constraint\[2\]: expected the sliding point as .*both"),
    (('body = "bead"\n[[load]]', 'node = "rail:2"\n[[load]]'),
     r"constraint\[2\]\.node: expected a node of another body"),
    (("constraint = 2\n", "constraint = 1\n"), r"sensor\[0\]\.constraint: expected the index "
                                               r"of a sliding joint"),
    (("position = [0.08, 0.0, -0.06]", 'node = "rail:2"'),
     r"constraint\[2\]\.body: the point mass \"bead\" sits on a node of the beam"),
])
def test_bad_sliding_joints_name_the_key(change, culprit):
    with pytest.raises(SceneError, match=culprit):
        scene_of(BAD.replace(*change))


def test_a_point_off_the_line_at_the_start_names_the_constraint():
    scene = scene_of(BAD.replace("position = [0.08, 0.0, -0.06]",
                                 "position = [0.08, 0.01, -0.06]"))
    with pytest.raises(SceneError, match=r"constraint\[2\]: point: the sliding point must be "
                                         r"on the centre line .* 0\.01 m from it"):
        Model(scene)


def test_a_normal_along_the_tangent_names_the_key():
    scene = scene_of(BAD.replace('body = "bead"\n[[load]]',
                                 'body = "bead"\nnormal = [0.8, 0.0, -0.6]\n[[load]]'))
    with pytest.raises(SceneError, match=r"constraint\[2\]: normal: expected a direction "
                                         r"across the line"):
        Model(scene)


def test_a_point_off_the_line_exits_2_from_the_cli(tmp_path, capsys):
    from runtime.cli import main

    path = tmp_path / "off.toml"
    path.write_text(BAD.replace("position = [0.08, 0.0, -0.06]",
                                "position = [0.08, 0.01, -0.06]"))
    assert main(["run", str(path), "--out", str(tmp_path / "out")]) == 2
    assert "constraint[2]" in capsys.readouterr().err


def test_a_plate_is_not_a_line_body():
    plate = """
[[body]]
name = "sheet"
element = "plate3d"
material = "steel"
section = {thickness = 0.01}
rectangle = {corner = [0.0, 0.0, 1.0], size = [1.0, 1.0], grid = [2, 2]}
"""
    with pytest.raises(SceneError, match=r"constraint\[2\]\.beam: a point slides along a "
                                         r"line body"):
        scene_of(BAD.replace('beam = "rail"', 'beam = "sheet"').replace(
            "[[body]]\ntype", plate + "[[body]]\ntype", 1))
