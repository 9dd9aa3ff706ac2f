"""The ``reaction`` sensor against closed forms: the equilibrium of a cantilever (static and
at rest after a damped dynamic run, both engines), a weld's multipliers, the pin of a
pendulum at the bottom of its swing (m (g + r_c omega^2)), the driving torque and
centripetal force of a prescribed hub (I theta'', m r_c omega^2), and the resultant held by
a clamped plate edge."""

from __future__ import annotations

import numpy as np
import pytest

from runtime import (
    Body,
    Clamp,
    CosineRamp,
    Dynamic,
    Gravity,
    Hub,
    LineForce,
    Material,
    Pin,
    PointForce,
    Position,
    Reaction,
    Rectangle,
    Scene,
    Solver,
    SpinUp,
    Static,
    Velocity,
    Weld,
    run_scene,
)

P, L, H = 300.0, 5.0, 0.1
STEEL = Material("steel", E=132e9, nu=0.0, rho=8245.2)
G = 9.81


def _cantilever(kind: str, engine: str, **extra) -> Scene:
    dim = 3 if "3d" in kind else 2
    z = (0.0,) * (dim - 2)
    return Scene(materials=[extra.pop("material", STEEL)],
                 bodies=[Body("beam", kind, "steel", height=H, width=H, elements=4,
                              start=(0.0, 0.0, *z), end=(L, 0.0, *z))],
                 constraints=[Clamp("beam:0")],
                 loads=[PointForce("beam:-1", (0.0, -P, *z), **extra.pop("load", {}))],
                 sensors=[Reaction("Fx", "beam:0", "force", "x"),
                          Reaction("Fy", "beam:0", "force", "y"),
                          Reaction("Mz", "beam:0", "moment", "z"),
                          Reaction("M", "beam:0", "moment", "norm"),
                          Position("tip_x", "beam:-1", "x")],
                 solver=Solver(engine=engine), **extra)


def _equilibrium(values: dict) -> None:
    """The clamp holds the tip load: force +P up, moment P x_tip about z (the tip's deformed
    lever arm), the whole of the moment."""
    np.testing.assert_allclose(values["Fy"], P, rtol=1e-9)
    assert abs(values["Fx"]) < 1e-6 * P
    np.testing.assert_allclose(values["Mz"], P * values["tip_x"], rtol=1e-8)
    np.testing.assert_allclose(values["M"], abs(values["Mz"]), rtol=1e-12)


@pytest.mark.parametrize("engine", ["compiled", "python"])
@pytest.mark.parametrize("kind", ["beam2d", "beam3d", "cable2d", "beam3d_3node"])
def test_clamp_reaction_of_a_static_cantilever_is_the_load_and_P_L(kind, engine):
    result = run_scene(_cantilever(kind, engine, static=Static()), progress=False)
    values = result.summary["static"]["sensors"]
    _equilibrium(values)
    np.testing.assert_allclose(values["Mz"], P * L, rtol=1e-4)   # small deflection


def test_clamp_reaction_at_rest_after_a_damped_dynamic_run_is_the_load():
    damped = Material("steel", E=132e9, nu=0.0, rho=8245.2, damping=0.12)  # critical, 16 rad/s
    scene = _cantilever("beam2d", "compiled", material=damped,
                        load={"time_law": CosineRamp(duration=0.5)},
                        dynamic=Dynamic(t_end=2.0, step=2e-3, output_every=0.1))
    result = run_scene(scene, progress=False)
    assert result.status == "ok"
    final = {name: values[-1] for name, values in result.sensors.items()}
    np.testing.assert_allclose(final["Fy"], P, rtol=1e-6)
    np.testing.assert_allclose(final["Mz"], P * final["tip_x"], rtol=1e-6)
    assert abs(result.sensors["Fy"][0]) < 1e-9    # no load at t = 0, at rest


