"""Box bodies of solid kinds (kinds whose meshes tile three axes): ``box = {corner, size,
grid}``, node references ``"BODY:I,J,K"``, faces ``"BODY:x=I"`` / ``y=J`` / ``z=K`` as
constraint targets and hexahedral VTK cells.  The scene tests read a stand-in: the node layout
of an 8-node brick carrying r only (a trilinear brick) as element.json states it, without
kernels (scenes are read and meshed, never solved); the shipped ANCF-3843 brick is solved in
tests/test_brick.py."""

from __future__ import annotations

import copy
import json
import tomllib

import numpy as np
import pytest

from runtime import Body, Clamp, Displacement, LineForce, Material, Scene, SceneError
from runtime.app import shapes
from runtime.catalog import generated_dir
from runtime.kernels import kind as kinds
from runtime.model.placements import Box
from runtime.model.scene import parse_scene

STEEL = Material("steel", E=2.1e11, nu=0.0, rho=7850.0)
BRICK = "brick_layout"
CORNERS = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1),
           (0, 1, 1)]
CORNER, SIZE, GRID = (0.5, -1.0, 2.0), (2.0, 0.6, 0.3), (4, 3, 2)


def _brick_document() -> dict:
    """element.json of the stand-in: the plate's document with a box domain x, y, z in
    [0, a] x [0, b] x [0, c] and r at its 8 corners (what the runtime meshes with)."""
    meta = copy.deepcopy(json.loads((generated_dir() / "plate3d" / "element.json").read_text()))
    axes = [{"coordinate": c, "low": [0, 1], "high": [1, 1], "scale": s}
            for c, s in zip("xyz", "abc", strict=True)]
    node = lambda p: [[float(p[a] if k == a else 0) for k in range(3)] + [0.0]  # noqa: E731
                      for a in range(3)]
    meta.update(name=BRICK, description="stand-in brick layout", n_shape=8, ndof=24,
                vectors=["r"], position_vectors=list(range(8)), quadrature=[2, 2, 2],
                nodes=[node(p) for p in CORNERS],
                straight_reference=[row for p in CORNERS for row in node(p)],
                laws={"svk": meta["laws"]["svk"]}, laws_not_applicable={},
                law_domains=["volume"],
                domain={"name": "box", "parameters": ["a", "b", "c"],
                        "labels": ["length", "height", "width"], "axes": axes,
                        "subdomains": {"volume": []}, "thickness": None})
    return meta


@pytest.fixture(autouse=True)
def brick_kind(tmp_path, monkeypatch):
    """A generated folder holding the shipped kinds and the stand-in brick."""
    for kind in generated_dir().glob("*/element.json"):
        (tmp_path / kind.parent.name).symlink_to(kind.parent)
    (tmp_path / BRICK).mkdir()
    (tmp_path / BRICK / "element.json").write_text(json.dumps(_brick_document()))
    monkeypatch.setattr("runtime.catalog.generated_dir", lambda: tmp_path)
    monkeypatch.setattr(kinds, "generated_dir", lambda: tmp_path)


def _box(grid=GRID) -> Body:
    return Body("blk", BRICK, "steel", box=Box(CORNER, SIZE, grid))


def test_box_body_places_a_node_at_every_lattice_point():
    body = Scene(materials=[STEEL], bodies=[_box()]).bodies[0]
    nx, ny, nz = GRID
    assert body.grid_shape == (nx + 1, ny + 1, nz + 1)
    assert body.n_nodes == len(body.mesh.points) == (nx + 1) * (ny + 1) * (nz + 1)
    assert body.geometry == pytest.approx(np.divide(SIZE, GRID))
    steps = np.divide(SIZE, GRID)
    # numbered x fastest, then y, then z
    expected = [np.add(CORNER, np.multiply((i, j, k), steps)) for k in range(nz + 1)
                for j in range(ny + 1) for i in range(nx + 1)]
    positions = [body.node_position(n) for n in range(body.n_nodes)]
    np.testing.assert_allclose(positions, expected, atol=1e-14)
    # each element's reference holds its corners' positions (r only: no gradients)
    e0 = body.placement.element_references(kinds.element_kind(BRICK), GRID)
    assert e0.shape == (nx * ny * nz, 24)
    nodes = np.array(positions)[body.mesh.connectivity]          # (elements, 8, 3)
    np.testing.assert_allclose(e0.reshape(-1, 8, 3), nodes, atol=1e-14)
    first = e0[0].reshape(8, 3) - CORNER
    np.testing.assert_allclose(first, np.multiply(CORNERS, steps), atol=1e-14)


