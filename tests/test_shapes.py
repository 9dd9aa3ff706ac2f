"""Shapes (runtime.app.shapes): centre lines and plate mid-surfaces sampled from the shape
functions of every generated kind, VTU files read back by meshio, the PVD collections, mode
shapes, the GIF and the static snapshot (beams and plates), through ``ancf run --vtk --gif``
too."""

from __future__ import annotations

import csv
import json
import os
import xml.etree.ElementTree as ET

import meshio
import numpy as np
import pytest
from scenes_small import body, cantilever, scene
from scipy.spatial.transform import Rotation

from runtime import Body, Clamp, LinearRamp, LineForce, Rectangle
from runtime.app import shapes
from runtime.app import writers as output
from runtime.app.run import run
from runtime.app.shapes import PER_ELEMENT, Frames, Shape, VtkSeries
from runtime.app.simulation import run_scene
from runtime.catalog import generated_kinds
from runtime.cli import main
from runtime.kernels.kind import element_kind
from runtime.model.model import Model
from runtime.model.placements import Box
from runtime.model.scene import parse_scene
from runtime.model.toml_io import toml_text

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
SENSORS = [{"name": "tip_y", "type": "displacement", "node": "beam:-1", "component": "y"},
           {"name": "tip_x", "type": "displacement", "node": "beam:-1", "component": "x"}]


def small(element: str = "beam2d", analyses=("static", "modal", "dynamic"),
          backend: str = "numpy") -> dict:
    tables = {"static": {}, "modal": {"modes": 2},
              "dynamic": {"t_end": 0.03, "step": 2.5e-3, "output_every": 5e-3}}
    force = [0.0, -1e5] + ([0.0] if element == "beam3d" else [])
    return cantilever(elements=2, element=element, force=force, sensors=SENSORS,
                      law={"type": "linear_ramp", "duration": 0.01},
                      **{k: tables[k] for k in analyses},
                      solver={"backend": backend}).to_dict()


def hermite(xi: float, length: float) -> np.ndarray:
    """Cubic Hermite weights of r0, r0_x, r1, r1_x at xi = x / L (textbook)."""
    return np.array([1 - 3 * xi**2 + 2 * xi**3, length * (xi - 2 * xi**2 + xi**3),
                     3 * xi**2 - 2 * xi**3, length * (xi**3 - xi**2)])


def read_pvd(path) -> list[tuple[float, str]]:
    root = ET.parse(path).getroot()
    return [(float(d.get("timestep")), d.get("file")) for d in root.iter("DataSet")]


def nodal_vectors(model: Model, q: np.ndarray) -> np.ndarray:
    """(nodes, 3) positions r of every node of ``q`` (z = 0 in 2D)."""
    nodes = model.n_nodes
    result = np.zeros((nodes, 3))
    for n in range(nodes):
        result[n, :model.dim] = q[model.node_dofs(n, "r")]
    return result


# --------------------------------------------------------------------------- centre lines

@pytest.mark.parametrize("element", ["beam2d", "beam3d"])
def test_centre_line_is_the_hermite_interpolation_of_the_nodes(element):
    model = Model(parse_scene(small(element)))
    line = Shape(model)
    assert line.points == 2 * PER_ELEMENT + 1
    assert [(name, cells.tolist()) for name, cells in line.cells] == [
        ("line", [[k, k + 1] for k in range(2 * PER_ELEMENT)])]
    assert line.outline.tolist() == list(range(line.points))
    assert line.node_points.tolist() == [0, PER_ELEMENT, 2 * PER_ELEMENT]
    # the reference: points equally spaced along the straight beam
    reference = line.sample(model.reference)
    assert reference[:, 0] == pytest.approx(np.linspace(0.0, 1.0, line.points), abs=1e-15)
    assert not reference[:, 1:].any()
    # any coordinates: nodes exactly, between them the cubic Hermite curve of r and r_x
    q = model.reference + np.random.default_rng(1).normal(0.0, 0.1, model.size)
    sampled = line.sample(q)
    assert np.array_equal(sampled[line.node_points], nodal_vectors(model, q))
    length = 0.5
    for k in range(1, PER_ELEMENT):
        xi = k / PER_ELEMENT
        nodes = [q[model.node_dofs(n, v)] for n, v in ((0, "r"), (0, "r_x"), (1, "r"),
                                                        (1, "r_x"))]
        expected = sum(w * r for w, r in zip(hermite(xi, length), nodes, strict=True))
        assert sampled[k, :model.dim] == pytest.approx(expected, rel=1e-12, abs=1e-14)