@pytest.mark.parametrize("engine", ["compiled", "python"])
def test_weld_reaction_from_the_multipliers_carries_the_load(engine):
    # a cantilever of two welded halves: the weld passes the tip load and its moment about
    # the weld to the second half (on its first node), and the opposite to the first
    scene = Scene(materials=[STEEL],
                  bodies=[Body("a", "beam2d", "steel", height=H, width=H, elements=2,
                               start=(0.0, 0.0), end=(L / 2, 0.0)),
                          Body("b", "beam2d", "steel", height=H, width=H, elements=2,
                               start=(L / 2, 0.0), end=(L, 0.0))],
                  constraints=[Clamp("a:0"), Weld(("a:-1", "b:0"))],
                  loads=[PointForce("b:-1", (0.0, -P))],
                  sensors=[Reaction("on_b_y", "b:0", "force", "y"),
                           Reaction("on_a_y", "a:-1", "force", "y"),
                           Reaction("on_b_m", "b:0", "moment", "z"),
                           Reaction("on_a_m", "a:-1", "moment", "z"),
                           Reaction("clamp_m", "a:0", "moment", "z"),
                           Position("tip_x", "b:-1", "x"), Position("weld_x", "b:0", "x")],
                  static=Static(), solver=Solver(engine=engine))
    values = run_scene(scene, progress=False).summary["static"]["sensors"]
    np.testing.assert_allclose(values["on_b_y"], P, rtol=1e-8)
    np.testing.assert_allclose(values["on_a_y"], -P, rtol=1e-8)
    arm = values["tip_x"] - values["weld_x"]
    np.testing.assert_allclose(values["on_b_m"], P * arm, rtol=1e-6)
    np.testing.assert_allclose(values["on_a_m"], -P * arm, rtol=1e-6)
    np.testing.assert_allclose(values["clamp_m"], P * values["tip_x"], rtol=1e-8)


def _pendulum(engine: str, t_end: float = 0.6) -> Scene:
    """A stiff rod (1 m, 5 cm square aluminium) pinned at one end, released horizontally; its
    stiff vibrations (bending from 1100 rad/s, axial 8000 rad/s) damped out by Kelvin-Voigt
    damping (alpha = 1 ms) and generalized-alpha (which the trapezoidal rule, undamped at
    high frequencies, would leave as a step-to-step oscillation of the accelerations)."""
    return Scene(materials=[Material("al", E=7e10, nu=0.0, rho=2700.0, damping=1e-3)],
                 bodies=[Body("rod", "beam2d", "al", height=0.05, width=0.05, elements=4,
                              start=(0.0, 0.0), end=(1.0, 0.0))],
                 constraints=[Pin("rod:0")], loads=[Gravity((0.0, -G))],
                 sensors=[Reaction("Fy", "rod:0", "force", "y"),
                          Position("x", "rod:-1", "x"), Velocity("vx", "rod:-1", "x"),
                          Velocity("vy", "rod:-1", "y")],
                 dynamic=Dynamic(t_end=t_end, step=5e-4, integrator="generalized_alpha",
                                 rho_inf=0.5),
                 solver=Solver(engine=engine))


def test_pendulum_pin_force_at_the_bottom_is_m_g_plus_rc_omega_squared():
    result = run_scene(_pendulum("compiled"), progress=False)
    s = {name: np.asarray(v) for name, v in result.sensors.items()}
    i = np.flatnonzero((s["x"][:-1] > 0) & (s["x"][1:] <= 0))[0]   # the tip passes under
    f = s["x"][i] / (s["x"][i] - s["x"][i + 1])

    def at(name: str) -> float:
        return float(s[name][i] + f * (s[name][i + 1] - s[name][i]))

    mass, arm = 2700.0 * 0.05 * 0.05 * 1.0, 0.5
    omega = np.hypot(at("vx"), at("vy")) / 1.0
    np.testing.assert_allclose(at("Fy"), mass * (G + arm * omega**2), rtol=5e-4)
    # and the rigid rod's omega^2 = 3 g / L: 2.5 m g
    np.testing.assert_allclose(at("Fy"), 2.5 * mass * G, rtol=2e-3)


