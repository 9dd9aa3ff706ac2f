"""Honest dynamic divergence (issue 18, item 5): a dynamic run of either engine stops with the
time and cause when a state or a sensor becomes non-finite or absurd (beyond
``runtime.solve.python_engine.StateLimits``: a million times what the scene can reach),
keeping the outputs before it; the issue's ``initial_velocity = [1e200, 0, 0]`` (refused by
the scene parser since; set behind its back) no longer ends ``ok`` with energies of inf."""

from __future__ import annotations

import numpy as np
import pytest
from scenes_small import cantilever

from runtime import Dynamic, run_scene
from runtime.app.simulation import Simulation
from runtime.model.dae import DAESystem
from runtime.solve.python_engine import Divergence, StateLimits

ENGINES = ("python", "compiled")


def _scene(**settings):
    return cantilever(elements=2, force=[0.0, -10.0],
                      dynamic=Dynamic(t_end=0.01, step=1e-3, **settings))


@pytest.mark.parametrize("engine", ENGINES)
def test_the_issues_initial_velocity_of_1e200_is_a_divergence_at_t_0(engine):
    scene = _scene()
    object.__setattr__(scene.bodies[0], "initial_velocity", (1e200, 0.0))
    result = run_scene(scene, engine=engine, progress=False)
    assert result.status == "diverged" and result.exit_code == 1
    assert result.summary["message"] == \
        "diverged at t = 0 s: non-finite sensor kinetic (inf)"
    assert result.summary["dynamic"]["t_reached"] == 0.0


@pytest.mark.parametrize("engine", ENGINES)
def test_a_sane_run_is_not_stopped(engine):
    result = run_scene(_scene(), engine=engine, progress=False)
    assert result.status == "ok" and result.sensors["t"][-1] == pytest.approx(0.01)


def _started(scene) -> Simulation:
    simulation = Simulation(scene)
    simulation.build()
    simulation.history = {name: [] for name in ["t", *simulation.sensors.names]}
    simulation._limits = StateLimits.of(DAESystem(simulation.model, simulation.model.reference),
                                        scene.dynamic.t_end)
    return simulation


@pytest.mark.parametrize("row, change, cause", [
    (2, lambda q, v: q.__setitem__(-2, q[-2] + 1e12), "absurd displacement 1e+12 m"),
    (1, lambda q, v: v.__setitem__(-2, 1e15), "absurd velocity 1e+15 m/s"),
    (3, lambda q, v: q.__setitem__(0, np.nan), "non-finite state"),
])
def test_an_absurd_output_stops_the_run_keeping_the_outputs_before_it(row, change, cause):
    simulation = _started(_scene())
    model = simulation.model
    times = np.arange(5) * 1e-3
    q, v = np.tile(model.reference, (5, 1)), np.zeros((5, model.size))
    change(q[row], v[row])
    with pytest.raises(Divergence) as info:
        simulation._observe(times, q, v, np.zeros(5), np.zeros((5, len(model.scene.loads))))
    assert info.value.time == times[row] and cause in info.value.cause
    assert simulation.history["t"] == list(times[:row])


def test_the_limits_cover_what_the_scene_can_reach():
    # 10 N on 2 elements of 78 kg (nodal masses down to ~14.6 kg: rho A l / 2 ... consistent
    # mass diagonal 13/35 of it), L = 1 m, t_end = 0.01 s: the limits are a million times
    # L + a t^2 / 2 and L / t + a t, a = 10 N / smallest nodal mass
    simulation = _started(_scene())
    limits = simulation._limits
    mass = 7800.0 * 0.1 * 0.1 * 0.5 * 13 / 35          # smallest nodal mass (tip), kg
    a = 10.0 / mass
    assert limits.displacement == pytest.approx(1e6 * (1.0 + a * 0.01**2 / 2), rel=1e-6)
    assert limits.velocity == pytest.approx(1e6 * (1.0 / 0.01 + a * 0.01), rel=1e-6)
