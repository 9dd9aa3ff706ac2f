"""The ``acceleration`` sensor: -g for a falling body (both engines), central differences of
the velocity sensor on a smooth swing, the trapezoidal rule's own relation between the
velocities and accelerations it advanced, and zero in a static state."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from runtime import (
    Acceleration,
    Body,
    Clamp,
    Constant,
    Dynamic,
    Gravity,
    Material,
    Pin,
    PointForce,
    Scene,
    Solver,
    Static,
    Velocity,
    run_scene,
)

G = 9.81
STEEL = Material("steel", E=2.1e11, nu=0.0, rho=7800.0)


@pytest.mark.parametrize("engine", ["compiled", "python"])
def test_acceleration_of_a_falling_body_is_minus_g(engine):
    scene = Scene(materials=[STEEL],
                  bodies=[Body("rod", "beam3d", "steel", height=0.02, width=0.02, elements=3,
                               start=(0.0, 0.0, 0.0), end=(1.0, 0.0, 0.0))],
                  loads=[Gravity((0.0, 0.0, -G), time_law=Constant())],
                  sensors=[Acceleration("az", "rod:-1", "z"), Acceleration("a", "rod:1", "norm"),
                           Acceleration("ax", "rod:0", "x")],
                  dynamic=Dynamic(t_end=0.05, step=1e-3, output_every=1e-2),
                  solver=Solver(engine=engine))
    result = run_scene(scene, progress=False)
    # exact but for rounding: the elastic force of a translated stiff rod is zero only in
    # exact arithmetic; its rounding, eps E A times the drop over the rod, is felt by an
    # element's mass (about 1e-9 m/s^2 here, a few ulps of g; the rounding of the kernels
    # depends on the machine's vector instructions)
    area, length = 0.02 * 0.02, 1.0 / 3
    drop = G * 0.05**2 / 2
    rounding = (10 * np.finfo(float).eps * STEEL.E * area * drop / length
                / (STEEL.rho * area * length))
    np.testing.assert_allclose(result.sensors["az"], -G, rtol=0, atol=rounding)
    np.testing.assert_allclose(result.sensors["a"], G, rtol=0, atol=rounding)
    np.testing.assert_allclose(result.sensors["ax"], 0.0, atol=rounding)


def _swing(integrator: str, engine: str = "compiled", **dynamic) -> Scene:
    """A stiff rod pinned at one end swinging down under gravity (its stiff vibrations
    damped by Kelvin-Voigt damping)."""
    return Scene(materials=[Material("al", E=7e10, nu=0.0, rho=2700.0, damping=1e-3)],
                 bodies=[Body("rod", "beam2d", "al", height=0.05, width=0.05, elements=4,
                              start=(0.0, 0.0), end=(1.0, 0.0))],
                 constraints=[Pin("rod:0")], loads=[Gravity((0.0, -G))],
                 sensors=[Velocity("vx", "rod:-1", "x"), Velocity("vy", "rod:-1", "y"),
                          Acceleration("ax", "rod:-1", "x"), Acceleration("ay", "rod:-1", "y")],
                 dynamic=Dynamic(t_end=0.5, step=5e-4, integrator=integrator, **dynamic),
                 solver=Solver(engine=engine))


def test_acceleration_is_the_central_difference_of_the_velocity_sensor():
    result = run_scene(_swing("generalized_alpha", rho_inf=0.5), progress=False)
    h = 5e-4
    for c in "xy":
        v, a = np.asarray(result.sensors[f"v{c}"]), np.asarray(result.sensors[f"a{c}"])
        central = (v[2:] - v[:-2]) / (2 * h)
        assert np.abs(a).max() > 20.0
        # after the release's transient (20 steps), to O(h^2)
        np.testing.assert_allclose(a[21:-1], central[20:], rtol=0,
                                   atol=2e-4 * np.abs(a).max())


def test_trapezoidal_velocities_and_accelerations_obey_its_rule():
    # v_{n+1} - v_n = h (a_n + a_{n+1}) / 2 exactly (no joints: no projection), with the
    # accelerations solved from the equations of motion at the output states (to the
    # Newton tolerance of the integrator's own accelerations: tightened here).  Full
    # Newton: the output accelerations are re-solved at the output states, where a position
    # error dq of the rod's stiff axial modes shows as omega^2 dq (about 1e9 dq); this
    # checks the sensor against the integrator's rule, for which full Newton's quadratic
    # convergence makes that error negligible (a kept Jacobian stops within the tolerance:
    # 1.2e-7 of the largest a_x here, against 0.8e-7 with full Newton)
    scene = dataclasses.replace(_swing("trapezoidal"),
                                dynamic=Dynamic(t_end=0.1, step=5e-4, tolerance=1e-13,
                                                newton="full"))
    result = run_scene(scene, progress=False)
    for c in "xy":
        v, a = np.asarray(result.sensors[f"v{c}"]), np.asarray(result.sensors[f"a{c}"])
        np.testing.assert_allclose(np.diff(v) / 5e-4, (a[1:] + a[:-1]) / 2, rtol=0,
                                   atol=1e-7 * np.abs(a).max())


def test_acceleration_is_zero_in_a_static_state():
    scene = Scene(materials=[STEEL],
                  bodies=[Body("beam", "beam2d", "steel", height=0.1, width=0.1, elements=2,
                               start=(0.0, 0.0), end=(1.0, 0.0))],
                  constraints=[Clamp("beam:0")], loads=[PointForce("beam:-1", (0.0, -1e3))],
                  sensors=[Acceleration("ay", "beam:-1", "y")], static=Static())
    assert run_scene(scene, progress=False).summary["static"]["sensors"]["ay"] == 0.0


@pytest.mark.parametrize("engine", ["compiled", "python"])
def test_accelerations_include_follower_loads(engine):
    # a cantilever under a tip force that turns with the tip (follower): the trapezoidal
    # relation holds only if the output accelerations feel the turned force, as the
    # integrator did; the clamp's reaction in the tip's frame is minus the force there
    force = (0.0, -2e4)
    scene = Scene(materials=[STEEL],
                  bodies=[Body("beam", "beam2d", "steel", height=0.05, width=0.05, elements=4,
                               start=(0.0, 0.0), end=(2.0, 0.0))],
                  constraints=[Clamp("beam:0")],
                  loads=[PointForce("beam:-1", force, follower=True)],
                  sensors=[Velocity("vy", "beam:-1", "y"), Acceleration("ay", "beam:-1", "y")],
                  dynamic=Dynamic(t_end=0.02, step=2e-4, tolerance=1e-13),
                  solver=Solver(engine=engine))
    result = run_scene(scene, progress=False)
    v, a = np.asarray(result.sensors["vy"]), np.asarray(result.sensors["ay"])
    assert np.abs(v).max() > 0.1
    np.testing.assert_allclose(np.diff(v) / 2e-4, (a[1:] + a[:-1]) / 2, rtol=0,
                               atol=1e-7 * np.abs(a).max())
