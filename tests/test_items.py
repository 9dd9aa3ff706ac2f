"""The items of a scene as registries: a sensor added as one class (``Velocity``) works in
TOML, in the Python API, in both engines and in the written outputs, checked against closed
forms and against the integrator's own relation between positions and velocities."""

from __future__ import annotations

import re

import numpy as np
import pytest

from runtime import (
    Body,
    Constant,
    Dynamic,
    Gravity,
    Material,
    Pin,
    Position,
    Scene,
    SceneError,
    Solver,
    Velocity,
    load_scene,
    run_scene,
)
from runtime.app.run import run
from runtime.model.items.sensors import SENSORS

G = 9.81
STEEL = Material("steel", E=2.1e11, nu=0.0, rho=7800.0)


def _falling(engine: str) -> Scene:
    """A free beam falling under gravity from rest: v_y(t) = -g t exactly (uniform
    acceleration, integrated exactly by both integrators)."""
    return Scene(materials=[STEEL],
                 bodies=[Body("rod", "beam2d", "steel", height=0.02, width=0.02, elements=3,
                              start=(0.0, 0.0), end=(1.0, 0.0))],
                 loads=[Gravity((0.0, -G), time_law=Constant())],
                 sensors=[Velocity("vy", "rod:-1", "y"), Velocity("speed", "rod:1", "norm")],
                 dynamic=Dynamic(t_end=0.1, step=1e-3, output_every=1e-2),
                 solver=Solver(engine=engine))


@pytest.mark.parametrize("engine", ["compiled", "python"])
def test_velocity_sensor_of_a_falling_body_is_minus_g_t(engine):
    result = run_scene(_falling(engine), progress=False)
    assert result.status == "ok", result.summary["message"]
    t = np.asarray(result.sensors["t"])
    np.testing.assert_allclose(result.sensors["vy"], -G * t, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(result.sensors["speed"], G * t, rtol=1e-9, atol=1e-12)


def _pendulum(engine: str) -> Scene:
    return Scene(materials=[STEEL],
                 bodies=[Body("rod", "beam2d", "steel", height=0.02, width=0.02, elements=4,
                              start=(0.0, 0.0), end=(1.0, 0.0))],
                 constraints=[Pin("rod:0")],
                 loads=[Gravity((0.0, -G), time_law=Constant())],
                 sensors=[Position("y", "rod:-1", "y"), Velocity("vy", "rod:-1", "y")],
                 dynamic=Dynamic(t_end=0.2, step=1e-3),
                 solver=Solver(engine=engine))


def test_velocity_sensor_obeys_the_trapezoidal_rule_and_engines_agree():
    # trapezoidal: q_{n+1} - q_n = h (v_n + v_{n+1}) / 2 at every step (no joints, so no
    # projection): the sensor reads the velocities the integrator advanced
    runs = {engine: run_scene(_pendulum(engine), progress=False)
            for engine in ("compiled", "python")}
    for result in runs.values():
        assert result.status == "ok"
        y, vy = np.asarray(result.sensors["y"]), np.asarray(result.sensors["vy"])
        assert np.abs(vy).max() > 0.5    # the tip swings down
        np.testing.assert_allclose(np.diff(y) / 1e-3, (vy[1:] + vy[:-1]) / 2, rtol=0,
                                   atol=1e-8 * np.abs(vy).max())
    np.testing.assert_allclose(runs["compiled"].sensors["vy"], runs["python"].sensors["vy"],
                               rtol=0, atol=1e-11)


def test_velocity_sensor_from_toml_round_trips_and_reports_its_unit(tmp_path):
    scene = _pendulum("python")
    path = tmp_path / "scene.toml"
    path.write_text(scene.to_toml())
    assert 'type = "velocity"' in path.read_text()
    assert load_scene(path) == scene
    assert SENSORS["velocity"] is Velocity and Velocity.unit == "m/s"
    _, code = run(path, tmp_path / "out", quiet=True)
    assert code == 0
    header = (tmp_path / "out" / "timeseries.csv").read_text().splitlines()[0]
    assert header.split(",") == ["t", "y", "vy"]
    assert (tmp_path / "out" / "vy.png").is_file()


@pytest.mark.parametrize("component, message", [
    ("z", 'sensor[0].component: unknown component "z"'),
    ("w", 'sensor[0].component: unknown component "w"'),
])
def test_velocity_sensor_checks_its_keys_like_any_sensor(component, message):
    with pytest.raises(SceneError, match=re.escape(message)):
        Scene(materials=[STEEL],
              bodies=[Body("rod", "beam2d", "steel", height=0.02, width=0.02, elements=2,
                           start=(0.0, 0.0), end=(1.0, 0.0))],
              sensors=[Velocity("v", "rod:-1", component)],
              dynamic=Dynamic(t_end=0.01, step=1e-3))
