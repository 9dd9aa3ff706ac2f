"""Prescribed joint motion (rheonomic constraint rows, docs/multibody.md "Prescribed joint
motion"): a revolute joint's angle and a prescribed joint's displacement as time laws, in
both engines, both integrators and the static analysis.

Checked against what does not share their code: the law itself (the crank's angle from its
natural coordinates), the closed-form drive torque I alpha + m g d cos(theta) and slider
force m d'', finite differences in time of the rows along a path (Phi_t, Phi_tt and Phi_qt
together) and of their Jacobians, the other engine, and a beam on a driven hub against the
same beam on a ``prescribed_rotation`` hub (the other way of prescribing the motion)."""

from __future__ import annotations

import numpy as np
import pytest
from test_multibody import G, _finite_difference_check, run, scene_of

from runtime.model.dae import DAESystem
from runtime.model.errors import SceneError
from runtime.model.holonomic import DrivenBlock
from runtime.model.model import Model

#: a steel bar 1 m long pinned at one end, its angle about z driven by a law (TOML)
DRIVEN_BAR = """
[[body]]
type = "rigid"
name = "bar"
box = {{size = [1.0, 0.05, 0.05]}}
density = 7800.0
centre_of_mass = [0.5, 0.0, 0.0]
[[constraint]]
type = "body_revolute"
body = "bar"
axis = [0, 0, 1]
angle = {law}
[[load]]
type = "gravity"
acceleration = [0, -9.81, 0]
[[sensor]]
name = "torque"
type = "body_reaction"
body = "bar"
quantity = "moment"
component = "z"
constraint = 0
[analysis.dynamic]
t_end = 1.0
step = 1e-3
"""
STEADY = '{type = "constant_rate", omega = 3.0}'
SWINGING = '{type = "sine", amplitude = 0.8, frequency_hz = 0.75}'


def _angle(q: np.ndarray, dofs: np.ndarray) -> np.ndarray:
    """The unwrapped angle (k,) about z of a rigid body's u axis from its coordinates."""
    return np.unwrap(np.arctan2(q[:, dofs[4]], q[:, dofs[3]]))


@pytest.mark.parametrize("integrator", ["trapezoidal", "generalized_alpha"])
def test_a_driven_crank_follows_its_law_in_both_engines(integrator):
    """theta = omega t against gravity: the bar's angle is the law to round-off, its rows
    hold, and the two engines take the same iterations to the same states."""
    scene = scene_of(DRIVEN_BAR.format(law=STEADY))
    # full Newton, for equal counters (a kept Jacobian may stop a step one iteration apart
    # in the two engines: tests/scenes_small.py, counts_agree)
    python = run(scene, "python", integrator=integrator, newton="full")
    compiled = run(scene, "compiled", integrator=integrator, newton="full")
    t, q, v, stepper = python
    dofs = Model(scene).rigid["bar"].dofs
    assert np.abs(_angle(q, dofs) - 3.0 * t).max() <= 1e-12
    assert _angle(q, dofs)[-1] == pytest.approx(3.0)
    model = Model(scene)
    assert max(np.abs(model.holonomic.value(x)).max() for x in q) <= 1e-12
    rate = q[:, 3] * v[:, 4] - q[:, 4] * v[:, 3]       # u x u' . z: the angular velocity
    # trapezoidal: velocities projected onto Phi_q v + Phi_t = 0; index-3 generalized-alpha
    # holds positions only (its velocities carry an O(h^2) error)
    assert np.abs(rate - 3.0).max() <= (1e-10 if integrator == "trapezoidal" else 1e-5)
    assert np.abs(compiled[1] - q).max() <= 1e-12
    assert np.abs(compiled[2] - v).max() <= 1e-10
    assert compiled[3].counters == stepper.counters
    assert stepper.counters.newton_iterations <= 2.5 * stepper.counters.steps


