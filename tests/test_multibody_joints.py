"""Cylindrical and universal joints of rigid bodies and the prismatic joint between two
bodies (docs/multibody.md): finite differences of their rows, the motions they leave at
the reference, and against closed forms: a body spinning and falling along a cylindrical
joint, a slider driven along a turning arm, a pendulum on a universal joint swinging about
its ground axis at the elliptic-integral period with no rotation about the blocked
direction; both engines."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.special
from test_multibody import G, _finite_difference_check, run, scene_of

from runtime.model.errors import SceneError
from runtime.model.model import Model

TWO_BODIES = """
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
"""

JOINTS = {
    "cylindrical to the ground": ('type = "body_cylindrical"\nbody = "a"\n'
                                  'axis = [0.6, 0.0, 0.8]\n', 4),
    "cylindrical": ('type = "body_cylindrical"\nbody = "a"\nother = "b"\n'
                    'point = [1.0, 0.0, 0.0]\naxis = [0.0, 0.6, 0.8]\n', 4),
    "universal to the ground": ('type = "body_universal"\nbody = "a"\naxis = [0, 0, 1]\n'
                                'other_axis = [1, 0, 0]\n', 4),
    "universal": ('type = "body_universal"\nbody = "a"\nother = "b"\npoint = [1, 0, 0]\n'
                  'axis = [0, 0, 1]\nother_axis = [0.6, 0.8, 0.0]\n', 4),
    "prismatic between bodies": ('type = "body_prismatic"\nbody = "a"\nother = "b"\n'
                                 'axis = [0.0, 0.6, 0.8]\n', 5),
    "driven prismatic between bodies": (
        'type = "body_prismatic"\nbody = "a"\nother = "b"\naxis = [0.0, 0.6, 0.8]\n'
        'displacement = {type = "cosine_ramp", duration = 0.5}\n', 6),
}


@pytest.mark.parametrize("name", JOINTS)
def test_joint_rows_hold_at_the_reference_and_match_finite_differences(name):
    """The rows vanish at t = 0, are independent (rank: 2 x 6 motions less the rows), and
    their Jacobian, geometric stiffness and curvature match central differences."""
    table, rows = JOINTS[name]
    model = Model(scene_of(TWO_BODIES + "[[constraint]]\n" + table))
    assert np.abs(model.holonomic.value(model.reference)).max() <= 1e-15
    jacobian = np.vstack([model.joints.toarray(),
                          model.holonomic.jacobian(model.reference).toarray()])
    assert np.linalg.matrix_rank(jacobian[:, model.free]) == 12 + rows
    rng = np.random.default_rng(5)
    for block in model.holonomic.blocks[2:]:
        _finite_difference_check(block, rng)


@pytest.mark.parametrize("integrator", ["trapezoidal", "generalized_alpha"])
def test_a_body_spins_and_falls_freely_along_a_cylindrical_joint(integrator):
    """The axis vertical, gravity along it: the body falls as g t^2 / 2 and keeps its spin
    omega t, while the joint holds it on the axis; both engines agree."""
    scene = scene_of("""
[[body]]
type = "rigid"
name = "spindle"
mass = 1.5
inertia = [0.02, 0.02, 0.01]
angular_velocity = [0.0, 0.0, 5.0]
[[constraint]]
type = "body_cylindrical"
body = "spindle"
[[load]]
type = "gravity"
acceleration = [0.0, 0.0, -9.81]
[analysis.dynamic]
t_end = 0.5
step = 1e-3
""")
    # full Newton, for equal counters (a kept Jacobian may stop a step one iteration apart
    # in the two engines: tests/scenes_small.py, counts_agree)
    t, q, _, stepper = run(scene, "python", integrator=integrator, newton="full")
    compiled = run(scene, "compiled", integrator=integrator, newton="full")
    assert np.abs(q[:, 2] + G * t**2 / 2).max() <= 1e-12
    assert np.abs(q[:, :2]).max() <= 1e-14
    spin = np.unwrap(np.arctan2(q[:, 4], q[:, 3]))
    assert np.abs(spin - 5.0 * t).max() <= 1e-4              # the O(h^2) of the rotation
    assert np.abs(compiled[1] - q).max() <= 1e-12
    assert compiled[3].counters == stepper.counters


@pytest.mark.parametrize("integrator", ["trapezoidal", "generalized_alpha"])
def test_a_slider_driven_along_a_turning_arm_is_where_the_kinematics_puts_it(integrator):
    """An arm driven about z at 2 rad/s, a slider on a prismatic joint along it driven to
    0.3 m by a cosine ramp: the slider is at R(2 t) (r_0 + d(t) e_x) and keeps the arm's
    orientation; both engines agree."""
    scene = scene_of("""
