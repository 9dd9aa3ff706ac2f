"""``strain``, ``stress`` and ``section`` sensors and the VTU fields against closed forms: a
bar pulled to a large strain (Cauchy F / A, second Piola-Kirchhoff F / (A lambda),
Green-Lagrange (lambda^2 - 1) / 2, N = F) in every kind and any placement, a bent cantilever
(M c / I at the surface, also with ecm at nu = 0.3, the section moments and shear), and both
engines agreeing on every new sensor."""

from __future__ import annotations

import dataclasses
import math

import meshio
import numpy as np
import pytest

from runtime import (
    Acceleration,
    Body,
    Clamp,
    CosineRamp,
    Dynamic,
    Material,
    Output,
    Pin,
    PointForce,
    Position,
    Reaction,
    Rectangle,
    Scene,
    SectionForce,
    Solver,
    Static,
    Strain,
    Stress,
    run_scene,
)
from runtime.app.run import run
from runtime.model.items.sensors import Sensors
from runtime.model.model import Model

E, L, H, W = 1.0e9, 2.0, 0.1, 0.08
SOFT = Material("soft", E=E, nu=0.0, rho=1000.0)
DAMPED = Material("soft", E=E, nu=0.0, rho=1000.0, damping=2.5e-3)
F = 0.02 * E * H * W        # a 2 % axial strain: the three measures differ by percents


def _bar(kind: str, angle_deg: float = 0.0, engine: str = "compiled") -> Scene:
    """A bar of ``kind`` (section H x W) pinned at one end and pulled along its axis by F at
    the other, placed along ``angle_deg`` in the x-y plane; ``at_rest`` gives the last
    output time.

    A clamp would hold r_x at the first node, hence zero axial strain there (an ANCF
    clamp holds the section's stretch too), so the stress would not be uniform: a pin holds
    the positions only.  A pinned bar is free to turn, which a static analysis refuses; the
    bar is brought to rest instead, the load ramped in over 20 ms and the axial waves
    (first mode 785 rad/s) damped critically (Kelvin-Voigt alpha = 2 / omega)."""
    dim = 3 if "3d" in kind else 2
    z = (0.0,) * (dim - 2)
    c, s = math.cos(math.radians(angle_deg)), math.sin(math.radians(angle_deg))
    law = CosineRamp(duration=0.02)
    body = Body("bar", kind, "soft", height=H, width=W, elements=4,
                start=(0.0, 0.0, *z), end=(L * c, L * s, *z))
    support, load = Pin("bar:0"), PointForce("bar:-1", (F * c, F * s, *z), time_law=law)
    across = 0.0 if kind.startswith("cable") else 1.0
    point = (0.3, 0.03 * across, *((-0.02 * across,) * (dim - 2)))
    sensors = [Stress("cauchy", "bar", 1, point, "xx"),
               Stress("pk2", "bar", 1, point, "xx", "pk2"),
               Stress("mises", "bar", 1, point, "von_mises"),
               Strain("green", "bar", 1, point, "xx"),
               Position("tip_x", "bar:-1", "x"), Position("tip_y", "bar:-1", "y")]
    sensors.append(SectionForce("N", "bar", 2, 0.1, "N"))
    return Scene(materials=[DAMPED], bodies=[body], constraints=[support], loads=[load],
                 sensors=sensors, solver=Solver(engine=engine),
                 dynamic=Dynamic(t_end=0.08, step=2e-4, output_every=0.04,
                                 integrator="generalized_alpha", rho_inf=0.5))


def at_rest(scene: Scene) -> dict[str, float]:
    """The sensors at the last output time of a run of ``scene``."""
    result = run_scene(scene, progress=False)
    assert result.status == "ok", result.summary["message"]
    return {name: float(values[-1]) for name, values in result.sensors.items()}


KINDS = ["beam2d", "beam3d", "beam2d_3node", "beam3d_3node", "cable2d", "cable3d"]


@pytest.mark.parametrize("kind", KINDS)
def test_axial_stress_of_a_pulled_bar_is_F_over_A_in_every_kind(kind):
    values = at_rest(_bar(kind))
    area = H * W
    stretch = values["tip_x"] / L
    assert stretch > 1.019                                    # a large strain indeed
    np.testing.assert_allclose(values["cauchy"], F / area, rtol=1e-8)
    np.testing.assert_allclose(values["mises"], F / area, rtol=1e-8)
    np.testing.assert_allclose(values["pk2"], F / (area * stretch), rtol=1e-8)
    np.testing.assert_allclose(values["green"], (stretch**2 - 1) / 2, rtol=1e-8)
    np.testing.assert_allclose(values["N"], F, rtol=1e-8)