def test_grid_indices_and_faces_of_a_box():
    nx, ny, nz = GRID
    scene = Scene(materials=[STEEL], bodies=[_box()],
                  constraints=[Clamp(edge="blk:z=0"), Clamp(edge="blk:x=-1")],
                  sensors=[Displacement("s", "blk:1,2,1", "z"),
                           Displacement("u", "blk:-1,-1,-1", "x")])
    body = scene.bodies[0]
    assert scene.sensors[0].node.index == 1 + 2 * (nx + 1) + 1 * (nx + 1) * (ny + 1)
    assert scene.sensors[1].node.index == body.n_nodes - 1
    positions = np.array([body.node_position(n) for n in range(body.n_nodes)])
    bottom = [n.index for n in scene.constraints[0].targets()]
    assert bottom == list(np.flatnonzero(np.isclose(positions[:, 2], CORNER[2])))
    assert len(bottom) == (nx + 1) * (ny + 1)
    end = [n.index for n in scene.constraints[1].targets()]
    assert end == list(np.flatnonzero(np.isclose(positions[:, 0], CORNER[0] + SIZE[0])))
    # written back as given
    text = scene.to_toml()
    assert "box = {corner = [0.5, -1.0, 2.0], size = [2.0, 0.6, 0.3], grid = [4, 3, 2]}" in text
    assert 'edge = "blk:x=-1"' in text
    assert 'node = "blk:1,2,1"' in text
    assert "section" not in text
    assert parse_scene(tomllib.loads(text)) == scene


@pytest.mark.parametrize("change, message", [
    ({"sensors": [Displacement("s", "blk:1,2", "z")]},
     'sensor[0].node: expected a grid index "BODY:I,J,K" (three integers)'),
    ({"sensors": [Displacement("s", "blk:1,2,9", "z")]},
     'sensor[0].node: grid index K 9 out of range for body "blk" with 3 node layers'),
    ({"constraints": [Clamp(edge="blk:w=0")]},
     'constraint[0].edge: expected a face "BODY:x=I", "BODY:y=J" or "BODY:z=K"'),
    ({"loads": [LineForce(edge="blk:x=-1", force_per_length=(0, 0, 1.0))]},
     'load[0].edge: blk:x=4 is a face of the box body "blk"; a line force acts along a grid '
     "line of a rectangle body"),
])
def test_bad_box_references_are_named(change, message):
    with pytest.raises(SceneError) as info:
        Scene(materials=[STEEL], bodies=[_box()], **change)
    assert str(info.value).startswith(message)


@pytest.mark.parametrize("change, message", [
    ({"section": {"thickness": 0.1}}, "body[0].section: brick_layout is a solid element; a "
                                      "solid body is a box"),
    ({"elements": 3}, "body[0].elements: the box's grid sets the elements of a solid body"),
    ({"box": {"corner": [0, 0, 0], "size": [1.0, 1.0], "grid": [1, 1, 1]}},
     "body[0].box.size: expected a list of 3 numbers"),
    ({"box": {"corner": [0, 0, 0], "size": [1.0, 1.0, 1.0], "grid": [1, 0, 1]}},
     "body[0].box.grid[1]: expected a positive integer"),
])
def test_bad_box_bodies_are_named(change, message):
    data = {"material": {"steel": STEEL.to_dict()}, "body": [{**_box().to_dict(), **change}]}
    with pytest.raises(SceneError) as info:
        parse_scene(data)
    assert str(info.value).startswith(message)


def test_boxes_are_for_solid_kinds_only():
    plate = {"name": "p", "element": "plate3d", "material": "steel",
             "section": {"thickness": 0.01},
             "box": {"corner": [0, 0, 0], "size": [1, 1, 1], "grid": [1, 1, 1]}}
    with pytest.raises(SceneError, match=r"^body\[0\].box: plate3d is not a solid element"):
        parse_scene({"material": {"steel": STEEL.to_dict()}, "body": [plate]})
    data = {"material": {"steel": STEEL.to_dict()},
            "body": [{"name": "b", "element": BRICK, "material": "steel"}]}
    with pytest.raises(SceneError, match=r"^body\[0\].box: missing required key"):
        parse_scene(data)


def test_hexahedral_cells_and_edges_of_a_sample_grid():
    fractions = [np.linspace(0, 1, 3), np.linspace(0, 1, 2), np.linspace(0, 1, 4)]
    points = shapes._grid(fractions)
    cells = shapes._grid_cells(fractions)
    assert cells.shape == (2 * 1 * 3, 8)
    corners = points[cells]                                    # (cells, 8, 3)
    # VTK order: the bottom quad counter-clockwise seen from +z, then the top one above it
    np.testing.assert_allclose(corners[:, 4:] - corners[:, :4],
                               np.broadcast_to([0, 0, 1 / 3], (6, 4, 3)), atol=1e-15)
    turn = np.cross(corners[:, 1] - corners[:, 0], corners[:, 3] - corners[:, 0])
    assert np.all(turn[:, 2] > 0)
    assert {tuple(np.round(c.min(axis=0), 12)) for c in corners} == {
        (i / 2, 0.0, round(k / 3, 12)) for i in range(2) for k in range(3)}
    # the outline walks the twelve edges of the element box, step by step
    loop = shapes._grid_loop(fractions)
    steps = np.abs(np.diff(points[loop], axis=0))
    assert np.all(np.count_nonzero(steps > 1e-12, axis=1) == 1)
    segments = {frozenset(pair) for pair in zip(loop[:-1], loop[1:], strict=True)}
    box_edges = 4 * (2 + 1 + 3)                                # four of each direction
    assert len(segments) == box_edges
    assert all(np.count_nonzero(np.isin(points[list(s)], [0.0, 1.0]).all(axis=0)) >= 2
               for s in segments)
