"""Planar multibody models: 2D rigid bodies in planar natural coordinates [r0, u], point
masses, their joints, loads and sensors in both engines (docs/multibody.md, "2D rigid
bodies").

Checked against what does not share their code: the rigid slider-crank's position formula,
the 3D scene of the same mechanism, the other engine, the closed-form free motion of a rigid
body (uniform translation of the centre of mass and rotation at constant rate, energy and
angular momentum from the centre of mass's motion), the elliptic-integral period of a
physical pendulum, finite differences of every constraint Jacobian."""

from __future__ import annotations

import dataclasses
import tomllib

import numpy as np
import pytest
import scipy.special
from test_multibody import G, crossings, run, scene_of, slider_position

from runtime.model.errors import SceneError
from runtime.model.model import Model
from runtime.model.scene import load_scene
from runtime.studies.bench_solvers import cable_rod
from scenes import path as scene_path

#: a 1 m steel bar (0.05 m x 0.05 m) pinned at its end in a 2D scene, released horizontally
PENDULUM_2D = """
[[body]]
type = "rigid"
name = "bar"
box = {size = [1.0, 0.05, 0.05]}
density = 7800.0
centre_of_mass = [0.5, 0.0]
position = [0.0, 0.0]
[[constraint]]
type = "body_revolute"
body = "bar"
[[load]]
type = "gravity"
acceleration = [0, -9.81]
[analysis.dynamic]
t_end = 0.6
step = 1e-3
"""

#: a free body: its origin off the centre of mass, moving and spinning, no loads
FREE_BODY = """
[[body]]
type = "rigid"
name = "plate"
mass = 3.0
inertia = 0.4
centre_of_mass = [0.3, -0.2]
position = [1.0, 2.0]
angle = 0.7
velocity = [0.5, -0.25]
angular_velocity = 4.0
[analysis.dynamic]
t_end = 2.0
step = 2e-3
integrator = "trapezoidal"
"""


def _angle(u: np.ndarray) -> np.ndarray:
    """The angle (rad, unwrapped) of the vectors u (k, 2) from the x axis."""
    return np.unwrap(np.arctan2(u[:, 1], u[:, 0]))


def _stiff(scene):
    stiff = dataclasses.replace(scene.materials["aluminium"], E=7.0e12)
    return dataclasses.replace(scene, materials={"aluminium": stiff})


def test_2d_slider_crank_with_a_stiff_rod_follows_the_rigid_position_formula():
    """scenes/slider_crank_2d.toml with the rod 100 times stiffer, over more than a
    revolution of the driven crank: the crank at phi = 60 deg + 10 t, the slider on the x
    axis at the rigid formula's x to 1e-5 of the crank length (as the 3D scene)."""
    scene = _stiff(load_scene(scene_path("slider_crank_2d")))
    t, q, _, _ = run(scene, "compiled", t_end=0.7)
    model = Model(scene)
    crank, slider = model.rigid["crank"].dofs, model.rigid["slider"].dofs
    assert crank.size == 4 and slider.size == 2
    phi = _angle(q[:, crank[2:]])
    assert np.abs(phi - (np.pi / 3 + 10.0 * t)).max() <= 1e-12
    assert phi[-1] - phi[0] > 2 * np.pi
    assert np.abs(q[:, crank[:2]]).max() <= 1e-12                 # the pivot holds
    r = 0.15
    assert np.abs(q[:, slider[0]] - slider_position(phi, r)).max() <= 1e-5 * r
    assert np.abs(q[:, slider[1]]).max() <= 1e-12                 # on the prismatic axis


def test_2d_and_3d_slider_cranks_agree():
    """The 2D scene (cable2d rod, planar coordinates: 4 + 2 rigid coordinates) and the 3D
    one with a cable3d rod (12 + 3 rigid coordinates, the same in-plane physics): the
    slider, the crank pin, the rod's middle (to 1e-12 m; 4e-14 m measured over the 0.7 s)
    and the drive torque agree over 0.2 s."""
    planar = load_scene(scene_path("slider_crank_2d"))
    spatial = cable_rod(load_scene(scene_path("slider_crank")))
    from runtime import run_scene

    results = [run_scene(dataclasses.replace(s, dynamic=dataclasses.replace(
        s.dynamic, t_end=0.2)), engine="compiled", progress=False)
        for s in (planar, spatial)]
    two, three = (r.sensors for r in results)
    assert np.array_equal(two["t"], three["t"])
    for name in ("slider_x", "crank_pin_y", "rod_mid_y"):
        assert np.abs(two[name] - three[name]).max() <= 1e-12, name
    torque = np.abs(three["drive_torque"]).max()
    assert np.abs(two["drive_torque"] - three["drive_torque"]).max() <= 1e-6 * torque
    assert np.abs(two["pivot_force"] - three["pivot_force"]).max() <= 1e-6 * np.abs(
        three["pivot_force"]).max()


