"""The 8-node serendipity shell (shell3d_8node, nodes at corners and mid-sides carrying r and
r_z) end to end: the shipped strip scene against beam theory, its mid-side nodes, and its
ParaView output."""

from __future__ import annotations

import dataclasses
import math

import meshio
import numpy as np
import pytest

import scenes
from runtime import Modal, load_scene, run_scene
from runtime.app.shapes import Shape, write_vtu


@pytest.fixture(scope="module")
def strip():
    scene = load_scene(scenes.path("shell_strip"))
    return scene, run_scene(dataclasses.replace(scene, dynamic=None, modal=Modal(modes=1)),
                            progress=False)


def test_shell_strip_bends_as_beam_theory_says(strip):
    scene, result = strip
    body = scene.bodies[0]
    assert body.element == "shell3d_8node" and scene.materials["steel"].nu == 0.0
    (length, width), thickness = body.rectangle.size, body.thickness
    material = scene.materials[body.material]
    load = scene.loads[0].force_per_length[2] * width
    inertia, area = width * thickness**3 / 12, width * thickness
    tip = result.summary["static"]["sensors"]["tip_z"]
    # Euler-Bernoulli P L^3 / 3 E I (measured -0.36 % with 8 elements)
    assert tip == pytest.approx(load * length**3 / (3 * material.E * inertia), rel=0.01)
    # the section stays straight: the mid-side node of the free edge moves as its corners
    assert result.summary["static"]["sensors"]["tip_z_middle"] == pytest.approx(tip, rel=1e-9)
    omega = 1.8751**2 * math.sqrt(material.E * inertia / (material.rho * area * length**4))
    assert result.modes.frequencies_rad_s[0] == pytest.approx(omega, rel=0.01)


def test_shell_strip_counts_corner_and_mid_side_nodes(strip):
    _, result = strip
    model = result.model
    # 8 x 1 elements: 9 x 2 corners and 8 x 2 + 9 mid-sides, r and r_z (6 coordinates) each
    assert model.n_nodes == 18 + 25 and model.size == 43 * 6
    positions = model.reference[model.position_dofs()]
    lattice = np.round(positions[:, :2] / [1.0 / 16, 0.1 / 2]).astype(int)
    assert not np.any((lattice[:, 0] % 2 == 1) & (lattice[:, 1] % 2 == 1))  # no centres


def test_shell_strip_writes_quads_through_every_node(strip, tmp_path):
    _, result = strip
    model = result.model
    shape = Shape(model)
    displacement = shape.sample(result.static) - shape.sample(model.reference)
    path = write_vtu(tmp_path / "static.vtu", shape, model.reference,
                     {"displacement": displacement})
    mesh = meshio.read(path)
    assert [block.type for block in mesh.cells] == ["quad"]
    assert mesh.cells[0].data.shape == (8 * 4 * 4, 4)
    # the sample points hold every node: its reference position, its displacement
    q = result.static
    np.testing.assert_allclose(mesh.points[shape.node_points],
                               model.reference[model.position_dofs()], atol=1e-14)
    np.testing.assert_allclose(
        mesh.point_data["displacement"][shape.node_points],
        (q - model.reference)[model.position_dofs()], atol=1e-12 * np.abs(q).max())
    # every quad is a proper cell of the flat strip: positive area, counter-clockwise in x-y
    corners = mesh.points[mesh.cells[0].data]
    normal = np.cross(corners[:, 2] - corners[:, 0], corners[:, 3] - corners[:, 1])
    assert np.all(normal[:, 2] > 0)
