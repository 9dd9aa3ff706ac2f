"""The torsional spring-damper of a revolute joint (``[[load]] type = "torsional_spring"``,
docs/multibody.md): exact Jacobians against finite differences, a body on a hinge and two
bodies on a shared hinge against the closed-form torsional oscillators (exact for any
amplitude: the moment is linear in the angle), the spring's energy in total_energy, the
damper's decay, both engines, bad keys."""

from __future__ import annotations

import numpy as np
import pytest
from test_multibody import run, scene_of

from runtime.model.errors import SceneError
from runtime.model.items.loads import TorsionalSpring
from runtime.model.model import Model

#: a rigid disc on a hinge about z at its centre, with a torsional spring (TOML)
HINGED = """
[[body]]
type = "rigid"
name = "disc"
mass = 2.0
inertia = [0.3, 0.3, 0.5]
angular_velocity = [0.0, 0.0, {omega}]
[[constraint]]
type = "body_revolute"
body = "disc"
[[load]]
type = "torsional_spring"
body = "disc"
stiffness = 8.0
damping = {damping}
[[sensor]]
name = "energy"
type = "total_energy"
[analysis.dynamic]
t_end = 2.0
step = 1e-3
"""


def _angle(q: np.ndarray, dofs: np.ndarray) -> np.ndarray:
    return np.unwrap(np.arctan2(q[:, dofs[4]], q[:, dofs[3]]))


def test_torsional_spring_jacobians_match_finite_differences():
    """dQ/dq and dQ/dv of the spring-damper to the ground, to another body and to a beam
    node, at random states, against central differences of Q."""
    model = Model(scene_of("""
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
[[load]]
type = "torsional_spring"
body = "a"
axis = [0.6, 0.0, 0.8]
stiffness = 3.0
damping = 0.7
angle = 0.4
[[load]]
type = "torsional_spring"
body = "b"
other = "a"
stiffness = 5.0
damping = 0.2
[[load]]
type = "torsional_spring"
body = "a"
node = "beam:-1"
stiffness = 2.0
damping = 1.1
angle = -0.3
"""))
    rng = np.random.default_rng(11)
    step = 1e-6
    for load in model.scene.loads:
        element = load.state_force(model)
        q = model.reference + 0.1 * rng.normal(size=model.size)
        v = rng.normal(size=model.size)
        patches = element(q, True, v)
        dofs = element.dofs[0]

        def force(q_, v_, element=element):
            return element(q_, False, v_).force[0]

        d_q = np.array([(force(q + step * e, v) - force(q - step * e, v)) / (2 * step)
                        for e in np.eye(model.size)[dofs]]).T
        d_v = np.array([(force(q, v + step * e) - force(q, v - step * e)) / (2 * step)
                        for e in np.eye(model.size)[dofs]]).T
        scale = np.abs(patches.jacobian[0]).max()
        assert np.abs(patches.jacobian[0] - d_q).max() <= 1e-7 * scale
        assert np.abs(patches.jacobian_dot[0] - d_v).max() <= 1e-7 * scale
        assert abs(element.deflection(q)) > 0.01      # the spring is loaded


@pytest.mark.parametrize("integrator", ["trapezoidal", "generalized_alpha"])
def test_a_hinged_disc_on_a_torsional_spring_oscillates_harmonically(integrator):
    """I phi'' = -k phi at an amplitude of 2 rad (the moment is linear in the angle):
    phi = (omega_0 / omega_n) sin(omega_n t), omega_n = sqrt(k / I); the two engines take
    the same steps; total_energy (kinetic and the spring's k phi^2 / 2) is conserved."""
    from runtime import run_scene

    natural = np.sqrt(8.0 / 0.5)
    scene = scene_of(HINGED.format(omega=2.0 * natural, damping=0.0))
    # full Newton, for equal counters (a kept Jacobian may stop a step one iteration apart
    # in the two engines: tests/scenes_small.py, counts_agree)
    t, q, _, stepper = run(scene, "python", integrator=integrator, newton="full")
    compiled = run(scene, "compiled", integrator=integrator, newton="full")
    dofs = Model(scene).rigid["disc"].dofs
    exact = 2.0 * np.sin(natural * t)
    # both errors are the integrators' O(h^2) ones of a rotation at up to 8 rad/s in natural
    # coordinates (measured: 9e-5 rad and 1.3e-5 of the energy, trapezoidal; 1.2e-4 and
    # 2.2e-5, generalized-alpha; four times smaller at h / 2)
    assert np.abs(_angle(q, dofs) - exact).max() <= 2e-4
    assert np.abs(compiled[1] - q).max() <= 1e-11
    assert compiled[3].counters == stepper.counters
    energy = np.asarray(run_scene(scene, engine="compiled", progress=False).sensors["energy"])
    start = 0.5 * 0.5 * (2.0 * natural) ** 2
    assert energy[0] == pytest.approx(start, rel=1e-12)
    assert np.abs(energy - start).max() <= 3e-5 * start