def test_several_bodies_are_separate_polylines():
    data = scene([body("a", "beam2d", 2, [0.0, 0.0], [1.0, 0.0]),
                  body("b", "beam2d", 3, [1.0, 0.0], [1.0, 1.0])],
                 [{"type": "clamp", "node": "a:0"}, {"type": "revolute",
                                                     "nodes": ["a:-1", "b:0"]}],
                 solver={"backend": "numpy"}).to_dict()
    line = Shape(Model(parse_scene(data)))
    first = 2 * PER_ELEMENT + 1
    assert line.points == first + 3 * PER_ELEMENT + 1
    [(name, segments)] = line.cells
    assert name == "line"
    assert [first - 1, first] not in segments.tolist()   # no cell across bodies
    assert len(segments) == line.points - 2
    # drawn as two polylines, not joined
    assert line.outline.tolist() == [*range(first), -1, *range(first, line.points)]


# --------------------------------------------------------------------------- every kind

KINDS = generated_kinds()
PLATE_KINDS = [k for k in KINDS if element_kind(k).mesh_axes == [0, 1]]
CORNER, SIZE = (0.1, -0.2, 0.3), (1.0, 0.4)     # a plate body's rectangle (m)
BOX_SIZE, BOX_GRID = (1.0, 0.4, 0.2), (2, 1, 1)  # a solid body's box from CORNER (m)


def kind_body(kind: str, name: str = "body") -> Body:
    """A small body of ``kind``: 2 elements along a slanted line from the origin (0.8, 0.6
    [, 0]) (m) for a line kind, a 2 x 3 grid over the rectangle CORNER, SIZE for a plate,
    a 2 x 1 x 1 grid over the box CORNER, BOX_SIZE for a solid."""
    info = element_kind(kind)
    if info.mesh_axes == [0]:
        return Body(name, kind, "m", 0.02, 0.01, 2, (0.0,) * info.dim,
                    (0.8, 0.6) + (0.0,) * (info.dim - 2))
    if len(info.mesh_axes) == 3:
        return Body(name, kind, "m", box=Box(CORNER, BOX_SIZE, BOX_GRID))
    return Body(name, kind, "m", rectangle=Rectangle(CORNER, SIZE, (2, 3)), thickness=0.01)


def kind_model(*bodies: Body) -> Model:
    return Model(scene(list(bodies), solver={"backend": "numpy"}))


def rotation(dim: int) -> np.ndarray:
    """A rotation matrix (dim, dim) about no particular axis."""
    if dim == 2:
        return np.array([[np.cos(1.1), -np.sin(1.1)], [np.sin(1.1), np.cos(1.1)]])
    return Rotation.from_rotvec([0.3, -1.1, 0.7]).as_matrix()


@pytest.mark.parametrize("per_element", [3, PER_ELEMENT])
@pytest.mark.parametrize("kind", KINDS)
def test_samples_at_the_nodes_are_the_nodal_positions(kind, per_element):
    model = kind_model(kind_body(kind))
    shape = Shape(model, per_element)
    assert len(set(shape.node_points.tolist())) == model.n_nodes
    q = model.reference + np.random.default_rng(2).normal(0.0, 0.1, model.size)
    sampled = shape.sample(q)
    assert sampled[shape.node_points, :model.dim] == pytest.approx(
        q[model.position_dofs()], rel=1e-13, abs=1e-15)
    assert not sampled[:, model.dim:].any()
    # every sample point belongs to a cell of the kind's type (line or quad) and the outline
    axes = element_kind(kind).mesh_axes
    [(name, cells)] = shape.cells
    assert name == shapes.CELL_TYPES[len(axes)] and cells.shape[1] == 2 ** len(axes)
    assert set(cells.ravel().tolist()) == set(range(shape.points))
    assert set(shape.outline.tolist()) - {-1} <= set(range(shape.points))