@pytest.mark.parametrize("integrator", ["trapezoidal", "generalized_alpha"])
def test_engines_agree_on_the_2d_slider_crank(integrator):
    scene = load_scene(scene_path("slider_crank_2d"))
    python = run(scene, "python", integrator=integrator, t_end=0.02, newton="full")
    compiled = run(scene, "compiled", integrator=integrator, t_end=0.02, newton="full")
    assert np.abs(python[1] - compiled[1]).max() <= 1e-12
    assert np.abs(python[2] - compiled[2]).max() <= 1e-9


def test_a_free_2d_rigid_body_moves_uniformly_and_conserves_energy_and_momentum():
    """No loads: the centre of mass moves at its initial velocity, the body turns at its
    initial rate (the trapezoidal rule's discrete rotation); kinetic energy 1/2 m |v_c|^2 +
    1/2 I w^2 and angular momentum about the origin m r_c x v_c + I w (from the centre of
    mass's motion) are constant."""
    scene = scene_of(FREE_BODY)
    t, q, v, _ = run(scene)
    body = scene.rigid_bodies[0]
    s = np.array(body.centre_of_mass)
    u, rate = q[:, 2:4], v[:, 2:4]
    perp_u, perp_rate = np.stack([-u[:, 1], u[:, 0]], 1), np.stack([-rate[:, 1], rate[:, 0]], 1)
    centre = q[:, :2] + s[0] * u + s[1] * perp_u
    speed = v[:, :2] + s[0] * rate + s[1] * perp_rate
    omega = u[:, 0] * rate[:, 1] - u[:, 1] * rate[:, 0]
    assert np.abs(omega - 4.0).max() <= 1e-9
    # the trapezoidal rule turns u by 2 atan(w h / 2) per step (a Cayley rotation), a
    # phase lag of (w h)^3 / 12 per step behind w t
    steps = np.arange(t.size)
    assert np.abs(_angle(u) - (0.7 + steps * 2 * np.arctan(4.0 * 2e-3 / 2))).max() <= 1e-9
    assert np.abs(centre - (centre[0] + np.outer(t, speed[0]))).max() <= 1e-9
    assert speed[0] == pytest.approx(np.array(body.velocity) + 4.0 * (
        np.array(body.frame) @ np.array([-s[1], s[0]])), abs=1e-14)
    energy = 0.5 * 3.0 * (speed**2).sum(axis=1) + 0.5 * 0.4 * omega**2
    momentum = 3.0 * (centre[:, 0] * speed[:, 1] - centre[:, 1] * speed[:, 0]) + 0.4 * omega
    assert np.ptp(energy) <= 1e-9 * energy[0]
    assert np.ptp(momentum) <= 1e-9 * abs(momentum[0])


def test_2d_rigid_pendulum_period_is_the_elliptic_integral_one():
    """The bar released horizontally passes the vertical at T/4, T = 4 sqrt(I_p / (m g d))
    K(sin^2 45 deg), I_p = m (a^2 + b^2) / 12 + m d^2 of the 1 m x 0.05 m box."""
    scene = scene_of(PENDULUM_2D)
    t, q, _, _ = run(scene, integrator="trapezoidal", newton="full")
    mass = 7800.0 * 1.0 * 0.05 * 0.05
    pivot = mass * (1.0 + 0.05**2) / 12 + mass * 0.5**2
    period = 4 * np.sqrt(pivot / (mass * G * 0.5)) * scipy.special.ellipk(0.5)
    assert crossings(t, q[:, 2])[0] == pytest.approx(period / 4, rel=2e-5)


