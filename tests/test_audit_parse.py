"""Second audit, scene level: sizes, moduli and motions a double cannot carry are named by
their scene key when the scene is parsed (not by an Element argument later); a Python Body
is checked as its TOML is; two clamped edges sharing a corner are one hold; a run's kernel
compile time is charged once (no negative pre-processing time)."""

from __future__ import annotations

import tomllib

import pytest
from test_scene_faults import BASE, PLATE, scene_data

from runtime import (
    Body,
    Clamp,
    Displacement,
    LineForce,
    Material,
    Rectangle,
    Scene,
    Static,
    run_scene,
)
from runtime.element import element as element_module
from runtime.element.element import MAGNITUDE, Element
from runtime.model.errors import SceneError
from runtime.model.scene import parse_scene

PLATE_SCENE = BASE + PLATE

CASES = [
    ("section height 1e200", {"body.0.section": {"height": 1e200, "width": 0.1}},
     "body[0].section.height: expected a section height in m between 1e-30 and 1e+30, got "
     "1e+200"),
    ("section width 1e-40", {"body.0.section": {"height": 0.1, "width": 1e-40}},
     "body[0].section.width: expected a section width in m between 1e-30 and 1e+30"),
    ("E of 1e-300", {"material.steel.E": 1e-300},
     "material.steel.E: expected Young's modulus in Pa between 1e-30 and 1e+30, got 1e-300"),
    ("rho of 1e40", {"material.steel.rho": 1e40},
     "material.steel.rho: expected a density in kg/m^3 between 1e-30 and 1e+30"),
    ("start and end 1e-300 apart", {"body.0.end": [1e-300, 0.0, 0.0]},
     "body[0].end: expected a body length |end - start| in m between 1e-30 and 1e+30"),
    ("elements of 2.5e-36 m", {"body.0.end": [2.5e-35, 0.0, 0.0], "body.0.elements": 10},
     "body[0].end: expected a body length"),
    ("many elements of a tiny body", {"body.0.end": [2.5e-29, 0.0, 0.0],
                                      "body.0.elements": 100},
     "body[0].elements: 100 elements make elements 2.5e-31 m long; expected elements of at "
     "least 1e-30 m (at most 24 elements)"),
    ("initial velocity of 1e200 m/s", {"body.0.initial_velocity": [1e200, 0.0, 0.0]},
     'body[0].initial_velocity: expected a motion of body "beam" (78 kg) at speeds of at most '
     "1.6e+49 m/s (a kinetic energy of at most 1e+100 J"),
    ("spin of 1e60 rad/s", {"body.0.initial_angular_velocity": {"omega": [0.0, 0.0, 1e60],
                                                                "about": [0.0, 0.0, 0.0]}},
     "body[0].initial_angular_velocity.omega: expected a motion of body"),
    ("shear correction of 1e30", {"material.steel.law": "ecm",
                                  "material.steel.shear_correction": 1e30},
     "material.steel.shear_correction: expected a shear correction factor in [0.01, 100]"),
]


@pytest.mark.parametrize("description, changes, message", CASES, ids=[c[0] for c in CASES])
def test_out_of_range_inputs_are_named_by_their_scene_key(description, changes, message):
    with pytest.raises(SceneError) as info:
        parse_scene(scene_data(changes))
    assert str(info.value).startswith(message), str(info.value)


PLATE_CASES = [
    ("corner of 1e300", ("corner = [0.0, 5.0, 0.0]", "corner = [1e300, 5.0, 0.0]"),
     "body[2].rectangle.corner: expected a point with coordinates of at most 1e+30 m"),
    ("side of 1e-31", ("size = [1.0, 0.5]", "size = [1.0, 1e-31]"),
     "body[2].rectangle.size: expected sides in m between 1e-30 and 1e+30, got 1e-31"),
    ("grid of too small elements", ("size = [1.0, 0.5]", "size = [1.0, 1e-30]"),
     "body[2].rectangle.grid[1]: 2 elements make elements 5e-31 m long"),
    ("plate thickness of 1e31", ("thickness = 0.01", "thickness = 1e31"),
     "body[2].section.thickness: expected a thickness in m between 1e-30 and 1e+30"),
]


@pytest.mark.parametrize("description, change, message", PLATE_CASES,
                         ids=[c[0] for c in PLATE_CASES])
def test_out_of_range_plates_are_named_by_their_scene_key(description, change, message):
    with pytest.raises(SceneError) as info:
        parse_scene(tomllib.loads(PLATE_SCENE.replace(*change)))
    assert str(info.value).startswith(message), str(info.value)


def test_the_scene_bounds_are_the_elements():
    # one definition: what the parser accepts at the edges the Element accepts
    scene = parse_scene(scene_data({"material.steel.E": 1 / MAGNITUDE,
                                    "body.0.section": {"height": MAGNITUDE, "width": 0.1}}))
    assert scene.materials["steel"].E == 1 / MAGNITUDE
    with pytest.raises(ValueError, match="height: expected a positive finite number between "
                                         "1e-30 and 1e\\+30"):
        Element("beam3d", 1.0, MAGNITUDE * 10, 0.1, 1e9, 0.0, 1.0, backend="numpy")


