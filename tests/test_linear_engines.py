"""Every linear solver in both engines: the compiled step and the Python engine agree to
round-off with the banded and the sparse solver on a plate, a jointed mechanism and a
static analysis; the two solvers give the same motion; the automatic choice is the one it
says, and the run summary names it."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from scenes_small import compare_engines, scene

import scenes
from runtime import (
    Body,
    Clamp,
    CosineRamp,
    Dynamic,
    Gravity,
    LineForce,
    Material,
    Pin,
    Position,
    Rectangle,
    Solver,
    Spherical,
    load_scene,
    run_scene,
)
from runtime.catalog import LINEAR_SOLVERS, NEWTON_MODES
from runtime.model.model import Model
from runtime.model.settings import Static
from runtime.solve import engines, linear, static
from runtime.solve.compiled_engine import CompiledStatic

ALUMINIUM = Material("m", E=7.0e10, nu=0.3, rho=2700.0)


def _plate(solver: str | None, integrator: str = "trapezoidal", grid: int = 3,
           ramp: float = 0.01, **dynamic):
    """A square plate (``grid`` x ``grid`` elements) clamped on one edge under a line load on
    the opposite edge ramped up over ``ramp`` s."""
    body = Body("p", "plate3d", "m", rectangle=Rectangle((0.0, 0.0, 0.0), (0.3, 0.3),
                                                         (grid, grid)), thickness=0.005)
    return scene([body], [Clamp(edge="p:x=0")],
                 [LineForce("p:x=-1", [0.0, 0.0, -400.0], time_law=CosineRamp(ramp))],
                 [Position("tip_z", "p:-1", "z")], ALUMINIUM,
                 dynamic=Dynamic(**{"t_end": 0.02, "step": 1e-3, "integrator": integrator,
                                    **dynamic}),
                 solver=Solver(linear_solver=solver))


def _mechanism(solver: str | None, integrator: str = "trapezoidal"):
    """A pinned beam with a plate hanging from its tip by a spherical joint."""
    bodies = [Body("a", "beam3d", "m", 0.02, 0.02, 3, (0.0, 0, 0), (0.6, 0, 0)),
              Body("p", "plate3d", "m", rectangle=Rectangle((0.6, 0.0, 0.0), (0.3, 0.2), (2, 2)),
                   thickness=0.01)]
    return scene(bodies, [Pin("a:0"), Spherical(("a:-1", "p:0,0"))],
                 [Gravity([0.0, 0.0, -9.81])], [Position("tip_z", "p:-1", "z")], ALUMINIUM,
                 dynamic=Dynamic(t_end=0.03, step=1e-3, integrator=integrator),
                 solver=Solver(linear_solver=solver))


@pytest.mark.parametrize("integrator", ["trapezoidal", "generalized_alpha"])
@pytest.mark.parametrize("solver", LINEAR_SOLVERS)
def test_engines_agree_on_a_plate_with_every_solver(solver, integrator):
    counters, states, failure = compare_engines(_plate(solver, integrator))
    assert failure is None and counters["newton_iterations"] > counters["steps"]
    assert np.abs(states[-1][1] - states[0][1]).max() > 1e-4       # it bent


@pytest.mark.parametrize("solver", LINEAR_SOLVERS)
def test_engines_agree_on_a_jointed_mechanism_with_every_solver(solver):
    counters, states, _ = compare_engines(_mechanism(solver))
    assert np.abs(states[-1][1] - states[0][1]).max() > 1e-4       # it swung


@pytest.mark.parametrize("solver", LINEAR_SOLVERS)
def test_engines_agree_with_modified_newton_and_every_solver(solver):
    counters, _, _ = compare_engines(_plate(solver, newton="modified"))
    assert counters["factorisations"] < counters["newton_iterations"]


def test_both_solvers_give_the_same_motion():
    banded, sparse = (compare_engines(_plate(s))[1] for s in LINEAR_SOLVERS)
    scale = max(np.abs(q).max() for _, q, _ in banded)
    for (_, qb, _), (_, qs, _) in zip(banded, sparse, strict=True):
        assert np.abs(qb - qs).max() <= 1e-12 * scale


@pytest.mark.parametrize("solver", LINEAR_SOLVERS)
def test_static_equilibrium_is_the_same_with_every_solver_and_engine(solver):
    data = dataclasses.replace(_plate(solver), dynamic=None)
    model = Model(data)
    settings = Static(load_steps=2)
    python = static.solve_static(model, settings)
    compiled = static.solve_static(model, settings, CompiledStatic(model, settings,
                                                                   "trapezoidal"))
    reference = static.solve_static(Model(dataclasses.replace(
        data, solver=Solver(linear_solver="banded"))), settings)
    scale = np.abs(python.q).max()
    assert python.iterations == compiled.iterations
    assert np.abs(compiled.q - python.q).max() <= 1e-12 * scale
    assert np.abs(reference.q - python.q).max() <= 1e-12 * scale
    assert np.abs(python.q - model.reference).max() > 1e-4            # it bent


def test_the_automatic_choice_is_banded_for_chains_and_sparse_for_plates():
    chain = Model(load_scene(scenes.path("cantilever")))
    plate = Model(_plate(None, grid=16))
    assert linear.band_fill(chain.pattern) < linear.BAND_FILL_LIMIT < linear.band_fill(
        plate.pattern)
    assert linear.choose(chain.pattern) == "banded"
    assert linear.choose(plate.pattern) == "sparse"
    assert linear.choose(plate.pattern, "banded") == "banded"      # the scene's key wins
    for data, expected in ((load_scene(scenes.path("cantilever")), "banded"),
                           (_plate(None, grid=16), "sparse"),
                           (_plate("banded", grid=16), "banded")):
        model = Model(data)
        for name in engines.ENGINES:
            runner = engines.make(name, model, data.dynamic, model.reference)
            assert runner.linear_solver == expected


def test_the_summary_names_the_linear_solver():
    result = run_scene(_plate(None, grid=16, t_end=0.001), progress=False)
    assert result.summary["dynamic"]["linear_solver"] == "sparse"


def test_engines_take_the_same_auto_newton_decisions():
    # the rotating-beam-like driven arm: modified Newton's kept Jacobian goes stale in most
    # steps, so auto runs mostly full steps; the plate under a slow ramp keeps it
    arm = _mechanism(None)
    counts = {mode: compare_engines(arm, newton=mode)[0] for mode in NEWTON_MODES}
    auto, full, modified = counts["auto"], counts["full"], counts["modified"]
    assert modified["factorisations"] < auto["factorisations"] <= full["factorisations"]
    plate = compare_engines(_plate(None, ramp=1.0), newton="auto")[0]
    assert plate["factorisations"] < plate["steps"] / 4        # mostly modified steps


