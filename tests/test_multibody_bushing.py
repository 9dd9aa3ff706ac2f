"""The linear 6 x 6 bushing between two rigid-body frames (``[[load]] type = "bushing"``,
docs/multibody.md): exact Jacobians against finite differences, a body on a bushing to the
ground oscillating at sqrt(k / m) and sqrt(k_theta / I) at small amplitude, its energy in
total_energy, the linear momentum of two bodies on a bushing, both engines, bad keys."""

from __future__ import annotations

import numpy as np
import pytest
from test_multibody import run, scene_of

from runtime.model.errors import SceneError
from runtime.model.model import Model

#: a block (2 kg, I_z = 0.05 kg m^2) on a bushing to the ground at its centre (TOML)
ON_BUSHING = """
[[body]]
type = "rigid"
name = "block"
mass = 2.0
inertia = [0.04, 0.045, 0.05]
position = [0.3, 0.1, 0.0]
velocity = [0.01, 0.0, 0.0]
angular_velocity = [0.0, 0.0, 0.02]
[[load]]
type = "bushing"
body = "block"
stiffness = [800.0, 900.0, 1000.0, 30.0, 35.0, 20.0]
[[sensor]]
name = "energy"
type = "total_energy"
[analysis.dynamic]
t_end = 1.0
step = 5e-4
integrator = "trapezoidal"
"""


def test_bushing_jacobians_match_finite_differences():
    """dQ/dq and dQ/dv of full 6 x 6 bushings, to the ground and between two bodies, at
    random states, against central differences of Q."""
    rng = np.random.default_rng(2)

    def matrix() -> str:
        root = rng.normal(size=(6, 6))
        spd = root @ root.T + np.eye(6)
        return "[" + ", ".join("[" + ", ".join(repr(float(x)) for x in row) + "]"
                               for row in spd) + "]"

    model = Model(scene_of(f"""
[[body]]
type = "rigid"
name = "a"
mass = 1.0
inertia = [0.1, 0.2, 0.25]
rotation = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
[[body]]
type = "rigid"
name = "b"
mass = 2.0
inertia = [0.3, 0.2, 0.4]
position = [1.0, 0.0, 0.0]
[[load]]
type = "bushing"
body = "a"
point = [0.2, -0.1, 0.3]
stiffness = {matrix()}
damping = {matrix()}
[[load]]
type = "bushing"
body = "b"
other = "a"
point = [-0.5, 0.0, 0.1]
stiffness = {matrix()}
damping = {matrix()}
"""))
    step = 1e-6
    for load in model.scene.loads:
        element = load.state_force(model)
        q = model.reference + 0.05 * rng.normal(size=model.size)
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
        assert np.abs(element.deflection(q)).max() > 0.01     # the bushing is loaded


@pytest.mark.parametrize("engine", ["python", "compiled"])
def test_a_block_on_a_bushing_oscillates_at_its_two_frequencies(engine):
    """Pushed along x and turned about z at small amplitude (5e-4 m, 1e-3 rad): x and the
    angle are (v0 / omega) sin(omega t) with omega = sqrt(800 / 2) and sqrt(20 / 0.05);
    total_energy (kinetic and delta^T K delta / 2) is conserved."""
    from runtime import run_scene

    scene = scene_of(ON_BUSHING)
    t, q, _, _ = run(scene, engine)
    along, turn = np.sqrt(800.0 / 2.0), np.sqrt(20.0 / 0.05)
    x = q[:, 0] - 0.3
    angle = np.arctan2(q[:, 4], q[:, 3])
    # the trapezoidal rule's phase lag (h omega)^2 / 12 per radian: 1.7e-4 of the amplitude
    # after the 20 rad of the run (measured 1.6e-4)
    assert np.abs(x - 0.01 / along * np.sin(along * t)).max() <= 1e-3 * 0.01 / along
    assert np.abs(angle - 0.02 / turn * np.sin(turn * t)).max() <= 1e-3 * 0.02 / turn
    energy = np.asarray(run_scene(scene, engine=engine, progress=False).sensors["energy"])
    start = 0.5 * 2.0 * 0.01**2 + 0.5 * 0.05 * 0.02**2
    assert energy[0] == pytest.approx(start, rel=1e-12)
    assert np.abs(energy - start).max() <= 1e-9 * start      # 1e-11 measured