PLANAR_JOINTS = """
[[body]]
type = "rigid"
name = "a"
mass = 1.0
inertia = 0.1
centre_of_mass = [0.4, 0.1]
position = [0.0, 0.0]
angle = 0.3
[[body]]
type = "rigid"
name = "b"
mass = 2.0
inertia = 0.3
position = [1.2, 0.5]
angle = -0.4
[[body]]
type = "point_mass"
name = "dot"
mass = 0.5
position = [2.0, 1.0]
[[body]]
type = "rigid"
name = "c"
mass = 1.5
inertia = 0.2
position = [1.5, -0.5]
angle = 1.1
[[constraint]]
type = "body_revolute"
body = "b"
other = "a"
point = [0.0, 0.0]
other_point = [{x}, {y}]
angle = {{type = "constant_rate", omega = 2.0}}
[[constraint]]
type = "body_prismatic"
body = "dot"
other = "b"
axis = [0.6, 0.8]
[[constraint]]
type = "body_prismatic"
body = "c"
other = "b"
point = [0.2, 0.1]
axis = [-0.8, 0.6]
[[constraint]]
type = "body_prismatic"
body = "a"
axis = [1.0, 1.0]
displacement = {{type = "constant_rate", omega = 0.5}}
"""


def _planar_joints():
    frame = np.array([[np.cos(0.3), -np.sin(0.3)], [np.sin(0.3), np.cos(0.3)]])
    x, y = frame.T @ np.array([1.2, 0.5])        # b's origin in a's body coordinates
    return scene_of(PLANAR_JOINTS.format(x=repr(float(x)), y=repr(float(y))))


def test_every_2d_constraint_jacobian_matches_finite_differences():
    """The 2D rigid body's row u.u = 1, the slider-crank's driven pin and slide, a driven
    pin between two bodies, a slide of a point mass and of a rigid body (with its relative
    rotation lock) on a body, and a driven slide of a body on the ground (with its rotation
    lock): the rows vanish at t = 0, the Jacobians,
    geometric stiffnesses and curvatures match central differences."""
    from test_multibody import _finite_difference_check

    rng = np.random.default_rng(2)
    blocks = []
    for scene in (load_scene(scene_path("slider_crank_2d")), _planar_joints()):
        model = Model(scene)
        assert np.abs(model.holonomic.value(model.reference)).max() <= 1e-12
        assert np.abs(model.joints @ model.reference - model.joint_offsets).max() <= 1e-12
        blocks += model.holonomic.blocks
    owners = [block.owner for block in blocks]
    assert {"body_prismatic of dot on b", "body_prismatic of c on b", "body 'b'"} <= set(owners)
    for block in blocks:
        _finite_difference_check(block, rng)


def test_2d_joints_leave_the_right_motions():
    """Rows of the joints (at the reference, A and Phi_q): a driven pin and a driven slide
    leave no motion, a slide of a point mass or of a rigid body one translation each, and a
    weld to a beam2d node holds the node's frame to the body."""
    scene = _planar_joints()
    model = Model(scene)
    rows = np.vstack([model.joints.toarray(), model.holonomic.jacobian(model.reference)
                      .toarray()])
    # 14 free coordinates: 3 unit rows, a's slide 1 + lock 1 + drive 1, b's pin 2 + drive 1,
    # dot's slide 1, c's slide 1 + lock 1: two free motions left (dot's and c's slides)
    assert model.free.size == 14 and rows.shape[0] == 12
    assert np.linalg.matrix_rank(rows[:, model.free]) == model.free.size - 2
    weld = scene_of("""
[material.steel]
E = 2.1e11
nu = 0.3
rho = 7800.0
[[body]]
name = "beam"
element = "beam2d"
material = "steel"
section = {height = 0.02, width = 0.02}
elements = 2
start = [1.0, 0.0]
end = [2.0, 0.0]
[[body]]
type = "rigid"
name = "hub"
mass = 1.0
inertia = 0.01
position = [0.0, 0.0]
[[constraint]]
type = "body_revolute"
body = "hub"
[[constraint]]
type = "body_weld"
body = "hub"
point = [1.0, 0.0]
node = "beam:0"
""")
    model = Model(weld)
    hub = model.rigid["hub"].dofs
    node = model.node_index(weld.constraints[1].node)
    angle = 0.2
    c, s = np.cos(angle), np.sin(angle)
    q = model.reference.copy()          # the hub and the node turned together by 0.2 rad
    q[hub[2:]] = [c, s]
    q[model.node_dofs(node, "r")] = [c, s]
    q[model.node_dofs(node, "r_x")] = [c, s]
    q[model.node_dofs(node, "r_y")] = [-s, c]
    assert np.abs(model.joints @ q - model.joint_offsets).max() <= 1e-15
    q[model.node_dofs(node, "r_y")] = [-s, c + 1e-3]       # a sheared section breaks it
    assert np.abs(model.joints @ q - model.joint_offsets).max() >= 1e-3 - 1e-15


