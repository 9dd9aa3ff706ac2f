"""Kelvin-Voigt damping in the dynamic engines: both engines agree, a free vibration decays
at the rate the law predicts for its first mode (damping ratio alpha omega / 2), and the
dissipated energy closes the energy balance."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scenes_small import cantilever
from scipy.signal import find_peaks

from runtime import Material
from runtime.model.model import Model
from runtime.model.scene import parse_scene
from runtime.solve import engines, modal

ALPHA = 2e-5   # s


def _pulse(integrator: str = "generalized_alpha", t_end: float = 0.3, law: str = "svk",
           damping: float = ALPHA) -> dict:
    """A 4-element beam2d cantilever kicked by a 2 ms tip force, then free."""
    return cantilever(
        elements=4, element="beam2d", height=0.05, width=0.05, force=[0.0, -50.0],
        law={"type": "table", "points": [[0.0, 1.0], [0.002, 1.0], [0.0021, 0.0]]},
        material=Material("m", E=2.1e11, nu=0.3 if law == "ecm" else 0.0, rho=7800.0,
                          law=law, damping=damping),
        dynamic={"t_end": t_end, "step": 1e-4, "output_every": 1e-4,
                 "integrator": integrator, "rho_inf": 1.0}).to_dict()


def _run(model: Model, settings, engine: str):
    runner = engines.make(engine, model, settings, model.reference)
    rows = []

    def observe(t, q, v):
        rows.append((t, q.copy(), v.copy(), model.strain_energy(q) + model.kinetic_energy(v),
                     model.dissipated_energy))

    runner.run(settings.t_end, settings.step, observe)
    return rows, dataclasses.asdict(runner.counters)


@pytest.mark.parametrize("newton", ["full", "modified"])
@pytest.mark.parametrize("integrator", ["trapezoidal", "generalized_alpha"])
def test_engines_agree_with_damping(integrator, newton):
    scene = parse_scene(_pulse(integrator, t_end=0.02, law="ecm"))
    settings = dataclasses.replace(scene.dynamic, newton=newton)
    model = Model(scene)
    (python, counted), (compiled, counted_c) = (_run(model, settings, e)
                                                for e in ("python", "compiled"))
    assert counted == counted_c
    scale = max(np.abs(r[1]).max() for r in python)
    for a, b in zip(python, compiled, strict=True):
        assert np.abs(a[1] - b[1]).max() <= 1e-12 * scale
        assert b[4] == pytest.approx(a[4], rel=1e-9, abs=1e-15)
    assert python[-1][4] > 0


def test_free_vibration_decays_at_the_kelvin_voigt_rate():
    scene = parse_scene(_pulse())
    model = Model(scene)
    omega = modal.modal(model, model.reference, 1)[0]
    rows, _ = _run(model, scene.dynamic, "compiled")
    t = np.array([r[0] for r in rows])
    tip = np.array([r[1][model.node_dofs(model.node_index(scene.sensors[1].node), "r")][1]
                    for r in rows])
    free = t > 0.05   # the higher modes (damping ratio ~ omega^2) have died out by then
    peaks, _ = find_peaks(np.abs(tip[free]))
    rate = -np.polyfit(t[free][peaks], np.log(np.abs(tip[free][peaks])), 1)[0]
    assert rate == pytest.approx(ALPHA * omega**2 / 2, rel=0.02)


def test_dissipated_energy_closes_the_energy_balance():
    scene = parse_scene(_pulse())
    model = Model(scene)
    rows, _ = _run(model, scene.dynamic, "compiled")
    after = next(r for r in rows if r[0] > 0.0021)   # the force is off from here
    end = rows[-1]
    dissipated = end[4] - after[4]
    assert dissipated > 0.3 * after[3]   # a sizeable part of the energy was dissipated
    assert after[3] - end[3] == pytest.approx(dissipated, rel=0.01)
    assert all(b[4] >= a[4] for a, b in zip(rows, rows[1:], strict=False))   # only grows


def test_undamped_models_dissipate_nothing():
    scene = parse_scene(_pulse(t_end=0.01, damping=0.0))
    model = Model(scene)
    rows, _ = _run(model, scene.dynamic, "compiled")
    assert all(r[4] == 0.0 for r in rows)
