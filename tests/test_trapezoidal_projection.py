"""The trapezoidal scheme's projection onto nonlinear constraint rows in the compiled step
(``project`` in templates/stepper.c.j2): the same states and counters as the Python
engine's ``ManifoldProjection`` on rigid mechanisms, a sliding joint and many rows (the KKT
system), and positions and velocities on the constraints after every step."""

from __future__ import annotations

import dataclasses
import tomllib

import numpy as np
import pytest
from scenes_small import compare_engines
from test_kkt_engines import _rigid_chain

from runtime.model.dae import DAESystem
from runtime.model.model import Model
from runtime.model.scene import load_scene, parse_scene
from runtime.solve import engines
from runtime.solve.compiled_engine import render
from scenes import path as scene_path

#: (scene, t_end (s), step (s)): short trapezoidal runs of shipped mechanisms
SHIPPED = {"double_pendulum": (0.1, 5e-4), "slider_crank": (0.05, 2.5e-4),
           "sliding_bead": (0.05, 5e-4)}


def _scene(name: str):
    if name == "rigid links (KKT)":
        return parse_scene(tomllib.loads(_rigid_chain(9))), {}
    t_end, step = SHIPPED[name]
    return load_scene(scene_path(name)), {"t_end": t_end, "step": step}


@pytest.mark.parametrize("name", [*SHIPPED, "rigid links (KKT)"])
def test_engines_agree_on_the_projection_and_it_holds_the_constraints(name):
    scene, times = _scene(name)
    settings = dataclasses.replace(scene.dynamic, integrator="trapezoidal", newton="full",
                                   output_every=None, **times)
    scene = dataclasses.replace(scene, dynamic=settings)
    model = Model(scene)
    runner = engines.make("compiled", model, settings, model.reference)
    assert runner.dae.nonlinear
    assert runner.kkt == (name == "rigid links (KKT)")
    # equal counters (full Newton), positions to 1e-12, velocities to 1e-9 of their largest
    counters, states, failure = compare_engines(scene)
    assert failure is None and counters["steps"] == round(settings.t_end / settings.step)
    assert np.abs(states[-1][1] - states[0][1]).max() > 1e-4       # it moved
    # after each step's projection: Phi(q) within the tolerance (m), and the velocities on
    # Phi_q v + Phi_t = 0 to round-off of the largest velocity
    drift = max(np.abs(model.constraint_values(q)).max() for _, q, _ in states)
    assert drift <= settings.tolerance * model.length_scale()
    speed = max(np.abs(v).max() for _, _, v in states)
    rate = max(np.abs(np.concatenate([model.joints @ v, model.holonomic.jacobian(q) @ v])).max()
               for _, q, v in states[1:])
    assert rate <= 1e-12 * speed


def test_the_projection_is_compiled_into_the_trapezoidal_step_only():
    model = Model(load_scene(scene_path("double_pendulum")))
    dae = DAESystem(model, model.reference)
    trapezoidal, alpha = (render(dae, integrator)[0] for integrator in
                          ("trapezoidal", "generalized_alpha"))
    assert "static int project(" in trapezoidal and "static int project(" not in alpha
