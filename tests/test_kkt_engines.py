"""Many joints through the KKT system (``runtime.solve.linear.KKTSystem``) in both engines:
the same states as the Schur complement of the banded solver, and the two engines agreeing
to round-off, for linear joints (a chain of beams) and quadratic rows (rigid links)."""

from __future__ import annotations

import dataclasses
import tomllib

import numpy as np
import pytest
from scenes_small import compare_engines, engine_history

from runtime.model.model import Model
from runtime.model.scene import parse_scene
from runtime.solve import engines, linear
from runtime.studies.bench_steps import joint_chain_scene


def _rigid_chain(links: int) -> str:
    """TOML of ``links`` steel boxes in a line along x, the first on a spherical joint at the
    origin, each on a spherical joint to the next, swinging under gravity."""
    text = []
    for i in range(links):
        text.append(f"""
[[body]]
type = "rigid"
name = "link{i}"
box = {{size = [0.2, 0.02, 0.02]}}
density = 7800.0
position = [{0.2 * i + 0.1}, 0.0, 0.0]
[[constraint]]
type = "body_spherical"
body = "link{i}"
point = [-0.1, 0.0, 0.0]
""" + (f'other = "link{i - 1}"\nother_point = [0.1, 0.0, 0.0]\n' if i else ""))
    text.append("""
[[load]]
type = "gravity"
acceleration = [0.0, -9.81, 0.0]
[analysis.dynamic]
t_end = 0.05
step = 1e-3
integrator = "generalized_alpha"
newton = "full"
""")
    return "".join(text)


def _scenes():
    chain = joint_chain_scene(30, 30)
    chain = dataclasses.replace(chain, dynamic=dataclasses.replace(chain.dynamic,
                                                                  newton="full"))
    return {"beam links": chain, "rigid links": parse_scene(tomllib.loads(_rigid_chain(9)))}


@pytest.mark.parametrize("name", ["beam links", "rigid links"])
def test_many_joints_go_through_the_kkt_system_in_both_engines(name):
    scene = _scenes()[name]
    model = Model(scene)
    runner = engines.make("compiled", model, scene.dynamic, model.reference)
    assert runner.dae.constraint_rows >= linear.KKT_ROWS
    assert runner.kkt and runner.linear_solver == "sparse"
    counters, states, failure = compare_engines(scene, q_rtol=1e-12, v_rtol=1e-9)
    assert failure is None and counters["newton_iterations"] > counters["steps"]
    # the Schur complement of the banded solver (forced) gives the same motion
    banded = dataclasses.replace(scene, solver=dataclasses.replace(scene.solver,
                                                                  linear_solver="banded"))
    schur = engine_history(Model(banded), banded.dynamic, "compiled")[0]
    scale = max(np.abs(q).max() for _, q, _ in states)
    assert max(np.abs(q - qs).max() for (_, q, _), (_, qs, _) in zip(
        states, schur, strict=True)) <= 1e-12 * scale
    assert np.abs(states[-1][1] - states[0][1]).max() > 1e-4      # it moved
