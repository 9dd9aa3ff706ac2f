"""Issue 19, symmetry constraints (``runtime.model.items.symmetry``): a symmetric half (or
quarter) model with ``symmetry`` rows equals the full model it mirrors, to the solver's
tolerance, on planes along the coordinate axes (fixed coordinates) and on an oblique plane
(joint rows with offsets); ``fix`` holds chosen components; bad input is a SceneError
naming its key."""

from __future__ import annotations

import tomllib

import numpy as np
import pytest

from runtime import (
    Body,
    Clamp,
    Displacement,
    Fix,
    Material,
    PointForce,
    Rectangle,
    Scene,
    SceneError,
    Static,
    Symmetry,
    run_scene,
)
from runtime.model.model import Model
from runtime.model.scene import parse_scene

STEEL = Material("steel", E=2.1e11, nu=0.0, rho=7800.0)


def _static(scene: Scene) -> dict[str, float]:
    result = run_scene(scene, progress=False)
    assert result.status == "ok", result.summary["message"]
    return result.summary["static"]["sensors"]


def _beam(half: bool, axis, force, elements: int = 6) -> dict[str, float]:
    """A beam clamped at both ends (length 4 m along the unit ``axis``, from an offset
    origin), loaded at its middle by ``force`` (large: the beam stretches as a cable), or
    its first half with a symmetry plane of normal ``axis`` at the middle and half the
    force.  Sensors: the middle's displacement."""
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    start = np.array([0.3, -0.2, 0.1])
    end = start + axis * (2.0 if half else 4.0)
    middle = "b:-1" if half else f"b:{elements}"
    held = Symmetry(node="b:-1", normal=tuple(axis)) if half else Clamp("b:-1")
    scene = Scene(
        materials=[STEEL],
        bodies=[Body("b", "beam3d", "steel", height=0.05, width=0.05,
                     elements=elements if half else 2 * elements, start=tuple(start),
                     end=tuple(end))],
        constraints=[Clamp("b:0"), held],
        loads=[PointForce(middle, tuple(np.asarray(force) * (0.5 if half else 1.0)))],
        sensors=[Displacement(c, middle, c) for c in "xyz"],
        static=Static(load_steps=4))
    return _static(scene)


@pytest.mark.parametrize("axis, force", [
    ((1.0, 0.0, 0.0), (0.0, -2e5, 0.0)),                       # plane x = const: fixed
    ((1.0, 2.0, 2.0), (2e5 / 5**0.5 * 2, -2e5 / 5**0.5, 0.0)),  # oblique: joint rows
])
def test_half_beam_equals_the_full_clamped_beam(axis, force):
    """Large deflection (the middle moves 0.12 m, 3 % of the span: membrane stretching
    matters), so every gradient row counts: the half model's middle moves as the full
    model's to round-off of the Newton solution."""
    full, half = _beam(False, axis, force), _beam(True, axis, force)
    scale = max(abs(v) for v in full.values())
    assert scale > 0.05
    for c in "xyz":
        assert half[c] == pytest.approx(full[c], abs=1e-9 * scale)


def _plate(quarter: bool) -> dict[str, float]:
    """A square plate3d plate (1 m, 10 mm) clamped along its four edges with a central point
    load of 100 kN, or its quarter [0, 0.5]^2 with symmetry planes x = 0.5 and y = 0.5 (the
    centre node on both) and a quarter of the load."""
    grid = 2 if quarter else 4
    size = 0.5 if quarter else 1.0
    centre = "p:-1,-1" if quarter else "p:2,2"
    edges = ["p:x=0", "p:y=0"] + ([] if quarter else ["p:x=-1", "p:y=-1"])
    planes = [Symmetry(edge="p:x=-1", normal=(1.0, 0.0, 0.0)),
              Symmetry(edge="p:y=-1", normal=(0.0, 1.0, 0.0))] if quarter else []
    scene = Scene(
        materials=[STEEL],
        bodies=[Body("p", "plate3d", "steel", thickness=0.01,
                     rectangle=Rectangle((0.0, 0.0, 0.0), (size, size), (grid, grid)))],
        constraints=[Clamp(edge=e) for e in edges] + planes,
        loads=[PointForce(centre, (0.0, 0.0, -1e5 / (4 if quarter else 1)))],
        sensors=[Displacement("w", centre, "z")],
        static=Static(load_steps=2))
    return _static(scene)


def test_quarter_plate_equals_the_full_plate():
    """Two planes along the axes (fixed coordinates, merged on the centre node; beside the
    clamps at the corners of the clamped and symmetry edges): the centre deflects as the
    full plate's (nonlinear: w / t = 0.2)."""
    full, quarter = _plate(False), _plate(True)
    assert full["w"] < -1e-3
    assert quarter["w"] == pytest.approx(full["w"], rel=1e-9)


