"""Solver layer: constraints, loads, static / modal / dynamic analyses, sensors, the paper's
acceptance values, and agreement of methods, backends and integrators.

Small models throughout (2-10 elements, short runs).  Every tolerance comes from beam theory,
the discretisation, the time step or the Newton tolerance (1e-10 of the model's length scale),
never from a previous output of the code.
"""

from __future__ import annotations

import dataclasses
import math
import time
from pathlib import Path

import numpy as np
import pytest
from scenes_small import (
    STEEL,
    body,
    cantilever,
    cantilever_frequency,
    scene,
    second_moment,
    simulate,
    tip_deflection,
)
from scipy.integrate import solve_ivp
from scipy.optimize import brentq
from scipy.spatial.transform import Rotation

import scenes
from runtime import (
    Clamp,
    Constant,
    ConstantRate,
    ConstraintViolation,
    CosineRamp,
    Displacement,
    Dynamic,
    Gravity,
    Hub,
    KineticEnergy,
    LinearRamp,
    Material,
    Modal,
    NodeRef,
    Pin,
    PointForce,
    Position,
    PotentialEnergy,
    Revolute,
    Scene,
    Sine,
    Spherical,
    SpinUp,
    Static,
    StrainEnergy,
    Table,
    TotalEnergy,
    load_scene,
)
from runtime.app.run import run
from runtime.model.items.sensors import Sensors
from runtime.model.model import Model
from runtime.solve import static as analysis

SCENES = Path(__file__).resolve().parent.parent / "scenes"
G = 9.81
ALUMINIUM = Material("m", E=7.0e10, nu=0.0, rho=2700.0)


def shipped(name: str, **dynamic) -> Scene:
    """A shipped scene, its dynamic analysis changed by ``dynamic``."""
    scene_ = load_scene(scenes.path(name))
    return dataclasses.replace(scene_, dynamic=dataclasses.replace(scene_.dynamic, **dynamic))


def node(model, ref: str) -> int:
    """Global node index of ``"BODY:INDEX"`` (negative indices from the end)."""
    name, index = ref.split(":")
    return model.node_index(NodeRef(name, int(index) % model.bodies[name].nodes))


def nodal(model, q, node: int, vector: str) -> np.ndarray:
    """One nodal vector (r, r_x, ...) of global node ``node`` in the global vector q."""
    return q[model.node_dofs(node, vector)]


def rot2(theta: float) -> np.ndarray:
    c, s = math.cos(theta), math.sin(theta)
    return np.array([[c, -s], [s, c]])


def spin_up(t: float, omega: float, t_ramp: float) -> tuple[float, float]:
    """Eq. 45 written out here: hub angle (rad) and rate (rad/s)."""
    if t <= t_ramp:
        c = t_ramp / (2 * math.pi)
        angle = omega / t_ramp * (t * t / 2 + c * c * (math.cos(2 * math.pi * t / t_ramp) - 1))
        rate = omega / t_ramp * (t - c * math.sin(2 * math.pi * t / t_ramp))
        return angle, rate
    return omega * (t - t_ramp / 2), omega


def run_scene(scene_: Scene, folder: Path, name: str = "scene"):
    """Write a scene as TOML and run it through ``runtime.app.run.run``."""
    path = folder / f"{name}.toml"
    path.write_text(scene_.to_toml())
    return run(path, folder / f"{name}_out", quiet=True)


# =========================================================================== constraints

def test_clamp_holds_every_coordinate_in_static_and_dynamic_runs():
    # 3D cantilever bent in two planes and twisted-free; the clamp must hold r, r_x, r_y, r_z
    data = cantilever(elements=3, element="beam3d", force=[200.0, -5e4, 3e4],
                      law=CosineRamp(0.04), gravity=[0.0, -G, 0.0], static=Static(),
                      dynamic=Dynamic(t_end=0.05, step=2.5e-3))
    result = simulate(data, keep_states=True)
    model = result.model
    root = model.node_dofs(0)
    tip = model.node_dofs(3, "r")
    assert np.array_equal(result.static.q[root], model.reference[root])
    assert np.abs(result.static.q[tip] - model.reference[tip]).max() > 1e-3  # it did bend
    assert len(result.states) == 21
    for _, q, v in result.states:
        assert np.array_equal(q[root], model.reference[root])
        assert np.array_equal(v[root], np.zeros(root.size))
    assert np.abs(result.states[-1][1][tip] - model.reference[tip]).max() > 1e-4


def test_pin_fixes_the_position_and_lets_a_beam_swing_like_a_rigid_pendulum():
    # a stiff aluminium rod pinned at x = 0, released horizontally: first bending frequency
    # ~450 rad/s, so over 0.1 s it turns as a rigid rod, angle = -(3 g / 4 L) t^2
    length = 1.0
    data = scene([body(elements=4, end=(length, 0.0), height=0.02, width=0.02)],
                 [Pin("beam:0")], [Gravity([0.0, -G])], [], ALUMINIUM,
                 dynamic=Dynamic(t_end=0.1, step=1e-3, output_every=0.02))
    result = simulate(data, keep_states=True)
    model = result.model
    for t, q, _ in result.states:
        assert np.array_equal(nodal(model, q, 0, "r"), [0.0, 0.0])
        r_x = nodal(model, q, 0, "r_x")
        rigid = -3 * G / (4 * length) * t * t
        if t >= 0.04:  # before, the bending transient (period 14 ms) is not negligible
            assert math.atan2(r_x[1], r_x[0]) == pytest.approx(rigid, rel=0.03)
        # the root section turns without stretching (strain ~ weight / EA ~ 1e-7)
        assert np.linalg.norm(r_x) == pytest.approx(1.0, abs=1e-6)
    assert math.atan2(*nodal(model, result.states[-1][1], 0, "r_x")[::-1]) < -0.07


