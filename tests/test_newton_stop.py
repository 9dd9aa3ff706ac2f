"""Newton's stop with a kept Jacobian (``runtime.solve.python_engine``,
``Integrator.iterations_left``): it bounds the accelerations of a step, not only their effect
on the positions, against a full-Newton step converged to round-off; and ``auto`` Newton, the
default, moves the shipped mechanisms as full Newton does to the tolerance."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import scenes
from runtime import Body, Dynamic, Gravity, Material, Pin, Scene
from runtime.model.model import Model
from runtime.model.scene import load_scene
from runtime.solve import engines

H = 5e-4
#: a loose tolerance, so that the step's accelerations are compared far above round-off
#: (4 eps |q| / h^2 = 4e-9 m/s^2 here)
TOLERANCE = 1e-8


def _rod(newton: str, tolerance: float = TOLERANCE) -> tuple[Model, Dynamic]:
    """A stiff damped aluminium rod pinned at one end swinging down under gravity
    (trapezoidal): its axial modes make k (dF/dq) dominate the iteration matrix."""
    scene = Scene(materials=[Material("al", E=7e10, nu=0.0, rho=2700.0, damping=1e-3)],
                  bodies=[Body("rod", "beam2d", "al", height=0.05, width=0.05, elements=4,
                               start=(0.0, 0.0), end=(1.0, 0.0))],
                  constraints=[Pin("rod:0")], loads=[Gravity((0.0, -9.81))],
                  dynamic=Dynamic(t_end=0.1, step=H, newton=newton, tolerance=tolerance))
    return Model(scene), scene.dynamic


def test_a_kept_jacobian_step_bounds_its_accelerations():
    model, settings = _rod("modified")
    stepper = engines.make("python", model, settings, model.reference.copy())
    state = stepper.initial_state()
    for n in range(1, 41):     # the Jacobian kept since the first steps
        state = stepper.advance(state, n, H)
    iterates = []
    iterations_left = stepper.iterations_left

    def record(increment, previous, v, a):
        iterates.append((np.abs(increment).max(), a.copy()))
        return iterations_left(increment, previous, v, a)

    stepper.iterations_left = record
    factorisations = stepper.counters.factorisations
    kept = stepper.advance(state, 41, H)
    assert stepper.counters.factorisations == factorisations    # a kept-Jacobian step
    assert len(iterates) >= 3
    reference_model, reference_settings = _rod("full", tolerance=1e-14)
    reference = engines.make("python", reference_model, reference_settings,
                             reference_model.reference.copy()).advance(state, 41, H)
    scale = max(np.abs(state.a).max(), np.abs(kept.a).max())
    bound = TOLERANCE * scale
    # within the bound (the contraction estimate is exact for a constant rate)
    assert np.abs(kept.a - reference.a).max() <= bound
    # the old stop (the correction's effect on the positions, h^2 / 4 times it, within the
    # tolerance times the length scale) ends at an iterate 100 times further off
    old = next(a for size, a in iterates
               if H * H / 4 * size <= TOLERANCE * model.length_scale())
    assert np.abs(old - reference.a).max() > 100 * bound


@pytest.mark.parametrize("name", ["double_pendulum", "slider_crank", "four_bar"])
def test_auto_newton_moves_the_mechanisms_as_full_newton_does(name):
    # every step of either mode is within the tolerance of its solution; over the whole
    # run the positions stay within tolerance x length scale of each other (worst: 1.1e-11
    # of it on the double pendulum; with the old stop 1.5e-7 to 5e-7)
    scene = load_scene(scenes.path(name))
    model = Model(scene)
    positions = {}
    for newton in ("full", "auto"):
        settings = dataclasses.replace(scene.dynamic, newton=newton)
        stepper = engines.make("compiled", model, settings, model.reference.copy())
        out: list[np.ndarray] = []
        stepper.run(settings.t_end, settings.step,
                    lambda t, q, v, out=out: out.append(q.copy()))
        positions[newton] = np.array(out)
    assert scene.dynamic.newton == "auto"     # the default
    difference = np.abs(positions["auto"] - positions["full"]).max()
    assert difference <= scene.dynamic.tolerance * model.length_scale()