@pytest.mark.parametrize("kind", KINDS)
def test_reference_samples_evenly_span_the_line_or_rectangle(kind):
    body = kind_body(kind)
    model = kind_model(body)
    shape = Shape(model)
    reference = shape.sample(model.reference)
    name, cells = shape.cells[0]
    if body.box is not None:        # an even grid filling the box, PER_ELEMENT^3 per element
        axes = [corner + np.linspace(0.0, size, count * PER_ELEMENT + 1)
                for corner, size, count in zip(CORNER, BOX_SIZE, BOX_GRID, strict=True)]
        grid = np.array(np.meshgrid(*axes, indexing="ij")).reshape(3, -1).T
        assert np.unique(np.round(reference, 12), axis=0) == pytest.approx(
            np.unique(np.round(grid, 12), axis=0), abs=1e-12)
        assert len(reference) == len(grid) and len(cells) == 2 * PER_ELEMENT**3
        return
    if body.rectangle is None:      # 2 elements, PER_ELEMENT intervals each, along the line
        t = np.linspace(0.0, 1.0, 2 * PER_ELEMENT + 1)
        assert reference == pytest.approx(np.outer(t, [0.8, 0.6, 0.0]), abs=1e-14)
        assert len(cells) == 2 * PER_ELEMENT
        assert shape.outline.tolist() == list(range(shape.points))
        return
    # the mid-surface of a flat plate: in its plane, an even grid over the rectangle
    x = CORNER[0] + np.linspace(0.0, SIZE[0], 2 * PER_ELEMENT + 1)
    y = CORNER[1] + np.linspace(0.0, SIZE[1], 3 * PER_ELEMENT + 1)
    grid = np.column_stack([np.tile(x, len(y)), np.repeat(y, len(x)),
                            np.full(len(x) * len(y), CORNER[2])])
    assert reference == pytest.approx(grid, abs=1e-14)
    # quads counter-clockwise seen from +z, tiling the rectangle
    corners = reference[cells]
    first, second = corners[:, 2] - corners[:, 0], corners[:, 3] - corners[:, 1]
    diagonals = first[:, 0] * second[:, 1] - first[:, 1] * second[:, 0]    # twice the area
    assert (diagonals > 0).all()
    assert 0.5 * diagonals.sum() == pytest.approx(SIZE[0] * SIZE[1], rel=1e-12)
    assert len(cells) == 6 * PER_ELEMENT**2
    # the outline: one closed loop of 4 PER_ELEMENT edges per element
    loops = np.split(shape.outline, np.flatnonzero(shape.outline < 0))
    loops = [loop[loop >= 0] for loop in loops]
    assert len(loops) == 6
    assert all(len(loop) == 4 * PER_ELEMENT + 1 and loop[0] == loop[-1] for loop in loops)


@pytest.mark.parametrize("kind", KINDS)
def test_a_rigid_motion_moves_the_samples_rigidly(kind):
    model = kind_model(kind_body(kind))
    dim = model.dim
    turn, shift = rotation(dim), np.arange(1.0, dim + 1.0)
    body = model.bodies["body"]
    nodes = body.reference.reshape(body.nodes, -1, dim) @ turn.T
    nodes[:, body.kind.vectors.index("r")] += shift
    shape = Shape(model)
    moved, reference = shape.sample(nodes.ravel()), shape.sample(model.reference)
    assert moved[:, :dim] == pytest.approx(reference[:, :dim] @ turn.T + shift, abs=1e-13)


@pytest.mark.parametrize("kind", KINDS)
def test_vtu_of_every_kind_reads_back_with_its_cells(kind, tmp_path):
    model = kind_model(kind_body(kind))
    shape = Shape(model)
    q = model.reference + np.random.default_rng(3).normal(0.0, 0.01, model.size)
    displacement = shape.sample(q - model.reference)
    shapes.write_vtu(tmp_path / "a.vtu", shape, q, {"displacement": displacement})
    mesh = meshio.read(tmp_path / "a.vtu")
    axes = len(element_kind(kind).mesh_axes)
    elements = model.bodies["body"].elements
    assert [(c.type, len(c.data)) for c in mesh.cells] == [
        (shapes.CELL_TYPES[axes], elements * PER_ELEMENT**axes)]
    assert mesh.points == pytest.approx(shape.sample(q), abs=1e-15)
    nodes = mesh.point_data["displacement"][shape.node_points, :model.dim]
    assert nodes == pytest.approx((q - model.reference)[model.position_dofs()], abs=1e-15)