def test_prescribed_constant_rate_rotation_drives_the_hub_gradients():
    omega, length = 2.0, 1.0
    data = scene([body(elements=3, end=(length, 0.0))],
                 [Hub("beam:0", ConstantRate(omega))],
                 dynamic=Dynamic(t_end=1.0, step=1e-2, integrator="generalized_alpha",
                                 rho_inf=0.5, output_every=0.05))
    result = simulate(data, keep_states=True)
    model = result.model
    # the hub starts impulsively: the tip rings with an amplitude ~ omega L / omega_1
    ring = omega * length / cantilever_frequency(STEEL.E, STEEL.rho, 0.1, 0.1, length)
    assert len(result.states) == 21
    for t, q, v in result.states:
        rot = rot2(omega * t)
        assert np.array_equal(nodal(model, q, 0, "r"), [0.0, 0.0])
        assert np.allclose(nodal(model, q, 0, "r_x"), [math.cos(omega * t), math.sin(omega * t)],
                           rtol=0, atol=1e-12)
        assert np.allclose(nodal(model, q, 0, "r_y"), rot @ [0.0, 1.0], rtol=0, atol=1e-12)
        assert np.allclose(nodal(model, v, 0, "r_x"), omega * rot @ [0.0, 1.0], atol=1e-12)
        tip = nodal(model, q, 3, "r")
        assert np.linalg.norm(tip - rot @ [length, 0.0]) < 2.5 * ring


def test_prescribed_spin_up_about_an_axis_in_3d():
    omega, t_ramp = 1.5, 0.4
    axis = np.array([0.0, 1.0, 1.0]) / math.sqrt(2)
    data = scene([body(element="beam3d", elements=2, start=(0, 0, 0), end=(1.0, 0, 0))],
                 [Hub("beam:0", SpinUp(omega, t_ramp), (0.0, 2.0, 2.0))],
                 dynamic=Dynamic(t_end=0.6, step=1e-2, output_every=0.1))
    result = simulate(data, keep_states=True)
    model = result.model
    for t, q, _ in result.states:
        angle, _ = spin_up(t, omega, t_ramp)
        rot = Rotation.from_rotvec(angle * axis).as_matrix()
        assert np.array_equal(nodal(model, q, 0, "r"), [0.0, 0.0, 0.0])
        for name in ("r_x", "r_y", "r_z"):
            reference = nodal(model, model.reference, 0, name)
            assert np.allclose(nodal(model, q, 0, name), rot @ reference, rtol=0, atol=1e-12)
    assert spin_up(0.6, omega, t_ramp)[0] > 0.5  # a sizeable turn was checked


def _double_pendulum(element: str, joint: type, elements: int, t_end: float, step: float,
                     integrator: str = "trapezoidal") -> Scene:
    z = [0.0] if element == "beam3d" else []
    sensors = [ConstraintViolation("violation"), TotalEnergy("total"), KineticEnergy("kinetic"),
               KineticEnergy("kinetic_a", "a"), KineticEnergy("kinetic_b", "b"),
               Position("tip_y", "b:-1", "y")]
    return scene([body("a", element, elements, [0.0, 0.0] + z, [0.5, 0.0] + z, 0.02, 0.02),
                  body("b", element, elements, [0.5, 0.0] + z, [1.0, 0.0] + z, 0.02, 0.02)],
                 [Pin("a:0"), joint(("a:-1", "b:0"))], [Gravity([0.0, -G] + z)], sensors,
                 ALUMINIUM, dynamic=Dynamic(t_end=t_end, step=step, integrator=integrator,
                                            rho_inf=0.9))


@pytest.mark.parametrize("integrator", ["trapezoidal", "generalized_alpha"])
def test_spherical_joint_keeps_a_3d_double_pendulum_together(integrator):
    result = simulate(_double_pendulum("beam3d", Spherical, 2, 0.3, 2.5e-3, integrator),
                      keep_states=True)
    model = result.model
    assert result["violation"].max() <= 1e-9
    for _, q, _ in result.states:
        a, b = node(model, "a:-1"), node(model, "b:0")
        assert np.abs(nodal(model, q, a, "r") - nodal(model, q, b, "r")).max() <= 1e-9
    # it falls: a rigid double pendulum drops its free end by ~ g t^2 / 2 scale
    assert result["tip_y"][-1] < -0.1
    # energy per body adds up to the whole
    assert np.allclose(result["kinetic_a"] + result["kinetic_b"], result["kinetic"],
                       rtol=1e-12, atol=1e-12)
    assert result["kinetic_a"][-1] > 0 and result["kinetic_b"][-1] > 0


