"""Multibody models: rigid bodies in natural coordinates, point masses, their joints and the
quadratic constraint rows in both engines and the static analysis (docs/multibody.md).

Checked against what does not share their code: the elliptic-integral period of a physical
pendulum, Euler's equations of a torque-free body (SciPy's ODE solver), conservation of
energy and angular momentum, free fall, finite differences of every constraint Jacobian and
geometric stiffness, the other engine, the same load as a point force."""

from __future__ import annotations

import dataclasses
import tomllib

import numpy as np
import pytest
import scipy.integrate
import scipy.special

from runtime.model.errors import SceneError
from runtime.model.model import Model
from runtime.model.scene import load_scene, parse_scene
from runtime.solve import engines
from runtime.solve.static import solve_static
from scenes import path as scene_path

G = 9.81

PENDULUM = """
[[body]]
type = "rigid"
name = "bar"
box = {size = [1.0, 0.05, 0.05]}
density = 7800.0
centre_of_mass = [0.5, 0.0, 0.0]
[[constraint]]
type = "body_revolute"
body = "bar"
axis = [0, 0, 1]
[[load]]
type = "gravity"
acceleration = [0, -9.81, 0]
[analysis.dynamic]
t_end = 1.5
step = 1e-3
"""


#: a 1 m steel beam3d cantilever of 4 elements, clamped at the origin (TOML)
CANTILEVER = """
[material.steel]
E = 2.1e11
nu = 0.0
rho = 7800.0
[[body]]
name = "beam"
element = "beam3d"
material = "steel"
section = {height = 0.02, width = 0.02}
elements = 4
start = [0, 0, 0]
end = [1, 0, 0]
[[constraint]]
type = "clamp"
node = "beam:0"
"""
GRAVITY = '[[load]]\ntype = "gravity"\nacceleration = [0, -9.81, 0]\n'


def scene_of(text: str):
    return parse_scene(tomllib.loads(text))


def run(scene, engine: str = "python", **settings):
    """(times (k,), q (k, size), v (k, size), engine) of a dynamic run of ``scene``."""
    dynamic = dataclasses.replace(scene.dynamic, **settings)
    model = Model(scene)
    stepper = engines.make(engine, model, dynamic, model.reference.copy())
    out = []
    stepper.run(dynamic.t_end, dynamic.step,
                lambda t, q, v: out.append((t, q.copy(), v.copy())))
    return (np.array([o[0] for o in out]), np.array([o[1] for o in out]),
            np.array([o[2] for o in out]), stepper)


def slider_position(phi: np.ndarray, crank: float = 0.15, rod: float = 0.5) -> np.ndarray:
    """The slider's x (m) of the rigid slider-crank (crank radius ``crank``, rod length
    ``rod``, m; the slider on the x axis through the crank's pivot) at the crank angle phi
    (rad): r cos(phi) + sqrt(L^2 - r^2 sin^2(phi))."""
    return crank * np.cos(phi) + np.sqrt(rod**2 - (crank * np.sin(phi)) ** 2)


