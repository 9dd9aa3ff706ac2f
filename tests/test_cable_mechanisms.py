"""Cable elements (cable2d, cable3d) in mechanisms: hubs (prescribed_rotation), joints
(spherical, revolute in 2D), gravity and initial velocities, and the two engines agreeing on
such scenes (the compiled stepper against the Python reference, tests/test_engines.py).

Figures measured when these tests were written: the engines' states differ by at most
2e-12 of their scale (velocities 1e-10), their counters are equal; the cable2d rotating beam
deflects 0.5 % more than the beam2d one at t = 4 s; the cable2d pendulum's energy drift is
that of the beam2d pendulum (1.1e-5 of the largest kinetic energy at step 1e-3)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scenes_small import body, compare_engines, engine_history, scene

import scenes
from runtime import (
    Clamp,
    ConstraintViolation,
    Dynamic,
    Gravity,
    Hub,
    KineticEnergy,
    Material,
    Pin,
    Position,
    Revolute,
    Scene,
    Spherical,
    Spin,
    SpinUp,
    TotalEnergy,
    load_scene,
)
from runtime.model.items.sensors import Sensors
from runtime.model.model import Model

ALUMINIUM = Material("m", E=7.0e10, nu=0.0, rho=2700.0)
G = 9.81
# whole runs of hundreds to thousands of steps (tests/test_engines.py, shipped scenes):
# positions to 1e-11 of their scale, velocities to 1e-9 of theirs, sensors to 1e-11
LONG = {"q_rtol": 1e-11, "v_rtol": 1e-9, "sensor_rtol": 1e-11}


def _series(model: Model, states) -> dict[str, np.ndarray]:
    """Every sensor of the model's scene over the states [(t, q, v)]."""
    sensors = Sensors(model)
    rows = [sensors.values(q, v, t) for t, q, v in states]
    return {name: np.array([row[name] for row in rows]) for name in sensors.names}


def _with_element(scene_: Scene, element: str, **dynamic) -> Scene:
    """A one-body shipped scene with its body's element kind and dynamic settings changed."""
    bodies = [dataclasses.replace(b, element=element) for b in scene_.bodies]
    return dataclasses.replace(scene_, bodies=bodies,
                               dynamic=dataclasses.replace(scene_.dynamic, **dynamic))


# --------------------------------------------------------------------------- (1) hub, 2D

def test_rotating_cable2d_agrees_with_beam2d_and_between_engines():
    base = load_scene(scenes.path("rotating_beam"))
    runs = {}
    for element in ("cable2d", "beam2d"):
        data = _with_element(base, element, t_end=4.0, integrator="generalized_alpha")
        if element == "cable2d":
            _, states, _ = compare_engines(data, **LONG)
        else:
            states = engine_history(Model(data), data.dynamic, "compiled")[0]
        runs[element] = _series(Model(data), states)
    cable, beam = runs["cable2d"]["tip_transverse"], runs["beam2d"]["tip_transverse"]
    length = 8.0
    # the tip lags behind the hub frame while it spins up (positive angular acceleration):
    # negative in the hub frame at every output after the start, small against the length
    assert np.all(cable[1:] < 0) and np.all(beam[1:] < 0)
    assert -cable[-1] < 0.1 * length
    # both are Euler-Bernoulli beams in this slender regime (L / h = 218): the same
    # deflection within 2 % (measured 0.54 % at t = 4 s: -0.3185 m against -0.3168 m)
    assert abs(cable[-1] - beam[-1]) <= 0.02 * abs(beam[-1])
    assert np.abs(cable - beam).max() <= 0.02 * np.abs(beam).max()


# --------------------------------------------------------------------------- (2) pendulum

def _pendulum_drift(element: str, step: float, compare: bool = False) -> tuple[float, float]:
    """(largest |E(t) - E(0)| / largest kinetic energy, largest kinetic energy (J)) of the
    shipped pendulum (pinned, released horizontally, trapezoidal) with ``element``."""
    data = _with_element(load_scene(scenes.path("pendulum")), element, step=step)
    if compare:
        # positions agree to 1.1e-12 of their scale; the strain and total energies, each
        # the difference of larger ones, differ by 7.2e-12 of the kinetic energy (the axial
        # stiffness EA = 2.8e7 N turns position round-off into strain energy): 2e-11
        _, states, _ = compare_engines(data, **{**LONG, "sensor_rtol": 2e-11})
    else:
        states = engine_history(Model(data), data.dynamic, "compiled")[0]
    series = _series(Model(data), states)
    energy, kinetic = series["total_energy"], series["kinetic_energy"]
    assert energy[0] == 0.0
    return np.abs(energy - energy[0]).max() / kinetic.max(), kinetic.max()