@pytest.mark.skipif(not PLATE_KINDS, reason="no plate kind generated")
def test_beams_and_plates_in_one_model_are_line_and_quad_cells(tmp_path):
    beam = next(k for k in KINDS if element_kind(k).dim == 3 and k not in PLATE_KINDS)
    model = kind_model(kind_body(beam, "beam"), kind_body(PLATE_KINDS[0], "plate"))
    shape = Shape(model)
    beam_points = 2 * PER_ELEMENT + 1
    shapes.write_vtu(tmp_path / "a.vtu", shape, model.reference, {})
    mesh = meshio.read(tmp_path / "a.vtu")
    assert [(c.type, len(c.data)) for c in mesh.cells] == [
        ("line", 2 * PER_ELEMENT), ("quad", 6 * PER_ELEMENT**2)]
    assert mesh.cells[0].data.max() < beam_points <= mesh.cells[1].data.min()
    assert shape.outline.tolist()[:beam_points + 1] == [*range(beam_points), -1]


@pytest.mark.skipif(not PLATE_KINDS, reason="no plate kind generated")
def test_ancf_run_draws_a_plate_scene(tmp_path):
    kind = PLATE_KINDS[0]
    plate = Body("plate", kind, "m", rectangle=Rectangle((0.0, 0.0, 0.0), (1.0, 0.2), (2, 1)),
                 thickness=0.01)
    data = scene([plate], [Clamp(edge="plate:x=0")],
                 [LineForce(edge="plate:x=-1", force_per_length=(0.0, 0.0, -50.0),
                            time_law=LinearRamp(0.01))],
                 static={}, dynamic={"t_end": 0.02, "step": 5e-3},
                 solver={"backend": "numpy", "engine": "python"})
    out = tmp_path / "out"
    summary, code = run(data, out, quiet=True, plots=False, vtk=True, animation=True,
                        plane="xz")
    assert code == 0 and summary["warnings"] == []
    assert (out / output.SHAPE_FILE).read_bytes()[:8] == PNG_SIGNATURE
    from PIL import Image

    with Image.open(out / output.ANIMATION_FILE) as image:
        assert image.format == "GIF" and image.n_frames == 5
    static = meshio.read(out / "vtk" / "static.vtu")
    assert [(c.type, len(c.data)) for c in static.cells] == [("quad", 2 * PER_ELEMENT**2)]
    # the free edge went down; the drawing is the element-edge wireframe in the x-z plane
    assert static.point_data["displacement"][:, 2].min() < 0
    shape = Shape(Model(data))
    # VTU points are the reference; the deformed shape is points + displacement
    x, z = shape.projected(static.points + static.point_data["displacement"], "xz")
    assert np.isnan(x).sum() == 1 and z[~np.isnan(z)].min() < 0


# --------------------------------------------------------------------------- VTU and PVD

@pytest.fixture(scope="module")
def series_run(tmp_path_factory):
    folder = tmp_path_factory.mktemp("vtk")
    series = VtkSeries(folder / "vtk")
    result = run_scene(parse_scene(small()), observers=[series], store_states=True,
                       progress=False)
    return folder / "vtk", series, result


def test_every_output_time_is_a_vtu_listed_with_its_time(series_run):
    folder, series, result = series_run
    entries = read_pvd(folder / "dynamic.pvd")
    assert [t for t, _ in entries] == result.sensors["t"].tolist()
    assert [name for _, name in entries] == [f"dynamic_{k:06d}.vtu" for k in range(7)]
    assert sorted(os.listdir(folder)) == sorted(
        [name for _, name in entries] + ["dynamic.pvd", "static.vtu", "modes.pvd",
                                         "mode_1.vtu", "mode_2.vtu"])
    assert series.files == ["vtk/static.vtu", "vtk/modes.pvd", "vtk/dynamic.pvd"]


def test_vtu_displacements_and_velocities_are_the_model_states(series_run):
    folder, _, result = series_run
    model, states = result.model, result.states
    for k, (_, name) in enumerate(read_pvd(folder / "dynamic.pvd")):
        mesh = meshio.read(folder / name)
        assert mesh.points.shape == (2 * PER_ELEMENT + 1, 3)
        assert mesh.cells[0].type == "line" and len(mesh.cells[0].data) == 2 * PER_ELEMENT
        nodes = [0, PER_ELEMENT, 2 * PER_ELEMENT]
        displacement = mesh.point_data["displacement"][nodes]
        velocity = mesh.point_data["velocity"][nodes]
        assert displacement == pytest.approx(
            nodal_vectors(model, states.q[k]) - nodal_vectors(model, model.reference),
            rel=1e-12, abs=1e-16)
        assert velocity == pytest.approx(nodal_vectors(model, states.v[k]), rel=1e-12,
                                         abs=1e-16)
        # points at the reference (Warp By Vector with displacement gives the deformed shape)
        assert mesh.points[nodes] == pytest.approx(nodal_vectors(model, model.reference))
        assert (mesh.points + mesh.point_data["displacement"])[nodes] == pytest.approx(
            nodal_vectors(model, states.q[k]))
        # the tip sensor is the tip's displacement
        assert displacement[-1, 1] == pytest.approx(result.sensors["tip_y"][k], rel=1e-12,
                                                    abs=1e-16)
    assert abs(result.sensors["tip_y"][-1]) > 1e-6  # the beam did move


