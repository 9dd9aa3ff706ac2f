"""Arc length through a limit point of a mechanism: a rigid bar hinged to the ground and held
by a spring (the quadratic rows of the rigid body and its hinge, a force element that the
load factor does not scale: scaled with the load, lambda would drop out of the equilibrium),
against the closed-form equilibrium path; the load stepping's equilibrium."""

from __future__ import annotations

import math
import tomllib

import numpy as np
import pytest

from runtime.model.model import Model
from runtime.model.scene import parse_scene
from runtime.solve.arc_length import trace_path
from runtime.solve.static import solve_static

LENGTH, ALPHA, STIFFNESS, LOAD = 1.0, math.radians(30.0), 1.0e4, 600.0


def _truss(method: str, load: float = LOAD, extra: str = "") -> str:
    """A 1 m bar (a rigid box along its body x) hinged at the origin about z, rising at
    ALPHA; a spring from its tip to the ground point (2 L cos ALPHA, 0, 0), unstretched at
    t = 0 (its length L); a downward force at the tip: a von Mises truss of one bar."""
    c, s = math.cos(ALPHA), math.sin(ALPHA)
    return f"""
[[body]]
type = "rigid"
name = "bar"
box = {{size = [{LENGTH}, 0.02, 0.02]}}
density = 7800.0
centre_of_mass = [{LENGTH / 2}, 0.0, 0.0]
rotation = [[{c}, {-s}, 0.0], [{s}, {c}, 0.0], [0.0, 0.0, 1.0]]
[[constraint]]
type = "body_revolute"
body = "bar"
axis = [0.0, 0.0, 1.0]
[[load]]
type = "spring_damper"
stiffness = {STIFFNESS}
end_a = {{body = "bar", point = [{LENGTH}, 0.0, 0.0]}}
end_b = [{2 * LENGTH * c}, 0.0, 0.0]
[[load]]
type = "body_force"
body = "bar"
point = [{LENGTH}, 0.0, 0.0]
force = [0.0, {-load}, 0.0]
[analysis.static]
method = "{method}"
{extra}
"""


def _load_on_the_path(theta: np.ndarray) -> np.ndarray:
    """The tip force P (N, downward) in equilibrium at the bar's angle theta:
    d/dtheta [k (l - L)^2 / 2 + P L sin(theta)] = 0 with
    l^2 = L^2 (4 cos^2 a - 4 cos a cos theta + 1)."""
    c = math.cos(ALPHA)
    length = LENGTH * np.sqrt(4 * c * c - 4 * c * np.cos(theta) + 1)
    return (-STIFFNESS * (length - LENGTH) * 2 * LENGTH * c * np.sin(theta)
            / (length * np.cos(theta)))


def _angles(model: Model, states: np.ndarray) -> np.ndarray:
    """The bar's angle (rad) in each state, continued along the states: its first axis u."""
    u = states[:, model.rigid["bar"].dofs[3:6]]
    return np.unwrap(np.arctan2(u[:, 1], u[:, 0]))


def test_arc_length_passes_the_limit_point_of_a_sprung_rigid_bar():
    scene = parse_scene(tomllib.loads(_truss("arc_length", extra="max_steps = 60\n"
                                                                 "arc_length = 0.05")))
    model = Model(scene)
    path = trace_path(model, scene.static, lambda q, lam: None)
    theta = _angles(model, path.states)
    forces = path.load_factors * LOAD
    # every converged point lies on the closed-form path, to the Newton tolerance's reach
    grid = np.linspace(0.0, ALPHA, 20001)
    on_grid = _load_on_the_path(grid)
    peak, peak_angle = float(on_grid.max()), float(grid[np.argmax(on_grid)])
    assert np.abs(forces - _load_on_the_path(theta)).max() <= 1e-8 * peak
    # the path climbs to the limit point (the largest force the raised bar carries), turns,
    # comes down through theta = 0 (the bar horizontal) and through the pulling branch
    # (negative forces) to the lower stable branch (theta below -ALPHA, forces rising)
    assert theta[0] == pytest.approx(ALPHA) and np.all(np.diff(theta) < 0)
    raised = theta > 0.0
    turn = int(np.argmax(np.where(raised, forces, -np.inf)))
    assert 0 < turn and forces[turn + 1] < forces[turn] <= peak
    assert theta[turn - 1] > peak_angle > theta[turn + 1]     # it went through the peak
    assert forces.min() < 0.0 and theta.min() < -ALPHA and forces[-1] > 0.0
    # the hinge and the body's unit axes hold along the path
    assert np.abs(model.holonomic.value(path.q)).max() <= 1e-9


def test_load_stepping_reaches_the_closed_form_equilibrium():
    # a load below the limit point: the equilibrium angle of the closed form from 1 or 8
    # load steps (the steps scale the force, not the spring: load_factors)
    ends = []
    for steps in (1, 8):
        scene = parse_scene(tomllib.loads(_truss("load_stepping", load=200.0,
                                                 extra=f"load_steps = {steps}")))
        model = Model(scene)
        found = solve_static(model, scene.static)
        ends.append(_angles(model, found.q[None, :])[0])
    assert _load_on_the_path(np.array(ends)) == pytest.approx([200.0, 200.0], rel=1e-9)
