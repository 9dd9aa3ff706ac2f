"""Weld joints: two nodes share their position and their deformation gradient (linear joint
rows, Lagrange multipliers).  The rows hold under any rigid motion of the welded assembly; a
straight weld is one continuous beam; the welded L-frame of scenes/l_frame.toml deflects as
beam theory says (superposition of the two cantilevers)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scenes_small import STEEL, body, cantilever, scene, simulate
from scipy.spatial.transform import Rotation

import scenes
from runtime import (
    Body,
    Clamp,
    Displacement,
    PointForce,
    Scene,
    SceneError,
    Static,
    Weld,
    load_scene,
)
from runtime.model.model import Model
from runtime.model.scene import parse_scene


def _rigid(model: Model, rotation: np.ndarray, shift: np.ndarray) -> np.ndarray:
    """Coordinates of the reference turned by ``rotation`` and moved by ``shift``."""
    vectors = model.node_vectors(0)     # every node of these scenes carries the same vectors
    nodes = model.reference.reshape(-1, len(vectors), model.dim) @ rotation.T
    nodes[:, vectors.index("r")] += shift
    return nodes.ravel()


def _frame(directions) -> Model:
    """Three welded straight 3D bodies along ``directions``, end to end."""
    points = np.cumsum([np.zeros(3), *directions], axis=0)
    bodies = [body(name, "beam3d", 2, tuple(a), tuple(b), 0.05, 0.03)
              for name, a, b in zip("abc", points, points[1:], strict=False)]
    return Model(scene(bodies, [Clamp("a:0"), Weld(("a:-1", "b:0")), Weld(("b:-1", "c:0"))]))


def test_weld_rows_hold_under_any_rigid_motion():
    # bodies in general directions (reference frames not aligned with the axes)
    model = _frame([(1.0, 0.3, 0.2), (-0.2, 0.8, 0.5), (0.1, -0.3, 0.9)])
    per_node = len(model.node_vectors(0)) * 3
    assert model.joints.shape[0] == 2 * per_node   # position and 3 gradients per weld
    assert np.abs(model.joints @ model.reference).max() < 1e-14
    rng = np.random.default_rng(1)
    for _ in range(5):
        rotation = Rotation.random(random_state=rng).as_matrix()
        q = _rigid(model, rotation, rng.normal(size=3))
        assert np.abs(model.joints @ q).max() < 1e-13
    # and a uniform stretch (F = 1.01 I) too: both nodes share the deformation gradient
    assert np.abs(model.joints @ _rigid(model, 1.01 * np.eye(3), np.zeros(3))).max() < 1e-13


def test_weld_rows_tie_the_frames_of_an_l_corner():
    # column along +x, arm along +y: the arm's r_x is the column's r_y, its r_y is -r_x
    model = Model(load_scene(scenes.path("l_frame")))
    a, b = (model.node_index(ref) for ref in model.scene.constraints[1].nodes)
    q = model.reference.copy()
    turn = 0.1
    for name, value in (("r_x", (math.cos(turn), math.sin(turn), 0.0)),
                        ("r_y", (-math.sin(turn), math.cos(turn), 0.0))):
        q[model.node_dofs(a, name)] = value
    violation = model.joints @ q
    tied = model.joints[:, model.node_dofs(b)]
    # solve the weld rows for node b's coordinates
    rest = violation - tied @ q[model.node_dofs(b)]
    q[model.node_dofs(b)] = np.linalg.lstsq(tied.toarray(), -rest, rcond=None)[0]
    assert np.allclose(q[model.node_dofs(b, "r_x")], (-math.sin(turn), math.cos(turn), 0.0))
    assert np.allclose(q[model.node_dofs(b, "r_y")], (-math.cos(turn), -math.sin(turn), 0.0))
    assert np.allclose(q[model.node_dofs(b, "r_z")], (0.0, 0.0, 1.0))


@pytest.mark.parametrize("element", ["beam2d", "beam3d"])
def test_a_straight_weld_is_one_continuous_beam(element):
    dim = 2 if element == "beam2d" else 3
    z = (0.0,) * (dim - 2)
    force = (0.0, -500.0) + z
    halves = scene([body("a", element, 3, (0.0, 0.0) + z, (0.5, 0.0) + z),
                    body("b", element, 3, (0.5, 0.0) + z, (1.0, 0.0) + z)],
                   [Clamp("a:0"), Weld(("a:-1", "b:0"))], [PointForce("b:-1", force)],
                   [Displacement("tip_y", "b:-1", "y")], static=Static())
    whole = simulate(cantilever(6, element, force=force, static=Static()))
    assert simulate(halves).static_values["tip_y"] == pytest.approx(
        whole.static_values["tip_y"], rel=1e-10)


def l_frame_closed_form(a: float, b: float, E: float, h: float, w: float, force) -> tuple:
    """Tip displacement (x, y) in m of an L-frame by Euler-Bernoulli superposition: column
    of length a along +x clamped at x = 0, arm of length b along +y welded at its end, force
    (Px, Py) at the arm's tip; bending about z (I = w h^3 / 12), axial stretch E A.

    The corner carries F and the moment M_c = -b Px (about z) into the column:
    u_c = Px a / EA, v_c = Py a^3 / 3EI + M_c a^2 / 2EI, theta_c = Py a^2 / 2EI + M_c a / EI;
    the arm turns with the corner (a point at distance b moves by -theta_c b along x), bends
    as a cantilever under Px (Px b^3 / 3EI) and stretches under Py (Py b / EA)."""
    px, py = force[:2]
    inertia, area = w * h**3 / 12, w * h
    moment = -b * px
    u_c = px * a / (E * area)
    v_c = py * a**3 / (3 * E * inertia) + moment * a**2 / (2 * E * inertia)
    theta_c = py * a**2 / (2 * E * inertia) + moment * a / (E * inertia)
    return (u_c - theta_c * b + px * b**3 / (3 * E * inertia), v_c + py * b / (E * area))


def test_shipped_l_frame_matches_beam_theory():
    scene_ = load_scene(scenes.path("l_frame"))
    column, arm = scene_.bodies
    material = scene_.material_of(column)
    a = column.end[0] - column.start[0]
    b = arm.end[1] - arm.start[1]
    force = scene_.loads[0].force
    x, y = l_frame_closed_form(a, b, material.E, column.height, column.width, force)
    values = simulate(dataclasses.replace(scene_, modal=None, dynamic=None)).static_values
    assert values["weld_violation"] < 1e-12
    # 8 elements per member: discretisation error ~0.1 %; geometric nonlinearity of the
    # 3 N load P L^2 / EI ~ 1e-3; the weld's corner adds O((h / L) (h / l_element)) ~ 0.3 %
    assert values["tip_x"] == pytest.approx(x, rel=5e-3)
    assert values["tip_y"] == pytest.approx(y, rel=5e-3)
    assert x == pytest.approx(1.1543e-3, rel=1e-4) and y == pytest.approx(-6.6669e-4, rel=1e-4)


def _l_frame(element: str, elements: int, h: float, force) -> Scene:
    dim = 2 if element == "beam2d" else 3
    z = (0.0,) * (dim - 2)
    return scene([Body("a", element, "m", h, h, elements, (0.0, 0.0) + z, (1.0, 0.0) + z),
                  Body("b", element, "m", h, h, elements, (1.0, 0.0) + z, (1.0, 0.8) + z)],
                 [Clamp("a:0"), Weld(("a:-1", "b:0"))], [PointForce("b:-1", force + z)],
                 [Displacement("x", "b:-1", "x"), Displacement("y", "b:-1", "y")],
                 static=Static())


def test_l_frame_converges_to_beam_theory_in_2d_and_3d():
    # a slender frame (h / L = 0.01) under a load small enough to stay linear
    h, force = 0.01, (0.3 / 16, -0.2 / 16)
    exact = l_frame_closed_form(1.0, 0.8, STEEL.E, h, h, force)
    errors = []
    for elements in (2, 4, 8):
        values = {}
        for element in ("beam2d", "beam3d"):
            static = simulate(_l_frame(element, elements, h, force)).static_values
            values[element] = np.array([static["x"], static["y"]])
        # the 3D frame bends in its plane exactly as the 2D one
        assert np.allclose(values["beam3d"], values["beam2d"], rtol=1e-9, atol=0)
        errors.append(np.abs(values["beam2d"] / exact - 1).max())
    assert errors[1] < errors[0] / 3 and errors[2] < errors[1] / 3   # ~4x per halving
    assert errors[2] < 2e-3


def test_weld_between_two_held_nodes_is_redundant():
    data = _l_frame("beam2d", 2, 0.02, (1.0, 0.0)).to_dict()
    data["constraint"].append({"type": "pin", "node": "b:0"})
    data["constraint"][0]["node"] = "a:-1"
    with pytest.raises(SceneError, match=r"^constraint\[1\]\.nodes: redundant joint: both "
                                         r"positions are already held"):
        parse_scene(data)