def test_speeds_within_the_bound_parse():
    scene = parse_scene(scene_data({"body.0.initial_velocity": [1e40, 0.0, 0.0]}))
    assert scene.bodies[0].initial_velocity == (1e40, 0.0, 0.0)


# --------------------------------------------------------------------------- Python bodies

STEEL = [Material("steel", E=2.1e11, nu=0.0, rho=7850.0)]
STRIP = Rectangle(corner=(0.0, 0.0, 0.0), size=(1.0, 0.1), grid=(4, 1))


def _scene_error(body: Body) -> str:
    with pytest.raises(SceneError) as info:
        Scene(materials=STEEL, bodies=[body])
    return str(info.value)


def test_a_plate_body_without_rectangle_names_rectangle():
    text = _scene_error(Body("p", "plate3d", "steel", thickness=0.01, rectangle=None))
    assert text.startswith("body[0].rectangle: missing required key"), text


def test_a_plate_body_with_a_height_is_refused_like_its_toml():
    text = _scene_error(Body("p", "plate3d", "steel", height=0.1, thickness=0.01,
                             rectangle=STRIP))
    assert text.startswith("body[0].section.height: unknown key; expected one of thickness")


def test_a_beam_body_with_a_thickness_is_refused_like_its_toml():
    text = _scene_error(Body("b", "beam3d", "steel", 0.1, 0.1, 2, (0.0, 0.0, 0.0),
                             (1.0, 0.0, 0.0), thickness=0.1))
    assert text.startswith("body[0].section.thickness: unknown key"), text


# --------------------------------------------------------------------------- two clamped edges

def test_two_clamped_edges_sharing_a_corner_hold_the_plate():
    plate = Body("plate", "plate3d", "steel", thickness=0.01,
                 rectangle=Rectangle(corner=(0.0, 0.0, 0.0), size=(1.0, 1.0), grid=(3, 3)))
    scene = Scene(materials=STEEL, bodies=[plate],
                  constraints=[Clamp(edge="plate:x=0"), Clamp(edge="plate:y=0")],
                  loads=[LineForce(edge="plate:x=-1", force_per_length=(0.0, 0.0, -100.0))],
                  sensors=[Displacement("far", "plate:-1,-1", "z"),
                           Displacement("corner", "plate:0,0", "z")],
                  static=Static(), solver={"backend": "numpy", "engine": "python"})
    result = run_scene(scene, progress=False)
    sensors = result.summary["static"]["sensors"]
    assert result.status == "ok" and sensors["corner"] == 0.0 and sensors["far"] < 0.0
    # the corner node's coordinates are held once
    assert len(set(result.model.fixed.tolist())) == len(result.model.fixed)


def test_conflicting_holds_of_a_corner_stay_errors():
    data = tomllib.loads(PLATE_SCENE + '[[constraint]]\ntype = "pin"\nnode = "sheet:0"\n'
                         '[[constraint]]\ntype = "clamp"\nedge = "sheet:x=0"\n')
    with pytest.raises(SceneError, match=r"constraint\[2\]\.edge: constraint\[1\] \(pin\) and "
                                         r"constraint\[2\] \(clamp\)"):
        parse_scene(data)


# --------------------------------------------------------------------------- timing

def test_a_kernel_family_compiled_for_an_element_is_charged_once(monkeypatch):
    real = element_module.kernel_family

    class Fresh:
        """A family just compiled (1 s) for the element asking."""

        def __init__(self, family):
            self._family = family
            self.compile_s, self.load_s, self.loaded_at = 1.0, 0.0, float("inf")

        def __getattr__(self, name):
            return getattr(self._family, name)

        def __call__(self, *args, **kwargs):
            return self._family(*args, **kwargs)

    monkeypatch.setattr(element_module, "kernel_family",
                        lambda *args: Fresh(real(*args)))
    beam = Element("beam3d", 0.5, 0.1, 0.1, 1e9, 0.3, 1000.0, backend="numpy", law="ecm",
                   damping=1e-3)
    assert beam.timing["compile_s"] == pytest.approx(len(beam.loaded_families))


def test_the_scene_engine_that_cannot_run_is_named_by_its_key():
    from scenes_small import cantilever

    scene = cantilever(elements=2, force=[0.0, -1.0], static=Static(),
                       solver={"engine": "compiled", "backend": "numpy"})
    with pytest.raises(ValueError) as info:
        run_scene(scene, progress=False)
    assert str(info.value).startswith('solver.engine: the compiled engine needs backend "c", '
                                      'got solver.backend = "numpy"'), str(info.value)
    with pytest.raises(ValueError, match='solver.engine: .* got the backend option "numpy"'):
        run_scene(cantilever(elements=2, force=[0.0, -1.0], static=Static(),
                             solver={"engine": "compiled"}), backend="numpy", progress=False)