def test_static_and_mode_vtu(series_run):
    folder, _, result = series_run
    static = meshio.read(folder / "static.vtu")
    assert static.point_data["displacement"][-1, 1] == pytest.approx(
        result.summary["static"]["sensors"]["tip_y"], rel=1e-12)
    assert read_pvd(folder / "modes.pvd") == [(1.0, "mode_1.vtu"), (2.0, "mode_2.vtu")]
    model = result.model
    for k in (1, 2):
        mesh = meshio.read(folder / f"mode_{k}.vtu")
        mode = mesh.point_data["mode"][[0, PER_ELEMENT, 2 * PER_ELEMENT]]
        assert mode == pytest.approx(nodal_vectors(model, result.modes.shapes[k - 1]))
        assert np.abs(mode).max() == pytest.approx(1.0)


def test_a_diverged_run_keeps_its_vtu_series(tmp_path):
    data = cantilever(elements=2, force=[0.0, -1e12], sensors=SENSORS,
                      law={"type": "table", "points": [[0.0, 0.0], [0.02, 0.0], [0.03, 1.0]]},
                      dynamic={"t_end": 0.2, "step": 5e-3},
                      solver={"backend": "numpy"}).to_dict()
    summary, code = run(parse_scene(data), tmp_path / "out", quiet=True, vtk=True)
    assert code == 1
    with (tmp_path / "out" / "timeseries.csv").open(newline="") as f:
        times = [float(row[0]) for row in list(csv.reader(f))[1:]]
    entries = read_pvd(tmp_path / "out" / "vtk" / "dynamic.pvd")
    assert [t for t, _ in entries] == times
    assert "vtk/dynamic.pvd" in summary["files"]


# --------------------------------------------------------------------------- ancf run

def test_ancf_run_vtk_and_gif(tmp_path, capsys):
    path = tmp_path / "scene.toml"
    path.write_text(toml_text(small("beam3d", backend="c")))
    out = tmp_path / "out"
    assert main(["run", str(path), "--out", str(out), "--quiet", "--vtk", "--gif",
                 "--plane", "xz"]) == 0
    assert capsys.readouterr().err == ""
    summary = json.loads((out / "summary.json").read_text())
    assert {"vtk/static.vtu", "vtk/modes.pvd", "vtk/dynamic.pvd", output.SHAPE_FILE,
            output.ANIMATION_FILE} <= set(summary["files"])
    assert summary["warnings"] == []
    gif = (out / output.ANIMATION_FILE).read_bytes()
    assert gif[:6] == b"GIF89a"
    from PIL import Image

    with Image.open(out / output.ANIMATION_FILE) as image:
        assert image.format == "GIF" and image.n_frames == 7
    assert (out / output.SHAPE_FILE).read_bytes()[:8] == PNG_SIGNATURE
    assert not [n for n in os.listdir(out) + os.listdir(out / "vtk") if ".tmp" in n]
    # by default: none of them
    assert main(["run", str(path), "--out", str(out), "--quiet"]) == 0
    assert not (out / "vtk").exists()
    assert not (out / output.ANIMATION_FILE).exists() and not (out / output.SHAPE_FILE).exists()


def test_a_reused_folder_loses_old_vtu_files_only(tmp_path):
    out = tmp_path / "out"
    assert run(parse_scene(small()), out, quiet=True, vtk=True, plots=False)[1] == 0
    (out / "vtk" / "notes.txt").write_text("mine")
    assert run(parse_scene(small(analyses=("static",))), out, quiet=True, vtk=True)[1] == 0
    assert sorted(os.listdir(out / "vtk")) == ["notes.txt", "static.vtu"]