def test_spherical_joint_is_a_hinge_between_two_cantilevers_in_static():
    # beam a clamped at x = 0, beam b clamped at x = 2, joined at x = 1 by a spherical joint,
    # load P at the joint: no moment crosses it, each cantilever carries P / 2
    P, h, n = 10.0, 0.05, 6
    sensors = [Displacement("joint_a", "a:-1", "y"), Displacement("joint_b", "b:0", "y"),
               ConstraintViolation("violation"), StrainEnergy("strain_a", "a"),
               StrainEnergy("strain_b", "b"), StrainEnergy("strain")]
    data = scene([body("a", "beam3d", n, [0, 0, 0], [1.0, 0, 0], h, h),
                  body("b", "beam3d", n, [1.0, 0, 0], [2.0, 0, 0], h, h)],
                 [Clamp("a:0"), Clamp("b:-1"), Spherical(("a:-1", "b:0"))],
                 [PointForce("a:-1", [0.0, -P, 0.0])], sensors, static=Static())
    result = simulate(data)
    values = result.static_values
    half = tip_deflection(P / 2, STEEL.E, h, h, 1.0)
    assert values["violation"] <= 1e-12
    assert values["joint_a"] == pytest.approx(values["joint_b"], rel=1e-12)
    # Euler-Bernoulli within the discretisation error of 6 elements (~1 %)
    assert -values["joint_a"] == pytest.approx(half, rel=0.015)
    # the same mesh as one cantilever under P / 2 gives the same deflection (the load splits
    # in two; the membrane force of the clamped-clamped pair is O(deflection^2))
    single = simulate(cantilever(elements=n, element="beam3d", height=h, width=h,
                                 force=[0.0, -P / 2, 0.0], static=Static()))
    assert values["joint_a"] == pytest.approx(single.static_values["tip_y"], rel=1e-4)
    # a kink at the hinge: opposite slopes of size (P/2) L^2 / (2 E I)
    model, q = result.model, result.static.q
    slope = (P / 2) / (2 * STEEL.E * second_moment(h, h))
    r_x_a = nodal(model, q, node(model, "a:-1"), "r_x")
    r_x_b = nodal(model, q, node(model, "b:0"), "r_x")
    assert r_x_a[1] == pytest.approx(-slope, rel=0.02)
    assert r_x_b[1] == pytest.approx(slope, rel=0.02)
    # symmetric halves; Clapeyron: U = P delta / 2 for a linear response
    assert values["strain_a"] == pytest.approx(values["strain_b"], rel=1e-8)
    assert values["strain_a"] + values["strain_b"] == pytest.approx(values["strain"], rel=1e-12)
    assert values["strain"] == pytest.approx(-P * values["joint_a"] / 2, rel=1e-4)


def test_modes_of_two_cantilevers_joined_by_a_hinge():
    # symmetric mode: no force crosses the hinge, each half is a free cantilever (1.8751);
    # antisymmetric mode: the hinge stays put, each half is clamped-pinned (3.9266)
    h, n = 0.05, 6
    data = scene([body("a", "beam2d", n, [0.0, 0.0], [1.0, 0.0], h, h),
                  body("b", "beam2d", n, [1.0, 0.0], [2.0, 0.0], h, h)],
                 [Clamp("a:0"), Clamp("b:-1"), Revolute(("a:-1", "b:0"))],
                 modal=Modal(modes=2))
    pair = simulate(data).frequencies
    scale = math.sqrt(STEEL.E * second_moment(h, h) / (STEEL.rho * h * h))
    assert pair[0] == pytest.approx(1.875104**2 * scale, rel=0.01)
    assert pair[1] == pytest.approx(3.926602**2 * scale, rel=0.04)  # 6 elements: ~3 % high
    # the same two modes of one half, free or pinned at its end, on the same mesh
    free = simulate(cantilever(elements=n, height=h, width=h,
                               modal=Modal(modes=1))).frequencies[0]
    propped = scene([body(elements=n, height=h, width=h)], [Clamp("beam:0"), Pin("beam:-1")],
                    modal=Modal(modes=1))
    pinned = simulate(propped).frequencies[0]
    assert pair[0] == pytest.approx(free, rel=1e-7)
    assert pair[1] == pytest.approx(pinned, rel=1e-7)


def test_revolute_joint_2d_double_pendulum_conserves_energy():
    result = simulate(_double_pendulum("beam2d", Revolute, 2, 0.4, 2e-3))
    assert result["violation"].max() <= 1e-9
    kinetic = result["kinetic"].max()
    assert kinetic > 1.0  # ~ m g h: it really swings
    # the trapezoidal rule conserves energy up to O(h^2) (and the Newton tolerance)
    assert np.abs(result["total"] - result["total"][0]).max() <= 1e-3 * kinetic


def test_revolute_joint_in_3d_hinges_about_z_as_the_spherical_one_in_a_planar_swing():
    # the 3D revolute joint (about z: quadratic rows, tests/test_multibody.py) allows the
    # planar swing that the spherical joint makes, and holds its nodes together
    hinge = simulate(_double_pendulum("beam3d", Revolute, 2, 0.1, 1e-2))
    ball = simulate(_double_pendulum("beam3d", Spherical, 2, 0.1, 1e-2))
    assert hinge["violation"].max() <= 1e-9
    assert np.abs(hinge["tip_y"] - ball["tip_y"]).max() <= 1e-9
    assert ball["tip_y"][-1] < -0.01


def test_3d_straight_body_bends_in_plane_like_the_2d_one():
    # height 0.1 along local y, width 0.05: in-plane (x-y) bending stiffness E w h^3 / 12
    h, w, P = 0.1, 0.05, 1000.0
    tips = {}
    for element, force in (("beam2d", [0.0, -P]), ("beam3d", [0.0, -P, 0.0])):
        data = cantilever(elements=6, element=element, height=h, width=w, force=force,
                          static=Static())
        result = simulate(data)
        tips[element] = result.static_values["tip_y"]
        reference = result.model.reference
        assert reference[result.model.node_dofs(0, "r_y")][1] == pytest.approx(1.0)
    assert -tips["beam2d"] == pytest.approx(tip_deflection(P, STEEL.E, h, w, 1.0), rel=0.01)
    assert tips["beam3d"] == pytest.approx(tips["beam2d"], rel=1e-6)


