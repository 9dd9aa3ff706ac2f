"""The new sensors as scene items: every key checked with its path (element index and local
coordinates range-checked, components by dimension and kind, reactions only where a
constraint is), exit 2 from ``ancf run``, the TOML round trip, units and the written
outputs."""

from __future__ import annotations

import re

import pytest

from runtime import (
    Acceleration,
    Body,
    Clamp,
    Dynamic,
    Material,
    PointForce,
    Reaction,
    Rectangle,
    Scene,
    SceneError,
    SectionForce,
    Static,
    Strain,
    Stress,
    Weld,
    load_scene,
)
from runtime.app.run import run
from runtime.model.items.sensors import Sensors
from runtime.model.model import Model

STEEL = Material("steel", E=2.1e11, nu=0.0, rho=7800.0)


def _scene(sensors, kind: str = "beam2d", **extra) -> Scene:
    dim = 3 if "3d" in kind else 2
    z = (0.0,) * (dim - 2)
    bodies = [Body("beam", kind, "steel", height=0.1, width=0.05, elements=4,
                   start=(0.0, 0.0, *z), end=(2.0, 0.0, *z))]
    if dim == 3:
        bodies.append(Body("sheet", "plate3d", "steel", thickness=0.01,
                           rectangle=Rectangle((0.0, 1.0, 0.0), (1.0, 1.0), (2, 2))))
    return Scene(materials=[STEEL], bodies=bodies, constraints=[Clamp("beam:0")],
                 loads=[PointForce("beam:-1", (0.0, -10.0, *z))], sensors=sensors,
                 static=Static(), **extra)


@pytest.mark.parametrize("kind, sensor, message", [
    ("beam2d", Strain("e", "beam", 4, (0.1, 0.0), "xx"),
     "sensor[0].element: element index 4 out of range for body \"beam\" with 4 elements"),
    ("beam2d", Strain("e", "beam", -5, (0.1, 0.0), "xx"),
     "sensor[0].element: element index -5 out of range"),
    ("beam2d", Stress("s", "beam", 0, (0.6, 0.0), "xx"),
     "sensor[0].point[0]: local x = 0.6 m outside the element of body \"beam\" (x in [0, 0.5]"),
    ("beam2d", Stress("s", "beam", 0, (0.1, 0.06), "xx"),
     "sensor[0].point[1]: local y = 0.06 m outside the element"),
    ("beam2d", Stress("s", "beam", 0, (0.1, 0.0, 0.0), "xx"),
     "sensor[0].point: expected a list of 2 numbers (local coordinates x, y in m)"),
    ("beam2d", Stress("s", "beam", 0, (0.1, 0.0), "zz"),
     'sensor[0].component: unknown component "zz"; expected one of xx, yy, xy, von_mises'),
    ("beam2d", Strain("e", "beam", 0, (0.1, 0.0), "von_mises"),
     "sensor[0].component: von_mises is a stress"),
    ("beam2d", Stress("s", "beam", 0, (0.1, 0.0), "xx", "kirchhoff"),
     'sensor[0].measure: unknown stress measure "kirchhoff"; expected one of cauchy, pk2'),
    ("beam2d", Stress("s", "bar", 0, (0.1, 0.0), "xx"), 'sensor[0].body: unknown body "bar"'),
    ("beam2d", Strain("e", "beam", 1.0, (0.1, 0.0), "xx"),
     "sensor[0].element: expected an integer element index"),
    ("cable2d", Strain("e", "beam", 0, (0.1, 0.01), "xx"),
     "sensor[0].point: a cable (cable2d) has no cross section"),
    ("beam2d", SectionForce("m", "beam", 0, 0.7, "M3"), "sensor[0].x[0]: local x = 0.7 m"),
    ("beam2d", SectionForce("m", "beam", 0, 0.1, "T"),
     'sensor[0].component: unknown section force "T"; expected one of N, Q2, M3, M'),
    ("cable2d", SectionForce("q", "beam", 0, 0.1, "Q2"),
     "sensor[0].component: a cable (cable2d) carries no shear, torsion; expected one of "
     "N, M3, M"),
    ("cable3d", SectionForce("m", "beam", 0, 0.1, "M3"),
     "sensor[0].component: a cable (cable3d) carries no shear, torsion or section "
     "orientation; expected one of N, M"),
    ("beam3d", SectionForce("m", "sheet", 0, 0.1, "N"),
     'sensor[0].body: body "sheet" is a plate3d surface; section forces are those of beams'),
    ("beam2d", Reaction("r", "beam:-1", "force", "y"),
     "sensor[0].node: node beam:4 is held by no clamp, pin or prescribed_rotation and in no "
     "joint"),
    ("beam2d", Reaction("r", "beam:0", "moment", "x"),
     'sensor[0].component: unknown component "x" of a 2D moment (a 2D moment is about z); '
     "expected one of z, norm"),
    ("beam2d", Reaction("r", "beam:0", "force", "z"),
     'sensor[0].component: unknown component "z" of a 2D force'),
    ("beam2d", Reaction("r", "beam:0", "torque", "z"),
     'sensor[0].quantity: unknown quantity "torque"; expected one of force, moment'),
    ("beam2d", Acceleration("a", "beam:9", "y"), "sensor[0].node: node index 9 out of range"),
    ("beam3d", Reaction("r", "beam:0", "force", "y", edge="sheet:x=0"),
     'sensor[0]: expected either node = "BODY:INDEX" or edge = "BODY:x=I" (a grid line of a '
     "rectangle body), got node and edge"),
    ("beam3d", Reaction("r", None, "force", "y"),
     'sensor[0]: expected either node = "BODY:INDEX" or edge'),
    ("beam3d", Reaction("r", None, "force", "z", edge="sheet:x=0"),
     "sensor[0].edge: node sheet:0 of edge sheet:x=0 is held by no clamp, pin or "
     "prescribed_rotation and in no joint"),
])
def test_keys_of_the_new_sensors_are_checked_with_their_path(kind, sensor, message):
    with pytest.raises(SceneError, match=re.escape(message)):
        _scene([sensor], kind)


