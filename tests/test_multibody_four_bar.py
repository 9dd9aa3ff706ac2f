"""scenes/four_bar.toml, the flexible four-bar linkage (docs/multibody.md): both engines
and both integrators agree and keep the loop closed; with a stiff coupler the rocker
follows the rigid linkage's closure (the circle intersection) at the driven crank angle."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from test_multibody import run

from runtime.model.model import Model
from runtime.model.scene import load_scene
from scenes import path as scene_path

CRANK, COUPLER, ROCKER, GROUND = 0.15, 0.5, 0.35, 0.45


def _rigid_rocker_tip(phi: np.ndarray) -> np.ndarray:
    """The rocker's tip C (k, 2) of the rigid linkage at the crank angles phi (k,): the
    intersection of the circles about the crank pin (the coupler) and about the rocker's
    pivot (the rocker), on the branch of the scene's start (above the line from B to O_B)."""
    pin = CRANK * np.stack([np.cos(phi), np.sin(phi)], axis=1)
    pivot = np.array([GROUND, 0.0])
    span = pivot - pin
    distance = np.linalg.norm(span, axis=1)
    along = (COUPLER**2 - ROCKER**2 + distance**2) / (2 * distance)
    across = np.sqrt(COUPLER**2 - along**2)
    unit = span / distance[:, None]
    normal = np.stack([-unit[:, 1], unit[:, 0]], axis=1)
    return pin + along[:, None] * unit + across[:, None] * normal


def _scene(**dynamic):
    scene = load_scene(scene_path("four_bar"))
    return dataclasses.replace(scene, dynamic=dataclasses.replace(scene.dynamic, **dynamic))


@pytest.mark.parametrize("integrator", ["trapezoidal", "generalized_alpha"])
def test_engines_agree_on_the_four_bar_and_the_loop_stays_closed(integrator):
    # full Newton, for equal counters: with a kept Jacobian a step whose error estimate ends
    # within round-off of the tolerance stops one iteration apart in the two engines (auto
    # Newton on the four-bar: tests/test_engines.py)
    scene = _scene(t_end=0.3, integrator=integrator, output_every=None, newton="full")
    t, q, _, stepper = run(scene, "python")
    compiled = run(scene, "compiled")
    assert np.abs(compiled[1] - q).max() <= 1e-10
    assert compiled[3].counters == stepper.counters
    model = Model(scene)
    drift = max(max(np.abs(model.holonomic.value(x)).max(), np.abs(model.joints @ x).max())
                for x in q)
    assert drift <= scene.dynamic.tolerance
    assert stepper.counters.newton_iterations <= 3.0 * stepper.counters.steps


def test_a_stiff_coupler_closes_the_loop_as_the_rigid_linkage():
    """The coupler 100 times stiffer, over 1.5 crank revolutions (a quarter in the spin-up
    to 1 rev/s in 0.5 s, then 1.3 s at 1 rev/s): the crank is at its law, the rocker's tip
    at the rigid linkage's C to 1e-6 of the crank length (1.1e-7 measured; the coupler's
    stretch under its inertial loads, F L / EA with F below 5 N, is 1e-9 m)."""
    scene = _scene(t_end=1.8)
    stiff = dataclasses.replace(scene.materials["aluminium"], E=7.0e12)
    scene = dataclasses.replace(scene, materials={"aluminium": stiff})
    t, q, _, _ = run(scene, "compiled")
    model = Model(scene)
    crank, rocker = model.rigid["crank"].dofs, model.rigid["rocker"].dofs
    phi = np.unwrap(np.arctan2(q[:, crank[4]], q[:, crank[3]]))
    law = scene.constraints[0].angle.sample(t)[0]
    assert np.abs(phi - np.pi / 2 - law).max() <= 1e-12
    assert phi[-1] - phi[0] > 3 * np.pi                   # 1.5 revolutions
    tip = q[:, rocker[:2]] + ROCKER * q[:, rocker[3:5]]   # origin + 0.35 u
    assert np.abs(tip - _rigid_rocker_tip(phi)).max() <= 1e-6 * CRANK