def test_a_torsional_damper_decays_at_the_closed_form_rate():
    """With damping c the amplitude decays as exp(-c t / (2 I)): the peaks of the angle
    over 2 s against the underdamped oscillator's."""
    scene = scene_of(HINGED.format(omega=1.0, damping=0.2))
    t, q, _, _ = run(scene, "compiled", integrator="trapezoidal")
    phi = _angle(q, Model(scene).rigid["disc"].dofs)
    inertia, k, c = 0.5, 8.0, 0.2
    decay = c / (2 * inertia)
    damped = np.sqrt(k / inertia - decay**2)
    exact = 1.0 / damped * np.exp(-decay * t) * np.sin(damped * t)
    assert np.abs(phi - exact).max() <= 2e-4 * np.abs(exact).max()
    # the first and last 0.4 s: exp(-0.2 x 1.6) = 0.73 of the amplitude is left
    assert np.abs(phi[-400:]).max() < 0.8 * np.abs(phi[:400]).max()


def test_two_bodies_on_a_sprung_hinge_oscillate_at_the_two_body_frequency():
    """Two free discs on a shared hinge (about their centres) with a spring between them:
    the relative angle oscillates at sqrt(k (1/I_1 + 1/I_2)), the total angular momentum
    (I_1 omega_1 + I_2 omega_2 = 0.3 - 0.3) stays zero."""
    scene = scene_of("""
[[body]]
type = "rigid"
name = "a"
mass = 1.0
inertia = [0.2, 0.2, 0.3]
angular_velocity = [0.0, 0.0, 1.0]
[[body]]
type = "rigid"
name = "b"
mass = 3.0
inertia = [0.4, 0.4, 0.6]
angular_velocity = [0.0, 0.0, -0.5]
[[constraint]]
type = "body_revolute"
body = "b"
other = "a"
[[load]]
type = "torsional_spring"
body = "b"
other = "a"
stiffness = 4.0
[analysis.dynamic]
t_end = 2.0
step = 1e-3
integrator = "trapezoidal"
""")
    t, q, v, _ = run(scene, "compiled")
    model = Model(scene)
    a, b = model.rigid["a"].dofs, model.rigid["b"].dofs
    relative = _angle(q, b) - _angle(q, a)
    frequency = np.sqrt(4.0 * (1 / 0.3 + 1 / 0.6))
    exact = -1.5 / frequency * np.sin(frequency * t)
    assert np.abs(relative - exact).max() <= 2e-4 * np.abs(exact).max()
    spin = [0.3 * (x[3] * y[4] - x[4] * y[3]) + 0.6 * (x[b[3]] * y[b[4]] - x[b[4]] * y[b[3]])
            for x, y in zip(q, v, strict=True)]
    # the spring's moments on the two bodies cancel exactly (its energy is invariant under
    # a common rotation); the integrator keeps the momentum to O(h^2) (2.5e-7 measured)
    assert np.abs(spin).max() <= 1e-6 * 0.3


@pytest.mark.parametrize("table, culprit", [
    ('body = "disc"\nstiffness = -1.0\n', "load[0].stiffness"),
    ('body = "disc"\nstiffness = 1.0\ndamping = -0.5\n', "load[0].damping"),
    ('body = "disc"\nstiffness = 1.0\nangle = "up"\n', "load[0].angle"),
    ('body = "disc"\nstiffness = 1.0\naxis = [0, 0, 0]\n', "load[0].axis"),
    ('body = "nobody"\nstiffness = 1.0\n', "load[0].body"),
    ('body = "disc"\nother = "disc"\nstiffness = 1.0\n', "load[0].other"),
    ('body = "dot"\nstiffness = 1.0\n', "load[0].body"),
    ('body = "disc"\nother = "dot"\nstiffness = 1.0\n', "load[0].other"),
])
def test_bad_torsional_springs_exit_2_naming_the_key(tmp_path, capsys, table, culprit):
    from runtime.cli import main

    text = ('[[body]]\ntype = "rigid"\nname = "disc"\nmass = 1.0\ninertia = [1, 1, 1]\n'
            '[[body]]\ntype = "point_mass"\nname = "dot"\nmass = 1.0\nposition = [1, 0, 0]\n'
            '[analysis.dynamic]\nt_end = 0.1\nstep = 0.01\n[[load]]\n'
            'type = "torsional_spring"\n' + table)
    scene = tmp_path / "bad.toml"
    scene.write_text(text)
    assert main(["run", str(scene), "--out", str(tmp_path / "out")]) == 2
    assert culprit in capsys.readouterr().err
    with pytest.raises(SceneError, match=culprit.replace("[", r"\[").replace("]", r"\]")):
        scene_of(text)


def test_torsional_springs_round_trip_through_toml():
    scene = scene_of(HINGED.format(omega=1.0, damping=0.3))
    assert isinstance(scene.loads[0], TorsionalSpring)
    assert scene_of(scene.to_toml()) == scene