# =========================================================================== loads

P_SMALL = 1000.0
LAWS = {
    "constant": Constant(0.8),
    "cosine_ramp": CosineRamp(1.0),
    "linear_ramp": LinearRamp(1.0, -0.5),
    "sine": Sine(amplitude=1.0, frequency_hz=1.0, phase_deg=30.0, offset=0.2),
    "table": Table(((0.0, 0.0), (0.5, 1.0), (1.0, -0.5), (1.5, -0.5))),
}


@pytest.fixture(scope="module")
def stiff_static_deflection() -> float:
    """Static tip deflection (m, signed) of the stiff 1 m cantilever under -1000 N."""
    result = simulate(cantilever(elements=4, force=[0.0, -P_SMALL], static=Static()))
    value = result.static_values["tip_y"]
    # beam theory within the 4-element discretisation error
    assert -value == pytest.approx(tip_deflection(P_SMALL, STEEL.E, 0.1, 0.1, 1.0), rel=0.02)
    return value


@pytest.mark.parametrize("name", LAWS)
def test_point_force_follows_its_time_law_quasi_statically(name, stiff_static_deflection):
    # first bending frequency ~530 rad/s against load time scales of ~1 s: the response is
    # law(t) * static deflection up to (6/530)^2; generalized-alpha with rho_inf = 0 and
    # omega_1 h ~ 5 wipes the transients of the start (a step for constant and sine laws) and
    # of the table's kinks within a few steps
    law = LAWS[name]
    data = cantilever(elements=4, force=[0.0, -P_SMALL], law=law,
                      dynamic=Dynamic(t_end=2.0, step=1e-2, integrator="generalized_alpha",
                                      rho_inf=0.0, output_every=0.05))
    result = simulate(data)
    checked = 0
    for t, tip in zip(result.t, result["tip_y"], strict=True):
        if t < 0.2:
            continue
        expected = law.value(t) * stiff_static_deflection
        assert tip == pytest.approx(expected, abs=0.02 * abs(stiff_static_deflection)), t
        checked += 1
    assert checked >= 30


def test_gravity_deflection_matches_uniform_load_beam_theory():
    # w L^4 / (8 E I), w = rho A g; slender (L / h = 50) so shear is negligible, nu = 0
    length, h, w = 1.0, 0.02, 0.02
    data = cantilever(elements=8, length=length, height=h, width=w, gravity=[0.0, -G],
                      static=Static())
    result = simulate(data)
    load = STEEL.rho * h * w * G
    exact = load * length**4 / (8 * STEEL.E * second_moment(h, w))
    assert -result.static_values["tip_y"] == pytest.approx(exact, rel=0.01)


def test_gravity_is_the_weight_of_the_whole_mesh():
    length, h, w = 2.0, 0.1, 0.05
    data = cantilever(elements=3, length=length, height=h, width=w, gravity=[0.0, -G])
    model = Model(data)
    force = model.external_forces(0.0)
    positions = np.concatenate([model.node_dofs(i, "r") for i in range(4)])
    weight = STEEL.rho * length * h * w * G
    assert force[positions].reshape(-1, 2).sum(axis=0) == pytest.approx([0.0, -weight],
                                                                         abs=1e-9 * weight)


# =========================================================================== static

def test_load_steps_reach_the_same_equilibrium():
    base = cantilever(elements=4, length=2.0, height=0.05, width=0.05, force=[0.0, -2e4],
                      static=Static())
    stepped = dataclasses.replace(base, static=Static(load_steps=4))
    one, four = simulate(base), simulate(stepped)
    assert four.static.load_steps == 4
    assert four.static.iterations > one.static.iterations
    scale = np.abs(one.static.q - one.model.reference).max()
    assert scale > 0.3  # a large deflection (the tip drops ~0.4 m of 2 m)
    assert np.abs(four.static.q - one.static.q).max() <= 1e-8 * scale


def _elastica(alpha: float) -> tuple[float, float]:
    """Tip deflection (transverse, axial shortening) / L of a cantilever under a fixed-
    direction transverse tip load with P L^2 / E I = alpha (shooting on theta'(0))."""
    def shoot(k0, full=False):
        sol = solve_ivp(lambda s, y: [y[1], -alpha * math.cos(y[0]), math.cos(y[0]),
                                      math.sin(y[0])], (0.0, 1.0), [0.0, k0, 0.0, 0.0],
                        rtol=1e-11, atol=1e-12)
        return sol.y[:, -1] if full else sol.y[1, -1]

    y = shoot(brentq(shoot, 0.0, 1.001 * alpha), full=True)
    return float(y[3]), float(1.0 - y[2])


def test_failed_load_increment_is_halved_and_matches_the_elastica():
    # P L^2 / EI = 1: a large deflection (30 % of L) that plain Newton with 6 iterations
    # cannot reach in one increment
    length, h, n = 2.0, 0.05, 10
    P = STEEL.E * second_moment(h, h) / length**2
    data = cantilever(elements=n, length=length, height=h, width=h, force=[0.0, -P],
                      static=Static(max_iterations=6))
    model = Model(data)
    settings = model.scene.static
    nominal = sum(vector for _, vector in model.nominal_loads())
    with pytest.raises(analysis.ConvergenceError, match="did not converge in 6"):
        analysis.newton_static(model, model.reference.copy(), nominal, settings,
                               np.zeros(0))
    result = analysis.solve_static(model, settings)
    assert result.load_steps > 1
    generous = simulate(cantilever(elements=n, length=length, height=h, width=h,
                                   force=[0.0, -P], static=Static()))
    assert generous.static.load_steps == 1
    assert np.abs(result.q - generous.static.q).max() <= 1e-8 * length
    # the large-deflection answer: the elastica, within the discretisation error of 10
    # elements (1.3 % at 8 elements, halving with the element length)
    sensors = Sensors(model).values(result.q)
    v, u = _elastica(1.0)
    assert -sensors["tip_y"] / length == pytest.approx(v, rel=0.015)
    assert -sensors["tip_x"] / length == pytest.approx(u, rel=0.03)