def _rotation(dim: int, angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    if dim == 2:
        return np.array([[c, -s], [s, c]])
    axis = np.array([1.0, 2.0, 2.0]) / 3.0
    cross = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return c * np.eye(3) + s * cross + (1 - c) * np.outer(axis, axis)


@pytest.mark.parametrize("kind", [*KINDS, "plate3d"])
def test_a_homogeneous_stretch_then_a_rotation_gives_its_closed_forms(kind):
    # q: the reference stretched by lam along local x (positions and r_x), then turned as a
    # whole: the local-frame components of E, S and sigma are those of the stretch (the
    # sensors are objective), whatever the turn
    dim = 3 if "3d" in kind else 2
    z = (0.0,) * (dim - 2)
    if kind == "plate3d":
        body = Body("bar", kind, "soft", thickness=W,
                    rectangle=Rectangle((0.0, 0.0, 0.0), (L, H), (3, 2)))
        point = (0.3, 0.05, 0.01)
    else:
        body = Body("bar", kind, "soft", height=H, width=W, elements=3,
                    start=(0.0, 0.0, *z), end=(L, 0.0, *z))
        across = 0.0 if kind.startswith("cable") else 1.0
        point = (0.3, 0.03 * across, *((-0.02 * across,) * (dim - 2)))
    sensors = [Stress("cauchy", "bar", 1, point, "xx"), Stress("pk2", "bar", 1, point, "xx",
                                                                 "pk2"),
               Stress("shear", "bar", 1, point, "xy"), Strain("green", "bar", 1, point, "xx"),
               Strain("green_yy", "bar", 1, point, "yy"), Stress("mises", "bar", 1, point,
                                                                 "von_mises")]
    model = Model(Scene(materials=[SOFT], bodies=[body], sensors=sensors))
    lam, q = 1.05, model.reference.copy()
    for node in range(model.n_nodes):
        names = model.node_vectors(node)
        for name in ("r", "r_x"):
            if name in names:
                q[model.node_dofs(node, name)] *= [lam, *(1.0,) * (dim - 1)]
    for angle in (0.0, 0.7, 2.5):
        turn = _rotation(dim, angle)
        turned = (q.reshape(-1, dim) @ turn.T).ravel()
        values = Sensors(model).values(turned)
        green = (lam**2 - 1) / 2
        np.testing.assert_allclose(values["green"], green, rtol=1e-12)
        np.testing.assert_allclose(values["pk2"], E * green, rtol=1e-12)
        np.testing.assert_allclose(values["cauchy"], lam * E * green, rtol=1e-12)
        np.testing.assert_allclose(values["mises"], lam * E * green, rtol=1e-12)
        assert abs(values["green_yy"]) < 1e-14 and abs(values["shear"]) < 1e-12 * E


@pytest.mark.parametrize("kind", ["beam2d", "beam3d", "cable3d"])
def test_components_are_in_the_element_frame_whatever_the_placement(kind):
    values = at_rest(_bar(kind, angle_deg=35.0))
    stretch = math.hypot(values["tip_x"], values["tip_y"]) / L
    np.testing.assert_allclose(values["cauchy"], F / (H * W), rtol=1e-8)
    np.testing.assert_allclose(values["green"], (stretch**2 - 1) / 2, rtol=1e-8)
    np.testing.assert_allclose(values["N"], F, rtol=1e-8)


P = 50.0


def _cantilever(kind: str, material: Material = SOFT, engine: str = "compiled",
                elements: int = 8, **analysis) -> Scene:
    """A cantilever of ``kind`` (length L, section H x W) under a small tip load P along -y
    (bending about z) and, in 3D, 0.5 P along +z (bending about y)."""
    dim = 3 if "3d" in kind else 2
    z = (0.0,) * (dim - 2)
    l_el = L / elements
    mid = l_el / 2
    # shear: the 2-node beams' is near constant in an element away from the clamp (which
    # holds r_x . r_y = 0), the 3-node beams' exact at the 2-point Gauss points (Barlow's)
    shear_at = mid if "3node" not in kind else mid * (1 - 1 / math.sqrt(3))
    load = (0.0, -P, *((0.5 * P,) * (dim - 2)))
    top = (mid, H / 2, *z)
    sensors = [*(Stress(f"top_{c}", "beam", 0, top, c)
                 for c in (("yy", "xy") if dim == 2 else ("yy", "zz", "yz", "xz", "xy"))),
               Stress("top", "beam", 0, (mid, H / 2, *z), "xx"),
               Stress("bottom", "beam", 0, (mid, -H / 2, *z), "xx"),
               Stress("top_mises", "beam", 0, (mid, H / 2, *z), "von_mises"),
               Strain("top_strain", "beam", 0, (mid, H / 2, *z), "xx"),
               SectionForce("M3", "beam", 0, mid, "M3"),
               SectionForce("Q2", "beam", 3, shear_at, "Q2"),
               SectionForce("N", "beam", 3, shear_at, "N"),
               Reaction("Mz", "beam:0", "moment", "z")]
    if dim == 3:
        sensors += [Stress("side", "beam", 0, (mid, 0.0, W / 2), "xx"),
                    SectionForce("M2", "beam", 0, mid, "M2"),
                    SectionForce("Q3", "beam", 3, shear_at, "Q3"),
                    SectionForce("torsion", "beam", 0, mid, "T")]
    return Scene(materials=[material],
                 bodies=[Body("beam", kind, material.name, height=H, width=W,
                              elements=elements, start=(0.0, 0.0, *z), end=(L, 0.0, *z))],
                 constraints=[Clamp("beam:0")], loads=[PointForce("beam:-1", load)],
                 sensors=sensors, solver=Solver(engine=engine), **analysis)


@pytest.mark.parametrize("kind, law, nu", [("beam2d", "svk", 0.0), ("beam3d", "svk", 0.0),
                                           ("beam2d", "ecm", 0.3), ("beam3d", "ecm", 0.3),
                                           ("beam3d_3node", "svk", 0.0),
                                           ("beam2d_3node", "ecm", 0.3)])
def test_surface_stress_of_a_bent_beam_is_M_c_over_I(kind, law, nu):
    material = Material("soft", E=E, nu=nu, rho=1000.0, law=law)
    values = run_scene(_cantilever(kind, material, static=Static()),
                       progress=False).summary["static"]["sensors"]
    x = L / 16                                   # the middle of the first element
    moment, inertia = P * (L - x), W * H**3 / 12
    # the element's curvature is constant (its mean): exact at the element's middle
    np.testing.assert_allclose(values["top"], moment * (H / 2) / inertia, rtol=1e-3)
    np.testing.assert_allclose(values["bottom"], -moment * (H / 2) / inertia, rtol=1e-3)
    s = {c: values["top" if c == "xx" else f"top_{c}"] for c in ("xx", "yy", "zz", "yz", "xz",
                                                                "xy") if c == "xx" or
         f"top_{c}" in values}
    mises = (math.sqrt(s["xx"]**2 - s["xx"] * s["yy"] + s["yy"]**2 + 3 * s["xy"]**2)
             if "2d" in kind else   # plane stress in 2D
             math.sqrt(((s["xx"] - s["yy"])**2 + (s["yy"] - s["zz"])**2
                        + (s["zz"] - s["xx"])**2) / 2 + 3 * (s["yz"]**2 + s["xz"]**2
                                                              + s["xy"]**2)))
    np.testing.assert_allclose(values["top_mises"], mises, rtol=1e-12)
    np.testing.assert_allclose(values["top_mises"], abs(values["top"]), rtol=3e-3)
    np.testing.assert_allclose(values["top_strain"], values["top"] / E, rtol=2e-3)
    np.testing.assert_allclose(values["M3"], -moment, rtol=1e-3)
    np.testing.assert_allclose(values["Q2"], -P, rtol=2e-3)
    # the fixed loads tilt against the turned section: N = F . t1 with the slopes of
    # small-deflection theory at the sensor (element 3)
    at = 3 * L / 8 + (L / 16 if "3node" not in kind else L / 16 * (1 - 1 / math.sqrt(3)))

    def slope(force: float, second_moment: float) -> float:
        return force / (E * second_moment) * (L * at - at**2 / 2)

    axial = P * slope(P, inertia)
    if "3d" in kind:
        axial += 0.5 * P * slope(0.5 * P, H * W**3 / 12)
    # (to 5 % in the 2-node beams; the 3-node beams' axial force is 10 % off there)
    np.testing.assert_allclose(values["N"], axial, rtol=5e-2 if "3node" not in kind else 0.15)
    np.testing.assert_allclose(values["Mz"], P * L, rtol=1e-3)
    if "3d" in kind:    # 0.5 P along +z bends about y: tension at z = -w/2
        side = 0.5 * P * (L - x) * (W / 2) / (H * W**3 / 12)
        np.testing.assert_allclose(values["side"], -side, rtol=3e-3)  # 3-node: 1.9e-3
        np.testing.assert_allclose(values["M2"], -0.5 * P * (L - x), rtol=1e-3)
        np.testing.assert_allclose(values["Q3"], 0.5 * P, rtol=2e-3)
        # second order only: the loads' lever arms grow with the deflections (2 cm)
        assert abs(values["torsion"]) < 1e-2 * P * L


@pytest.mark.parametrize("kind", ["cable2d", "cable3d"])
def test_cable_section_moment_is_EI_kappa_and_exact_along_the_element(kind):
    dim = 3 if kind == "cable3d" else 2
    z = (0.0,) * (dim - 2)
    sensors = [SectionForce(f"M_{i}", "beam", 0, x, "M") for i, x in
               enumerate((0.0, 0.1, L / 8))]
    if dim == 2:
        sensors.append(SectionForce("M3", "beam", 0, 0.0, "M3"))
    scene = Scene(materials=[SOFT],
                  bodies=[Body("beam", kind, "soft", height=H, width=W, elements=4,
                               start=(0.0, 0.0, *z), end=(L, 0.0, *z))],
                  constraints=[Clamp("beam:0")], loads=[PointForce("beam:-1", (0.0, -P, *z))],
                  sensors=sensors, static=Static())
    values = run_scene(scene, progress=False).summary["static"]["sensors"]
    for i, x in enumerate((0.0, 0.1, L / 8)):     # a cubic element: M linear, exact
        np.testing.assert_allclose(values[f"M_{i}"], P * (L - x), rtol=1e-3)
    if dim == 2:
        np.testing.assert_allclose(values["M3"], -P * L, rtol=1e-3)


def test_both_engines_agree_on_every_new_sensor():
    scene = {engine: _cantilever("beam3d", engine=engine, elements=4,
                                 dynamic=Dynamic(t_end=0.02, step=1e-3))
             for engine in ("compiled", "python")}
    for engine in scene:   # and the acceleration of the tip, the reaction's force
        scene[engine] = type(scene[engine])(**{
            **{f: getattr(scene[engine], f) for f in ("title", "materials", "bodies",
                                                       "constraints", "loads", "dynamic",
                                                       "solver")},
            "sensors": [*scene[engine].sensors, Acceleration("a_tip", "beam:-1", "y"),
                        Reaction("Fy", "beam:0", "force", "y")]})
    runs = {engine: run_scene(s, progress=False) for engine, s in scene.items()}
    compiled, python = runs["compiled"].sensors, runs["python"].sensors
    assert set(compiled) == set(python) and len(compiled["t"]) == 21
    for name, values in compiled.items():
        scale = max(np.abs(values).max(), 1e-30)
        np.testing.assert_allclose(values, python[name], rtol=0, atol=1e-7 * scale,
                                   err_msg=name)
    assert np.abs(compiled["a_tip"]).max() > 1.0 and np.abs(compiled["Fy"]).max() > 1.0


def test_vtu_fields_of_a_pulled_bar_are_F_over_A_everywhere(tmp_path):
    scene = dataclasses.replace(_bar("beam3d"), output=Output(vtk=True))
    path = tmp_path / "bar.toml"
    path.write_text(scene.to_toml())
    _, code = run(path, tmp_path / "out", quiet=True)
    assert code == 0
    mesh = meshio.read(tmp_path / "out" / "vtk" / "dynamic_000002.vtu")   # at rest
    stress = mesh.point_data["cauchy_stress"]
    assert stress.shape == (len(mesh.points), 6)
    np.testing.assert_allclose(stress[:, 0], F / (H * W), rtol=1e-8)
    np.testing.assert_allclose(stress[:, 1:], 0.0, atol=1e-8 * F / (H * W))
    np.testing.assert_allclose(mesh.point_data["von_mises_stress"], F / (H * W), rtol=1e-8)
    strain = mesh.point_data["green_lagrange_strain"][:, 0]
    # sigma = lam E (lam^2 - 1) / 2 with lam = sqrt(1 + 2 E11): every point
    np.testing.assert_allclose(np.sqrt(1 + 2 * strain) * E * strain, F / (H * W), rtol=1e-8)
