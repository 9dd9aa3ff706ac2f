"""Torsional springs count turns (issue 17): wound past half a turn, the deflection
phi - phi_0 goes on growing instead of jumping from +pi to -pi, in both engines and in the
static analysis.

Checked against closed forms: a disc driven at a constant rate against the spring (the
drive torque k omega t, the spring's energy k (omega t)^2 / 2, the spring_angle sensor
omega t), a free torsional oscillator released 1.5 turns wound (k phi = -J phi'':
3 pi cos(sqrt(k / J) t)), and a static twist of 1.25 turns (phi = M / k; on the arc-length
path lambda M / k)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from test_multibody import scene_of

from runtime import run_scene
from runtime.model.errors import SceneError
from runtime.model.model import Model
from runtime.solve import engines

#: a disc on a hinge about z, driven at ``omega`` rad/s against a spring to the ground
DRIVEN = """
[[body]]
type = "rigid"
name = "disc"
mass = 2.0
inertia = [0.3, 0.3, 0.5]
angular_velocity = [0.0, 0.0, {omega}]
[[constraint]]
type = "body_revolute"
body = "disc"
angle = {{type = "constant_rate", omega = {omega}}}
[[load]]
type = "torsional_spring"
body = "disc"
stiffness = {k}
[[sensor]]
name = "torque"
type = "body_reaction"
body = "disc"
quantity = "moment"
component = "z"
constraint = 0
[[sensor]]
name = "twist"
type = "spring_angle"
load = 0
[[sensor]]
name = "spring"
type = "potential_energy"
[analysis.dynamic]
t_end = 2.5
step = 1e-2
"""

#: a free disc on a hinge, its spring's free angle 1.5 turns back: released wound
WOUND = """
[[body]]
type = "rigid"
name = "disc"
mass = 2.0
inertia = [0.3, 0.3, {inertia}]
[[constraint]]
type = "body_revolute"
body = "disc"
[[load]]
type = "torsional_spring"
body = "disc"
stiffness = {k}
angle = {angle}
[[sensor]]
name = "twist"
type = "spring_angle"
load = 0
[[sensor]]
name = "energy"
type = "total_energy"
[analysis.dynamic]
t_end = 1.0
step = 5e-4
output_every = 5e-3
integrator = "trapezoidal"
"""


def _sensors(scene, engine: str) -> dict[str, np.ndarray]:
    result = run_scene(scene, engine=engine, progress=False)
    return {name: np.asarray(values) for name, values in result.sensors.items()}


def test_a_spring_driven_through_turns_has_no_jump_at_half_a_turn():
    """2.5 turns at 2 pi rad/s against k = 3 N m/rad: the drive torque is k omega t (no
    inertia at a constant rate), the spring's energy k (omega t)^2 / 2 and its angle omega t
    at every output, in both engines alike."""
    omega, k = 2 * math.pi, 3.0
    scene = scene_of(DRIVEN.format(omega=omega, k=k))
    python, compiled = _sensors(scene, "python"), _sensors(scene, "compiled")
    t = python["t"]
    twist = omega * t
    assert twist[-1] == pytest.approx(5 * math.pi)           # 2.5 turns
    for out in (python, compiled):
        assert out["twist"] == pytest.approx(twist, rel=1e-12, abs=1e-12)
        assert out["torque"] == pytest.approx(k * twist, rel=1e-8, abs=1e-8 * k)
        assert out["spring"] == pytest.approx(0.5 * k * twist**2, rel=1e-12, abs=1e-12)
    for name in ("twist", "torque", "spring"):
        scale = np.abs(python[name]).max()
        assert np.abs(python[name] - compiled[name]).max() <= 1e-11 * scale


@pytest.mark.parametrize("engine", ["python", "compiled"])
def test_a_second_run_of_an_engine_counts_turns_afresh(engine):
    """The same engine run twice through 2.5 turns: the second run's angles start again
    within half a turn of 0 and equal the first run's, omega t (no count kept over)."""
    omega = 2 * math.pi
    scene = scene_of(DRIVEN.format(omega=omega, k=3.0))
    model = Model(scene)
    stepper = engines.make(engine, model, scene.dynamic, model.reference.copy())
    runs: list[list] = [[], []]
    for blocks in runs:
        stepper.run(scene.dynamic.t_end, scene.dynamic.step,
                    observe_block=lambda t, q, v, e, angles, blocks=blocks: blocks.append(
                        np.column_stack([t, angles[:, 0]])))
    runs = [np.concatenate(blocks) for blocks in runs]
    t, angle = runs[0].T
    assert angle == pytest.approx(omega * t, rel=1e-12, abs=1e-12)
    # (to round-off: the Python engine's second run starts from the Jacobian it kept)
    assert runs[1] == pytest.approx(runs[0], rel=1e-12, abs=1e-12)