def test_static_that_cannot_converge_raises_a_convergence_error():
    data = cantilever(elements=2, force=[0.0, -1e5], static=Static(max_iterations=1))
    model = Model(data)
    with pytest.raises(analysis.ConvergenceError, match="1/1024"):
        analysis.solve_static(model, model.scene.static)


# =========================================================================== modal

def test_lowest_modal_frequency_matches_the_closed_form():
    length, h = 2.0, 0.05
    data = cantilever(elements=10, length=length, height=h, width=h, modal=Modal(modes=3))
    result = simulate(data)
    exact = cantilever_frequency(STEEL.E, STEEL.rho, h, h, length)
    assert result.frequencies[0] == pytest.approx(exact, rel=0.01)
    # second bending mode: (4.6941 / 1.8751)^2 times the first
    assert result.frequencies[1] == pytest.approx(exact * (4.694091 / 1.875104) ** 2, rel=0.02)
    assert np.all(np.diff(result.frequencies) > 0)


def _rayleigh_tension_ratio(length: float) -> float:
    """int phi'^2 / int phi^2 of the first clamped-free mode shape (1/m^2)."""
    beta = 1.875104068711961 / length
    x = np.linspace(0.0, length, 20001)
    sigma = (math.sinh(beta * length) - math.sin(beta * length)) / \
        (math.cosh(beta * length) + math.cos(beta * length))
    phi = np.cosh(beta * x) - np.cos(beta * x) - sigma * (np.sinh(beta * x) - np.sin(beta * x))
    dphi = np.gradient(phi, x)
    return float(np.trapezoid(dphi**2, x) / np.trapezoid(phi**2, x))


@pytest.mark.parametrize("axial", [5000.0, -5000.0])
def test_modal_about_the_static_state_feels_the_axial_preload(axial):
    # tension stiffens, compression softens (7 % of the buckling load): first order
    # omega^2 = omega_0^2 + T int phi'^2 / (rho A int phi^2)
    length, h = 2.0, 0.05
    about_static = simulate(cantilever(elements=10, length=length, height=h, width=h,
                                       force=[axial, 0.0], static=Static(),
                                       modal=Modal(modes=2, about="static")))
    about_reference = simulate(cantilever(elements=10, length=length, height=h, width=h,
                                          force=[axial, 0.0], modal=Modal(modes=2)))
    omega0 = about_reference.frequencies[0]
    rho_a = STEEL.rho * h * h
    expected = math.sqrt(omega0**2 + axial * _rayleigh_tension_ratio(length) / rho_a)
    assert about_static.frequencies[0] == pytest.approx(expected, rel=0.005)
    assert abs(about_static.frequencies[0] / omega0 - 1) > 0.02


def test_modal_about_static_and_reference_differ_slightly_under_a_tip_load():
    length, h = 2.0, 0.05
    values = {}
    for about in ("reference", "static"):
        data = cantilever(elements=10, length=length, height=h, width=h, force=[0.0, -1000.0],
                          static=Static(), modal=Modal(modes=3, about=about))
        values[about] = simulate(data).frequencies
    assert np.all(values["reference"] > 0) and np.all(values["static"] > 0)
    change = np.abs(values["static"] / values["reference"] - 1)
    # the tip drops 1.2 % of L: a geometric effect of that order squared at most
    assert change.max() < 0.01
    assert change.max() > 1e-6


# =========================================================================== dynamic

def _vibrating(integrator: str, rho_inf: float = 0.8, step: float = 1e-3) -> Scene:
    """A 2 m cantilever (omega_1 ~ 66 rad/s) under a tip load ramped in 0.02 s: it vibrates
    about the static deflection."""
    return cantilever(elements=4, length=2.0, height=0.05, width=0.05, force=[0.0, -1000.0],
                      law=LinearRamp(0.02), sensors=[Displacement("tip_y", "beam:-1", "y")],
                      modal=Modal(modes=2),
                      dynamic=Dynamic(t_end=0.6, step=step, integrator=integrator,
                                      output_every=2e-3, rho_inf=rho_inf, frequency_of="tip_y",
                                      frequency_after=0.1))


@pytest.mark.parametrize("integrator, rho_inf", [("trapezoidal", 0.8),
                                                  ("generalized_alpha", 1.0),
                                                  ("generalized_alpha", 0.8)])
def test_response_frequency_equals_the_modal_frequency(integrator, rho_inf, tmp_path):
    # omega_1 h = 0.067: the period error of both schemes ~ (omega h)^2 / 12 < 1e-3
    summary, code = run_scene(_vibrating(integrator, rho_inf), tmp_path)
    assert code == 0, summary["message"]
    modal = summary["modal"]["frequencies_rad_s"][0]
    assert summary["dynamic"]["response_frequency_rad_s"] == pytest.approx(modal, rel=0.01)