@pytest.mark.parametrize("engine", ["python", "compiled"])
def test_drive_torque_of_a_swinging_crank_is_the_closed_form_one(engine):
    """theta = 0.8 sin(2 pi 0.75 t): the driving row's multiplier, read by body_reaction
    as the joint's moment about z, is I_p theta'' + m g d cos(theta) at every output."""
    from runtime import run_scene

    scene = scene_of(DRIVEN_BAR.format(law=SWINGING))
    result = run_scene(scene, engine=engine, progress=False, store_states=True)
    mass, inertia = scene.rigid_bodies[0].mass_properties()
    d = 0.5
    pivot = inertia[2, 2] + mass * d * d
    t = np.asarray(result.sensors["t"])
    omega = 2 * np.pi * 0.75
    theta, alpha = 0.8 * np.sin(omega * t), -0.8 * omega**2 * np.sin(omega * t)
    expected = pivot * alpha + mass * G * d * np.cos(theta)
    assert np.asarray(result.sensors["torque"]) == pytest.approx(
        expected, rel=1e-8, abs=1e-8 * mass * G * d)
    assert np.ptp(expected) > mass * G * d           # inertia matters as well as gravity


def _driven_models():
    """Models with every driven joint: a bar on the ground, a second bar hinged to it with
    a driven relative angle, a third driven against a beam node, a slider driven along
    a prismatic joint."""
    return Model(scene_of("""
[material.steel]
E = 2.1e11
nu = 0.0
rho = 7800.0
[[body]]
name = "beam"
element = "beam3d"
material = "steel"
section = {height = 0.02, width = 0.02}
elements = 2
start = [0, 2, 0]
end = [1, 2, 0]
[[body]]
type = "rigid"
name = "a"
mass = 1.0
inertia = [0.1, 0.2, 0.25]
[[body]]
type = "rigid"
name = "b"
mass = 2.0
inertia = [0.3, 0.2, 0.4]
position = [1.0, 0.0, 0.0]
rotation = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
[[body]]
type = "rigid"
name = "c"
mass = 1.5
inertia = [0.1, 0.1, 0.1]
position = [1.0, 2.0, 0.0]
[[body]]
type = "point_mass"
name = "slider"
mass = 0.5
position = [0.0, -1.0, 0.0]
[[constraint]]
type = "body_revolute"
body = "a"
angle = {type = "sine", amplitude = 0.7, frequency_hz = 1.3}
[[constraint]]
type = "body_revolute"
body = "b"
other = "a"
other_point = [1.0, 0.0, 0.0]
axis = [0.0, 0.0, 1.0]
angle = {type = "spin_up", omega = 2.0, t_ramp = 1.0}
[[constraint]]
type = "body_revolute"
body = "c"
node = "beam:-1"
axis = [0.0, 0.0, 1.0]
angle = {type = "spin_up", omega = -1.5, t_ramp = 1.0}
[[constraint]]
type = "body_prismatic"
body = "slider"
axis = [0.6, 0.8, 0.0]
displacement = {type = "cosine_ramp", duration = 0.5}
[[load]]
type = "gravity"
acceleration = [0, -9.81, 0]
[analysis.dynamic]
t_end = 0.3
step = 1e-3
"""))


def test_driven_rows_jacobians_match_finite_differences():
    """Phi_x, the full second derivative (geometric stiffness with the driver columns) and
    x'^T Phi_xx x' of every driven block, against central differences at random points."""
    model = _driven_models()
    driven = [block for block in model.holonomic.blocks if isinstance(block, DrivenBlock)]
    assert len(driven) == 4
    rng = np.random.default_rng(6)
    for block in driven:
        _finite_difference_check(block, rng)


