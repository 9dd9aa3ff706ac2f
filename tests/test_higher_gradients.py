"""Higher gradients in element files (r_zz, r_xy, ...) and Chrono's ANCF-3833 shell
(``shell3d_3833``: r, r_z, r_zz at the 8 serendipity nodes) end to end: the names an element
file may use, the interpolation check of second derivatives, references (zero second
derivatives on straight, flat and straight-fibre placements; refused along a curved axis),
node frames (first gradients only), welds, and the shipped strip scene against beam theory,
free of the Poisson thickness locking of the shell without r_zz."""

from __future__ import annotations

import dataclasses
import math

import meshio
import numpy as np
import pytest

import scenes
from runtime import Body, Material, Modal, Rectangle, Scene, SceneError, Weld, load_scene, run_scene
from runtime.app.shapes import Shape, write_vtu
from runtime.element import reference as geometry
from runtime.kernels.kind import element_kind
from symgen import domains
from symgen.element import ElementSpec, vector_axes, x
from symgen.elements import get

KIND = "shell3d_3833"


def test_vector_names_are_r_and_its_derivatives_in_axis_order():
    assert vector_axes("r", 3) == ()
    assert vector_axes("r_x", 3) == (0,)
    assert vector_axes("r_zz", 3) == (2, 2)
    assert vector_axes("r_xy", 3) == (0, 1)
    assert vector_axes("r_xxz", 3) == (0, 0, 2)
    for name in ("r_yx", "r_w", "r_", "rz", "s_x"):
        assert vector_axes(name, 3) is None, name
    assert vector_axes("r_z", 2) is None       # a planar element has no z


def test_element_file_refuses_unknown_and_repeated_vectors():
    spec = get(KIND)
    with pytest.raises(ValueError, match=r"unknown nodal vectors \['r_zy'\]"):
        dataclasses.replace(spec, vectors=("r", "r_z", "r_zy"))
    with pytest.raises(ValueError, match="repeated nodal vectors"):
        dataclasses.replace(spec, vectors=("r", "r_z", "r_z"))


def test_interpolation_check_reads_second_derivatives():
    spec = get(KIND)
    spec.check_interpolation()
    # z^2 S instead of z^2 / 2 S: d^2/dz^2 gives 2 at its node, not 1
    wrong = list(spec.shape_functions)
    wrong[2] = 2 * wrong[2]
    with pytest.raises(ValueError, match="shape function 2 gives 2 for r_zz of node 0"):
        dataclasses.replace(spec, shape_functions=tuple(wrong)).check_interpolation()


def test_a_derivative_along_the_axis_is_a_vector_like_any_other():
    # a quintic Hermite beam (r, r_x, r_xx at both ends): its file is accepted, its
    # interpolation checked by second x derivatives, its straight reference has r_xx = 0
    t, length = x / domains.length, domains.length
    ends = ((1 - 10 * t**3 + 15 * t**4 - 6 * t**5, length * (t - 6 * t**3 + 8 * t**4 - 3 * t**5),
             length**2 / 2 * (t**2 - 3 * t**3 + 3 * t**4 - t**5)),
            (10 * t**3 - 15 * t**4 + 6 * t**5, length * (-4 * t**3 + 7 * t**4 - 3 * t**5),
             length**2 / 2 * (t**3 - 2 * t**4 + t**5)))
    spec = ElementSpec(name="quintic", domain=domains.beam(2), nodes=((0, 0), (length, 0)),
                       vectors=("r", "r_x", "r_xx"), shape_functions=ends[0] + ends[1],
                       quadrature=(5, 3))
    spec.check_interpolation()
    assert spec.straight_reference() == [0, 0, 1, 0, 0, 0, length, 0, 1, 0, 0, 0]
    swapped = ends[0][:1] + ends[0][2:0:-1] + ends[1]   # r_x and r_xx functions exchanged
    with pytest.raises(ValueError, match="for r_x of node 0"):
        dataclasses.replace(spec, shape_functions=swapped).check_interpolation()


def test_straight_reference_has_unit_normals_and_zero_r_zz():
    spec, kind = get(KIND), element_kind(KIND)
    e0 = np.array(spec.straight_reference(), dtype=object).reshape(8, 3, 3)
    assert np.all(e0[:, 1] == [0, 0, 1]) and np.all(e0[:, 2] == 0)
    flat = kind.straight_reference(2.0, 0.5, 0.01).reshape(8, 3, 3)
    assert np.all(flat[:, 1] == [0, 0, 1]) and np.all(flat[:, 2] == 0)
    # a flat element placed in space: r_z the unit normal of its sides, r_zz zero
    sides = np.array([0.0, 2.0, 0.0]), np.array([0.0, 0.0, 0.5])
    placed = geometry.rectangle_reference(kind, (1.0, 2.0, 3.0), *sides).reshape(8, 3, 3)
    np.testing.assert_allclose(placed[:, 1], np.broadcast_to([1.0, 0.0, 0.0], (8, 3)))
    assert np.all(placed[:, 2] == 0)


def test_bent_panel_keeps_straight_fibres_and_refuses_curvature_vectors():
    kind = element_kind(KIND)
    radius = 2.0
    e0 = geometry.bent_reference(kind, (1.0, 0.5, 0.01), radius).reshape(8, 3, 3)
    # the fibre through a node is straight along the panel's normal: r_z = the unit normal
    # (position - centre) / R of the cylinder about (0, y, R), r_zz = 0
    centre = np.array([0.0, 0.0, radius])
    normals = (e0[:, 0] - centre) * [1, 0, 1] / radius
    np.testing.assert_allclose(e0[:, 1], -normals, atol=1e-15)
    assert np.all(e0[:, 2] == 0)
    # a kind with a derivative along its curved axis (r_xx of a beam) is refused where the
    # placement does not compute the curvature (a file mesh), taken where it does (arcs);
    # other derivatives along it (r_xy) are refused everywhere
    beam = dataclasses.replace(element_kind("beam3d_3node"), vectors=("r", "r_y", "r_xx"))
    with pytest.raises(ValueError, match="carries r_xx, derivatives along the curved axis"):
        geometry.curved_reference_check(beam, "file mesh")
    geometry.curved_reference_check(beam, "arc", curvature=True)
    mixed = dataclasses.replace(beam, vectors=("r", "r_y", "r_xy"))
    with pytest.raises(ValueError, match="carries r_xy"):
        geometry.curved_reference_check(mixed, "arc", curvature=True)