def test_rows_of_a_shell_node_and_of_an_oblique_plane():
    """What the rows are: on an axis plane, single coordinates (a 3833 shell node on the
    plane y = 0: r.y, r_z.y, r_zz.y); on an oblique plane, joint rows A q = A q0 that the
    reference satisfies, their offsets the plane's distance."""
    shell = Scene(materials=[STEEL], bodies=[
        Body("s", "shell3d_3833", "steel", thickness=0.01,
             rectangle=Rectangle((0.0, 0.0, 0.0), (1.0, 1.0), (2, 2)))],
        constraints=[Symmetry(edge="s:y=0", normal=(0.0, -1.0, 0.0))])
    model = Model(shell)
    names = model.coordinate_names()
    assert model.joints.shape[0] == 0
    assert sorted({names[i] for i in model.fixed}) == ["r.y", "r_z.y", "r_zz.y"]
    assert model.fixed.size == 3 * 5           # five lattice nodes on y = 0
    axis = np.array([1.0, 2.0, 2.0]) / 3.0
    beam = Scene(materials=[STEEL], bodies=[
        Body("b", "beam3d", "steel", height=0.05, width=0.05, elements=2,
             start=(0.0, 0.0, 0.0), end=tuple(3.0 * axis))],
        constraints=[Symmetry(node="b:-1", normal=tuple(axis))])
    model = Model(beam)
    # position 1, r_x along the normal 2, r_y and r_z in the plane 1 each
    assert model.joints.shape[0] == 5 and model.fixed.size == 0
    np.testing.assert_allclose(model.joints @ model.reference, model.joint_offsets,
                               atol=1e-14)
    assert model.joint_offsets[0] == pytest.approx(3.0)


def test_fix_holds_the_chosen_components():
    scene = Scene(materials=[STEEL], bodies=[
        Body("b", "beam3d", "steel", height=0.05, width=0.05, elements=2,
             start=(0.0, 0.0, 0.0), end=(1.0, 0.0, 0.0))],
        constraints=[Clamp("b:0"), Fix(node="b:-1", components=("x", "z"))])
    model = Model(scene)
    names = model.coordinate_names()
    tip = set(model.node_dofs(2).tolist())
    assert sorted(names[i] for i in model.fixed if i in tip) == ["r.x", "r.z"]


SCENE = """
[material.steel]
E = 2.1e11
nu = 0.0
rho = 7800.0

[[body]]
name = "{body}"
element = "{element}"
material = "steel"
{placement}

[[constraint]]
type = "clamp"
node = "{body}:0"

[[constraint]]
{constraint}
"""

BEAM = ('section = { height = 0.05, width = 0.05 }\nelements = 2\nstart = [0.0, 0.0, 0.0]\n'
        'end = [1.0, 0.0, 0.0]')
PLATE = 'section = { thickness = 0.01 }\nrectangle = { corner = [0.0, 0.0, 0.0], ' \
        'size = [1.0, 1.0], grid = [2, 2] }'


@pytest.mark.parametrize("element, placement, constraint, message", [
    ("beam3d", BEAM, 'type = "symmetry"\nnode = "b:-1"',
     "constraint[1].normal: missing required key"),
    ("beam3d", BEAM, 'type = "symmetry"\nnode = "b:-1"\nnormal = [0.0, 0.0, 0.0]',
     "constraint[1].normal: expected a non-zero normal"),
    ("beam3d", BEAM, 'type = "symmetry"\nnode = "b:-1"\nnormal = [1.0, 0.0]',
     "constraint[1].normal: expected a list of 3 numbers"),
    ("beam3d", BEAM, 'type = "symmetry"\nnormal = [1.0, 0.0, 0.0]',
     'constraint[1]: expected either node = "BODY:INDEX" or edge'),
    ("beam3d", BEAM, 'type = "symmetry"\nnode = "b:-1"\nnormal = [1.0, 0.0, 0.0]\n'
     'point = [0.0, 0.0, 0.0]', "constraint[1].point: unknown key"),
    ("beam3d", BEAM, 'type = "fix"\nnode = "b:-1"\ncomponents = ["x", "x"]',
     "constraint[1].components: expected a list of distinct components among x, y, z"),
    ("beam3d", BEAM, 'type = "fix"\nnode = "b:-1"\ncomponents = []',
     "constraint[1].components: expected a list of distinct components"),
    ("beam3d", BEAM, 'type = "fix"\nnode = "b:-1"\ncomponents = ["w"]',
     "constraint[1].components: expected a list of distinct components"),
    ("plate3d", PLATE, 'type = "symmetry"\nedge = "b:y=-1"\nnormal = [1.0, 0.0, 0.0]',
     "constraint[1]: edge: node b:7 is 0.5 m off the symmetry plane"),
    ("cable3d", BEAM, 'type = "symmetry"\nnode = "b:-1"\nnormal = [1.0, 1.0, 0.0]',
     "constraint[1]: node: b:2: the mirror image of its gradients r_x is not a combination"),
    ("beam3d", BEAM, 'type = "prescribed_rotation"\nnode = "b:-1"\nangle = { type = '
     '"constant", value = 1.0 }\n\n[[constraint]]\ntype = "symmetry"\nnode = "b:-1"\n'
     'normal = [1.0, 0.0, 0.0]', "constraint[2].node: constraint[1] (prescribed_rotation) "
     "and constraint[2] (symmetry) on node b:2: contradictory"),
])
def test_scene_errors(element, placement, constraint, message):
    text = SCENE.format(body="b", element=element, placement=placement,
                        constraint=constraint)
    with pytest.raises(SceneError) as info:
        Model(parse_scene(tomllib.loads(text)))
    assert str(info.value).startswith(message), str(info.value)
