"""The Exudyn peer models of runtime/studies/peers.py are faithful to the paper problems: the
cantilever's static deflection and first frequency against the closed forms, short dynamic
runs, and the rotating beam against our own solver.  Skipped without Exudyn."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
from scenes_small import cantilever_frequency, simulate, tip_deflection

from runtime import load_scene, run_scene
from runtime.studies import peers

pytestmark = pytest.mark.skipif(
    not peers.exudyn_available(),
    reason="exudyn is not importable (optional peer: pip install exudyn==1.13.6)")

SCENES = Path(__file__).resolve().parent.parent / "scenes"
C = peers.CANTILEVER


def test_cantilever_static_deflection_is_the_closed_form():
    closed = tip_deflection(C["force"], C["E"], C["height"], C["width"], C["length"])
    assert closed == pytest.approx(1.136e-2, abs=1e-5)
    assert peers.exudyn_cantilever_static(10) == pytest.approx(-closed, rel=0.01)


def test_cantilever_first_frequency_is_the_closed_form():
    closed = cantilever_frequency(C["E"], C["rho"], C["height"], C["width"], C["length"])
    omega = peers.exudyn_cantilever_frequencies(10, modes=2)
    assert closed == pytest.approx(16.24, abs=0.01)
    assert omega == pytest.approx([closed, closed], rel=0.005)  # bending in y and in z


@pytest.mark.parametrize("integrator", peers.INTEGRATORS)
def test_cantilever_short_run_modified_and_full_newton_agree(integrator):
    modified = peers.exudyn_cantilever(10, t_end=0.05, integrator=integrator)
    full = peers.exudyn_cantilever(10, t_end=0.05, newton="full", integrator=integrator)
    assert modified.steps == full.steps == 50
    assert full.jacobian_evaluations == full.newton_iterations
    assert modified.jacobian_evaluations < modified.newton_iterations
    assert modified.tip_displacement < 0  # the load pulls the tip down (-y)
    assert modified.tip_displacement == pytest.approx(full.tip_displacement, rel=1e-4)
    assert modified.simulate_s > 0 and modified.build_s > 0
    assert "modified Newton" in modified.note and "full Newton" in full.note


def test_rotating_beam_matches_our_solver_at_two_seconds():
    scene = load_scene(SCENES / "rotating_beam.toml")
    dynamic = dataclasses.replace(scene.dynamic, t_end=2.0, integrator="generalized_alpha",
                                  rho_inf=0.8)   # rho_inf 0.8 on both sides
    ours = simulate(dataclasses.replace(scene, dynamic=dynamic))["tip_transverse"][-1]
    peer = peers.exudyn_rotating_beam(10, t_end=2.0, step=dynamic.step, rho_inf=0.8)
    assert peer.steps == 400
    # the beam lags behind the spinning hub: a few cm, the same in both models (the peer is an
    # Euler-Bernoulli cable, ours a shear-deformable continuum beam)
    assert -0.2 < ours < -0.05
    assert peer.tip_displacement == pytest.approx(ours, rel=0.02)


def test_unknown_settings_are_refused():
    with pytest.raises(ValueError, match="newton"):
        peers.exudyn_cantilever(2, t_end=0.01, newton="quasi")
    with pytest.raises(ValueError, match="integrator"):
        peers.exudyn_rotating_beam(2, t_end=0.01, integrator="euler")


def test_slider_crank_peer_starts_as_the_shipped_scene_and_moves_as_our_mechanism():
    """Exudyn's slider-crank (RigidBody2D crank driven by a coordinate constraint on its
    angle, ANCFCable2D rod, MassPoint2D slider) starts from the shipped scene's positions
    and velocities, and its slider follows ours (rigid flywheel in natural coordinates
    driven by a rheonomic row, beam3d rod, nonlinear joints) to 2e-6 of the crank radius
    over the scene's 0.7 s, and to 1e-9 m with our rod of cable3d elements (Exudyn's
    element in 3D) and with the 2D scene (planar crank, cable2d rod, 2D slider): two codes
    sharing nothing, a nearly rigid aluminium rod."""
    from runtime.studies.bench_solvers import cable_rod

    scene = load_scene(SCENES / "slider_crank.toml")
    rod = next(body for body in scene.bodies if body.name == "rod")
    start = peers._slider_crank_kinematics()
    assert start["pin"] == pytest.approx(rod.start[:2], abs=1e-15)
    assert start["slider"] == pytest.approx(rod.end[:2], abs=1e-15)
    assert start["pin_velocity"] == pytest.approx(rod.initial_velocity[:2], abs=1e-14)
    assert start["rod_rate"] == pytest.approx(rod.initial_angular_velocity.omega[2], abs=1e-14)
    assert scene.constraints[0].angle.rate(0.0) == peers.SLIDER_CRANK["omega"]
    every = 0.01
    scene = dataclasses.replace(scene, dynamic=dataclasses.replace(
        scene.dynamic, output_every=every))
    peer = peers.exudyn_slider_crank(every=every)
    t, x = peer.history
    assert t[-1] == pytest.approx(scene.dynamic.t_end)
    assert np.ptp(x) > 1.9 * peers.SLIDER_CRANK["radius"]     # the slider's whole stroke
    planar = load_scene(SCENES / "slider_crank_2d.toml")
    planar = dataclasses.replace(planar, dynamic=dataclasses.replace(
        planar.dynamic, output_every=every))
    for ours, tolerance in ((scene, 2e-6 * peers.SLIDER_CRANK["radius"]),
                            (cable_rod(scene), 1e-9), (planar, 1e-9)):
        result = run_scene(ours, progress=False)
        assert result.status == "ok"
        difference = np.interp(t, result.sensors["t"], result.sensors["slider_x"]) - x
        assert np.abs(difference).max() < tolerance


def test_four_bar_peer_swings_its_rocker_as_our_linkage():
    """Exudyn's four-bar (RigidBody2D crank driven by a coordinate constraint on its angle,
    ANCFCable2D coupler, RigidBody2D rocker) starts from the shipped scene's closure, and
    its rocker's angle follows ours over the scene's 1.5 s (a 58 degree swing) to 1e-8
    rad with the shipped beam3d coupler and to 1e-9 rad with a cable3d one (7.6e-10 and
    3.2e-11 measured)."""
    from runtime.model.model import Model
    from runtime.studies.bench_solvers import cable_rod

    scene = load_scene(SCENES / "four_bar.toml")
    coupler = next(body for body in scene.bodies if body.name == "coupler")
    assert peers.four_bar_tip() == pytest.approx(coupler.end[:2], abs=1e-15)
    every = 0.01
    scene = dataclasses.replace(scene, dynamic=dataclasses.replace(
        scene.dynamic, output_every=every))
    peer = peers.exudyn_four_bar(every=every)
    t, angle = peer.history
    assert t[-1] == pytest.approx(scene.dynamic.t_end)
    assert np.ptp(angle) > 1.0
    cable = cable_rod(dataclasses.replace(scene, sensors=()), "coupler")
    for ours, tolerance in ((scene, 1e-8), (cable, 1e-9)):
        result = run_scene(ours, progress=False, store_states=True)
        assert result.status == "ok"
        rocker = Model(ours).rigid["rocker"].dofs
        q = result.states.q
        ours_angle = np.arctan2(q[:, rocker[4]], q[:, rocker[3]])
        difference = np.interp(t, result.states.t, ours_angle) - angle
        assert np.abs(difference).max() < tolerance