def test_velocity_and_acceleration_constraints_are_the_time_derivatives_of_the_rows():
    """Along a path q(t) = q0 + t v0 + t^2/2 a0 of the free coordinates with the drivers at
    their laws, d/dt Phi = Phi_q v + Phi_t and d2/dt2 Phi = Phi_q a + Phi_tt + 2 Phi_qt v
    + v^T Phi_qq v (the DAE's velocity and acceleration violations), by central
    differences in time."""
    model = _driven_models()
    dae = DAESystem(model, model.reference)
    rng = np.random.default_rng(3)
    q0 = model.reference[dae.free] + 0.05 * rng.normal(size=dae.free.size)
    v0, a0 = rng.normal(size=dae.free.size), rng.normal(size=dae.free.size)

    def state(t: float):
        qp, vp, ap = (x[0] for x in dae.prescribed_motion([t]))
        return (dae.full_coordinates(q0 + t * v0 + t * t / 2 * a0, qp),
                dae.full_velocities(v0 + t * a0, vp), dae.full_accelerations(a0, ap))

    for t in (0.2, 0.35, 0.8):      # inside the ramps: every law has a rate and a curvature
        step = 1e-3                  # five-point stencils: errors O(step^4)
        f = [dae.violation(state(t + k * step)[0]) for k in (-2, -1, 0, 1, 2)]
        rate = (f[0] - 8 * f[1] + 8 * f[3] - f[4]) / (12 * step)
        second = (-f[0] + 16 * f[1] - 30 * f[2] + 16 * f[3] - f[4]) / (12 * step**2)
        q, v, a = state(t)
        assert np.abs(dae.velocity_violation(q, v) - rate).max() <= 1e-8
        assert np.abs(dae.acceleration_violation(q, v, a) - second).max() <= 1e-7


@pytest.mark.parametrize("integrator", ["trapezoidal", "generalized_alpha"])
def test_engines_agree_on_every_driven_joint(integrator):
    """The four driven joints (body-ground, body-body, body-node, prismatic) under gravity
    in both engines; every row holds; the second bar turns by the sum of both laws; the
    slider is at its law."""
    model = _driven_models()
    scene = model.scene
    # full Newton, for equal counters (a kept Jacobian may stop a step one iteration apart
    # in the two engines: tests/scenes_small.py, counts_agree)
    t, q, _, stepper = run(scene, "python", integrator=integrator, newton="full")
    compiled = run(scene, "compiled", integrator=integrator, newton="full")
    assert np.abs(compiled[1] - q).max() <= 1e-11
    assert compiled[3].counters == stepper.counters
    assert max(np.abs(model.holonomic.value(x)).max() for x in q) <= 1e-10
    a, b = model.rigid["a"].dofs, model.rigid["b"].dofs
    theta_a = 0.7 * np.sin(2 * np.pi * 1.3 * t)
    ramp = model.scene.constraints[1].angle.sample(t)[0]
    assert np.abs(_angle(q, a) - theta_a).max() <= 1e-10
    assert np.abs(_angle(q, b) - np.pi / 2 - theta_a - ramp).max() <= 1e-10
    slider = model.rigid["slider"].dofs
    law = model.scene.constraints[3].displacement.sample(t)[0]
    along = q[:, slider] - np.array([0.0, -1.0, 0.0])
    assert np.abs(along - law[:, None] * np.array([0.6, 0.8, 0.0])).max() <= 1e-10


@pytest.mark.parametrize("engine", ["python", "compiled"])
def test_slider_force_of_a_driven_prismatic_joint_is_m_times_its_acceleration(engine):
    from runtime import run_scene

    scene = scene_of("""
[[body]]
type = "rigid"
name = "slider"
mass = 0.5
inertia = [0.001, 0.001, 0.001]
[[constraint]]
type = "body_prismatic"
body = "slider"
axis = [1.0, 0.0, 0.0]
displacement = {type = "sine", amplitude = 0.1, frequency_hz = 2.0}
[[sensor]]
name = "force"
type = "body_reaction"
body = "slider"
component = "x"
[analysis.dynamic]
t_end = 0.5
step = 1e-3
""")
    result = run_scene(scene, engine=engine, progress=False)
    t = np.asarray(result.sensors["t"])
    omega = 4 * np.pi
    expected = 0.5 * -0.1 * omega**2 * np.sin(omega * t)
    assert np.asarray(result.sensors["force"]) == pytest.approx(expected, abs=1e-9)