def test_two_bodies_on_a_bushing_keep_their_linear_momentum():
    """The bushing's forces on the two bodies cancel (its deflection does not change under
    a common translation): the total linear momentum stays at its start to round-off, while
    the bodies exchange it."""
    scene = scene_of("""
[[body]]
type = "rigid"
name = "a"
mass = 1.0
inertia = [0.1, 0.2, 0.25]
velocity = [0.0, 0.3, 0.1]
angular_velocity = [0.5, 0.0, 0.2]
[[body]]
type = "rigid"
name = "b"
mass = 2.0
inertia = [0.3, 0.2, 0.4]
position = [1.0, 0.0, 0.0]
[[load]]
type = "bushing"
body = "b"
other = "a"
point = [-0.5, 0.0, 0.0]
stiffness = [100.0, 200.0, 300.0, 5.0, 6.0, 7.0]
damping = [1.0, 1.0, 1.0, 0.1, 0.1, 0.1]
[analysis.dynamic]
t_end = 1.0
step = 1e-3
integrator = "trapezoidal"
""")
    t, q, v, _ = run(scene, "compiled")
    model = Model(scene)
    momentum = v @ model.mass.toarray()
    total = momentum[:, model.rigid["a"].dofs[:3]] + momentum[:, model.rigid["b"].dofs[:3]]
    assert np.abs(total - total[0]).max() <= 1e-12
    assert np.abs(momentum[:, model.rigid["b"].dofs[:3]]).max() > 0.05   # b was pushed


@pytest.mark.parametrize("table, culprit", [
    ('body = "block"\nstiffness = [1, 2, 3]\n', "load[0].stiffness"),
    ('body = "block"\nstiffness = [1, 2, 3, 4, 5, -6]\n', "load[0].stiffness"),
    ('body = "block"\nstiffness = [[1, 2, 0, 0, 0, 0], [0, 1, 0, 0, 0, 0], [0, 0, 1, 0, 0, 0],'
     ' [0, 0, 0, 1, 0, 0], [0, 0, 0, 0, 1, 0], [0, 0, 0, 0, 0, 1]]\n', "load[0].stiffness"),
    ('body = "block"\nstiffness = [1, 2, 3, 4, 5, 6]\ndamping = "none"\n', "load[0].damping"),
    ('body = "dot"\nstiffness = [1, 2, 3, 4, 5, 6]\n', "load[0].body"),
    ('body = "block"\nother = "block"\nstiffness = [1, 2, 3, 4, 5, 6]\n', "load[0].other"),
    ('body = "block"\nstiffness = [1, 2, 3, 4, 5, 6]\npoint = [0, 0]\n', "load[0].point"),
])
def test_bad_bushings_exit_2_naming_the_key(tmp_path, capsys, table, culprit):
    from runtime.cli import main

    text = ('[[body]]\ntype = "rigid"\nname = "block"\nmass = 1.0\ninertia = [1, 1, 1]\n'
            '[[body]]\ntype = "point_mass"\nname = "dot"\nmass = 1.0\nposition = [1, 0, 0]\n'
            '[analysis.dynamic]\nt_end = 0.1\nstep = 0.01\n[[load]]\ntype = "bushing"\n'
            + table)
    scene = tmp_path / "bad.toml"
    scene.write_text(text)
    assert main(["run", str(scene), "--out", str(tmp_path / "out")]) == 2
    assert culprit in capsys.readouterr().err
    with pytest.raises(SceneError, match=culprit.replace("[", r"\[").replace("]", r"\]")):
        scene_of(text)


def test_bushings_round_trip_through_toml():
    scene = scene_of(ON_BUSHING)
    assert scene_of(scene.to_toml()) == scene