def test_node_frames_are_made_of_first_gradients_only():
    rng = np.random.default_rng(3)
    gradients = {"r_x": rng.normal(size=3), "r_y": rng.normal(size=3)}
    frame = geometry.gradient_frame(gradients, 3)
    with_second = geometry.gradient_frame({**gradients, "r_zz": rng.normal(size=3)}, 3)
    np.testing.assert_array_equal(with_second, frame)
    assert element_kind(KIND).first_gradients == ("r_z",)
    assert "r_z fixes only the node's normal" in element_kind(KIND).frame_gap()


def test_weld_of_shell_nodes_with_r_zz_is_refused():
    steel = Material("steel", E=2.1e11, nu=0.0, rho=7850.0)
    bodies = [Body(name, KIND, "steel", thickness=0.01,
                   rectangle=Rectangle(corner=(x, 0.0, 0.0), size=(1.0, 0.1), grid=(1, 1)))
              for name, x in (("a", 0.0), ("b", 1.0))]
    with pytest.raises(SceneError, match=r"constraint\[0\]\.nodes: a weld ties the full "
                                         r"frames .* carry r, r_z, r_zz"):
        Scene(materials=[steel], bodies=bodies, constraints=[Weld(("a:-1", "b:0"))])


@pytest.fixture(scope="module")
def strip():
    scene = load_scene(scenes.path("shell3833_strip"))
    return scene, run_scene(dataclasses.replace(scene, dynamic=None, modal=Modal(modes=1)),
                            progress=False)


def beam_tip(scene: Scene, modulus: float) -> float:
    """Euler-Bernoulli P L^3 / (3 E I) of the strip's tip line load (m)."""
    body = scene.bodies[0]
    (length, width), thickness = body.rectangle.size, body.thickness
    load = scene.loads[0].force_per_length[2] * width
    return load * length**3 / (3 * modulus * width * thickness**3 / 12)


def test_shell3833_strip_bends_as_beam_theory_says(strip):
    scene, result = strip
    body, material = scene.bodies[0], scene.materials["steel"]
    assert body.element == KIND and material.nu == 0.0
    tip = result.summary["static"]["sensors"]["tip_z"]
    assert tip == pytest.approx(beam_tip(scene, material.E), rel=0.01)   # measured -0.36 %
    assert result.summary["static"]["sensors"]["tip_z_middle"] == pytest.approx(tip, rel=1e-9)
    (length, width), thickness = body.rectangle.size, body.thickness
    inertia, area = width * thickness**3 / 12, width * thickness
    omega = 1.8751**2 * math.sqrt(material.E * inertia / (material.rho * area * length**4))
    assert result.modes.frequencies_rad_s[0] == pytest.approx(omega, rel=0.01)
    # 43 nodes (as the 8-node shell's strip), each carrying r, r_z, r_zz
    assert result.model.n_nodes == 43 and result.model.size == 43 * 9


def test_r_zz_removes_the_poisson_thickness_locking_of_the_strip():
    # at nu = 0.3 the narrow strip's tip lies between plate theory (E / (1 - nu^2), the
    # stiffest a free-edged strip can be) and beam theory (E); without r_zz the fibre
    # cannot thin with the bending strain and the shell is stiffer than plate theory
    scene = load_scene(scenes.path("shell3833_strip"))
    nu = 0.3
    steel = dataclasses.replace(scene.materials["steel"], nu=nu)
    tips = {}
    for kind in (KIND, "shell3d_8node"):
        body = dataclasses.replace(scene.bodies[0], element=kind)
        run = dataclasses.replace(scene, materials={"steel": steel}, bodies=(body,),
                                  modal=None, dynamic=None)
        tips[kind] = run_scene(run, progress=False).summary["static"]["sensors"]["tip_z"]
    beam, plate = beam_tip(scene, steel.E), beam_tip(scene, steel.E / (1 - nu**2))
    assert beam < tips[KIND] < plate          # measured -1.847 mm: 0.97 of beam theory
    assert tips["shell3d_8node"] > plate      # measured -1.665 mm, 4 % stiffer than plate
    # so a run warns of Poisson thickness locking for the shell without r_zz only
    warned = {kind: element_kind(kind).svk_locking(nu) for kind in tips}
    assert warned[KIND] is None
    assert warned["shell3d_8node"][0] == "plates"


def test_shell3833_strip_writes_quads_through_every_node(strip, tmp_path):
    _, result = strip
    model, q = result.model, result.static
    shape = Shape(model)
    displacement = shape.sample(q) - shape.sample(model.reference)
    mesh = meshio.read(write_vtu(tmp_path / "static.vtu", shape, model.reference,
                                 {"displacement": displacement}))
    assert [block.type for block in mesh.cells] == ["quad"]
    np.testing.assert_allclose(mesh.points[shape.node_points],
                               model.reference[model.position_dofs()], atol=1e-14)
    np.testing.assert_allclose(
        mesh.point_data["displacement"][shape.node_points],
        (q - model.reference)[model.position_dofs()], atol=1e-12 * np.abs(q).max())
