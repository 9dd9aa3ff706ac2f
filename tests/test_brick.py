"""Chrono's ANCF-3843 brick (``brick3d_3843``: r, r_x, r_y, r_z at the 8 corners of a box)
end to end: its storage (no structural zeros, straight invariants by an exact Gauss rule at
load time instead of closed forms), the shipped box cantilever against Timoshenko's beam, its
hexahedral VTU cells, the same bar read from a file of hexahedra, and face forces.  Chrono's
unit-test files are checked in tests/test_chrono.py, the generic element tests take the kind
from the registry (tests/test_element.py)."""

from __future__ import annotations

import dataclasses
import json

import meshio
import numpy as np
import pytest

import scenes
from runtime import (
    Body,
    Element,
    FaceForce,
    Material,
    Modal,
    Rectangle,
    Scene,
    SceneError,
    load_scene,
    run_scene,
)
from runtime.app.shapes import Shape, write_vtu
from runtime.catalog import generated_dir
from runtime.element import invariants as inv
from runtime.kernels.kind import element_kind
from runtime.model.model import Model
from symgen.elements import get

KIND = "brick3d_3843"


def test_the_brick_is_chronos_layout():
    spec = get(KIND)
    spec.check_interpolation()
    kind = element_kind(KIND)
    assert (kind.n_shape, kind.ndof, kind.vectors) == (32, 96, ("r", "r_x", "r_y", "r_z"))
    assert list(kind.mesh_axes) == [0, 1, 2]
    # Chrono's corners: A, B, C, D counter-clockwise on z = 0, then E, F, G, H above them
    corners = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1),
               (0, 1, 1)]
    np.testing.assert_array_equal(kind.node_points(2.0, 3.0, 5.0), np.multiply(corners,
                                                                              (2, 3, 5)))


