"""Modal analysis of models with rigid bodies (quadratic constraint rows): the linearisation
on the constraint manifold with the rows' geometric stiffness, against the closed-form
frequencies of compound pendulums and against a dynamic run's small oscillation."""

from __future__ import annotations

import dataclasses
import math
import tomllib

import numpy as np
import pytest
import scipy.sparse

from runtime.app.simulation import Simulation
from runtime.model.model import Model
from runtime.model.scene import Scene, parse_scene
from runtime.model.settings import Dynamic
from runtime.solve import engines
from runtime.solve.modal import modal, modal_shapes
from runtime.solve.static import solve_static

SIZE, DENSITY, G = (0.6, 0.1, 0.04), 7800.0, 9.81
PIVOT = 0.2          # m: the pivot above the centre of mass (body x = -PIVOT)


def _pendulum(joint: str, extra: str = "") -> Scene:
    """A steel box hanging from a pivot at the origin, its long side along -y (body x
    along -y: the rotation's first column), the centre of mass PIVOT below the pivot."""
    text = f"""
[[body]]
type = "rigid"
name = "box"
box = {{size = [{SIZE[0]}, {SIZE[1]}, {SIZE[2]}]}}
density = {DENSITY}
position = [0.0, {-PIVOT}, 0.0]
rotation = [[0, 1, 0], [-1, 0, 0], [0, 0, 1]]
[[constraint]]
type = "{joint}"
body = "box"
point = [{-PIVOT}, 0.0, 0.0]
{extra}
[[load]]
type = "gravity"
acceleration = [0, {-G}, 0]
[analysis.static]
[analysis.modal]
modes = 3
about = "static"
"""
    return parse_scene(tomllib.loads(text))


def _compound(moment_about_com: float) -> float:
    """omega (rad/s) of a compound pendulum: sqrt(m g d / (I_c + m d^2))."""
    mass = DENSITY * math.prod(SIZE)
    return math.sqrt(mass * G * PIVOT / (moment_about_com + mass * PIVOT ** 2))


def _box_moments() -> tuple[float, float, float]:
    """Principal moments about the centre of mass, body axes (kg m^2)."""
    a, b, c = SIZE
    mass = DENSITY * a * b * c
    return mass * (b * b + c * c) / 12, mass * (a * a + c * c) / 12, mass * (a * a + b * b) / 12


def _static_modes(scene: Scene, modes: int):
    model = Model(scene)
    found = solve_static(model, scene.static)
    return model, modal_shapes(model, found.q, modes, found.multipliers)


def _balancing_multipliers(model: Model) -> np.ndarray:
    """The multipliers that balance the nominal loads at the reference, C^T mu = F + load
    (least squares over every constraint row, as a static solution's)."""
    rows = scipy.sparse.vstack([model.joints_free,
                                model.holonomic.jacobian_free(model.reference)]).toarray()
    force = model.internal_forces(model.reference, jacobian=False)[0] + model.nominal_load()
    return np.linalg.lstsq(rows.T, force[model.free], rcond=None)[0]


def test_a_compound_pendulum_on_a_revolute_joint_swings_at_its_closed_form_frequency():
    # one degree of freedom left by the hinge (body z along global z): the swing in the x-y
    # plane, whose restoring moment comes only from the rows' geometric stiffness
    model, found = _static_modes(_pendulum("body_revolute", "axis = [0, 0, 1]"), 3)
    assert found.frequencies.size == 1
    assert found.frequencies[0] == pytest.approx(_compound(_box_moments()[2]), rel=1e-9)
    # the mode turns the box about the pivot: the centre of mass (the body origin) moves
    # along x, the first axis (along -y) turns towards x, nothing moves along z
    shape = found.shapes[0][model.rigid["box"].dofs]
    origin, first_axis = shape[0:3], shape[3:6]
    assert abs(origin[0]) == pytest.approx(1.0)
    assert np.abs(origin[1:]).max() <= 1e-9
    assert first_axis[0] == pytest.approx(origin[0] / PIVOT, rel=1e-9)   # r0 = pivot + d u
    assert np.abs(shape[2::3]).max() <= 1e-9


def test_a_body_on_a_spherical_joint_has_two_swings_and_a_free_spin():
    # three rotations: the swings about global x (about body y) and about global z (body
    # z), each at its compound-pendulum frequency, and the spin about the vertical (the
    # body's long axis, body x), which gravity does not restore.  (Its static solve would
    # meet that free spin: the multipliers are the loads' balance at the reference.)
    model = Model(_pendulum("body_spherical"))
    found = modal(model, model.reference, 3, _balancing_multipliers(model))
    moments = _box_moments()
    expected = sorted([0.0, _compound(moments[1]), _compound(moments[2])])
    assert found == pytest.approx(expected, rel=1e-8, abs=1e-6)


def test_the_modal_frequency_is_the_period_of_a_small_swing():
    # independent of the linearisation: release the hinged box 0.01 rad off the vertical and
    # time its period in a dynamic run (generalized-alpha without numerical damping)
    scene = _pendulum("body_revolute", "axis = [0, 0, 1]")
    period = 2 * math.pi / _static_modes(scene, 1)[1].frequencies[0]
    theta = 0.01
    rotation = np.array([[math.sin(theta), math.cos(theta), 0.0],
                         [-math.cos(theta), math.sin(theta), 0.0], [0.0, 0.0, 1.0]])
    origin = -rotation @ np.array([-PIVOT, 0.0, 0.0])       # the pivot stays at 0
    tilted = dataclasses.replace(scene.rigid_bodies[0], position=tuple(origin),
                                 rotation=tuple(map(tuple, rotation)))
    dynamic = Dynamic(t_end=3 * period, step=period / 400, integrator="generalized_alpha",
                      rho_inf=1.0)
    scene = dataclasses.replace(scene, rigid_bodies=(tilted,), static=None, modal=None,
                                dynamic=dynamic)
    model = Model(scene)
    runner = engines.make("compiled", model, dynamic, model.reference.copy())
    states = []
    runner.run(dynamic.t_end, dynamic.step, lambda t, q, v: states.append((t, q.copy())))
    times = np.array([t for t, _ in states])
    x = np.array([q[model.rigid["box"].dofs[0]] for _, q in states])   # centre of mass
    up = np.flatnonzero((x[:-1] < 0) & (x[1:] >= 0))
    crossings = times[up] - x[up] * (times[up + 1] - times[up]) / (x[up + 1] - x[up])
    assert crossings.size >= 2
    assert np.diff(crossings) == pytest.approx(period, rel=1e-4)


def test_a_scene_with_a_rigid_body_runs_its_modal_analysis():
    simulation = Simulation(_pendulum("body_revolute", "axis = [0, 0, 1]"))
    simulation.build()
    assert simulation.analyses() == 0
    assert simulation.modes.frequencies_rad_s == pytest.approx([_compound(_box_moments()[2])],
                                                         rel=1e-9)


def test_modes_about_an_unloaded_reference_need_no_multipliers():
    # no loads: the rows carry no multipliers, and the hinged box is free to turn (one
    # zero frequency); multipliers of the wrong size are refused, naming the size
    scene = _pendulum("body_revolute", "axis = [0, 0, 1]")
    model = Model(dataclasses.replace(scene, loads=()))
    assert modal(model, model.reference, 1) == pytest.approx([0.0], abs=1e-6)
    with pytest.raises(ValueError, match=r"modal: multipliers: expected \d+ values"):
        modal(model, model.reference, 1, np.zeros(3))