def test_cable2d_pendulum_conserves_energy_like_beam2d():
    coarse, kinetic = _pendulum_drift("cable2d", 1e-3, compare=True)
    fine, _ = _pendulum_drift("cable2d", 5e-4)
    # gravity is the consistent force of the cable's mass: at the bottom the rod (1.08 kg,
    # 1 m) has turned its drop m g L / 2 into motion (its stretch stores 1e-4 J of 5.3)
    mass = ALUMINIUM.rho * 0.02 * 0.02 * 1.0
    assert kinetic == pytest.approx(mass * G / 2, rel=1e-3)
    # the trapezoidal rule's energy error is O((h w)^2) on the swing (w ~ sqrt(3 g / 2 L)
    # = 3.8 rad/s, h w = 4e-3): measured 1.10e-5 at h = 1e-3 and 2.76e-6 at 5e-4 (ratio
    # 4.0), the beam2d pendulum's figures to three digits (tests/test_model.py asserts
    # < 1e-4 and a ratio > 3 for beam2d); 3e-5 is 2 (h w)^2
    assert coarse < 3e-5
    assert fine < coarse / 3.5
    beam, _ = _pendulum_drift("beam2d", 1e-3)
    assert coarse == pytest.approx(beam, rel=0.05)   # the rigid swing's error, not the cable's


# --------------------------------------------------------------------------- (3) joints, 2D

def _double_pendulum(joint: type, integrator: str) -> Scene:
    sensors = [ConstraintViolation("violation"), TotalEnergy("total"), KineticEnergy("kinetic"),
               Position("tip_y", "b:-1", "y")]
    return scene([body("a", "cable2d", 2, [0.0, 0.0], [0.5, 0.0], 0.02, 0.02),
                  body("b", "cable2d", 2, [0.5, 0.0], [1.0, 0.0], 0.02, 0.02)],
                 [Pin("a:0"), joint(("a:-1", "b:0"))], [Gravity([0.0, -G])], sensors,
                 ALUMINIUM, dynamic=Dynamic(t_end=0.4, step=2e-3, integrator=integrator,
                                            rho_inf=0.9))


@pytest.mark.parametrize("integrator", ["trapezoidal", "generalized_alpha"])
@pytest.mark.parametrize("joint", [Spherical, Revolute])
def test_cable2d_double_pendulum(joint, integrator):
    data = _double_pendulum(joint, integrator)
    counters, states, _ = compare_engines(data, sensor_rtol=1e-11)
    model = Model(data)
    series = _series(model, states)
    assert counters["newton_iterations"] > counters["steps"]     # a nonlinear motion
    assert series["tip_y"][-1] < -0.5                             # it fell and swung
    # the joint rows hold to round-off (measured exactly 0), node against node too
    assert series["violation"].max() <= 1e-12
    a, b = (model.node_dofs(model.node_index(n), "r") for n in data.constraints[1].nodes)
    assert max(np.abs(q[a] - q[b]).max() for _, q, _ in states) <= 1e-12
    if integrator == "trapezoidal":   # as the beam2d double pendulum (tests/test_model.py)
        total, kinetic = series["total"], series["kinetic"]
        assert np.abs(total - total[0]).max() <= 1e-3 * kinetic.max()   # measured 1.1e-4


# --------------------------------------------------------------------------- (4) joints, 3D

def _cable3d_pendulum(integrator: str) -> Scene:
    """A cable3d rod hung by a spherical joint from the tip of a clamped cable3d arm (along
    y), horizontal along x, started turning about the vertical through the joint at 2 rad/s
    under gravity along -z: a conical, fully 3D swing."""
    sensors = [ConstraintViolation("violation"), TotalEnergy("total"), KineticEnergy("kinetic"),
               *(Position(f"tip_{c}", "rod:-1", c) for c in "xyz")]
    rod = dataclasses.replace(body("rod", "cable3d", 4, [0.0, 0.2, 0.0], [0.8, 0.2, 0.0],
                                   0.02, 0.02),
                              initial_angular_velocity=Spin((0.0, 0.0, 2.0), (0.0, 0.2, 0.0)))
    return scene([body("arm", "cable3d", 1, [0.0, 0.0, 0.0], [0.0, 0.2, 0.0], 0.02, 0.02), rod],
                 [Clamp("arm:0"), Spherical(("arm:-1", "rod:0"))], [Gravity([0.0, 0.0, -G])],
                 sensors, ALUMINIUM,
                 dynamic=Dynamic(t_end=0.4, step=2e-3, integrator=integrator, rho_inf=0.9))