def test_scene_output_table_asks_for_shapes(tmp_path, monkeypatch):
    from types import SimpleNamespace

    from runtime.app import run as run_module

    wanted = SimpleNamespace(vtk=True, animation=True, states=False)
    monkeypatch.setattr(run_module, "requested", lambda scene, name: getattr(wanted, name))
    summary, code = run(parse_scene(small(analyses=("static",))), tmp_path / "out",
                        quiet=True)
    assert code == 0
    assert {"vtk/static.vtu", output.SHAPE_FILE} <= set(summary["files"])


def test_a_failing_animation_is_a_warning(tmp_path, monkeypatch):
    def broken(*args, **kwargs):
        raise RuntimeError("no pillow")

    monkeypatch.setattr(shapes, "write_animation", broken)
    summary, code = run(parse_scene(small(analyses=("dynamic",))), tmp_path / "out",
                        quiet=True, animation=True)
    assert code == 0
    assert summary["warnings"] == [f"{output.ANIMATION_FILE}: not written (RuntimeError: no "
                                   f"pillow)"]


# --------------------------------------------------------------------------- drawing

def test_small_displacements_are_magnified_large_ones_not():
    reference = np.column_stack([np.linspace(0.0, 5.0, 11), np.zeros(11), np.zeros(11)])
    bent = reference.copy()
    bent[:, 1] = -2e-3 * reference[:, 0] / 5.0       # 2 mm at the tip of a 5 m beam
    assert shapes.magnification(reference, [bent]) == 200.0
    swung = reference[:, [1, 0, 2]]                  # rotated by 90 degrees
    assert shapes.magnification(reference, [swung]) == 1.0
    assert shapes.magnification(reference, [reference]) == 1.0


def test_animation_frames_are_at_most_max_frames(tmp_path, monkeypatch):
    monkeypatch.setattr(shapes, "MAX_FRAMES", 4)
    frames = Frames()
    run_scene(parse_scene(small(analyses=("dynamic",))), observers=[frames], progress=False)
    assert len(frames.frames) == 7
    path = shapes.write_animation(tmp_path / "a.gif", frames, "t" * 200, plane="xy")
    from PIL import Image

    with Image.open(path) as image:
        assert image.n_frames == 4
    with pytest.raises(ValueError, match="plane"):
        shapes.write_animation(tmp_path / "b.gif", frames, "t", plane="xw")
    assert sorted(os.listdir(tmp_path)) == ["a.gif"]


def test_frames_stay_few_evenly_spaced_with_the_latest(monkeypatch):
    from types import SimpleNamespace

    monkeypatch.setattr(shapes, "MAX_FRAMES", 3)
    frames = Frames()
    frames.shape = SimpleNamespace(sample=lambda q: q)
    for n in range(50):
        frames.sample(float(n), np.full((2, 3), n), None, {})
        assert len(frames.frames) <= 6 and frames.times[-1] == n
        kept = frames.times[:-1]
        steps = {b - a for a, b in zip(kept, kept[1:], strict=False)}
        assert frames.times[0] == 0.0 and len(steps) <= 1  # evenly spaced from the start
        assert [f[0, 0] for f in frames.frames] == frames.times
    assert frames.times == [0.0, 16.0, 32.0, 48.0, 49.0]


def test_a_bad_plane_is_an_invalid_option(tmp_path):
    summary, code = run(parse_scene(small(analyses=("static",))), tmp_path / "out",
                        quiet=True, animation=True, plane="xw")
    assert code == 2 and summary["message"] == ("plane: expected auto or one of xy, xz, yz, "
                                                 "got 'xw'")


def test_reserved_names_are_not_sensor_plots():
    assert output.plot_file_name("shape_static") != output.SHAPE_FILE
    assert output.plot_file_name("energies") != output.ENERGIES_FILE


@pytest.mark.parametrize("extent, motion, plane", [
    ((5.0, 0.1, 0.1), (0.0, -0.3, 0.0), "xy"),     # a cantilever along x bending along y
    ((1.0, 0.1, 0.0), (0.0, 0.0, -0.01), "xz"),    # a plate strip in x-y bending along z
    ((0.1, 0.1, 2.0), (0.0, 0.02, 0.0), "yz"),     # a vertical beam swinging along y
    ((1.0, 0.5, 0.0), (0.0, 0.0, 0.0), "xy"),      # no motion: the two largest extents
])
def test_the_automatic_plane_shows_the_longest_axis_and_the_motion(extent, motion, plane):
    reference = np.array([np.zeros(3), extent])
    moved = reference + np.array(motion)
    assert shapes.view_plane(reference, [moved]) == plane
