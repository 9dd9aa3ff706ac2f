"""Meshes as data for any node layout: the structured meshes of every kind place exactly the
nodes its layout has (corners, mid-sides, interior), and node references, grid indices and
edges are taken from node positions, checked against the element nodes placed in metres
(``ElementKind.node_points``) without the mesh code."""

from __future__ import annotations

import math

import numpy as np
import pytest

from runtime import (
    Body,
    Clamp,
    Displacement,
    Hub,
    LineForce,
    Material,
    PointMoment,
    Rectangle,
    Scene,
    SceneError,
    SpinUp,
    Static,
    run_scene,
)
from runtime.catalog import generated_kinds
from runtime.cli import main
from runtime.kernels.kind import element_kind
from runtime.model import mesh as meshing
from runtime.model.model import Model

STEEL = Material("steel", E=2.1e11, nu=0.0, rho=7850.0)
KINDS = generated_kinds()
SURFACE_KINDS = [k for k in KINDS if len(element_kind(k).mesh_axes) == 2]
CORNER, SIZE = (0.1, -0.2, 0.3), (1.2, 0.4)


def _counts(kind: str) -> list[tuple[int, ...]]:
    return {1: [(1,), (2,), (9,)], 2: [(1, 1), (3, 2), (2, 5), (7, 1)],
            3: [(1, 1, 1), (3, 2, 1), (1, 2, 4)]}[len(element_kind(kind).mesh_axes)]


def _placed_nodes(kind: str, counts: tuple[int, ...], sides: tuple[float, ...]) -> set:
    """Distinct node points (rounded to 1e-12 m) of ``counts`` elements of sides ``sides``
    laid edge to edge from the origin: each element's node points in metres, shifted."""
    info = element_kind(kind)
    points = info.node_points(*sides, *(0.01,) * (3 - len(sides)))[:, info.mesh_axes]
    return {tuple(np.round(points[k] + np.multiply(cell, sides), 12))
            for cell in np.ndindex(*counts) for k in range(info.n_nodes)}


@pytest.mark.parametrize("kind", KINDS)
def test_node_counts_are_the_nodes_the_layout_places(kind):
    info = element_kind(kind)
    for counts in _counts(kind):
        placed = _placed_nodes(kind, counts, (0.5,) * len(counts))
        mesh = meshing.structured_mesh(info, counts)
        assert meshing.node_count(info, counts) == len(mesh.points) == len(placed)
        assert {tuple(np.round(p * 0.5, 12)) for p in mesh.points} == placed
        # every element's nodes are its layout's node points, in the kind's order
        cells = np.floor(mesh.points[mesh.connectivity[:, 0]] + 1e-9)
        assert np.allclose(mesh.points[mesh.connectivity] - cells[:, None, :],
                           info.node_fractions[:, info.mesh_axes], atol=1e-12)
    # large counts are counted without meshing (a grid of a million elements)
    big = (1000,) * len(info.mesh_axes)
    small = [meshing.node_count(info, (n,) * len(big)) for n in (1, 2, 3)]
    assert meshing.node_count(info, big) > small[-1] > small[0]


def test_serendipity_counts_corners_and_mid_sides():
    # (nx + 1)(ny + 1) corners, nx (ny + 1) + (nx + 1) ny mid-sides: the 3 x 2 grid of the
    # issue has 12 + 17 = 29 nodes, not the 35 of its full 7 x 5 lattice
    layouts = [k for k in SURFACE_KINDS if element_kind(k).n_nodes == 8]
    assert layouts
    for kind in layouts:
        for nx, ny in [(3, 2), (1, 1), (4, 7)]:
            expected = (nx + 1) * (ny + 1) + nx * (ny + 1) + (nx + 1) * ny
            assert meshing.node_count(element_kind(kind), (nx, ny)) == expected


def _plate(kind: str, grid=(3, 2)) -> Body:
    return Body("plate", kind, "steel", rectangle=Rectangle(CORNER, SIZE, grid), thickness=0.01)


def _lattice_point(kind: str, grid, i: int, j: int) -> tuple[float, float]:
    steps = [g * s for g, s in zip(grid, element_kind(kind).lattice_steps, strict=True)]
    return CORNER[0] + SIZE[0] * i / steps[0], CORNER[1] + SIZE[1] * j / steps[1]


@pytest.mark.parametrize("kind", SURFACE_KINDS)
def test_grid_indices_and_edges_name_the_nodes_at_those_points(kind):
    grid = (3, 2)
    model = Model(Scene(materials=[STEEL], bodies=[_plate(kind, grid)]))
    positions = model.reference[model.position_dofs()]
    body = model.scene.bodies[0]
    nx, ny = body.grid_shape
    found = 0
    for i in range(nx):
        for j in range(ny):
            x, y = _lattice_point(kind, grid, i, j)
            at = np.flatnonzero(np.hypot(positions[:, 0] - x, positions[:, 1] - y) < 1e-12)
            scene = dict(materials=[STEEL], bodies=[body])
            if at.size:
                sensor = Displacement("s", f"plate:{i},{j}", "z")
                assert Scene(**scene, sensors=[sensor]).sensors[0].node.index == at[0]
                found += 1
                continue
            # no node there: the error lists the nearest nodes, which exist
            with pytest.raises(SceneError) as info:
                Scene(**scene, sensors=[Displacement("s", f"plate:{i},{j}", "z")])
            text = str(info.value)
            assert text.startswith(f"sensor[0].node: no node at grid point {i},{j} of body "
                                   f'"plate"')
            distance = np.hypot((positions[:, 0] - x) / SIZE[0] * nx,
                                (positions[:, 1] - y) / SIZE[1] * ny)
            nearest = np.flatnonzero(distance <= distance.min() + 1e-9)
            for node in nearest:
                assert f"(node {node})" in text
    assert found == model.n_nodes
    # an edge holds the nodes on its lattice line, in order along it
    for axis, lines in (("x", nx), ("y", ny)):
        a = "xy".index(axis)
        for line in range(lines):
            edge = Scene(materials=[STEEL], bodies=[body],
                         constraints=[Clamp(edge=f"plate:{axis}={line}")]).constraints[0]
            place = _lattice_point(kind, grid, line, line)[a]
            on_line = np.flatnonzero(np.abs(positions[:, a] - place) < 1e-12)
            assert [n.index for n in edge.targets()] == list(on_line)
            assert np.all(np.diff(positions[on_line, 1 - a]) > 0)


