"""Point moments: the consistent generalised force on a node's section gradients does the
virtual work M . d theta of the moment on a small rotation of the section, and a cantilever
under a tip moment bends as Euler-Bernoulli says (tip slope M L / EI, deflection
M L^2 / 2EI: pure bending, which the elements represent exactly)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scenes_small import STEEL, body, cantilever, scene, second_moment, simulate

from runtime import Arc, Body, Clamp, Pin, PointMoment, SceneError, Static
from runtime.model.model import Model


def _node_rotation_work(model: Model, node: int, force: np.ndarray,
                        turn: np.ndarray) -> float:
    """Q . dq for the small rotation ``turn`` (rad; a number in 2D) of the node's section
    vectors in the reference (dq = turn x r_k on every gradient)."""
    work = 0.0
    for name in model.node_vectors(node)[1:]:
        dofs = model.node_dofs(node, name)
        gradient = model.reference[dofs]
        change = (turn * np.array([-gradient[1], gradient[0]]) if model.dim == 2
                  else np.cross(turn, gradient))
        work += force[dofs] @ change
    return work


def test_virtual_work_of_a_moment_on_a_turned_section_3d():
    # a curved body: the node's reference frame is not the global one
    arc = Arc((0.0, 1.0, 0.5), 1.0, -70.0, 80.0)
    rng = np.random.default_rng(3)
    moment = rng.normal(size=3)
    data = scene([Body("arc", "beam3d", "m", 0.1, 0.05, 3, arc=arc)], [Clamp("arc:0")],
                 [PointMoment("arc:2", moment)])
    model = Model(data)
    force = model.nominal_load()
    node = model.node_index(data.loads[0].node)
    assert np.count_nonzero(force) <= 6                         # r_y and r_z of one node
    assert np.all(force[model.node_dofs(node, "r")] == 0)
    assert np.all(force[model.node_dofs(node, "r_x")] == 0)
    for _ in range(4):
        turn = rng.normal(size=3)
        assert _node_rotation_work(model, node, force, turn) == pytest.approx(moment @ turn,
                                                                              rel=1e-12)
    # a rigid rotation of the whole body: the same work (nothing else is loaded)
    turn = rng.normal(size=3)
    assert force @ model.rigid_field(rotation=turn) == pytest.approx(moment @ turn, rel=1e-12)


def test_virtual_work_of_a_moment_in_2d():
    data = scene([body(elements=2, start=(0.0, 0.0), end=(0.6, 0.8))], [Clamp("beam:0")],
                 [PointMoment("beam:1", 7.0)])
    model = Model(data)
    force = model.nominal_load()
    assert _node_rotation_work(model, 1, force, 0.3) == pytest.approx(7.0 * 0.3, rel=1e-12)
    assert np.linalg.norm(force[model.node_dofs(1, "r_y")]) == pytest.approx(7.0)


@pytest.mark.parametrize("element, moment, axis", [
    ("beam2d", 175.0, 1),
    ("beam3d", (0.0, 0.0, 175.0), 1),      # about z: bends towards +y
    ("beam3d", (0.0, 90.0, 0.0), 2),       # about y: bends towards -z
])
@pytest.mark.parametrize("elements", [1, 4])
def test_cantilever_under_a_tip_moment(element, moment, axis, elements):
    h, w, length = 0.1, 0.06, 1.5
    data = cantilever(elements, element, length, h, w, sensors=[], static=Static())
    data = scene(data.bodies, data.constraints, [PointMoment("beam:-1", moment)],
                 static=Static())
    result = simulate(data)
    model, q = result.model, result.static.q
    tip = model.node_index(data.loads[0].node)
    size = moment if element == "beam2d" else np.linalg.norm(moment)
    # bending about z uses I = w h^3 / 12, about y I = h w^3 / 12
    inertia = second_moment(h, w) if axis == 1 else second_moment(w, h)
    sign = 1.0 if axis == 1 else -1.0
    slope = size * length / (STEEL.E * inertia)
    deflection = size * length**2 / (2 * STEEL.E * inertia)
    assert slope < 1e-3                                       # small rotations
    r_x = q[model.node_dofs(tip, "r_x")]
    displacement = q[model.node_dofs(tip, "r")] - model.reference[model.node_dofs(tip, "r")]
    # exact for pure bending; the moment of the fixed tractions is M cos(theta)
    assert sign * math.atan2(r_x[axis], r_x[0]) == pytest.approx(slope, rel=1e-5)
    assert sign * displacement[axis] == pytest.approx(deflection, rel=1e-5)


def test_moment_on_a_pinned_node_but_not_on_a_clamped_one():
    bodies = [body(elements=2)]
    pinned = scene(bodies, [Pin("beam:0"), Pin("beam:-1")], [PointMoment("beam:0", 5.0)],
                   static=Static())
    assert simulate(pinned).static.q is not None
    with pytest.raises(SceneError, match=r"^load\[0\]\.node: the section of beam:0 is held "
                                         r"by constraint\[0\] \(clamp\): a moment there does "
                                         r"nothing; expected a node whose section can turn$"):
        scene(bodies, [Clamp("beam:0")], [PointMoment("beam:0", 5.0)])
    with pytest.raises(SceneError, match=r"^load\[0\]\.moment: expected a number \(the moment "
                                         r"in N m about z; the scene is 2D\), got \[0, 0, 1\]"):
        scene(bodies, [Clamp("beam:0")], [PointMoment("beam:1", [0, 0, 1])])
