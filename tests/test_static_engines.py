"""The static analysis through either engine: the compiled one's Newton solve (``ancf_static``
of the generated step: its kernels, banded assembly, factorisation and joint solve) finds the
equilibrium the Python one finds, to round-off, on every shipped scene with a static analysis,
with joints, hubs and load stepping; failures are the same named divergences."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scenes_small import cantilever

import scenes
from runtime import Displacement, LinearRamp, Static, load_scene, run_scene
from runtime.solve import engines
from runtime.solve.static import ConvergenceError, solve_static

# load stepping (arc length makes its solves in Python whatever the engine:
# tests/test_arc_length.py)
STATIC_SCENES = [name for name in scenes.names()
                 if load_scene(scenes.path(name)).static is not None
                 and load_scene(scenes.path(name)).static.method == "load_stepping"]


def _both(scene):
    return {engine: run_scene(scene, engine=engine, progress=False)
            for engine in ("python", "compiled")}


@pytest.mark.parametrize("name", STATIC_SCENES)
def test_engines_find_the_same_equilibrium_on_the_shipped_scenes(name):
    scene = load_scene(scenes.path(name))
    scene = dataclasses.replace(scene, dynamic=None, modal=None)
    runs = _both(scene)
    python, compiled = runs["python"], runs["compiled"]
    assert python.status == compiled.status == "ok"
    scale = np.abs(python.static).max()
    np.testing.assert_allclose(compiled.static, python.static, rtol=0, atol=1e-12 * scale)
    for sensor, value in python.summary["static"]["sensors"].items():
        assert compiled.summary["static"]["sensors"][sensor] == pytest.approx(
            value, rel=1e-9, abs=1e-15)
    assert "stepper/trapezoidal" in compiled.summary["kernels"]
    assert not any(k.startswith("stepper/") for k in python.summary["kernels"])


def test_load_stepping_through_the_compiled_solve_is_the_python_one():
    # a large deflection needs several load steps; both engines take the same increments
    scene = cantilever(elements=8, length=1.0, height=0.02, width=0.02, force=[0.0, -2000.0],
                       law=LinearRamp(1.0), sensors=[Displacement("tip_y", "beam:-1", "y")],
                       static=Static(load_steps=8))
    runs = _both(scene)
    assert runs["python"].summary["static"]["load_steps"] == \
        runs["compiled"].summary["static"]["load_steps"] == 8
    tip = runs["python"].summary["static"]["sensors"]["tip_y"]
    assert tip < -0.1   # large deflection: geometrically nonlinear
    assert runs["compiled"].summary["static"]["sensors"]["tip_y"] == pytest.approx(tip,
                                                                                  rel=1e-10)


def test_a_failed_newton_solve_is_the_same_named_divergence():
    scene = cantilever(elements=4, force=[0.0, -1e9], static=Static(max_iterations=2))
    from runtime.model.model import Model

    model = Model(scene)
    settings = scene.static
    messages = []
    for name in ("python", "compiled"):
        with pytest.raises(ConvergenceError) as info:
            solve_static(model, settings, engines.static_newton(name, model, settings,
                                                                "trapezoidal"))
        messages.append(str(info.value))
    assert messages[0].split(" (last step")[0] == messages[1].split(" (last step")[0]
    assert "load stepping reached 1/1024 of the load" in messages[1]