@pytest.mark.parametrize("engine", ["python", "compiled"])
def test_a_spring_released_one_and_a_half_turns_wound_oscillates_at_sqrt_k_over_j(engine):
    """J phi'' = -k phi from phi = 3 pi at rest (the free angle -3 pi): the spring's angle
    is 3 pi cos(w t), w = sqrt(k / J), period 2 pi sqrt(J / k); the amplitude stays 3 pi
    (undamped) and total_energy k (3 pi)^2 / 2."""
    inertia, k = 0.5, 8.0
    scene = scene_of(WOUND.format(inertia=inertia, k=k, angle=-3 * math.pi))
    out = _sensors(scene, engine)
    t, twist = out["t"], out["twist"]
    natural = math.sqrt(k / inertia)
    amplitude = 3 * math.pi
    # the trapezoidal rule's O(h^2) error of a rotation at up to 3 pi w = 38 rad/s in
    # natural coordinates, (38 h)^2 / 12 = 3e-5 per radian of phase, over the 4 rad of
    # phase: 1.2e-4 of the amplitude (measured 8.9e-5; over 8 rad 2.7e-4, and 6.8e-5 there
    # at h / 2)
    assert np.abs(twist - amplitude * np.cos(natural * t)).max() <= 1.5e-4 * amplitude
    # the extremes, sampled every 5 ms: within (w 2.5 ms)^2 / 2 = 5e-5 of the amplitude
    assert twist.max() == pytest.approx(amplitude, rel=5e-5)
    assert twist.min() == pytest.approx(-amplitude, rel=5e-5)
    half = t[1:][(twist[1:] < 0) & (twist[:-1] >= 0)]          # downward crossings
    assert half[0] == pytest.approx(0.25 * 2 * math.pi / natural, abs=5e-3)
    start = 0.5 * k * amplitude**2
    assert out["energy"][0] == pytest.approx(start, rel=1e-12)
    # the integrator's O(h^2) energy error of a rotation at up to 38 rad/s in natural
    # coordinates (measured 7.4e-5, and 1.9e-5 at h / 2 over 2 s)
    assert np.abs(out["energy"] - start).max() <= 1e-4 * start


def _twisted(k: float, method: str):
    """The wound-disc scene with a torque 2.5 pi k on the disc and a static analysis of
    10 load steps by ``method``."""
    return scene_of(WOUND.format(inertia=0.5, k=k, angle=0.0).replace(
        "[analysis.dynamic]", f"""[[load]]
type = "body_torque"
body = "disc"
torque = {2.5 * math.pi * k}
[analysis.static]
method = "{method}"
load_steps = 10
[analysis.dynamic]""").replace("t_end = 1.0", "t_end = 1e-2"))


def test_a_static_twist_of_one_and_a_quarter_turns_is_m_over_k():
    """A torque M = 2.5 pi k applied in 10 load steps turns the disc through 1.25 turns on
    its spring: the static spring_angle is M / k (each step less than half a turn), with
    either engine's Newton solves."""
    scene = _twisted(4.0, "load_stepping")
    for engine in ("python", "compiled"):
        result = run_scene(scene, engine=engine, progress=False)
        assert result.summary["static"]["sensors"]["twist"] == pytest.approx(2.5 * math.pi,
                                                                             rel=1e-9)


def test_an_arc_length_path_twists_the_spring_by_lambda_m_over_k():
    """Along the arc-length path of the same torque the spring's angle is lambda M / k at
    every point, past half a turn and on to 1.25 turns (the path's last load factor, just
    over 1)."""
    result = run_scene(_twisted(4.0, "arc_length"), engine="python", progress=False)
    factors, twist = result.path["load_factor"], result.path["twist"]
    assert factors[-1] >= 1.0
    assert twist == pytest.approx(2.5 * math.pi * factors, rel=1e-9, abs=1e-12)


@pytest.mark.parametrize("load", [2, 1])
def test_spring_angle_names_a_torsional_spring(load):
    """An index past the loads, or of a load that is no torsional spring (the gravity):
    a SceneError naming the sensor's key."""
    text = DRIVEN.format(omega=1.0, k=1.0).replace("load = 0", f"load = {load}").replace(
        "[[sensor]]", '[[load]]\ntype = "gravity"\nacceleration = [0, -9.81, 0]\n[[sensor]]',
        1)
    with pytest.raises(SceneError, match=r"sensor\[1\]\.load: expected the index of a "
                                         r"torsional_spring among the 2"):
        scene_of(text)