@pytest.mark.parametrize("integrator", ["trapezoidal", "generalized_alpha"])
def test_cable3d_pendulum_on_a_spherical_joint(integrator):
    data = _cable3d_pendulum(integrator)
    _, states, _ = compare_engines(data, sensor_rtol=1e-11)
    model = Model(data)
    series = _series(model, states)
    assert np.array_equal(states[0][2], model.initial_velocities())
    assert series["kinetic"][0] == pytest.approx(
        0.5 * (ALUMINIUM.rho * 0.02 * 0.02 * 0.8) * 0.8**2 / 3 * 2.0**2, rel=1e-12)
    assert series["violation"].max() <= 1e-12
    # it swings in 3D: turned about z (x shrinks, y grows) while falling
    start = {c: series[f"tip_{c}"][0] for c in "xyz"}
    assert series["tip_x"][-1] < start["x"] - 0.1
    assert series["tip_y"][-1] > start["y"] + 0.1
    assert series["tip_z"][-1] < start["z"] - 0.5
    if integrator == "trapezoidal":
        total, kinetic = series["total"], series["kinetic"]
        assert np.abs(total - total[0]).max() <= 1e-3 * kinetic.max()   # measured 6.5e-5


def test_cable3d_mechanism_names_the_rotations_it_leaves_free():
    # the rod turns freely about the joint, about y and z: its spin about its own axis (x)
    # moves no coordinate of a 3D cable and is not a motion (it was "(nan, nan, nan)")
    model = Model(_cable3d_pendulum("trapezoidal"))
    assert model.free_motions() == ["body 'rod' is free to rotate about y and z"]


# --------------------------------------------------------------------------- (5) hub, 3D

def _spun(element: str, integrator: str, axis=None) -> Scene:
    dim = 2 if element == "cable2d" else 3
    zero = [0.0] * (dim - 2)
    sensors = [Position(f"tip_{c}", "beam:-1", c) for c in "xyz"[:dim]]
    hub = Hub("beam:0", SpinUp(4.0, 15.0)) if axis is None else \
        Hub("beam:0", SpinUp(4.0, 15.0), axis=axis)
    return scene([body("beam", element, 10, [0.0, 0.0] + zero, [8.0, 0.0] + zero, 0.02, 0.02)],
                 [hub], [], sensors, ALUMINIUM,
                 dynamic=Dynamic(t_end=2.0, step=5e-3, integrator=integrator,
                                 output_every=0.05, newton="full"))   # round-off equal runs


@pytest.mark.parametrize("integrator", ["trapezoidal", "generalized_alpha"])
@pytest.mark.parametrize("axis", [(0.0, 0.0, 1.0), (0.0, 1.0, 0.0)])
def test_hub_on_cable3d_turns_it_as_the_planar_cable(axis, integrator):
    data = _spun("cable3d", integrator, axis)
    _, states, _ = compare_engines(data, **LONG)
    series = _series(Model(data), states)
    planar = _series(Model(_spun("cable2d", integrator)),
                     engine_history(Model(_spun("cable2d", integrator)), data.dynamic,
                                    "compiled")[0])
    # the square section bends alike about any axis: the spin about z is the planar run
    # (measured equal to 4e-15 m), the spin about y its image turned into the x-z plane
    # (R_y(theta) e_x = (cos, 0, -sin)); the third coordinate stays at rest
    assert planar["tip_y"][-1] > 0.04          # it turned and bent (0.049 m at t = 2 s)
    in_plane, out = ("tip_y", "tip_z") if axis[2] else ("tip_z", "tip_y")
    sign = 1.0 if axis[2] else -1.0
    assert np.abs(series["tip_x"] - planar["tip_x"]).max() <= 1e-12 * 8.0
    assert np.abs(series[in_plane] - sign * planar["tip_y"]).max() <= 1e-12 * 8.0
    assert np.abs(series[out]).max() <= 1e-15


def test_hub_about_the_axis_of_a_cable3d_is_refused():
    # it turned nothing (the node carries only r, r_x): silently a clamp before
    with pytest.raises(ValueError, match=r"constraint\[0\]\.axis: a rotation about the axis "
                                         r"of body 'beam' \(cable3d"):
        _spun("cable3d", "trapezoidal", (-1.0, 0.0, 0.0))