def test_2d_rigid_scene_round_trips_through_toml():
    from runtime.model.scene import parse_scene

    for scene in (load_scene(scene_path("slider_crank_2d")), _planar_joints(),
                  scene_of(FREE_BODY)):
        assert parse_scene(tomllib.loads(scene.to_toml())) == scene
    assert scene_of(FREE_BODY).dim == 2


def test_2d_pendulum_sensors_and_loads():
    """The pendulum's tip position and velocity sensors against its coordinates, the pivot
    reaction at rest (hanging) the weight, a body_force at the tip as the same force."""
    hanging = PENDULUM_2D.replace('centre_of_mass = [0.5, 0.0]',
                                  'centre_of_mass = [0.5, 0.0]\nangle = -1.5707963267948966')
    sensors = """
[[sensor]]
name = "tip_x"
type = "body_position"
body = "bar"
point = [1.0, 0.0]
component = "x"
[[sensor]]
name = "tip_vy"
type = "body_velocity"
body = "bar"
point = [1.0, 0.0]
component = "y"
[[sensor]]
name = "ry"
type = "body_reaction"
body = "bar"
component = "y"
[[sensor]]
name = "mz"
type = "body_reaction"
body = "bar"
quantity = "moment"
component = "z"
"""
    from runtime import run_scene

    mass = 7800.0 * 1.0 * 0.05 * 0.05
    result = run_scene(scene_of(hanging + sensors), progress=False)
    assert np.abs(result.sensors["ry"] - mass * G).max() <= 1e-9 * mass * G
    assert np.abs(result.sensors["mz"]).max() <= 1e-9 * mass * G
    assert np.abs(result.sensors["tip_x"]).max() <= 1e-12
    swinging = run_scene(scene_of(PENDULUM_2D + sensors), progress=False, store_states=True)
    u = swinging.states.q[:, 2:4]
    rate = swinging.states.v[:, 2:4]
    assert swinging.sensors["tip_x"] == pytest.approx(u[:, 0], abs=1e-14)
    assert swinging.sensors["tip_vy"] == pytest.approx(rate[:, 1], abs=1e-14)
    pushed = PENDULUM_2D.replace('acceleration = [0, -9.81]', 'acceleration = [0, 0]') + (
        '[[load]]\ntype = "body_force"\nbody = "bar"\npoint = [0.5, 0.0]\n'
        f'force = [0.0, {-mass * G!r}]\n')
    pushed_result = run_scene(scene_of(pushed), progress=False, store_states=True)
    assert pushed_result.states.q == pytest.approx(swinging.states.q, abs=1e-12)


@pytest.mark.parametrize(("text", "culprit"), [
    ('position = [0.0, 0.0, 0.0]', r"body\[0\]\.position: expected a list of 2 numbers"),
    ('angular_velocity = [0.0, 0.0, 1.0]', r"body\[0\]\.angular_velocity: expected a number"),
    ('velocity = [1.0, 0.0, 0.0]', r"body\[0\]\.velocity: expected a list of 2 numbers"),
    ('rotation = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]',
     r"body\[0\]\.rotation: expected a 2 x 2 matrix"),
    ('angle = 0.1\nrotation = [[1.0, 0.0], [0.0, 1.0]]', r"body\[0\]\.angle: expected an angle "
                                                         "or a rotation, got both"),
])
def test_bad_2d_rigid_input_names_the_key(text, culprit):
    """The bar of a scene of rigid items only that is 2D (a particle at a 2D position)."""
    body, rest = PENDULUM_2D.replace('position = [0.0, 0.0]\n', '').split("[[constraint]]")
    particle = '[[body]]\ntype = "point_mass"\nname = "dot"\nmass = 1.0\nposition = [5, 5]\n'
    with pytest.raises(SceneError, match=culprit):
        scene_of(body + text + "\n" + particle + "[[constraint]]" + rest)