def test_static_analysis_holds_a_driven_crank_at_its_angle_at_t_0():
    """The static equilibrium at t = 0 of the horizontal bar: the driving row carries the
    whole gravity moment, m g d."""
    from runtime import run_scene

    scene = scene_of(DRIVEN_BAR.format(law=STEADY).replace(
        "[analysis.dynamic]\nt_end = 1.0\nstep = 1e-3\n", "[analysis.static]\n"))
    torque = run_scene(scene, progress=False).summary["static"]["sensors"]["torque"]
    mass, _ = scene.rigid_bodies[0].mass_properties()
    assert torque == pytest.approx(mass * G * 0.5, rel=1e-10)


def test_a_beam_on_a_driven_hub_moves_as_on_a_prescribed_rotation_hub():
    """The paper's spin-up (eq. 45) of a 3D beam: welded to a rigid hub whose revolute
    joint's angle is the law, and clamped to a prescribed_rotation hub node with the same
    law; the tip's lag (in the hub's frame) agrees to the Newton tolerance."""
    beam = """
[material.aluminium]
E = 68.95e9
nu = 0.0
rho = 2766.67
[[body]]
name = "beam"
element = "beam3d"
material = "aluminium"
section = { height = 0.03675006, width = 0.001986119 }
elements = 6
start = [0.0, 0.0, 0.0]
end = [8.0, 0.0, 0.0]
[[sensor]]
name = "tip"
type = "displacement"
node = "beam:-1"
frame = "beam:0"
component = "y"
[analysis.dynamic]
t_end = 3.0
step = 5e-3
integrator = "generalized_alpha"
output_every = 0.1
"""
    law = '{ type = "spin_up", omega = 4.0, t_ramp = 15.0 }'
    hub = scene_of(beam + f"""
[[constraint]]
type = "prescribed_rotation"
node = "beam:0"
angle = {law}
""")
    driven = scene_of(beam + f"""
[[body]]
type = "rigid"
name = "hub"
cylinder = {{ radius = 0.2, length = 0.1 }}
density = 7800.0
[[constraint]]
type = "body_revolute"
body = "hub"
axis = [0.0, 0.0, 1.0]
angle = {law}
[[constraint]]
type = "body_weld"
body = "hub"
node = "beam:0"
""")
    from runtime import run_scene

    reference = run_scene(hub, engine="compiled", progress=False).sensors["tip"]
    ours = run_scene(driven, engine="compiled", progress=False).sensors["tip"]
    assert np.min(reference) < -0.02                      # the tip lags by centimetres
    assert np.abs(np.asarray(ours) - reference).max() <= 1e-6 * np.abs(reference).max()


@pytest.mark.parametrize("table, culprit, message", [
    ('type = "body_revolute"\nbody = "bar"\nangle = {type = "sine", amplitude = 1.0, '
     'frequency_hz = 1.0, phase_deg = 90.0}\n', "constraint[0].angle",
     "expected a law that is 0 at t = 0"),
    ('type = "body_revolute"\nbody = "bar"\nangle = 3.0\n', "constraint[0].angle", ""),
    ('type = "body_prismatic"\nbody = "bar"\ndisplacement = {type = "constant", '
     'value = 0.1}\n', "constraint[0].displacement", "expected a law that is 0 at t = 0"),
    ('type = "body_prismatic"\nbody = "bar"\ndisplacement = {type = "linear_ramp"}\n',
     "constraint[0].displacement", ""),
])
def test_bad_prescribed_motion_exits_2_naming_the_key(tmp_path, capsys, table, culprit,
                                                        message):
    from runtime.cli import main

    bar = ('[[body]]\ntype = "rigid"\nname = "bar"\nmass = 1.0\ninertia = [1, 1, 1]\n'
           '[analysis.dynamic]\nt_end = 0.1\nstep = 0.01\n')
    scene = tmp_path / "bad.toml"
    scene.write_text(bar + "[[constraint]]\n" + table)
    assert main(["run", str(scene), "--out", str(tmp_path / "out")]) == 2
    error = capsys.readouterr().err
    assert culprit in error and message in error
    with pytest.raises(SceneError, match=culprit.replace("[", r"\[").replace("]", r"\]")):
        scene_of(bar + "[[constraint]]\n" + table)


def test_driven_joints_round_trip_through_toml():
    scene = _driven_models().scene
    assert scene_of(scene.to_toml()) == scene
