"""The compiled engine against the Python engine (the reference): whole-run agreement to
round-off of every state, the same Newton counters, the same divergence time and cause, on
the shipped scenes (shortened) and on small variants with joints, hubs, curved bodies,
both integrators and both Newton modes."""

from __future__ import annotations

import dataclasses
import json
import tomllib

import numpy as np
import pytest
from scenes_small import body, cantilever, scene

import scenes
from runtime import engines
from runtime.integrators import Divergence
from runtime.model import Model
from runtime.run import run
from runtime.scene import parse_scene

ALUMINIUM = {"E": 7.0e10, "nu": 0.0, "rho": 2700.0}


def _shipped(name: str, t_end: float | None = None) -> dict:
    data = tomllib.loads(scenes.path(name).read_text())
    if t_end is not None:
        data["analysis"]["dynamic"]["t_end"] = t_end
    data["analysis"]["dynamic"].pop("frequency_of", None)
    data["analysis"]["dynamic"].pop("frequency_after", None)
    data.pop("study", None)
    return data


def _two_bodies(element: str, joint: str, integrator: str, hub: bool = False) -> dict:
    """A double pendulum (or, with ``hub``, a driven two-link arm) joined by ``joint``."""
    z = [0.0] if element == "beam3d" else []
    root = ({"type": "prescribed_rotation", "node": "a:0",
             "angle": {"type": "spin_up", "omega": 3.0, "t_ramp": 0.2}} if hub
            else {"type": "pin", "node": "a:0"})
    return scene([body("a", element, 2, [0.0, 0.0] + z, [0.5, 0.0] + z, 0.02, 0.02),
                  body("b", element, 2, [0.5, 0.0] + z, [1.0, 0.0] + z, 0.02, 0.02)],
                 [root, {"type": joint, "nodes": ["a:-1", "b:0"]}],
                 [{"type": "gravity", "acceleration": [0.0, -9.81] + z}],
                 [{"name": "tip_y", "type": "position", "node": "b:-1", "component": "y"}],
                 {"dynamic": {"t_end": 0.1, "step": 2.5e-3, "integrator": integrator,
                              "rho_inf": 0.9}},
                 material=ALUMINIUM)


def _curved(integrator: str) -> dict:
    data = scene([{"name": "arc", "element": "beam3d", "material": "m",
                   "section": {"height": 0.05, "width": 0.05}, "elements": 3,
                   "arc": {"center": [0.0, 1.0, 0.0], "radius": 1.0, "angle_deg": 60.0,
                           "start_angle_deg": -90.0}}],
                 [{"type": "clamp", "node": "arc:0"}],
                 [{"type": "point_force", "node": "arc:-1", "force": [0.0, 0.0, -2e3],
                   "time_law": {"type": "cosine_ramp", "duration": 0.05}}],
                 [{"name": "tip_z", "type": "displacement", "node": "arc:-1",
                   "component": "z"}],
                 {"dynamic": {"t_end": 0.1, "step": 1e-3, "integrator": integrator}},
                 material=ALUMINIUM)
    return data


def _history(model: Model, settings, engine: str):
    """(states [(t, q_full, v_full)], counters, divergence or None) of one engine."""
    runner = engines.make(engine, model, settings, model.reference)
    states = []
    failure = None
    try:
        runner.run(settings.t_end, settings.step,
                   lambda t, q, v: states.append((t, q.copy(), v.copy())))
    except Divergence as error:
        failure = (error.time, error.cause)
    return states, dataclasses.asdict(runner.counters), failure


def _compare(data: dict, q_rtol: float = 1e-12, v_rtol: float = 1e-9,
             **dynamic) -> tuple[dict, list, tuple | None]:
    """Run both engines; assert equal counters and failures, and states equal to q_rtol of
    the largest coordinate and velocities to v_rtol of the largest velocity."""
    scene_ = parse_scene(data)
    settings = dataclasses.replace(scene_.dynamic, **dynamic)
    model = Model(scene_)
    python = _history(model, settings, "python")
    compiled = _history(model, settings, "compiled")
    assert compiled[1] == python[1]          # steps, Newton iterations, evaluations
    assert compiled[2] == python[2]          # divergence time and cause (or none)
    assert len(compiled[0]) == len(python[0]) >= 1
    q_scale = max(np.abs(q).max() for _, q, _ in python[0])
    v_scale = max(max(np.abs(v).max() for _, _, v in python[0]), 1e-3)
    for (tp, qp, vp), (tc, qc, vc) in zip(python[0], compiled[0], strict=True):
        assert tc == tp
        assert np.abs(qc - qp).max() <= q_rtol * q_scale
        assert np.abs(vc - vp).max() <= v_rtol * v_scale
    return python[1], python[0], python[2]