def test_bad_2d_joint_and_load_input_names_the_key():
    twice = PENDULUM_2D.replace('[[load]]', '[[constraint]]\ntype = "body_spherical"\n'
                                'body = "bar"\n[[load]]', 1)
    with pytest.raises(SceneError, match=r"constraint\[1\]: redundant: a row of this "
                                         r"body_spherical joint repeats"):
        Model(scene_of(twice))
    with pytest.raises(SceneError, match=r"constraint\[0\]\.axis: only allowed in 3D"):
        scene_of(PENDULUM_2D.replace('body = "bar"\n[[load]]',
                                     'body = "bar"\naxis = [0, 0, 1]\n[[load]]'))
    with pytest.raises(SceneError, match=r"constraint\[0\]\.point: expected a list of 2"):
        scene_of(PENDULUM_2D.replace('body = "bar"\n[[load]]',
                                     'body = "bar"\npoint = [0, 0, 0]\n[[load]]'))
    with pytest.raises(SceneError, match=r"body\[0\]\.inertia: expected a number"):
        scene_of(FREE_BODY.replace("inertia = 0.4", "inertia = [0.4, 0.4, 0.4]"))
    with pytest.raises(SceneError, match=r"body\[0\]\.angle: an angle gives a 2D body"):
        scene_of("[[body]]\ntype = \"rigid\"\nname = \"b\"\nmass = 1.0\n"
                 "inertia = [1, 1, 1]\nangle = 0.5\n")
    with pytest.raises(SceneError, match=r"sensor\[0\]\.component: unknown component \"z\""):
        scene_of(PENDULUM_2D + '[[sensor]]\nname = "r"\ntype = "body_reaction"\n'
                 'body = "bar"\ncomponent = "z"\n')


def test_a_torque_spins_a_pinned_2d_disc_up_at_t_over_i():
    """A body_torque T on a disc pinned at its centre: w = T t / I in both engines (the
    trapezoidal rule's error, O(h^2), quarters with the step), and the torque's Jacobian
    (constant, T PERP on u) against central differences."""
    from runtime.model.items.force_elements import BodyTorqueForce

    text = FREE_BODY.replace("centre_of_mass = [0.3, -0.2]\n", "").replace(
        "velocity = [0.5, -0.25]\nangular_velocity = 4.0\n", "") + (
        '[[constraint]]\ntype = "body_revolute"\nbody = "plate"\n'
        '[[load]]\ntype = "body_torque"\nbody = "plate"\ntorque = 2.0\n')
    scene = scene_of(text)
    rates, errors = [], []
    for engine, step in (("python", 2e-3), ("compiled", 2e-3), ("compiled", 1e-3)):
        t, q, v, _ = run(scene, engine, t_end=0.5, step=step)
        omega = q[:, 2] * v[:, 3] - q[:, 3] * v[:, 2]
        rates.append(omega)
        errors.append(np.abs(omega - 2.0 * t / 0.4).max() / 2.5)
    assert np.abs(rates[0] - rates[1]).max() <= 1e-12
    assert errors[1] <= 1e-5 and 3.9 <= errors[1] / errors[2] <= 4.1
    force = BodyTorqueForce(np.arange(4), np.zeros(3), 2.0)
    x = np.random.default_rng(3).normal(size=4)
    step = 1e-6
    numeric = np.array([(force(x + step * e, False).force[0]
                         - force(x - step * e, False).force[0]) / (2 * step)
                        for e in np.eye(4)]).T
    assert np.abs(force(x, True).jacobian[0] - numeric).max() <= 1e-8
    with pytest.raises(SceneError, match=r"load\[0\]\.axis: only allowed in 3D"):
        scene_of(text + 'axis = [0, 0, 1]\n')


