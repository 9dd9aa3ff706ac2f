"""Follower loads (``follower = true``, ``pressure``): exact Jacobians against finite
differences, rigid-motion properties, resultants, the roll-up of a cantilever under a
follower end moment (Euler-Bernoulli: a full circle), a clamped plate under pressure against
Kirchhoff's solution, and both engines on a dynamic follower-load scene."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scenes_small import scene

from runtime import (
    Body,
    Clamp,
    Displacement,
    DistributedForce,
    Dynamic,
    LineForce,
    LineMoment,
    Material,
    NodeRef,
    PointForce,
    PointMoment,
    Pressure,
    Rectangle,
    Scene,
    Solver,
    Static,
    run_scene,
)
from runtime.model.dae import StateLoads
from runtime.model.model import Model

VECTOR = (1.0, 2.0, 3.0)


def _beam(element: str, elements: int = 2, height: float = 0.1) -> Body:
    dim = 2 if "2d" in element else 3
    return Body("beam", element, "m", height, height, elements, (0.0,) * dim,
                (1.0,) + (0.0,) * (dim - 1))


def _plate(grid=(2, 2), size=(1.0, 0.5)) -> Body:
    return Body("plate", "plate3d", "m", thickness=0.01,
                rectangle=Rectangle(corner=(0.0, 0.0, 0.0), size=size, grid=grid))


def _beam_cases():
    for element in ("beam2d", "beam2d_3node", "cable2d", "beam3d", "beam3d_3node"):
        dim = 2 if "2d" in element else 3
        force, moment = VECTOR[:dim], (3.0 if dim == 2 else VECTOR)
        for load in (PointMoment("beam:-1", moment, follower=True),
                     PointForce("beam:-1", force, follower=True),
                     DistributedForce("beam", force, follower=True)):
            yield pytest.param(_beam(element), load, id=f"{element}-{load.type}")


PLATE_LOADS = [Pressure("plate", 100.0), LineMoment("plate:x=-1", VECTOR, follower=True),
               LineMoment("plate:x=1", VECTOR, follower=True),
               LineMoment("plate:y=1", VECTOR, follower=True),
               LineForce("plate:y=1", VECTOR, follower=True),
               PointForce("plate:-1", VECTOR, follower=True),
               PointMoment("plate:-1", VECTOR, follower=True)]


@pytest.mark.parametrize("body, load", [*_beam_cases(), *(
    pytest.param(_plate(), load, id=f"plate3d-{load.type}-{i}")
    for i, load in enumerate(PLATE_LOADS))])
def test_jacobian_against_finite_differences(body, load):
    clamp = Clamp("beam:0") if body.name == "beam" else Clamp(edge="plate:x=0")
    model = Model(scene([body], [clamp], [load]))
    loads = StateLoads(model)
    q = model.reference + 0.05 * np.random.default_rng(1).normal(size=model.size)
    factors = np.array([0.7])
    force, data, _ = loads.evaluate(q, factors, True)
    jacobian = model.jacobian_matrix(data).toarray()
    numeric = np.zeros_like(jacobian)
    h = 1e-6
    for k, c in enumerate(model.free):
        step = np.zeros(model.size)
        step[c] = h
        numeric[:, k] = ((loads.evaluate(q + step, factors, False)[0]
                          - loads.evaluate(q - step, factors, False)[0]) / (2 * h))[model.free]
    assert np.abs(force).max() > 0.1
    np.testing.assert_allclose(jacobian, numeric, atol=1e-8 * np.abs(jacobian).max())


def _rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    axis = axis / np.linalg.norm(axis)
    cross = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + math.sin(angle) * cross + (1 - math.cos(angle)) * cross @ cross


def _rigidly_turned(model: Model, rotation: np.ndarray) -> np.ndarray:
    """Coordinates of the reference turned by ``rotation`` about the origin."""
    return (model.reference.reshape(-1, 3) @ rotation.T).ravel()


def test_a_follower_force_turns_with_its_node():
    data = scene([_beam("beam3d")], [Clamp("beam:0")],
                 [PointForce("beam:-1", VECTOR, follower=True)])
    model = Model(data)
    loads = StateLoads(model)
    tip = model.node_dofs(model.node_index(data.loads[0].node), "r")
    rotation = _rotation(np.array([0.3, -1.0, 0.4]), 2.1)
    force = loads.evaluate(_rigidly_turned(model, rotation), np.ones(1), False)[0]
    np.testing.assert_allclose(force[tip], rotation @ VECTOR, rtol=1e-13, atol=1e-13)
    assert np.count_nonzero(force) == 3


def _work_along(model: Model, loads: StateLoads, axis: np.ndarray, angle: float) -> float:
    """Work (J) of the loads along the rigid rotation about ``axis`` from 0 to ``angle``
    (Simpson's rule on Q . dq/dphi)."""
    phis = np.linspace(0.0, angle, 401)
    unit = axis / np.linalg.norm(axis)
    cross = np.array([[0, -unit[2], unit[1]], [unit[2], 0, -unit[0]], [-unit[1], unit[0], 0]])
    power = []
    for phi in phis:
        q = _rigidly_turned(model, _rotation(axis, phi))
        rate = (q.reshape(-1, 3) @ cross.T).ravel()
        power.append(loads.evaluate(q, np.ones(1), False)[0] @ rate)
    h = phis[1] - phis[0]
    return float(h / 3 * (power[0] + power[-1] + 4 * sum(power[1:-1:2])
                          + 2 * sum(power[2:-1:2])))


@pytest.mark.parametrize("element", ["beam3d", "beam3d_3node"])
def test_a_follower_moment_does_m_theta_of_work_about_its_axis_and_none_across(element):
    moment = np.array([0.0, 0.0, 5.0])
    data = scene([_beam(element)], [Clamp("beam:0")],
                 [PointMoment("beam:-1", tuple(moment), follower=True)])
    model = Model(data)
    loads = StateLoads(model)
    # about its own axis: M theta, past a half turn (the fixed small-rotation forces of
    # point_moment would do M sin theta)
    assert _work_along(model, loads, moment, 4.0) == pytest.approx(5.0 * 4.0, rel=1e-9)
    # about an axis perpendicular to it the follower moment stays perpendicular: no work
    assert abs(_work_along(model, loads, np.array([1.0, 0.5, 0.0]), 4.0)) < 1e-9


@pytest.mark.parametrize("line", ["plate:x=-1", "plate:x=2", "plate:y=0", "plate:y=1"])
def test_edge_moment_and_force_resultants_on_boundary_and_interior_lines(line):
    size, grid = (1.6, 0.6), (4, 2)
    a, b = size
    length = b if "x=" in line else a
    for follower in (False, True):
        model = Model(scene([_plate(grid, size)], [Clamp(edge="plate:x=0")],
                            [LineMoment(line, VECTOR, follower=follower),
                             LineForce(line, VECTOR, follower=follower)]))
        force = model.nominal_load() + StateLoads(model).evaluate(
            model.reference, np.ones(2), False)[0]
        # virtual work on rigid translations and rotations: the resultants
        for k in range(3):
            unit = np.eye(3)[k]
            assert force @ model.rigid_field(translation=unit) == pytest.approx(
                VECTOR[k] * length, rel=1e-12)
        centre = np.array([2 * a / 4, b / 2, 0.0]) if line == "plate:x=2" else None
        if centre is not None:   # moment about the line's centre: the line moment only
            for k in range(3):
                unit = np.eye(3)[k]
                work = force @ model.rigid_field(rotation=unit, about=centre)
                assert work == pytest.approx(VECTOR[k] * length, rel=1e-12)


def test_pressure_and_distributed_force_resultants():
    model = Model(scene([_plate((3, 2), (1.5, 0.4))], [Clamp(edge="plate:x=0")],
                        [Pressure("plate", 250.0)]))
    force = StateLoads(model).evaluate(model.reference, np.ones(1), False)[0]
    resultant = [force @ model.rigid_field(translation=u) for u in np.eye(3)]
    np.testing.assert_allclose(resultant, [0.0, 0.0, 250.0 * 1.5 * 0.4], atol=1e-10)
    for follower in (False, True):
        model = Model(scene([_beam("beam3d", 3)], [Clamp("beam:0")],
                            [DistributedForce("beam", VECTOR, follower=follower)]))
        force = model.nominal_load() + StateLoads(model).evaluate(
            model.reference, np.ones(1), False)[0]
        resultant = [force @ model.rigid_field(translation=u) for u in np.eye(3)]
        np.testing.assert_allclose(resultant, VECTOR, rtol=1e-12)
        # first moment about the clamp: the resultant at the middle of the 1 m beam
        work = force @ model.rigid_field(rotation=(0.0, 0.0, 1.0))
        assert work == pytest.approx(0.5 * VECTOR[1], rel=1e-12)


@pytest.mark.parametrize("element", ["beam2d", "beam3d"])
def test_rollup_of_a_cantilever_under_a_follower_end_moment(element):
    """M = 2 pi E I / L: a full circle of radius L / (2 pi) (Euler-Bernoulli): the tip back
    at the clamp, the middle node at the top (0, L / pi), the tip turned by 2 pi."""
    E, h, length = 2.1e11, 0.02, 1.0
    dim = 2 if element == "beam2d" else 3
    moment = 2 * math.pi * E * h**4 / 12 / length
    data = scene([_beam(element, 32, h)], [Clamp("beam:0")],
                 [PointMoment("beam:-1", moment if dim == 2 else (0.0, 0.0, moment),
                              follower=True)],
                 material=Material("m", E=E, nu=0.0, rho=7800.0),
                 static=Static(load_steps=10), solver=Solver(engine="python"))
    result = run_scene(data, progress=False)
    model, q = result.model, result.static
    tip, middle = model.node_index(data.loads[0].node), model.node_index(NodeRef("beam", 16))
    assert np.linalg.norm(q[model.node_dofs(tip, "r")]) < 0.005 * length
    np.testing.assert_allclose(q[model.node_dofs(middle, "r")][:2], [0.0, length / math.pi],
                               atol=0.005 * length)
    frame = model.node_frame(q, tip)
    turned = math.atan2(frame[1, 0], frame[0, 0])     # 2 pi, seen as 0 (middle: pi)
    assert abs(turned) < 0.005 * 2 * math.pi


def test_clamped_square_plate_under_pressure_against_kirchhoff():
    """w_max = 0.00126 q a^4 / D (Timoshenko and Woinowsky-Krieger, clamped square plate) at
    a low pressure; 12 x 12 plate3d elements, a / t = 25 (shear flexibility adds about 1 %,
    the mesh takes about as much away)."""
    a, t, E, pressure = 1.0, 0.04, 2.1e11, 1000.0
    plate = Body("plate", "plate3d", "m", thickness=t,
                 rectangle=Rectangle(corner=(0.0, 0.0, 0.0), size=(a, a), grid=(12, 12)))
    data = Scene(materials=[Material("m", E=E, nu=0.0, rho=7800.0)], bodies=[plate],
                 constraints=[Clamp(edge=f"plate:{e}") for e in ("x=0", "x=-1", "y=0", "y=-1")],
                 loads=[Pressure("plate", pressure)],
                 sensors=[Displacement("w", "plate:6,6", component="z")], static=Static())
    w = run_scene(data, progress=False).summary["static"]["sensors"]["w"]
    assert w == pytest.approx(0.00126 * pressure * a**4 / (E * t**3 / 12), rel=0.02)


def test_both_engines_agree_on_a_dynamic_follower_load_scene():
    data = scene([_beam("beam2d", 4)], [Clamp("beam:0")],
                 [PointForce("beam:-1", (0.0, -2e5), follower=True),
                  PointMoment("beam:2", 3e4, follower=True)],
                 [Displacement("tip_x", "beam:-1", component="x"),
                  Displacement("tip_y", "beam:-1", component="y")],
                 dynamic=Dynamic(t_end=0.02, step=1e-3, integrator="generalized_alpha"))
    runs = [run_scene(data, engine=engine, progress=False) for engine in ("python", "compiled")]
    for name in ("tip_x", "tip_y"):
        python, compiled = (run.sensors[name] for run in runs)
        assert np.abs(python).max() > 1e-3
        np.testing.assert_allclose(compiled, python, rtol=0, atol=1e-12)