def test_a_corner_function_has_no_structural_zero_so_nothing_is_stored_per_entry():
    """Every storage pattern of the straight brick is complete (element.json says so in one
    word) and its closed forms are not shipped: the runtime integrates them."""
    folder = generated_dir() / KIND
    meta = json.loads((folder / "element.json").read_text())
    assert all(meta["patterns"][variant][name] == "complete"
               for variant in ("straight", "general") for name in ("i4", "gram", "cij"))
    assert meta["closed_tables"] is None and meta["straight_invariants"] == "quadrature"
    assert not (folder / "closed.json").exists()
    assert (folder / "element.json").stat().st_size < 100_000
    kind = element_kind(KIND)
    npairs = 32 * 33 // 2
    assert kind.pattern("straight", "gram").shape == (npairs * (npairs + 1) // 2, 2)
    assert kind.pattern("general", "cij").shape == (npairs * 32 * 32, 4)


def test_quadrature_families_loop_over_the_shape_functions_at_each_point():
    """One copy of the per-shape-function statements of a point (``ShapeLoop``), not 32:
    unrolled, quadrature_law's C was 511 kB of code besides the tables and took 49 s to
    compile (docs/new-element.md section 6); the smaller elements keep their unrolled points."""
    from symgen.methods.common import shape_looped

    assert shape_looped(get(KIND))
    assert not any(shape_looped(get(kind)) for kind in ("plate3d", "shell3d_3833", "beam3d"))
    for family in ("quadrature", "quadrature_law"):
        text = (generated_dir() / KIND / f"{family}.c").read_text()
        code = "".join(line for line in text.splitlines(keepends=True)
                       if not line.startswith("static const int "))
        assert "for (int k = 0; k < 32; k++)" in code
        assert len(code) < 200_000, (family, len(code))


def test_straight_invariants_are_exact_and_cached_per_dimensions():
    """The load-time rule is exact: one more Gauss point per axis changes no stored invariant
    beyond round-off; elements of the same dimensions share the cached arrays."""
    first = Element(KIND, 0.3, 0.2, 0.1, E=2.1e11, nu=0.3, rho=7850.0, backend="numpy")
    again = Element(KIND, 0.3, 0.2, 0.1, E=2.1e11, nu=0.3, rho=7850.0, backend="numpy")
    assert first.invariants["gram"] is again.invariants["gram"]
    kind = element_kind(KIND)
    family = first._family("invariants")
    rules = inv.law_rules(kind, family, first.geometry, first.e0,
                          tuple(o + 1 for o in kind.exact_orders))
    finer = inv.numeric_law_invariants(kind, family, "straight", first.geometry, rules,
                                       first.law_coefficients(), first.rho)
    for name in ("mass", "k1", "gram", "cij", "u0"):
        ours, theirs = first.invariants[name], finer[name]
        assert np.abs(ours - theirs).max() <= 1e-13 * np.abs(theirs).max(), name
    # the mass: rho V over the position functions' sum, each corner's share of a uniform
    # translation (the sum of all position functions is 1)
    mass = np.zeros((32, 32))
    rows, cols = np.triu_indices(32)
    mass[rows, cols] = mass[cols, rows] = first.invariants["mass"]
    positions = list(kind.position_vectors)
    assert mass[np.ix_(positions, positions)].sum() == pytest.approx(7850.0 * 0.3 * 0.2 * 0.1,
                                                                     rel=1e-14)


@pytest.fixture(scope="module")
def cantilever():
    scene = load_scene(scenes.path("brick_cantilever"))
    return scene, run_scene(dataclasses.replace(scene, modal=Modal(modes=1)), progress=False)


def test_a_bent_brick_keeps_its_nodes_through_the_thickness():
    """``bent_reference`` of a solid bends it about the z axis through (0, R): each corner
    keeps its z, lies at R - y from the axis, and the element is unstrained there (the
    mapping was degenerate when z was dropped: ``ancf invariants --reference curved``)."""
    from runtime.element.reference import bent_reference

    kind, radius, geometry = element_kind(KIND), 2.0, (1.0, 0.1, 0.1)
    points = kind.node_points(*geometry)
    e0 = bent_reference(kind, geometry, radius).reshape(len(points), -1, 3)
    positions = e0[:, 0]
    np.testing.assert_allclose(positions[:, 2], points[:, 2], atol=1e-15)
    distance = np.hypot(positions[:, 0], positions[:, 1] - radius)
    np.testing.assert_allclose(distance, radius - points[:, 1], rtol=1e-14)
    brick = Element(KIND, *geometry, E=2.1e11, nu=0.3, rho=7800.0, e0=e0.ravel())
    assert np.abs(brick.elastic_force(e0.ravel())).max() <= 1e-6
    assert brick.strain_energy(e0.ravel()) <= 1e-12


def test_box_cantilever_bends_as_timoshenko_beam(cantilever):
    """Tip deflection against P L^3 / (3 E I) + P L / (k G A), k = 5/6, at nu = 0 (the shear
    part is 0.6 % of the bending one at L / h = 10); measured -0.75 % with 40 x 1 x 1 bricks
    (20: -1.7 %, 10: -3.6 %)."""
    scene, result = cantilever
    body, material = scene.bodies[0], scene.materials["steel"]
    assert body.element == KIND and material.nu == 0.0
    length, width, height = body.box.size
    load = sum(item.force[2] for item in scene.loads)
    inertia, area = width * height**3 / 12, width * height
    shear = material.E / 2
    timoshenko = (load * length**3 / (3 * material.E * inertia)
                  + load * length / (5 / 6 * shear * area))
    sensors = result.summary["static"]["sensors"]
    for name in ("tip_z_bottom", "tip_z_top"):
        assert sensors[name] == pytest.approx(timoshenko, rel=0.01)
        assert sensors[name] > timoshenko         # stiffer, never softer, than the beam
    # the work of the load is the strain energy (linear range): P delta / 2
    mean_tip = (sensors["tip_z_bottom"] + sensors["tip_z_top"]) / 2
    assert sensors["strain_energy"] == pytest.approx(load * mean_tip / 2, rel=1e-4)
    assert result.model.n_nodes == 41 * 2 * 2 and result.model.size == 41 * 4 * 12


def test_box_cantilever_writes_hexahedra_through_every_node(cantilever, tmp_path):
    _, result = cantilever
    model, q = result.model, result.static
    shape = Shape(model)
    displacement = shape.sample(q) - shape.sample(model.reference)
    mesh = meshio.read(write_vtu(tmp_path / "static.vtu", shape, model.reference,
                                 {"displacement": displacement}))
    assert [block.type for block in mesh.cells] == ["hexahedron"]
    np.testing.assert_allclose(mesh.points[shape.node_points],
                               model.reference[model.position_dofs()], atol=1e-14)
    np.testing.assert_allclose(
        mesh.point_data["displacement"][shape.node_points],
        (q - model.reference)[model.position_dofs()], atol=1e-12 * np.abs(q).max())


def _hexahedra(path, grid, size, turn):
    """A VTU of grid (nx, ny, nz) hexahedra filling the box ``size`` from the origin, turned
    by ``turn``, its points numbered z-major (not the box body's order), with the point set
    "root" (x = 0)."""
    nx, ny, nz = grid
    index = {}
    points = []
    for i in range(nx + 1):
        for j in range(ny + 1):
            for k in range(nz + 1):
                index[i, j, k] = len(points)
                points.append(np.multiply((i / nx, j / ny, k / nz), size))
    cells = [[index[i + a, j + b, k + c] for c, b, a in
              ((0, 0, 0), (0, 0, 1), (0, 1, 1), (0, 1, 0), (1, 0, 0), (1, 0, 1), (1, 1, 1),
               (1, 1, 0))]
             for i in range(nx) for j in range(ny) for k in range(nz)]
    points = np.array(points)
    root = (points[:, 0] == 0).astype(np.int64)
    meshio.write(path, meshio.Mesh(points @ turn.T, [("hexahedron", np.array(cells))],
                                   point_data={"root": root}))
    return points @ turn.T


def test_hexahedra_from_a_file_give_the_box_bodys_deflection(cantilever, tmp_path):
    """The cantilever's 40 x 1 x 1 box as a mesh file, numbered otherwise and turned about
    z: the same tip deflection; a cell that is not a box is refused."""
    scene, result = cantilever
    body = scene.bodies[0]
    turn = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])   # x -> y
    points = _hexahedra(tmp_path / "bar.vtu", body.box.grid, body.box.size, turn)
    length, width, height = body.box.size
    corners = [int(np.flatnonzero(np.all(np.isclose(points, turn @ (length, y, z)), axis=1))[0])
               for y in (0.0, width) for z in (0.0, height)]
    tip = corners[0]
    loads = "".join(f"""
[[load]]
type = "point_force"
node = "bar:{node}"
force = [0.0, 0.0, -25.0]
""" for node in corners)
    text = f"""[material.steel]
E = 2.1e11
nu = 0.0
rho = 7850.0

[[body]]
name = "bar"
element = "{KIND}"
material = "steel"
mesh = {{ file = "bar.vtu" }}

[[constraint]]
type = "clamp"
edge = "bar:root"

{loads}
[[sensor]]
name = "tip_z"
type = "displacement"
node = "bar:{tip}"
component = "z"

[analysis.static]
"""
    (tmp_path / "bar.toml").write_text(text)
    from_file = run_scene(load_scene(tmp_path / "bar.toml"), progress=False)
    # the same model turned and numbered otherwise: the same deflection, to round-off
    tip_z = from_file.summary["static"]["sensors"]["tip_z"]
    assert tip_z == pytest.approx(result.summary["static"]["sensors"]["tip_z_bottom"],
                                  rel=1e-8)
    assert from_file.model.n_nodes == result.model.n_nodes
    # a sheared cell: not a box
    sheared = points.copy()
    sheared[tip] += (0.0, 0.0, 0.01)
    meshio.write(tmp_path / "bar.vtu", meshio.Mesh(sheared, meshio.read(
        tmp_path / "bar.vtu").cells))
    with pytest.raises(SceneError, match=r"is not a box with edges along element 0's axes"):
        load_scene(tmp_path / "bar.toml")