def test_body_angle_and_angular_velocity_sensors_read_the_spin_in_2d_and_3d():
    """The free 2D body spins at its initial 4 rad/s and its angle is the trapezoidal rule's
    rotation (wrapped to (-pi, pi]); a free 3D body of equal principal moments keeps its
    initial angular velocity [1, -2, 3] rad/s (global axes)."""
    from runtime import run_scene

    sensor = '[[sensor]]\nname = "w"\ntype = "body_angular_velocity"\nbody = "plate"\n'
    angle = '[[sensor]]\nname = "a"\ntype = "body_angle"\nbody = "plate"\n'
    read = run_scene(scene_of(FREE_BODY + sensor + angle), progress=False).sensors
    assert np.abs(read["w"] - 4.0).max() <= 1e-9
    steps = np.rint(read["t"] / 2e-3)
    turned = 0.7 + steps * 2 * np.arctan(4.0 * 2e-3 / 2)
    assert np.abs(np.angle(np.exp(1j * (read["a"] - turned)))).max() <= 1e-9
    assert read["a"].min() > -np.pi and read["a"].max() <= np.pi and np.ptp(read["a"]) > 6
    ball = ('[[body]]\ntype = "rigid"\nname = "ball"\nmass = 2.0\ninertia = [0.5, 0.5, 0.5]\n'
            'rotation = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]\n'
            'angular_velocity = [1.0, -2.0, 3.0]\n'
            '[analysis.dynamic]\nt_end = 0.5\nstep = 1e-3\nintegrator = "trapezoidal"\n')
    for component, value in (("x", 1.0), ("y", -2.0), ("z", 3.0), ("norm", np.sqrt(14.0))):
        text = ball + sensor.replace('"plate"', '"ball"') + f'component = "{component}"\n'
        read = run_scene(scene_of(text), progress=False).sensors["w"]
        assert np.abs(read - value).max() <= 1e-9 * np.sqrt(14.0), component
    with pytest.raises(SceneError, match=r"sensor\[0\]\.component: .*rotation is about z"):
        scene_of(FREE_BODY + sensor + 'component = "x"\n')
    with pytest.raises(SceneError, match=r"sensor\[0\]\.type: a 3D body's orientation"):
        scene_of(ball + angle.replace('"plate"', '"ball"'))


#: a ball 0.1 m short of the rest length of a spring hung from the origin (no gravity)
BALL_ON_SPRING = """
[[body]]
type = "point_mass"
name = "ball"
mass = 2.0
position = [0.0, -0.9]
[[load]]
type = "spring_damper"
end_a = [0.0, 0.0]
end_b = {body = "ball"}
stiffness = 800.0
length = 1.0
"""

#: the ball, and a spring-damper from it to the tip of a spinning bar
SPRINGS_2D = BALL_ON_SPRING + """
[[body]]
type = "rigid"
name = "bar"
mass = 1.0
inertia = 0.05
centre_of_mass = [0.5, 0.0]
position = [1.0, 0.0]
angular_velocity = 3.0
[[constraint]]
type = "body_revolute"
body = "bar"
[[load]]
type = "spring_damper"
end_a = {body = "bar", point = [1.0, 0.0]}
end_b = {body = "ball"}
stiffness = 50.0
damping = 0.5
"""


def test_2d_spring_dampers_match_finite_differences_closed_form_and_the_other_engine():
    """The 2D spring-damper's Jacobians against central differences; a ball 0.1 m short of
    the rest length of a spring to an anchor oscillates at sqrt(k / m) about the rest
    length; the engines agree
    on a spring between the ball and a spinning bar."""
    from test_multibody import check_state_force_jacobians

    check_state_force_jacobians(scene_of(SPRINGS_2D))
    scene = scene_of(BALL_ON_SPRING + "[analysis.dynamic]\nt_end = 1.0\nstep = 1e-3\n")
    t, q, _, _ = run(scene, integrator="trapezoidal")
    exact = -1.0 + 0.1 * np.cos(np.sqrt(800.0 / 2.0) * t)     # about y = -1 m
    assert np.abs(q[:, 1] - exact).max() <= 1e-4
    assert np.abs(q[:, 0]).max() <= 1e-15
    both = scene_of(SPRINGS_2D + "[analysis.dynamic]\nt_end = 0.3\nstep = 1e-3\n")
    python = run(both, "python", newton="full")
    compiled = run(both, "compiled", newton="full")
    assert np.abs(python[1] - compiled[1]).max() <= 1e-12
    assert np.abs(python[2] - compiled[2]).max() <= 1e-10