def crossings(t: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Times where x changes sign from + to - (linear interpolation)."""
    k = np.flatnonzero((x[:-1] > 0) & (x[1:] <= 0))
    return t[k] + (t[k + 1] - t[k]) * x[k] / (x[k] - x[k + 1])


@pytest.mark.parametrize("integrator", ["trapezoidal", "generalized_alpha"])
def test_rigid_pendulum_period_is_the_elliptic_integral_one(integrator):
    """A box pinned at one end, released horizontally (amplitude 90 degrees): its axis
    passes the vertical at T/4 and 5T/4 with T = 4 sqrt(I_p / (m g d)) K(sin^2 45 deg)."""
    scene = scene_of(PENDULUM)
    t, q, _, stepper = run(scene, integrator=integrator, newton="full")
    mass, inertia = scene.rigid_bodies[0].mass_properties()
    pivot_inertia = inertia[2, 2] + mass * 0.5**2
    period = 4 * np.sqrt(pivot_inertia / (mass * G * 0.5)) * scipy.special.ellipk(0.5)
    down = crossings(t, q[:, 3])          # u_x: the bar's axis through the vertical
    assert down[0] == pytest.approx(period / 4, rel=2e-5)
    t, q, _, _ = run(scene, integrator=integrator, t_end=2.5, newton="full")
    down = crossings(t, q[:, 3])
    assert down[1] - down[0] == pytest.approx(period, rel=1e-5)
    # the quadratic rows converge quadratically (full Newton): a few iterations per step
    assert stepper.counters.newton_iterations <= 2.5 * stepper.counters.steps


@pytest.mark.parametrize("integrator", ["trapezoidal", "generalized_alpha"])
def test_constraint_drift_stays_below_the_tolerance_over_a_long_run(integrator):
    scene = scene_of(PENDULUM)
    _, q, v, stepper = run(scene, integrator=integrator, t_end=6.0, step=2e-3)
    model = Model(scene)
    drift = max(np.abs(model.holonomic.value(x)).max() for x in q)
    assert drift <= scene.dynamic.tolerance
    velocity = max(np.abs(model.holonomic.jacobian(x) @ y).max() for x, y in
                   zip(q, v, strict=True))
    if integrator == "trapezoidal":      # projected onto Phi_q v = 0 as well
        assert velocity <= 1e-9


def _body_rates(q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Angular velocities in body axes (k, 3) from natural coordinates: R^T dR/dt."""
    rot = q[:, 3:12].reshape(-1, 3, 3).transpose(0, 2, 1)      # columns u, v, w
    rate = v[:, 3:12].reshape(-1, 3, 3).transpose(0, 2, 1)
    skew = np.einsum("kji,kjl->kil", rot, rate)
    return np.stack([skew[:, 2, 1], skew[:, 0, 2], skew[:, 1, 0]], axis=1)


def test_torque_free_asymmetric_body_follows_eulers_equations():
    """A box spinning near its intermediate axis tumbles; its body rates follow Euler's
    equations (SciPy, to 1e-11), its energy and angular momentum (from R I R^T omega, not
    the mass matrix) are conserved."""
    omega0 = np.array([0.05, 4.0, 0.02])
    scene = scene_of(f"""
[[body]]
type = "rigid"
name = "box"
box = {{size = [0.3, 0.2, 0.1]}}
density = 1000.0
position = [1.0, 2.0, 3.0]
velocity = [0.1, -0.2, 0.3]
angular_velocity = {omega0.tolist()}
[analysis.dynamic]
t_end = 3.0
step = 1e-3
""")
    # full Newton: a kept Jacobian stops at the tolerance, and its bias of 1e-10 per step
    # adds up to 1.2e-4 of the energy over these 3000 steps (2e-7 at tolerance 1e-12)
    t, q, v, _ = run(scene, integrator="trapezoidal")
    _, inertia = scene.rigid_bodies[0].mass_properties()
    moments = np.diag(inertia)

    def euler(_, w):
        a, b, c = moments
        return [(b - c) / a * w[1] * w[2], (c - a) / b * w[2] * w[0],
                (a - b) / c * w[0] * w[1]]

    exact = scipy.integrate.solve_ivp(euler, (0, t[-1]), omega0, t_eval=t, rtol=1e-11,
                                      atol=1e-12).y.T
    rates = _body_rates(q, v)
    assert np.abs(rates[:, 0]).max() > 1.0          # it tumbles
    assert np.abs(rates - exact).max() <= 2e-3 * np.abs(omega0).max()
    energy = 0.5 * np.einsum("ki,i,ki->k", rates, moments, rates)
    assert np.ptp(energy) <= 1e-6 * energy[0]
    rot = q[:, 3:12].reshape(-1, 3, 3).transpose(0, 2, 1)
    momentum = np.einsum("kij,j,kj->ki", rot, moments, rates)
    assert np.abs(momentum - momentum[0]).max() <= 1e-6 * np.linalg.norm(momentum[0])
    # the centre of mass moves uniformly
    assert np.abs(q[:, :3] - (np.array([1.0, 2.0, 3.0]) + np.outer(t, [0.1, -0.2, 0.3]))
                  ).max() <= 1e-9


def test_a_particle_falls_freely():
    scene = scene_of("""
[[body]]
type = "point_mass"
name = "ball"
mass = 2.0
position = [0.0, 0.0, 1.0]
velocity = [1.0, 0.0, 0.0]
[[load]]
type = "gravity"
acceleration = [0, 0, -9.81]
[[sensor]]
name = "z"
type = "body_position"
body = "ball"
component = "z"
[analysis.dynamic]
t_end = 0.5
step = 1e-2
""")
    t, q, _, _ = run(scene)
    assert np.allclose(q[:, 2], 1.0 - G * t**2 / 2, atol=1e-12)
    assert np.allclose(q[:, 0], t, atol=1e-12)


def _finite_difference_check(block, rng):
    """Phi_q against central differences of Phi, the geometric stiffness against those of
    Phi_q^T lambda, and v^T H v against the difference of Phi_q v along v."""
    x = rng.normal(size=block.dofs.size)
    lam = rng.normal(size=block.rows)
    step = 1e-6
    identity = np.eye(x.size)
    numeric = np.array([(block.value(x + step * e) - block.value(x - step * e)) / (2 * step)
                        for e in identity]).T
    assert np.abs(block.jacobian(x) - numeric).max() <= 1e-8
    stiffness = np.tensordot(lam, block.hessian(x), 1)
    numeric = np.array([(block.jacobian(x + step * e).T @ lam - block.jacobian(x - step * e).T
                         @ lam) / (2 * step) for e in identity]).T
    assert np.abs(stiffness - numeric).max() <= 1e-8
    velocity = rng.normal(size=x.size)
    numeric = (block.jacobian(x + step * velocity) @ velocity
               - block.jacobian(x - step * velocity) @ velocity) / (2 * step)
    assert np.abs(block.curvature(x, velocity) - numeric).max() <= 1e-8


def test_every_constraint_jacobian_matches_finite_differences():
    """The rigid body's six rows, the revolute joint to the ground (linear rows with a
    constant), to a beam node and between two bodies (bilinear rows)."""
    scene = load_scene(scene_path("double_pendulum"))
    extra = scene_of("""
[[body]]
type = "rigid"
name = "a"
mass = 1.0
inertia = [0.1, 0.2, 0.25]
[[body]]
type = "rigid"
name = "b"
mass = 2.0
inertia = [[0.3, 0.01, 0.0], [0.01, 0.2, 0.0], [0.0, 0.0, 0.4]]
position = [1.0, 0.0, 0.0]
rotation = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
[[constraint]]
type = "body_revolute"
body = "a"
point = [1.0, 0.0, 0.0]
other = "b"
axis = [0.6, 0.0, 0.8]
[[constraint]]
type = "body_spherical"
body = "a"
""")
    rng = np.random.default_rng(17)
    blocks = Model(scene).holonomic.blocks + Model(extra).holonomic.blocks
    owners = [block.owner for block in blocks]
    assert len(blocks) == 7 and "body_revolute of a" in owners
    for block in blocks:
        _finite_difference_check(block, rng)


def test_joints_hold_at_the_initial_pose():
    """Every constraint row vanishes at t = 0 (the joined points coincide, the axes align),
    and the two-body revolute leaves exactly one relative rotation: 2 x 6 free motions
    less 5 rows, at the reference."""
    extra = scene_of("""
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
[[constraint]]
type = "body_revolute"
body = "a"
point = [1.0, 0.0, 0.0]
other = "b"
axis = [0.6, 0.0, 0.8]
""")
    model = Model(extra)
    assert np.abs(model.holonomic.value(model.reference)).max() == 0.0
    assert np.abs(model.joints @ model.reference).max() <= 1e-15
    jacobian = np.vstack([model.joints.toarray(),
                          model.holonomic.jacobian(model.reference).toarray()])
    assert 24 - np.linalg.matrix_rank(jacobian) == 7


@pytest.mark.parametrize("integrator", ["trapezoidal", "generalized_alpha"])
def test_engines_agree_on_the_double_pendulum(integrator):
    scene = load_scene(scene_path("double_pendulum"))
    # full Newton, for equal counters (a kept Jacobian may stop a step one iteration apart
    # in the two engines: tests/scenes_small.py, counts_agree)
    python = run(scene, "python", integrator=integrator, t_end=0.1, newton="full")
    compiled = run(scene, "compiled", integrator=integrator, t_end=0.1, newton="full")
    assert np.abs(python[1] - compiled[1]).max() <= 1e-10
    assert np.abs(python[2] - compiled[2]).max() <= 1e-8
    assert python[3].counters == compiled[3].counters


def test_static_rigid_body_on_a_cantilever_weighs_as_a_point_force():
    """A rigid body hanging from a cantilever's tip by a revolute joint (held about its
    axis by gravity alone: the constraints' geometric stiffness) bends the beam as its
    weight m g at the tip does."""
    beam = CANTILEVER + "[analysis.static]\n"
    hanging = scene_of(beam + """
[[body]]
type = "rigid"
name = "weight"
mass = 5.0
inertia = [0.01, 0.01, 0.01]
centre_of_mass = [0.0, -0.2, 0.0]
position = [1, 0, 0]
[[constraint]]
type = "body_revolute"
body = "weight"
node = "beam:-1"
axis = [0, 0, 1]
[[load]]
type = "body_force"
body = "weight"
point = [0.0, -0.2, 0.0]
force = [0, -49.05, 0]
""")
    loaded = scene_of(beam + """
[[load]]
type = "point_force"
node = "beam:-1"
force = [0, -49.05, 0]
""")
    results = []
    for scene in (hanging, loaded):
        model = Model(scene)
        results.append((model, solve_static(model, scene.static)))
    (model, hung), (_, point) = results
    tip = model.node_dofs(model.node_index(scene.constraints[0].node) + 4, "r")
    assert abs(point.q[tip[1]]) > 1e-4
    assert hung.q[tip] == pytest.approx(point.q[tip], rel=1e-9, abs=1e-12)
    # a rigid body's coordinates have no stiffness for the compiled step's Schur
    # complement: the static solve is the Python one with either engine
    assert engines.static_newton("compiled", model, hanging.static, "trapezoidal") is None


@pytest.mark.parametrize("table, culprit", [
    ('mass = -1.0\ninertia = [1, 1, 1]', "body[0].mass: expected a positive number"),
    ('mass = 1.0\ninertia = [1, 1, -1]', "body[0].inertia: expected a positive definite"),
    ('mass = 1.0\ninertia = [1, 1, 3]', "body[0].inertia: principal moments"),
    ('mass = 1.0\ninertia = [[1, 0.5, 0], [0, 1, 0], [0, 0, 1]]',
     "body[0].inertia: expected a symmetric"),
    ('mass = 1.0\ninertia = [1, 1, 1]\nrotation = [[1, 0, 0], [0, 1, 0.1], [0, 0, 1]]',
     "body[0].rotation: expected a rotation matrix"),
    ('mass = 1.0\ninertia = [1, 1, 1]\nrotation = [[1, 0, 0], [0, 1, 0], [0, 0, -1]]',
     "body[0].rotation: expected a rotation matrix"),
    ('mass = 1.0', "body[0].inertia: missing required key"),
    ('box = {size = [1, 1, 1]}\nmass = 1.0', "body[0].mass: a box takes a density"),
    ('box = {size = [1, -1, 1]}\ndensity = 1.0', "body[0].box.size: expected positive"),
])
def test_bad_rigid_bodies_name_the_key(table, culprit):
    with pytest.raises(SceneError, match=culprit.replace("[", r"\[")):
        scene_of(f'[[body]]\ntype = "rigid"\nname = "b"\n{table}\n')


def test_bad_joint_points_and_names_are_scene_errors():
    head = '[[body]]\ntype = "rigid"\nname = "b"\nmass = 1.0\ninertia = [1, 1, 1]\n'
    with pytest.raises(SceneError, match=r"constraint\[0\].body: expected the name of a rigid"):
        scene_of(head + '[[constraint]]\ntype = "body_spherical"\nbody = "nope"\n')
    with pytest.raises(SceneError, match=r"constraint\[0\].point: the joined points must"):
        scene_of(head + '[[body]]\ntype = "point_mass"\nname = "p"\nmass = 1.0\n'
                 'position = [1, 0, 0]\n[[constraint]]\ntype = "body_spherical"\n'
                 'body = "b"\nother = "p"\n')


def test_bad_rigid_body_exits_2_from_the_cli(tmp_path, capsys):
    from runtime.cli import main

    scene = tmp_path / "bad.toml"
    scene.write_text('[[body]]\ntype = "rigid"\nname = "b"\nmass = -2.0\n'
                     'inertia = [1, 1, 1]\n')
    assert main(["run", str(scene), "--out", str(tmp_path / "out")]) == 2
    assert "body[0].mass" in capsys.readouterr().err


def test_rigid_scene_round_trips_through_toml():
    scene = load_scene(scene_path("double_pendulum"))
    again = parse_scene(tomllib.loads(scene.to_toml()))
    assert again == scene


SPRING = """
[[body]]
type = "point_mass"
name = "ball"
mass = 2.0
position = [0.0, 0.0, -1.0]
[[body]]
type = "rigid"
name = "plate"
mass = 3.0
inertia = [0.2, 0.3, 0.4]
position = [1.0, 0.0, 0.0]
angular_velocity = [0.0, 0.0, 0.5]
[[load]]
type = "spring_damper"
end_a = [0.0, 0.0, 0.0]
end_b = {body = "ball"}
stiffness = 800.0
length = 0.9
[[load]]
type = "spring_damper"
end_a = {body = "ball"}
end_b = {body = "plate", point = [0.1, 0.2, -0.3]}
stiffness = 50.0
damping = 3.0
[analysis.dynamic]
t_end = 1.0
step = 1e-3
"""


def test_spring_damper_jacobians_match_finite_differences():
    check_state_force_jacobians(scene_of(SPRING))


def check_state_force_jacobians(scene) -> None:
    """d force / d q and d force / d v of every state load of ``scene`` against central
    differences at a random state near the reference."""
    model = Model(scene)
    rng = np.random.default_rng(5)
    for load in scene.loads:
        element = load.state_force(model)
        dofs = element.dofs[0]
        q = model.reference + 0.05 * rng.normal(size=model.size)
        v = rng.normal(size=model.size)
        patches = element(q, True, v)
        step = 1e-6
        for derivative, moved in ((patches.jacobian[0], "q"), (patches.jacobian_dot[0], "v")):
            numeric = np.zeros_like(derivative)
            for j, dof in enumerate(dofs):
                plus, minus = (q.copy(), v.copy()), (q.copy(), v.copy())
                which = 0 if moved == "q" else 1
                plus[which][dof] += step
                minus[which][dof] -= step
                numeric[:, j] = (element(*plus[:1], False, plus[1]).force[0]
                                 - element(*minus[:1], False, minus[1]).force[0]) / (2 * step)
            assert np.abs(derivative - numeric).max() <= 1e-6 * max(1.0, np.abs(numeric).max())


def test_a_mass_on_a_spring_oscillates_at_sqrt_k_over_m():
    """The ball hangs 0.1 m below the spring's rest length (no gravity): it oscillates
    along z at omega = sqrt(k / m) about z = -0.9 (the second spring is removed); both
    engines agree."""
    scene = scene_of(SPRING.split("[[load]]\ntype = \"spring_damper\"\nend_a = {body")[0]
                     + "[analysis.dynamic]\nt_end = 1.0\nstep = 1e-3\n")
    t, q, _, _ = run(scene, integrator="trapezoidal")
    z = q[:, 2]
    exact = -0.9 - 0.1 * np.cos(np.sqrt(800.0 / 2.0) * t)
    assert np.abs(z - exact).max() <= 1e-4
    compiled = run(scene, "compiled", integrator="trapezoidal")
    assert np.abs(compiled[1] - q).max() <= 1e-12


@pytest.mark.parametrize("integrator", ["trapezoidal", "generalized_alpha"])
def test_engines_agree_on_springs_between_a_particle_and_a_spinning_body(integrator):
    # full Newton, for equal counters: with a kept Jacobian a step whose error estimate
    # ends within round-off of the tolerance stops one iteration apart in the two engines
    # (generalized-alpha: at 0.995 of it in step 143, 1641 against 1642 iterations)
    scene = scene_of(SPRING)
    python = run(scene, "python", integrator=integrator, t_end=0.3, newton="full")
    compiled = run(scene, "compiled", integrator=integrator, t_end=0.3, newton="full")
    assert np.abs(python[1] - compiled[1]).max() <= 1e-12
    assert np.abs(python[2] - compiled[2]).max() <= 1e-10
    assert python[3].counters == compiled[3].counters


def test_python_api_builds_the_same_scene_as_toml():
    from runtime import (
        BodyPosition,
        BodyRevolute,
        Dynamic,
        Gravity,
        RigidBody,
        Scene,
        SpringDamper,
    )
    from runtime.model.items.loads import End

    scene = Scene(materials={}, bodies=(),
                  rigid_bodies=[RigidBody("bar", box={"size": [1.0, 0.05, 0.05]},
                                          density=7800.0, centre_of_mass=(0.5, 0.0, 0.0))],
                  constraints=[BodyRevolute(body="bar", axis=(0, 0, 1))],
                  loads=[Gravity((0, -9.81, 0)),
                         SpringDamper(End(body="bar", point=(1.0, 0.0, 0.0)),
                                      End(anchor=(1.0, 1.0, 0.0)), 10.0)],
                  sensors=[BodyPosition("tip_y", body="bar", component="y",
                                        point=(1.0, 0.0, 0.0))],
                  dynamic=Dynamic(t_end=1.5, step=1e-3))
    assert parse_scene(tomllib.loads(scene.to_toml())) == scene
    with pytest.raises(SceneError, match=r"body\[0\].mass: expected a positive number"):
        Scene(materials={}, bodies=(), rigid_bodies=[RigidBody("b", mass=-1.0,
                                                               inertia=(1, 1, 1))])


def test_static_analysis_of_a_free_rigid_body_names_it():
    from runtime.solve.static import FreeMechanismError

    scene = scene_of('[[body]]\ntype = "rigid"\nname = "loose"\nmass = 1.0\n'
                     'inertia = [1, 1, 1]\n[[load]]\ntype = "gravity"\n'
                     'acceleration = [0, 0, -9.81]\n[analysis.static]\n')
    with pytest.raises(FreeMechanismError, match="rigid body 'loose' is free to move"):
        solve_static(Model(scene), scene.static)


def test_pivot_reaction_of_the_pendulum_is_the_closed_form_one():
    """The pivot's force on the released bar, from the multipliers, against m (a_c - g)
    with the rigid pendulum's closed form a_c (tangential d alpha, centripetal d omega^2),
    at t = 0 and after 0.3 s (angle and angular velocity of the run's state); zero moment
    about the pivot's axis."""
    from runtime import run_scene

    text = PENDULUM.replace("t_end = 1.5", "t_end = 0.3") + "".join(
        f'[[sensor]]\nname = "{name}"\ntype = "body_reaction"\nbody = "bar"\n'
        f'component = "{component}"\nquantity = "{quantity}"\nconstraint = 0\n'
        for name, component, quantity in (("rx", "x", "force"), ("ry", "y", "force"),
                                          ("mz", "z", "moment")))
    scene = scene_of(text)
    result = run_scene(scene, engine="python", progress=False, store_states=True)
    mass, inertia = scene.rigid_bodies[0].mass_properties()
    d = 0.5
    pivot = inertia[2, 2] + mass * d * d
    for row in (0, -1):
        u, rate = result.states.q[row, 3:6], result.states.v[row, 3:6]
        theta = np.arctan2(-u[1], u[0])                 # below the horizontal
        omega2 = (u[0] * rate[1] - u[1] * rate[0]) ** 2
        alpha = mass * G * d * np.cos(theta) / pivot
        radial, tangent = -u[:2], np.array([-u[1], u[0]]) * -1.0
        accel = d * omega2 * radial + d * alpha * tangent
        expected = mass * (accel - np.array([0.0, -G]))
        got = np.array([result.sensors["rx"][row], result.sensors["ry"][row]])
        assert got == pytest.approx(expected, rel=1e-9, abs=1e-9 * mass * G)
        assert abs(result.sensors["mz"][row]) <= 1e-9 * mass * G
    assert theta > 0.3
    with pytest.raises(SceneError, match=r"sensor\[0\].constraint: expected the index"):
        scene_of(PENDULUM + '[[sensor]]\nname = "r"\ntype = "body_reaction"\nbody = "bar"\n'
                 'constraint = 3\n')
    # a point mass has no frame to react on: a scene error, not a failure during the run
    with pytest.raises(SceneError, match=r"^sensor\[0\].body: a body_reaction reads a rigid "
                                         r"body .*the point mass \"dot\""):
        scene_of(PENDULUM + '[[body]]\ntype = "point_mass"\nname = "dot"\nmass = 1.0\n'
                 'position = [2, 0, 0]\n[[sensor]]\nname = "r"\ntype = "body_reaction"\n'
                 'body = "dot"\n')


def test_slider_crank_with_a_stiff_rod_follows_the_rigid_position_formula():
    """scenes/slider_crank.toml with the rod 100 times stiffer, over two revolutions of the
    driven crank: the crank is at phi = 60 deg + 10 t (the drive's law) and the slider at
    x = r cos(phi) + sqrt(L^2 - r^2 sin^2(phi)) to 1e-5 of the crank length r (the rod's own
    stretch, F L / EA with the pivot force below 30 N, is 2e-8 m, 1e-7 r)."""
    scene = load_scene(scene_path("slider_crank"))
    stiff = dataclasses.replace(scene.materials["aluminium"], E=7.0e12)
    scene = dataclasses.replace(scene, materials={"aluminium": stiff})
    t, q, _, _ = run(scene, "compiled", t_end=1.26)
    model = Model(scene)
    crank = model.rigid["crank"].dofs
    slider = model.rigid["slider"].dofs
    phi = np.unwrap(np.arctan2(q[:, crank[4]], q[:, crank[3]]))
    assert np.abs(phi - (np.pi / 3 + 10.0 * t)).max() <= 1e-12
    assert phi[-1] - phi[0] > 4 * np.pi                   # two revolutions
    r = 0.15
    assert np.abs(q[:, slider[0]] - slider_position(phi, r)).max() <= 1e-5 * r
    assert np.abs(q[:, slider[1:]]).max() <= 1e-12      # on the prismatic axis


def test_the_drive_of_the_slider_crank_puts_in_the_energy_the_mechanism_gains():
    """scenes/slider_crank.toml: the work of the drive torque (its multiplier, read by the
    drive_torque sensor), int T omega dt, equals the change of the total energy (kinetic
    and strain) over the run, to the trapezoidal rule's error on the outputs."""
    from runtime import run_scene

    scene = load_scene(scene_path("slider_crank"))
    result = run_scene(scene, engine="compiled", progress=False)
    t = np.asarray(result.sensors["t"])
    torque = np.asarray(result.sensors["drive_torque"])
    energy = np.asarray(result.sensors["total_energy"])
    work = np.concatenate([[0.0], np.cumsum(np.diff(t) * 10.0 * (torque[1:] + torque[:-1])
                                             / 2)])
    assert np.abs(torque).max() > 1.0                    # the drive does work both ways
    assert np.abs(energy - energy[0] - work).max() <= 1e-4 * np.ptp(work)


def test_undamped_springs_conserve_energy_and_the_damper_dissipates():
    """The ball and the spinning plate on springs (SPRING, the damper set to zero): the
    total energy (kinetic + spring energy) stays within 1e-5 of its start over 1 s; with the
    damper it falls."""
    from runtime.model.items.sensors import Samples, TotalEnergy

    undamped = scene_of(SPRING.replace("damping = 3.0", "damping = 0.0"))
    damped = scene_of(SPRING)
    energies = []
    for scene in (undamped, damped):
        t, q, v, _ = run(scene, integrator="trapezoidal")
        model = Model(scene)
        energies.append(TotalEnergy("e").values(model, Samples(t, q, v, np.zeros(t.size))))
    assert np.ptp(energies[0]) <= 1e-5 * energies[0][0]
    assert energies[0].min() > 0.05 * energies[0][0]           # springs hold energy
    assert energies[1][-1] < 0.9 * energies[1][0]


def test_a_point_mass_on_a_node_weighs_as_its_point_force():
    """A 3 kg mass on a cantilever's tip under gravity bends it as 3 g N at the tip does
    (the beam's own weight in both), and adds 3 kg to the model's translational mass."""
    beam = CANTILEVER + GRAVITY + "[analysis.static]\n"
    with_mass = scene_of(beam + '[[body]]\ntype = "point_mass"\nname = "m"\nmass = 3.0\n'
                         'node = "beam:-1"\n')
    with_force = scene_of(beam + '[[load]]\ntype = "point_force"\nnode = "beam:-1"\n'
                          'force = [0, -29.43, 0]\n')
    a, b = Model(with_mass), Model(with_force)
    translation = a.rigid_field(translation=(0.0, 1.0, 0.0))
    assert translation @ (a.mass @ translation) - translation @ (b.mass @ translation) == \
        pytest.approx(3.0, rel=1e-12)
    qa = solve_static(a, with_mass.static).q
    qb = solve_static(b, with_force.static).q
    assert np.abs(qa - qb).max() <= 1e-12 * np.abs(qb).max() + 1e-15


def test_a_redundant_joint_is_named_when_the_model_is_built():
    text = PENDULUM + ('[[constraint]]\ntype = "body_spherical"\nbody = "bar"\n'
                       'point = [0.0, 0.0, 0.0]\n')
    with pytest.raises(SceneError, match=r"^constraint\[1\]: redundant: a row of this "
                                         r"body_spherical joint"):
        Model(scene_of(text))
    Model(scene_of(PENDULUM))           # the pendulum's own joint is not


def test_compiled_static_takes_quadratic_rows_on_nodes():
    """A cantilever whose tip (a point mass on it) slides along x on a body_prismatic
    roller: a propped cantilever.  Under a uniform load w its root moment is w L^2 / 8
    (beam theory, to the shear and discretisation error of 8 elements), and the compiled
    static step (the rows in C, no rigid coordinates) finds the Python equilibrium."""
    scene = scene_of("""
[material.steel]
E = 2.1e11
nu = 0.0
rho = 7800.0
[[body]]
name = "beam"
element = "beam3d"
material = "steel"
section = {height = 0.02, width = 0.02}
elements = 8
start = [0, 0, 0]
end = [1, 0, 0]
[[body]]
type = "point_mass"
name = "tip"
mass = 1.0
node = "beam:-1"
[[constraint]]
type = "clamp"
node = "beam:0"
[[constraint]]
type = "body_prismatic"
body = "tip"
axis = [1, 0, 0]
[[load]]
type = "distributed_force"
body = "beam"
force_per_length = [0, -1000.0, 0]
[[sensor]]
name = "root_moment"
type = "reaction"
node = "beam:0"
quantity = "moment"
component = "z"
[analysis.static]
""")
    model = Model(scene)
    python = solve_static(model, scene.static)
    compiled = solve_static(model, scene.static, engines.static_newton(
        "compiled", model, scene.static, "generalized_alpha"))
    assert np.abs(compiled.q - python.q).max() <= 1e-12
    tip = model.node_dofs(model.node_index(scene.constraints[0].node) + 8, "r")
    assert abs(python.q[tip[1]]) <= 1e-12
    from runtime import run_scene

    moment = run_scene(scene, engine="python", progress=False).summary["static"]["sensors"][
        "root_moment"]
    assert moment == pytest.approx(1000.0 / 8, rel=2e-2)


def test_inconsistent_initial_velocities_are_projected_onto_the_joints():
    """The pendulum given a spin about x, which its revolute joint forbids, starts with the
    spin removed (mass-orthogonally): the joint's velocity rows hold at t = 0 (and at every
    step of the trapezoidal scheme, which projects them), in both engines alike."""
    scene = scene_of(PENDULUM.replace('centre_of_mass = [0.5, 0.0, 0.0]',
                                      'centre_of_mass = [0.5, 0.0, 0.0]\n'
                                      'angular_velocity = [3.0, 0.0, 2.0]'))
    model = Model(scene)
    _, q, v, _ = run(scene, integrator="trapezoidal", t_end=0.05)
    for x, y in zip(q, v, strict=True):
        assert np.abs(model.holonomic.jacobian(x) @ y).max() <= 1e-9
    t, q, v, _ = run(scene, integrator="generalized_alpha", t_end=0.05)
    assert np.abs(model.holonomic.jacobian(q[0]) @ v[0]).max() <= 1e-12
    assert v[0, 9:12] == pytest.approx([0.0, 0.0, 0.0], abs=1e-12)     # w stays z
    assert np.cross([0, 0, 1], q[0, 3:6]) * 2.0 == pytest.approx(v[0, 3:6], abs=1e-12)
    compiled = run(scene, "compiled", integrator="generalized_alpha", t_end=0.05)
    assert np.abs(compiled[2] - v).max() <= 1e-9


def test_vtu_draws_a_rigid_body_as_its_box(tmp_path):
    """The double pendulum's VTU files hold the rigid link as a hexahedron of its box whose
    corners move with the body (origin r0 plus the corners' body coordinates on u, v, w)."""
    import meshio

    from runtime.app.shapes import VtkSeries

    scene = load_scene(scene_path("double_pendulum"))
    scene = dataclasses.replace(scene, dynamic=dataclasses.replace(scene.dynamic,
                                                                   t_end=0.05))
    from runtime import run_scene

    series = VtkSeries(tmp_path)
    result = run_scene(scene, engine="python", progress=False, store_states=True,
                       observers=[series])
    mesh = meshio.read(tmp_path / "dynamic_000100.vtu")
    boxes = [c.data for c in mesh.cells if c.type == "hexahedron"]
    assert len(boxes) == 1 and boxes[0].shape == (1, 8)
    corners = mesh.points[boxes[0][0]] + mesh.point_data["displacement"][boxes[0][0]]
    q = result.states.q[-1]
    link = result.model.rigid["link"]
    origin, axes = q[link.dofs[:3]], q[link.dofs[3:]].reshape(3, 3)
    local = link.item.extent()
    assert np.abs(corners - (origin + local @ axes)).max() <= 1e-12
    assert np.ptp(local[:, 0]) == pytest.approx(0.5)


HUB = """
[material.steel]
E = 2.1e13
nu = 0.0
rho = 7800.0
[[body]]
name = "beam"
element = "beam3d"
material = "steel"
section = {height = 0.02, width = 0.02}
elements = 4
start = [0.1, 0, 0]
end = [1.1, 0, 0]
[[body]]
type = "rigid"
name = "hub"
cylinder = {radius = 0.1, length = 0.05}
density = 7800.0
rotation = [[0.6, -0.8, 0.0], [0.8, 0.6, 0.0], [0.0, 0.0, 1.0]]
[[constraint]]
type = "body_revolute"
body = "hub"
[[constraint]]
type = "body_weld"
body = "hub"
point = [0.1, 0, 0]
node = "beam:0"
[[load]]
type = "body_torque"
body = "hub"
torque = 5.0
[analysis.dynamic]
t_end = 0.3
step = 2.5e-4
integrator = "trapezoidal"
"""


def _hub_scene():
    """HUB with the beam placed along the hub's rotated x axis (the weld's node at the hub
    point (0.1, 0, 0) of the turned hub)."""
    c, s = 0.6, 0.8
    return scene_of(HUB.replace("start = [0.1, 0, 0]", f"start = [{0.1 * c}, {0.1 * s}, 0]")
                    .replace("end = [1.1, 0, 0]", f"end = [{1.1 * c}, {1.1 * s}, 0]"))


def test_body_torque_jacobian_matches_finite_differences():
    scene = _hub_scene()
    model = Model(scene)
    element = scene.loads[0].state_force(model)
    rng = np.random.default_rng(3)
    q = model.reference + 0.1 * rng.normal(size=model.size)
    dofs = element.dofs[0]
    analytic = element(q, True).jacobian[0]
    numeric = np.zeros_like(analytic)
    for j, dof in enumerate(dofs):
        plus, minus = q.copy(), q.copy()
        plus[dof] += 1e-6
        minus[dof] -= 1e-6
        numeric[:, j] = (element(plus, False).force[0] - element(minus, False).force[0]) / 2e-6
    assert np.abs(analytic - numeric).max() <= 1e-8
    # on an orthonormal frame its virtual work is M . d theta: sum_a u_a x Q_a = T w
    force = element(model.reference, False).force[0]
    axes = model.reference[dofs[3:]].reshape(3, 3)
    moment = sum(np.cross(axes[a], force[3 + 3 * a:6 + 3 * a]) for a in range(3))
    assert moment == pytest.approx([0.0, 0.0, 5.0], abs=1e-14)


def test_a_torque_spins_a_welded_hub_and_beam_up_as_a_rigid_body():
    """A constant torque on a hub welded to a very stiff beam: theta = T t^2 / (2 I) with
    I the hub's and the beam's inertia about the axis, to the elastic vibration the torque
    step starts (the hub turns ahead of the beam at first: 5.5e-6 rad, 3.5e-5 of the final
    angle; the strain energy is 1e-5 of the kinetic), and the work T theta equals kinetic
    plus strain energy (6e-8 at this step); both engines agree."""
    scene = _hub_scene()
    t, q, v, _ = run(scene, "compiled")
    model = Model(scene)
    hub = model.rigid["hub"].dofs
    theta = np.unwrap(np.arctan2(q[:, hub[4]], q[:, hub[3]])) - np.arctan2(0.8, 0.6)
    _, inertia = scene.rigid_bodies[0].mass_properties()
    beam = 7800 * 0.02 * 0.02 * 1.0
    total = inertia[2, 2] + beam * ((1.1**3 - 0.1**3) / 3 + 0.02**2 / 12)
    exact = 5.0 * t**2 / (2 * total)
    assert np.abs(theta - exact).max() <= 5e-5 * exact[-1]
    kinetic = np.array([model.kinetic_energy(x) for x in v])
    balance = kinetic + model.strain_energy(q) - 5.0 * theta
    assert np.abs(balance).max() <= 2e-7 * kinetic[-1]
    python = run(scene, "python", t_end=0.02)
    assert np.abs(python[1] - q[:python[1].shape[0]]).max() <= 1e-12


TWO_BEAMS = """
[material.m]
E = 7.0e10
nu = 0.0
rho = 2700.0
[[body]]
name = "a"
element = "beam3d"
material = "m"
section = {height = 0.02, width = 0.02}
elements = 2
start = [0, 0, 0]
end = [0.5, 0, 0]
[[body]]
name = "b"
element = "beam3d"
material = "m"
section = {height = 0.02, width = 0.02}
elements = 2
start = [0.5, 0, 0]
end = [1.0, 0, 0]
[[constraint]]
type = "pin"
node = "a:0"
[[constraint]]
type = "JOINT"
nodes = ["a:-1", "b:0"]
[[load]]
type = "gravity"
acceleration = [0, -9.81, 0]
[analysis.dynamic]
t_end = 0.1
step = 2.5e-3
integrator = "generalized_alpha"
rho_inf = 0.9
"""


def test_3d_revolute_between_beam_nodes():
    """Two beam3d links hinged about z (quadratic rows between the nodes' gradients): the
    rows match finite differences, a planar swing under gravity is the spherical joint's
    (the rows allow it: their multipliers vanish), and both engines agree."""
    revolute = scene_of(TWO_BEAMS.replace("JOINT", "revolute"))
    spherical = scene_of(TWO_BEAMS.replace("JOINT", "spherical"))
    assert revolute.constraints[1].axis == (0.0, 0.0, 1.0)
    model = Model(revolute)
    (block,) = model.holonomic.blocks
    _finite_difference_check(block, np.random.default_rng(11))
    # full Newton, for equal counters (a kept Jacobian may stop a step one iteration apart
    # in the two engines: tests/scenes_small.py, counts_agree)
    _, q_rev, _, python = run(revolute, "python", newton="full")
    _, q_sph, _, _ = run(spherical, "python", newton="full")
    assert np.abs(q_rev[-1] - q_rev[0]).max() > 1e-2                  # it swung
    assert np.abs(q_rev - q_sph).max() <= 1e-9
    compiled = run(revolute, "compiled", newton="full")
    assert np.abs(compiled[1] - q_rev).max() <= 1e-12
    assert compiled[3].counters == python.counters


def test_3d_revolute_axis_outside_the_gradients_is_a_scene_error():
    text = TWO_BEAMS.replace("JOINT", "revolute").replace('element = "beam3d"',
                                                          'element = "cable3d"')
    with pytest.raises(SceneError, match=r"^constraint\[1\]: revolute: the axis"):
        Model(scene_of(text))


def test_joint_forces_on_the_node_and_on_the_body_are_opposite():
    """Newton's third law across the double pendulum's hinge: the reaction sensor of the
    rod's first node (its joint's multipliers on the node) is minus the body_reaction of the
    link's joint to it (on the body), at every output."""
    scene = load_scene(scene_path("double_pendulum"))
    extra = "".join(
        f'[[sensor]]\nname = "{kind}_{c}"\ntype = "{kind}"\n{where}\ncomponent = "{c}"\n'
        for kind, where in (("reaction", 'node = "rod:0"'),
                            ("body_reaction", 'body = "link"\nconstraint = 1'))
        for c in "xyz")
    text = scene_path("double_pendulum").read_text().replace(
        "[analysis.dynamic]", extra + "[analysis.dynamic]").replace("t_end = 1.0",
                                                                   "t_end = 0.1")
    from runtime import run_scene

    result = run_scene(scene_of(text), engine="python", progress=False)
    for c in "xyz":
        node, body = result.sensors[f"reaction_{c}"], result.sensors[f"body_reaction_{c}"]
        assert np.abs(node + body).max() <= 1e-9 * max(1.0, np.abs(body).max())
    assert np.abs(result.sensors["reaction_y"]).max() > 0.1       # it carries the rod
    assert scene.constraints[1].node is not None