def test_a_face_force_is_the_consistent_load_of_a_uniform_traction(cantilever):
    """The tip load as a shear traction P / A over the free face: resultant P on the face's
    positions (the position functions sum to 1), nothing off the face, and the tip within
    1 % of Timoshenko's beam as with the corner forces (a smoother load: closer)."""
    scene, result = cantilever
    body = scene.bodies[0]
    length, width, height = body.box.size
    load = sum(item.force[2] for item in scene.loads)
    traction = FaceForce("bar:x=-1", (0.0, 0.0, load / (width * height)))
    faced = dataclasses.replace(scene, loads=(traction,), modal=None)
    model = Model(faced)
    nominal = model.nominal_load()
    positions = model.reference[model.position_dofs()]
    assert nominal[model.position_dofs()][:, 2].sum() == pytest.approx(load, rel=1e-13)
    loaded = {n for n in range(model.n_nodes)
              if np.abs(nominal[model.node_dofs(n)]).max() > 0}
    assert loaded == set(np.flatnonzero(np.isclose(positions[:, 0], length)))
    tip = run_scene(faced, progress=False).summary["static"]["sensors"]["tip_z_bottom"]
    corners = result.summary["static"]["sensors"]["tip_z_bottom"]
    assert tip == pytest.approx(corners, rel=0.01)
    assert tip > corners      # no indentation under point loads: a little stiffer


def test_a_face_force_needs_a_face_of_a_box_body():
    plate = Body("p", "plate3d", "steel", thickness=0.01,
                 rectangle=Rectangle((0.0, 0.0, 0.0), (1.0, 0.1), (2, 1)))
    steel = Material("steel", E=2.1e11, nu=0.0, rho=7850.0)
    with pytest.raises(SceneError, match=r'^load\[0\]\.face: p:x=2 is not a face of a box '
                                         r'body'):
        Scene(materials=[steel], bodies=[plate],
              loads=[FaceForce("p:x=-1", (0.0, 0.0, -1.0))])