def test_generalized_alpha_without_damping_matches_the_trapezoidal_rule():
    trapezoidal = simulate(_vibrating("trapezoidal"))
    alpha = simulate(_vibrating("generalized_alpha", 1.0))
    # both are second-order and non-dissipative (alpha_m = alpha_f = 1/2 is the trapezoidal
    # rule); they differ by their truncation errors, far below (omega h)^2 = 4e-3
    amplitude = np.abs(trapezoidal["tip_y"]).max()
    assert np.abs(alpha["tip_y"] - trapezoidal["tip_y"]).max() <= 1e-4 * amplitude


def _pulsed(integrator: str, rho_inf: float) -> Scene:
    """A tip load pulse (8 ms, shorter than the first period 95 ms) on the 2 m cantilever,
    then free vibration; a large step (2 ms) leaves the high modes with omega h >> 1."""
    return cantilever(elements=4, length=2.0, height=0.05, width=0.05, force=[0.0, -5000.0],
                      law=Table(((0.0, 0.0), (0.004, 1.0), (0.008, 0.0))),
                      sensors=[TotalEnergy("energy")],
                      dynamic=Dynamic(t_end=0.5, step=2e-3, integrator=integrator,
                                      rho_inf=rho_inf))


@pytest.mark.parametrize("integrator, rho_inf, dissipative", [
    ("trapezoidal", 0.8, False), ("generalized_alpha", 1.0, False),
    ("generalized_alpha", 0.5, True), ("generalized_alpha", 0.0, True)])
def test_numerical_damping_only_below_rho_inf_one(integrator, rho_inf, dissipative):
    result = simulate(_pulsed(integrator, rho_inf))
    after = result.t >= 0.01
    energy = result["energy"][after]
    assert energy[0] > 1.0
    ratio = energy[-1] / energy[0]
    if dissipative:
        assert ratio < 0.9
        assert energy.max() <= energy[0] * (1 + 1e-3)  # never gains energy
    else:
        # conserved up to the geometric nonlinearity of the O(h^2) scheme
        assert abs(ratio - 1) < 1e-3
        assert np.abs(energy / energy[0] - 1).max() < 1e-3


def test_pendulum_energy_drift_is_small_and_second_order():
    drifts = {}
    for step in (1e-3, 5e-4):
        result = simulate(shipped("pendulum", step=step))
        energy, kinetic = result["total_energy"], result["kinetic_energy"]
        assert energy[0] == 0.0 and kinetic.max() > 1.0
        drifts[step] = np.abs(energy - energy[0]).max() / kinetic.max()
    assert drifts[1e-3] < 1e-4
    assert drifts[5e-4] < drifts[1e-3] / 3  # 4 for a second-order scheme


# =========================================================================== sensors

SPIN_SENSORS = [
    Displacement("transverse", "beam:-1", "y", "beam:0"),
    Displacement("axial", "beam:-1", "x", "beam:0"),
    Displacement("dy", "beam:-1", "y"),
    Displacement("dnorm", "beam:-1", "norm"),
    Position("px", "beam:-1", "x"),
    Position("py", "beam:-1", "y"),
    Position("pnorm", "beam:-1", "norm"),
    Position("local_x", "beam:-1", "x", "beam:0"),
    Position("local_y", "beam:-1", "y", "beam:0"),
    KineticEnergy("kinetic"),
]


def test_sensors_of_a_stiff_beam_spun_by_its_hub():
    # E = 1000 x steel: the beam turns rigidly; its deflection under the angular
    # acceleration alpha is 11 rho A alpha L^5 / (120 E I) (uniformly varying load)
    length, h, omega, t_ramp = 2.0, 0.1, 2.0, 1.0
    material = Material("m", E=2.1e14, nu=0.0, rho=7800.0)
    data = scene([body(elements=3, end=(length, 0.0), height=h, width=h)],
                 [Hub("beam:0", SpinUp(omega, t_ramp))], [], SPIN_SENSORS, material,
                 dynamic=Dynamic(t_end=1.5, step=1e-2))
    result = simulate(data)
    alpha = 2 * omega / t_ramp
    bound = 10 * 11 * material.rho * h * h * alpha * length**5 / (
        120 * material.E * second_moment(h, h))
    assert bound < 1e-5
    for sensor in SPIN_SENSORS:
        assert result[sensor.name][0] == pytest.approx(
            {"px": length, "pnorm": length, "local_x": length}.get(sensor.name, 0.0), abs=0)
    angle = np.array([spin_up(t, omega, t_ramp)[0] for t in result.t])
    rate = np.array([spin_up(t, omega, t_ramp)[1] for t in result.t])
    assert np.abs(result["transverse"]).max() < bound
    assert np.abs(result["axial"]).max() < bound
    assert np.abs(result["local_x"] - length).max() < bound
    assert np.abs(result["local_y"]).max() < bound
    assert np.abs(result["dy"]).max() > 0.9 * length  # globally it moves a lot
    assert np.abs(result["px"] - length * np.cos(angle)).max() < bound
    assert np.abs(result["py"] - length * np.sin(angle)).max() < bound
    assert np.abs(result["dy"] - length * np.sin(angle)).max() < bound
    assert np.abs(result["pnorm"] - length).max() < bound
    assert np.abs(result["dnorm"] - 2 * length * np.abs(np.sin(angle / 2))).max() < bound
    # kinetic energy of a rigid rotation, I = rho w (h L^3 / 3 + L h^3 / 12); the trapezoidal
    # velocities carry an O((omega h)^2) = 4e-4 error
    inertia = material.rho * h * (h * length**3 / 3 + length * h**3 / 12)
    kinetic = 0.5 * inertia * rate**2
    assert np.abs(result["kinetic"] - kinetic).max() < 1e-3 * kinetic.max()