[[body]]
type = "rigid"
name = "arm"
box = {size = [1.0, 0.05, 0.05]}
density = 2700.0
[[body]]
type = "rigid"
name = "slider"
mass = 0.4
inertia = [0.001, 0.002, 0.002]
position = [0.2, 0.0, 0.0]
[[constraint]]
type = "body_revolute"
body = "arm"
angle = {type = "constant_rate", omega = 2.0}
[[constraint]]
type = "body_prismatic"
body = "slider"
other = "arm"
axis = [1.0, 0.0, 0.0]
displacement = {type = "cosine_ramp", duration = 0.4, value = 0.3}
[analysis.dynamic]
t_end = 0.6
step = 1e-3
""")
    # full Newton, for equal counters (a kept Jacobian may stop a step one iteration apart
    # in the two engines: tests/scenes_small.py, counts_agree)
    t, q, _, stepper = run(scene, "python", integrator=integrator, newton="full")
    compiled = run(scene, "compiled", integrator=integrator, newton="full")
    model = Model(scene)
    slider = model.rigid["slider"].dofs
    d = scene.constraints[1].displacement.sample(t)[0]
    angle = 2.0 * t
    exact = np.stack([(0.2 + d) * np.cos(angle), (0.2 + d) * np.sin(angle),
                      np.zeros_like(t)], axis=1)
    assert np.abs(q[:, slider[:3]] - exact).max() <= 1e-12
    u = q[:, slider[3:6]]
    assert np.abs(u - np.stack([np.cos(angle), np.sin(angle), 0 * t], axis=1)).max() <= 1e-12
    assert np.abs(compiled[1] - q).max() <= 1e-12
    assert compiled[3].counters == stepper.counters


@pytest.mark.parametrize("engine", ["python", "compiled"])
def test_a_pendulum_on_a_universal_joint_swings_about_its_ground_axis(engine):
    """A bar hanging from a universal joint (cross: the bar's axis z, the ground's x),
    released at 90 degrees about the ground axis: it swings as a plane pendulum (the
    elliptic-integral period) and never turns about the blocked direction a x b."""
    scene = scene_of("""
[[body]]
type = "rigid"
name = "bar"
box = {size = [1.0, 0.05, 0.05]}
density = 7800.0
centre_of_mass = [0.5, 0.0, 0.0]
[[constraint]]
type = "body_universal"
body = "bar"
axis = [0.0, 0.0, 1.0]
other_axis = [1.0, 0.0, 0.0]
[[load]]
type = "gravity"
acceleration = [0, -9.81, 0]
[analysis.dynamic]
t_end = 1.2
step = 1e-3
integrator = "trapezoidal"
""")
    t, q, v, _ = run(scene, engine)
    mass, inertia = scene.rigid_bodies[0].mass_properties()
    pivot = inertia[2, 2] + mass * 0.5**2
    period = 4 * np.sqrt(pivot / (mass * G * 0.5)) * scipy.special.ellipk(0.5)
    u_x = q[:, 3]
    k = np.flatnonzero((u_x[:-1] > 0) & (u_x[1:] <= 0))
    down = t[k] + (t[k + 1] - t[k]) * u_x[k] / (u_x[k] - u_x[k + 1])
    assert down[0] == pytest.approx(period / 4, rel=2e-5)
    # the cross row w . e_x = 0 and its rate (omega . (w x e_x) = 0) hold
    w, w_rate = q[:, 9:12], v[:, 9:12]
    assert np.abs(w[:, 0]).max() <= 1e-12 and np.abs(w_rate[:, 0]).max() <= 1e-9
    assert np.abs(q[:, :3]).max() <= 1e-12         # the shared point stays at the pivot
    assert np.abs(q[:, 5]).max() <= 1e-12          # the bar swings in the plane normal to w


@pytest.mark.parametrize("table, culprit", [
    ('type = "body_universal"\nbody = "a"\naxis = [0, 0, 1]\nother_axis = [0, 0.6, 0.8]\n',
     "constraint[0].other_axis"),
    ('type = "body_universal"\nbody = "a"\nother = "a"\n', "constraint[0].other"),
    ('type = "body_cylindrical"\nbody = "dot"\n', "constraint[0].body"),
    ('type = "body_cylindrical"\nbody = "a"\nother = "dot"\n', "constraint[0].other"),
    ('type = "body_cylindrical"\nbody = "a"\naxis = [0, 0, 0]\n', "constraint[0].axis"),
    ('type = "body_prismatic"\nbody = "a"\nother = "dot"\n', "constraint[0].other"),
    ('type = "body_prismatic"\nbody = "a"\nother = "a"\n', "constraint[0].other"),
])
def test_bad_joints_exit_2_naming_the_key(tmp_path, capsys, table, culprit):
    from runtime.cli import main

    text = (TWO_BODIES + '[[body]]\ntype = "point_mass"\nname = "dot"\nmass = 1.0\n'
            'position = [3, 0, 0]\n[analysis.dynamic]\nt_end = 0.1\nstep = 0.01\n'
            "[[constraint]]\n" + table)
    scene = tmp_path / "bad.toml"
    scene.write_text(text)
    assert main(["run", str(scene), "--out", str(tmp_path / "out")]) == 2
    assert culprit in capsys.readouterr().err
    with pytest.raises(SceneError, match=culprit.replace("[", r"\[").replace("]", r"\]")):
        scene_of(text)


def test_new_joints_round_trip_through_toml():
    text = TWO_BODIES + "".join("[[constraint]]\n" + table for table, _ in
                                list(JOINTS.values())[:2])
    scene = scene_of(text)
    assert scene_of(scene.to_toml()) == scene