def test_an_invalid_sensor_is_exit_2_from_ancf_run(tmp_path):
    path = tmp_path / "bad.toml"
    text = _scene([Strain("e", "beam", 0, (0.1, 0.0), "xx")]).to_toml()
    path.write_text(text.replace("element = 0", "element = 7"))
    summary, code = run(path, tmp_path / "out", quiet=True)
    assert code == 2
    assert summary["message"].startswith("sensor[0].element: element index 7 out of range")


def test_negative_element_indices_count_from_the_end_and_reaction_on_joints():
    scene = Scene(materials=[STEEL],
                  bodies=[Body("a", "beam2d", "steel", height=0.1, width=0.05, elements=2,
                               start=(0.0, 0.0), end=(1.0, 0.0)),
                          Body("b", "beam2d", "steel", height=0.1, width=0.05, elements=2,
                               start=(1.0, 0.0), end=(2.0, 0.0))],
                  constraints=[Clamp("a:0"), Weld(("a:-1", "b:0"))],
                  sensors=[Strain("e", "b", -1, (0.1, 0.0), "xx"),
                           Reaction("r", "b:0", "force", "x")])
    assert scene.sensors[0].element == 1


def test_new_sensors_round_trip_through_toml_and_write_their_columns_and_units(tmp_path):
    sensors = [Acceleration("acc", "beam:-1", "y", ), Reaction("Fy", "beam:0", "force", "y"),
               Reaction("Mz", "beam:0", "moment", "z", frame="beam:0"),
               Strain("eps", "beam", 1, (0.2, 0.05), "xy"),
               Stress("sig", "beam", -1, (0.5, -0.05), "xx", "pk2"),
               Stress("mises", "beam", 0, (0.0, 0.0), "von_mises"),
               SectionForce("N", "beam", 2, 0.25, "N"), SectionForce("M", "beam", 3, 0.5, "M3")]
    scene = _scene(sensors, dynamic=Dynamic(t_end=0.004, step=1e-3))
    path = tmp_path / "scene.toml"
    path.write_text(scene.to_toml())
    text = path.read_text()
    for snippet in ('type = "reaction"', 'quantity = "moment"', 'frame = "beam:0"',
                    'type = "section"', "x = 0.25", 'measure = "pk2"', "point = [0.2, 0.05]",
                    "element = 3"):
        assert snippet in text
    assert 'measure = "cauchy"' not in text    # the default is not written
    assert load_scene(path) == scene
    assert [s.unit for s in scene.sensors] == ["m/s^2", "N", "N m", "1", "Pa", "Pa", "N",
                                               "N m"]
    summary, code = run(path, tmp_path / "out", quiet=True)
    assert code == 0, summary["message"]
    header = (tmp_path / "out" / "timeseries.csv").read_text().splitlines()[0]
    assert header.split(",") == ["t", *(s.name for s in sensors)]
    assert set(summary["static"]["sensors"]) == {s.name for s in sensors}
    assert (tmp_path / "out" / "sig.png").is_file()


def test_sensors_needing_the_equations_of_motion_say_so_without_them():
    model = Model(_scene([Reaction("Fy", "beam:0", "force", "y"),
                          Acceleration("ay", "beam:-1", "y")]))
    with pytest.raises(ValueError, match="sensors Fy, ay: need the accelerations"):
        Sensors(model).values(model.reference)