@pytest.mark.parametrize("name", ["cantilever", "rotating_beam", "pendulum", "arc_cantilever"])
def test_engines_agree_on_the_shipped_scenes(name):
    # The whole run: thousands of steps of schemes that do not damp (trapezoidal), in which
    # round-off differences of the two engines (other summation orders, SIMD) grow - in the
    # rotating beam after the spin-up by about 5x per 2 s.  Positions still agree to 1e-11
    # of their scale (worst seen: 4e-13), velocities to 1e-6 of theirs (worst: 1.5e-7, the
    # quasi-static cantilever, where they are 1e-4 m/s), the Newton counters exactly.
    _compare(_shipped(name), q_rtol=1e-11, v_rtol=1e-6)


@pytest.mark.parametrize("integrator", ["trapezoidal", "generalized_alpha"])
@pytest.mark.parametrize("element,joint", [("beam2d", "revolute"), ("beam3d", "spherical")])
def test_engines_agree_with_joints(element, joint, integrator):
    counters, states, _ = _compare(_two_bodies(element, joint, integrator))
    assert counters["newton_iterations"] > counters["steps"]   # a real nonlinear motion
    assert np.abs(states[-1][1] - states[0][1]).max() > 1e-2   # it swung


@pytest.mark.parametrize("integrator", ["trapezoidal", "generalized_alpha"])
def test_engines_agree_with_a_hub_and_a_joint(integrator):
    _compare(_two_bodies("beam2d", "revolute", integrator, hub=True))


@pytest.mark.parametrize("integrator", ["trapezoidal", "generalized_alpha"])
def test_engines_agree_on_a_curved_body(integrator):
    _compare(_curved(integrator))


@pytest.mark.parametrize("integrator", ["trapezoidal", "generalized_alpha"])
def test_engines_agree_with_modified_newton(integrator):
    full, full_states, _ = _compare(_two_bodies("beam2d", "revolute", integrator))
    modified, modified_states, _ = _compare(_two_bodies("beam2d", "revolute", integrator),
                                         newton="modified")
    # fewer Jacobians and factorisations than iterations, and fewer than full Newton
    assert modified["factorisations"] == modified["jacobian_evaluations"]
    assert modified["jacobian_evaluations"] < modified["newton_iterations"]
    assert modified["jacobian_evaluations"] < full["jacobian_evaluations"]
    assert full["factorisations"] == full["newton_iterations"]
    # the same solution within the Newton tolerance's reach
    for (_, q_full, _), (_, q_modified, _) in zip(full_states, modified_states, strict=True):
        assert np.abs(q_full - q_modified).max() <= 1e-7


def test_engines_report_the_same_newton_failure():
    # the load grows until three iterations no longer reach the tolerance
    data = cantilever(elements=3, force=[0.0, -2e6], sensors=[],
                      law={"type": "linear_ramp", "duration": 0.1},
                      analysis_tables={"dynamic": {"t_end": 0.1, "step": 2e-3}})
    _, states, failure = _compare(data, max_iterations=3)
    assert failure is not None and "did not converge" in failure[1]
    # it failed after some steps, and every output before the failure is kept
    assert failure[0] >= 2 * 2e-3 and states[-1][0] == pytest.approx(failure[0] - 2e-3)


def test_engines_report_the_same_blow_up():
    # a force that overflows the elastic force kernels: non-finite at the first step
    data = cantilever(elements=2, force=[0.0, -1e305], sensors=[],
                      analysis_tables={"dynamic": {"t_end": 0.01, "step": 1e-3}})
    scene_ = parse_scene(data)
    model = Model(scene_)
    results = [_history(model, scene_.dynamic, name) for name in ("python", "compiled")]
    assert results[0][2] is not None and results[0][2] == results[1][2]
    assert results[0][1] == results[1][1]


def test_engine_choice():
    assert engines.choose(None, "c") == "compiled"
    assert engines.choose(None, "numpy") == "python"
    with pytest.raises(ValueError, match="engine: the compiled engine needs backend"):
        engines.choose("compiled", "numpy")
    with pytest.raises(ValueError, match="engine: expected one of"):
        engines.choose("fortran", "c")


def test_run_reports_engine_counters_and_built_modules(tmp_path):
    data = _shipped("rotating_beam", 0.05)
    summaries = {}
    for engine in ("python", "compiled"):
        summary, code = run(parse_scene(data), tmp_path / engine, engine=engine, quiet=True)
        assert code == 0
        summaries[engine] = summary
        written = json.loads((tmp_path / engine / "summary.json").read_text())
        assert written["dynamic"]["engine"] == engine
    compiled, python = summaries["compiled"]["dynamic"], summaries["python"]["dynamic"]
    integrator = data["analysis"]["dynamic"].get("integrator", "trapezoidal")
    assert f"stepper/{integrator}" in summaries["compiled"]["kernels"]
    assert not any(k.startswith("stepper") for k in summaries["python"]["kernels"])
    for key in ("steps", "newton_iterations", "jacobian_evaluations", "factorisations"):
        assert compiled[key] == python[key]
    for name, value in python["sensors_final"].items():
        assert compiled["sensors_final"][name] == pytest.approx(value, rel=1e-9, abs=1e-12)