BEAD_2D = """
[material.steel]
E = 2.1e14
nu = 0.3
rho = 7800.0
[[body]]
name = "rail"
element = "cable2d"
material = "steel"
section = {height = 0.02, width = 0.02}
elements = 8
start = [0.0, 0.0]
end = [0.8, -0.6]
[[body]]
type = "point_mass"
name = "bead"
mass = 0.5
position = [0.08, -0.06]
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
acceleration = [0.0, -9.81]
[[sensor]]
name = "s"
type = "slide"
constraint = 2
[analysis.dynamic]
t_end = 0.3
step = 1e-3
integrator = "generalized_alpha"
"""


def test_a_2d_point_mass_slides_down_a_stiff_rail_as_on_an_incline():
    """A bead on a sliding joint along a clamped, very stiff cable2d rail at 3-4-5 slope:
    s = s0 + g sin(alpha) t^2 / 2 (sin alpha = 0.6), in both engines."""
    from runtime import run_scene

    for engine in ("python", "compiled"):
        sensors = run_scene(scene_of(BEAD_2D), engine=engine, progress=False).sensors
        exact = 0.1 + 0.5 * G * 0.6 * sensors["t"] ** 2
        assert np.abs(sensors["s"] - exact).max() <= 1e-6, engine


def test_a_hanging_2d_pendulum_statics_and_its_modal_frequency():
    """The bar hanging from its pin: the static solution keeps it there with the pivot
    reaction m g, and its one mode swings at the compound pendulum's sqrt(m g d / I_p)."""
    from runtime.solve.modal import modal_shapes
    from runtime.solve.static import solve_static

    down = 'centre_of_mass = [0.5, 0.0]\nangle = -1.5707963267948966'
    hanging = scene_of(PENDULUM_2D.replace('centre_of_mass = [0.5, 0.0]', down)
                       + '[analysis.static]\n[analysis.modal]\nmodes = 1\nabout = "static"\n')
    model = Model(hanging)
    found = solve_static(model, hanging.static)
    assert np.abs(found.q - model.reference).max() <= 1e-12
    mass = 7800.0 * 1.0 * 0.05 * 0.05
    pivot = mass * (1.0 + 0.05**2) / 12 + mass * 0.5**2
    modes = modal_shapes(model, found.q, 1, found.multipliers)
    assert modes.frequencies == pytest.approx([np.sqrt(mass * G * 0.5 / pivot)], rel=1e-9)
    shape = modes.shapes[0][model.rigid["bar"].dofs]
    assert np.abs(shape[:2]).max() <= 1e-9 * np.abs(shape).max()      # the pin holds
    assert abs(shape[3]) <= 1e-9 * abs(shape[2])       # u = (0, -1) turns along x


def test_vtu_draws_a_2d_rigid_body_as_its_rectangle(tmp_path):
    """The 2D pendulum's VTU files hold the bar as a quad of its box's 1 m x 0.05 m whose
    corners move with the body (r0 + x_1 u + x_2 perp(u), perp(u) = [-u_y, u_x])."""
    import meshio

    from runtime import run_scene
    from runtime.app.shapes import VtkSeries

    scene = scene_of(PENDULUM_2D.replace("t_end = 0.6", "t_end = 0.05"))
    result = run_scene(scene, engine="python", progress=False, store_states=True,
                       observers=[VtkSeries(tmp_path)])
    mesh = meshio.read(tmp_path / "dynamic_000050.vtu")
    quads = [c.data for c in mesh.cells if c.type == "quad"]
    assert len(quads) == 1 and quads[0].shape == (1, 4)
    corners = (mesh.points[quads[0][0]] + mesh.point_data["displacement"][quads[0][0]])
    q = result.states.q[-1]
    origin, u = q[:2], q[2:4]
    local = np.array([[0.0, -0.025], [1.0, -0.025], [1.0, 0.025], [0.0, 0.025]])
    expected = origin + np.outer(local[:, 0], u) + np.outer(local[:, 1], [-u[1], u[0]])
    assert np.abs(corners[:, :2] - expected).max() <= 1e-12
    assert np.abs(corners[:, 2]).max() == 0.0