def test_hub_reaction_is_the_driving_torque_and_the_centripetal_force():
    length, rho, side = 2.0, 2700.0, 0.05
    law = SpinUp(omega=2.0, t_ramp=1.0)
    scene = Scene(materials=[Material("al", E=7e10, nu=0.0, rho=rho)],
                  bodies=[Body("b", "beam2d", "al", height=side, width=side, elements=4,
                               start=(0.0, 0.0), end=(length, 0.0))],
                  constraints=[Hub("b:0", angle=law)],
                  sensors=[Reaction("torque", "b:0", "moment", "z"),
                           Reaction("radial", "b:0", "force", "x", frame="b:0")],
                  dynamic=Dynamic(t_end=1.5, step=1e-3, output_every=0.05))
    result = run_scene(scene, progress=False)
    t = np.asarray(result.sensors["t"])
    _, omega, alpha = law.sample(t)
    mass = rho * side * side * length
    torque, radial = np.asarray(result.sensors["torque"]), np.asarray(result.sensors["radial"])
    # a stiff rod: I theta'' with I = m L^2 / 3 about the hub, up to its vibration
    np.testing.assert_allclose(torque, mass * length**2 / 3 * alpha, rtol=0, atol=1.5)
    assert torque.max() > 60.0
    after = t > 1.0       # constant speed: the hub pulls the rod in by m (L / 2) omega^2
    np.testing.assert_allclose(radial[after], -mass * length / 2 * omega[after] ** 2,
                               rtol=1e-3)


@pytest.mark.parametrize("engine", ["compiled", "python"])
def test_reaction_of_a_clamped_plate_edge_is_the_resultant_of_the_line_load(engine):
    # a strip a x b clamped along x = 0, a line load q (N/m) down along x = a: the edge
    # holds q b up and the moment of the load about its first node (the corner at the
    # origin): (q b^2 / 2, -q a b, 0) (a small deflection: the lever arms of the reference)
    a, b, q = 1.0, 0.2, 100.0
    scene = Scene(materials=[Material("steel", E=2.1e11, nu=0.0, rho=7850.0)],
                  bodies=[Body("plate", "plate3d", "steel", thickness=0.01,
                               rectangle=Rectangle((0.0, 0.0, 0.0), (a, b), (4, 2)))],
                  constraints=[Clamp(edge="plate:x=0")],
                  loads=[LineForce(edge="plate:x=-1", force_per_length=(0.0, 0.0, -q))],
                  sensors=[Reaction(f"{quantity}_{c}", None, quantity, c, edge="plate:x=0")
                           for quantity in ("force", "moment") for c in "xyz"]
                  + [Reaction("corner", "plate:0,0", "force", "z")],
                  static=Static(), solver=Solver(engine=engine))
    values = run_scene(scene, progress=False).summary["static"]["sensors"]
    np.testing.assert_allclose([values[f"force_{c}"] for c in "xyz"], [0.0, 0.0, q * b],
                               rtol=1e-9, atol=1e-9 * q * b)
    np.testing.assert_allclose([values[f"moment_{c}"] for c in "xyz"],
                               [q * b**2 / 2, -q * a * b, 0.0], rtol=1e-5, atol=1e-9 * q * a * b)
    assert 0.0 < values["corner"] < q * b    # one node's share


def test_clamp_reaction_balances_a_follower_tip_force_in_the_tip_frame():
    # the tip force turns with the tip (follower, its components in the tip's frame): at
    # equilibrium the clamp holds minus that force, whose components in the tip's frame are
    # those of the load, and its moment is that of the load about the clamp
    load = (0.0, -2e4)
    scene = Scene(materials=[STEEL],
                  bodies=[Body("beam", "beam2d", "steel", height=0.05, width=0.05, elements=8,
                               start=(0.0, 0.0), end=(2.0, 0.0))],
                  constraints=[Clamp("beam:0")],
                  loads=[PointForce("beam:-1", load, follower=True)],
                  sensors=[Reaction("Rx", "beam:0", "force", "x", frame="beam:-1"),
                           Reaction("Ry", "beam:0", "force", "y", frame="beam:-1"),
                           Reaction("R", "beam:0", "force", "norm"),
                           Reaction("Fx_global", "beam:0", "force", "x")],
                  static=Static(load_steps=4))
    values = run_scene(scene, progress=False).summary["static"]["sensors"]
    np.testing.assert_allclose([values["Rx"], values["Ry"]], [0.0, 2e4], rtol=1e-8,
                               atol=1e-8 * 2e4)
    np.testing.assert_allclose(values["R"], 2e4, rtol=1e-10)
    # the tip turned down: the load (along its -t2) points back towards -x, the clamp +x
    assert values["Fx_global"] > 100.0