def test_sensors_on_hand_made_states():
    sensors = [
        Displacement("d_x", "b:-1", "x"),
        Displacement("d_y", "b:-1", "y"),
        Displacement("d_norm", "b:-1", "norm"),
        Position("p_x", "b:-1", "x"),
        Position("p_y", "b:-1", "y"),
        Position("local_x", "b:-1", "x", "a:0"),
        Position("local_y", "b:-1", "y", "a:0"),
        Displacement("local_d", "b:-1", "norm", "a:0"),
        StrainEnergy("strain"),
        StrainEnergy("strain_a", "a"),
        KineticEnergy("kinetic"),
        KineticEnergy("kinetic_a", "a"),
        KineticEnergy("kinetic_b", "b"),
        PotentialEnergy("potential"),
        TotalEnergy("total"),
        ConstraintViolation("violation"),
    ]
    h, w = 0.1, 0.05
    data = scene([body("a", elements=2, start=(0.0, 0.0), end=(1.0, 0.0), height=h, width=w),
                  body("b", elements=3, start=(1.0, 0.0), end=(3.0, 0.0), height=h, width=w)],
                 [Revolute(("a:-1", "b:0"))], [Gravity([0.0, -G])], sensors)
    model = Model(data)
    probe = Sensors(model)
    mass_a, mass_b = STEEL.rho * h * w * 1.0, STEEL.rho * h * w * 2.0

    # rigid motion: turn by 0.7 rad about the origin, then shift by (0.3, -0.2)
    angle, shift = 0.7, np.array([0.3, -0.2])
    q = model.reference.reshape(-1, 2) @ rot2(angle).T
    positions = np.array([model.node_dofs(i, "r")[0] // 2 for i in range(7)])  # rows of r
    q[positions] += shift
    q = q.ravel()
    velocity = np.zeros_like(q)
    velocity.reshape(-1, 2)[positions] = [1.5, -2.0]  # a translation at 2.5 m/s
    values = probe.values(q, velocity)
    tip = rot2(angle) @ [3.0, 0.0] + shift
    assert values["p_x"] == pytest.approx(tip[0], abs=1e-14)
    assert values["p_y"] == pytest.approx(tip[1], abs=1e-14)
    assert values["d_x"] == pytest.approx(tip[0] - 3.0, abs=1e-14)
    assert values["d_y"] == pytest.approx(tip[1], abs=1e-14)
    assert values["d_norm"] == pytest.approx(math.hypot(tip[0] - 3.0, tip[1]), abs=1e-14)
    # in the frame of the first node (turned with the bodies) nothing moved
    assert values["local_x"] == pytest.approx(3.0, abs=1e-14)
    assert values["local_y"] == pytest.approx(0.0, abs=1e-14)
    assert values["local_d"] == pytest.approx(0.0, abs=1e-14)
    assert 0.0 <= values["strain"] < 1e-9 and values["strain_a"] <= values["strain"]
    assert values["kinetic_a"] == pytest.approx(0.5 * mass_a * 6.25, rel=1e-12)
    assert values["kinetic_b"] == pytest.approx(0.5 * mass_b * 6.25, rel=1e-12)
    assert values["kinetic"] == pytest.approx(0.5 * (mass_a + mass_b) * 6.25, rel=1e-12)
    # the centre of mass moved up by 0.5 sin(0.7) * m_a + 2 sin(0.7) * m_b, then down 0.2
    rise = (mass_a * 0.5 + mass_b * 2.0) * math.sin(angle) - 0.2 * (mass_a + mass_b)
    assert values["potential"] == pytest.approx(G * rise, rel=1e-12)
    assert values["total"] == pytest.approx(values["strain"] + values["kinetic"]
                                            + values["potential"], rel=1e-12)
    assert values["violation"] == 0.0

    # pull the joint apart by 1.5 mm along y; stretch body a by 1 %
    q = model.reference.copy()
    q[model.node_dofs(node(model, "b:0"), "r")] += [0.0, 1.5e-3]
    values = probe.values(q)
    assert values["violation"] == pytest.approx(1.5e-3, rel=1e-12)
    q = model.reference.copy()
    q.reshape(-1, 2)[positions[:3], 0] *= 1.01
    for i in range(3):
        q[model.node_dofs(i, "r_x")] = [1.01, 0.0]
    values = probe.values(q)
    # uniform axial Green strain 0.01005 with nu = 0: U = E V eps^2 / 2
    eps = (1.01**2 - 1) / 2
    assert values["strain_a"] == pytest.approx(STEEL.E * h * w * 1.0 * eps**2 / 2, rel=1e-9)


@pytest.mark.parametrize("law", [Constant(), CosineRamp(1.0)])
def test_static_potential_energy_of_gravity(law, tmp_path):
    # linear response: the loads do work 2 U, so the potential of gravity is -2 U
    data = cantilever(elements=4, static=Static(),
                      sensors=[PotentialEnergy("potential"), StrainEnergy("strain"),
                               TotalEnergy("total")])
    data = dataclasses.replace(data, loads=[Gravity([0.0, -G], time_law=law)])
    summary, code = run_scene(data, tmp_path)
    assert code == 0
    values = summary["static"]["sensors"]
    assert values["strain"] > 0
    assert values["potential"] == pytest.approx(-2 * values["strain"], rel=1e-4)
    assert values["total"] == pytest.approx(-values["strain"], rel=1e-4)


# =========================================================================== methods, backends

@pytest.fixture(scope="module")
def rotating_reference() -> np.ndarray:
    # full Newton: the methods' round-off then stays round-off (with a kept Jacobian each
    # run stops at the tolerance, and the auto mode's decisions can differ between them)
    return simulate(shipped("rotating_beam", t_end=3.0, newton="full"), "gram",
                    "c")["tip_transverse"]


@pytest.mark.parametrize("method, backend, t_end", [
    ("cij", "c", 3.0), ("quadrature", "c", 3.0), ("gram", "numpy", 3.0), ("cij", "numpy", 3.0),
    ("quadrature", "numpy", 0.5)])  # numpy quadrature is ~50x slower: a shorter run
def test_methods_and_backends_give_the_same_rotating_beam(method, backend, t_end,
                                                          rotating_reference):
    series = simulate(shipped("rotating_beam", t_end=t_end, newton="full"), method,
                      backend)["tip_transverse"]
    reference = rotating_reference[: series.size]
    assert np.abs(reference).max() > (0.1 if t_end == 3.0 else 1e-4)
    assert np.abs(series - reference).max() <= 1e-7 * np.abs(reference).max()


# =========================================================================== acceptance

PAPER = {2: (1.065, 17.07), 5: (1.125, 16.37), 10: (1.134, 16.27)}


@pytest.mark.parametrize("elements", [2, 5, 10])
def test_paper_cantilever_table_one(elements, tmp_path):
    data = load_scene(scenes.path("cantilever"))
    data = dataclasses.replace(data, bodies=[dataclasses.replace(data.bodies[0],
                                                                 elements=elements)])
    if elements != 10:
        data = dataclasses.replace(data, dynamic=None)  # the dynamic run once, with 10
    summary, code = run_scene(data, tmp_path, f"cantilever{elements}")
    assert code == 0, summary["message"]
    deflection_cm, omega = PAPER[elements]
    assert abs(summary["static"]["sensors"]["tip_y"]) * 100 == pytest.approx(deflection_cm,
                                                                              abs=0.005)
    first = summary["modal"]["frequencies_rad_s"][0]
    assert first == pytest.approx(omega, rel=0.01)
    if elements == 10:
        # after the ramp (t_c = 3.5 s) the tip vibrates at the first modal frequency
        response = summary["dynamic"]["response_frequency_rad_s"]
        assert response == pytest.approx(first, rel=0.01)
        assert summary["dynamic"]["steps"] == 4000


def test_rotating_beam_spin_up(tmp_path):
    summary, code = run(SCENES / "rotating_beam.toml", tmp_path, quiet=True)
    assert code == 0, summary["message"]
    data = np.genfromtxt(tmp_path / "timeseries.csv", delimiter=",", names=True)
    t, tip, energy = data["t"], data["tip_transverse"], data["strain_energy"]
    assert t[-1] == pytest.approx(20.0)
    spin = t < 15.0
    assert -0.6 < tip[spin].min() < -0.4
    after = t > 16.0
    assert abs(tip[after].mean()) < 0.02
    assert (tip[after].max() - tip[after].min()) / 2 < 0.03
    peak = int(np.argmax(energy))
    assert 0.0 < t[peak] < 15.0
    assert np.all(energy[after] > 0) and energy[after].max() < 0.05 * energy[peak]
    # the plateau is the centrifugal stretch: U = rho^2 A omega^4 L^5 / (15 E)
    rho, area, omega, length, E = 2766.67, 7.299e-5, 4.0, 8.0, 68.95e9
    stretch = rho**2 * area * omega**4 * length**5 / (15 * E)
    assert energy[after].mean() == pytest.approx(stretch, rel=0.05)


def test_a_family_compiled_before_is_not_charged_again(monkeypatch):
    # kernel families are memoised per process: one compiled earlier (by another model, a
    # benchmark) must not add its compile time to a later model (a report once showed
    # compile 8.5 s and pre-processing -8.5 s for warm runs)
    from runtime.kernels.loader import kernel_family
    scene_ = load_scene(scenes.path("cantilever"))
    family = kernel_family("beam3d", "gram_straight", "c")
    monkeypatch.setattr(family, "compile_s", 5.0)
    model = Model(scene_)
    assert model.timing["compile_s"] == 0.0 and model.timing["preprocess_s"] >= 0.0
    monkeypatch.setattr(family, "loaded_at", time.perf_counter() + 1e3)   # loaded "for it"
    assert Model(scene_).timing["compile_s"] == 5.0


def _band(rows: np.ndarray, cols: np.ndarray) -> int:
    return int(np.abs(rows - cols).max())


@pytest.mark.parametrize("name, reordered", [("slider_crank", True), ("plate_cantilever", True),
                                             ("cantilever", False)])
def test_unknowns_are_numbered_for_a_narrow_band(name, reordered):
    """Rigid bodies numbered after the meshes and plates numbered along their long side
    are reordered where that at least halves the Jacobian's bandwidth; chains of beams keep
    the global order."""
    model = Model(load_scene(scenes.path(name)))
    pattern = model.pattern.tocoo()
    assert model.bandwidth == _band(pattern.row, pattern.col)
    rank = np.argsort(np.argsort(model.free))       # each unknown's place in global order
    natural = _band(rank[pattern.row], rank[pattern.col])
    assert (2 * model.bandwidth <= natural) == reordered
    assert bool(np.any(np.diff(model.free) < 0)) == reordered