@pytest.mark.parametrize("kind", SURFACE_KINDS)
def test_clamped_strip_holds_the_nodes_at_its_edge_and_loads_the_free_edge(kind):
    # the case: a 3 x 2 grid; the clamp x = 0 holds exactly the nodes at x = corner
    # (all they carry), the tip line load acts on nodes at x = corner + a only (beyond
    # round-off), the sensor reads
    scene = Scene(materials=[STEEL], bodies=[_plate(kind)],
                  constraints=[Clamp(edge="plate:x=0")],
                  loads=[LineForce(edge="plate:x=-1", force_per_length=(0, 0, -10.0))],
                  sensors=[Displacement("tip", "plate:-1", "z")], static=Static())
    model = Model(scene)
    positions = model.reference[model.position_dofs()]
    at_root = np.flatnonzero(np.abs(positions[:, 0] - CORNER[0]) < 1e-12)
    held = np.concatenate([model.node_dofs(n) for n in at_root])
    assert sorted(model.fixed) == sorted(held)
    load = model.nominal_load()
    loaded = {n for n in range(model.n_nodes)
              if np.abs(load[model.node_dofs(n)]).max() > 1e-12 * np.abs(load).max()}
    assert loaded == set(np.flatnonzero(np.abs(positions[:, 0] - CORNER[0] - SIZE[0]) < 1e-12))
    assert load[model.position_dofs()][:, 2].sum() == pytest.approx(-10.0 * SIZE[1], rel=1e-12)
    result = run_scene(scene, progress=False)
    assert result.status == "ok" and result.summary["static"]["sensors"]["tip"] < 0


FRAMELESS = [k for k in KINDS if element_kind(k).frame_gap() is not None]


@pytest.mark.parametrize("kind", FRAMELESS)
def test_frames_and_moments_on_nodes_without_a_frame_are_scene_errors(kind, tmp_path):
    info = element_kind(kind)
    body = (_plate(kind) if len(info.mesh_axes) == 2 else
            Body("beam", kind, "steel", 0.02, 0.02, 2, (0.0,) * info.dim, (1.0,) + (0.0,) *
                 (info.dim - 1)))
    name = body.name
    carried = ", ".join(info.vectors)
    with pytest.raises(SceneError) as error:
        Scene(materials=[STEEL], bodies=[body],
              sensors=[Displacement("s", f"{name}:1", "z", frame=f"{name}:0")])
    assert str(error.value).startswith(f'sensor[0].frame: node "{name}:0" of body "{name}" '
                                       f"({kind}) has no frame: its nodes carry only {carried}")
    with pytest.raises(SceneError) as error:
        Scene(materials=[STEEL], bodies=[body], loads=[PointMoment(f"{name}:-1", (0, 1.0, 0))])
    assert str(error.value).startswith(f'load[0].node: node "{name}:-1" of body "{name}" '
                                       f"({kind}) cannot take a moment: its nodes carry only "
                                       f"{carried}")
    # from the command line: exit 2, the message on one line
    path = tmp_path / "scene.toml"
    text = Scene(materials=[STEEL], bodies=[body]).to_toml()
    path.write_text(text + f'\n[[load]]\ntype = "point_moment"\nnode = "{name}:-1"\n'
                           "moment = [0.0, 1.0, 0.0]\n")
    assert main(["run", str(path), "--out", str(tmp_path / "out"), "--quiet"]) == 2


def test_lattice_steps_follow_the_node_fractions():
    for kind in KINDS:
        info = element_kind(kind)
        for a, steps in zip(info.mesh_axes, info.lattice_steps, strict=True):
            fractions = info.node_fractions[:, a] * steps
            assert np.allclose(fractions, np.round(fractions), atol=1e-12)
            assert math.gcd(steps, *np.round(fractions).astype(int)) == 1


@pytest.mark.parametrize("kind", [k for k in FRAMELESS if element_kind(k).dim == 3])
def test_a_hub_about_the_one_direction_a_node_carries_is_refused(kind):
    # its only gradient (a cable's tangent, a shell's normal) would not turn: a silent clamp
    info = element_kind(kind)
    surface = len(info.mesh_axes) == 2
    body = (_plate(kind) if surface else
            Body("beam", kind, "steel", 0.02, 0.02, 2, (0.0, 0.0, 0.0), (0.0, 1.0, 0.0)))
    along = (0.0, 0.0, 2.0) if surface else (0.0, -3.0, 0.0)
    across = (1.0, 0.0, 0.0)
    name = body.name
    with pytest.raises(SceneError, match=r"^constraint\[0\]\.axis: a rotation about the "
                                         f"{'normal' if surface else 'axis'} of body '{name}'"):
        Scene(materials=[STEEL], bodies=[body], constraints=[Hub(f"{name}:1", SpinUp(1.0, 1.0),
                                                                 axis=along)])
    Scene(materials=[STEEL], bodies=[body], constraints=[Hub(f"{name}:1", SpinUp(1.0, 1.0),
                                                             axis=across)])
