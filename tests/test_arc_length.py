"""Arc-length continuation (issue 18, item 6): the static path through limit points.

* the two-bar von Mises truss (pinned bars of beam2d elements, a load at the apex) follows
  its closed-form load-displacement curve P(w) = EA w (h^2 - w^2) / L0^3 (each bar's Green
  strain (L^2 - L0^2) / 2 L0^2 uniform; the bars stay straight) through its limit point,
  zero load, the inverted minimum and beyond, where load stepping stops with a named
  divergence at the limit load;
* Lee's frame (scenes/lee_frame.toml) passes its first limit point at the published
  P L^2 / EI = 18.5 (Schweizerhof and Wriggers 1986), Da Deppo and Schmidt's deep arch
  (scenes/deep_arch.toml) its limit point at P R^2 / EI = 8.97;
* the path's CSV and plot, and the keys of [analysis.static].
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scenes_small import body, scene

import scenes
from runtime import Displacement, Material, Pin, PointForce, Revolute, Static, load_scene, run_scene
from runtime.model.errors import SceneError
from runtime.model.scene import parse_scene

HALF_SPAN, RISE, SECTION = 1.0, 0.1, 0.1       # m; the bars' Euler strain 8e-3 > 5e-3 used
TRUSS = Material("m", E=1e7, nu=0.0, rho=1.0)
EA = TRUSS.E * SECTION * SECTION
L0 = math.hypot(HALF_SPAN, RISE)


def truss_load(w):
    """The apex load (N, downward) in equilibrium at apex height w (m) above the supports."""
    return EA * w * (RISE**2 - w**2) / L0**3


LIMIT = truss_load(RISE / math.sqrt(3))        # 2 EA h^3 / (3 sqrt(3) L0^3)


def truss(static: Static, load: float):
    bars = [body("left", elements=2, start=(-HALF_SPAN, 0.0), end=(0.0, RISE),
                 height=SECTION, width=SECTION),
            body("right", elements=2, start=(0.0, RISE), end=(HALF_SPAN, 0.0),
                 height=SECTION, width=SECTION)]
    return scene(bars, [Pin("left:0"), Pin("right:-1"), Revolute(("left:-1", "right:0"))],
                 [PointForce("left:-1", [0.0, -load])],
                 [Displacement("apex_v", "left:-1", "y"),
                  Displacement("apex_u", "left:-1", "x")], TRUSS, static=static)


def test_the_von_mises_truss_follows_its_closed_form_path_through_snap_through():
    settings = Static(method="arc_length", arc_length=0.005, max_steps=300,
                      max_load_factor=10.0, stop_sensor="apex_v", stop_value=-2.4 * RISE)
    result = run_scene(truss(settings, LIMIT), progress=False)
    assert result.status == "ok"
    path = result.path
    factors, w = path["load_factor"], RISE + path["apex_v"]
    # past the limit point (load factor 1), through zero load (flat), the inverted minimum
    # (-1) and zero again, to the rising branch beyond
    between = factors[np.abs(w) <= RISE]
    assert 0.97 < between.max() <= 1.0 + 1e-9 and -1.0 - 1e-9 <= between.min() < -0.97
    assert w[-1] < -RISE < w[0] and factors[-1] > 1.0
    # every converged point on the closed-form curve, and symmetric (the apex stays on x = 0)
    np.testing.assert_allclose(factors * LIMIT, truss_load(w), rtol=0, atol=1e-7 * LIMIT)
    assert np.abs(path["apex_u"]).max() < 1e-9 * RISE
    assert result.summary["static"]["stopped"].startswith("sensor apex_v")
    assert result.summary["static"]["path_points"] == factors.size


def test_load_stepping_stops_at_the_limit_point_with_a_named_divergence():
    result = run_scene(truss(Static(load_steps=10), 1.2 * LIMIT), progress=False)
    assert result.status == "diverged" and result.exit_code == 1
    message = result.summary["message"]
    assert "load stepping reached 1/1024 of the load" in message
    assert 'a limit point: larger increments jumped past it; method = "arc_length"' in message
    reached = float(message.split("load stepping reached 1/1024 of the load at ")[1]
                    .split(" of it")[0])
    assert reached * 1.2 == pytest.approx(1.0, rel=2e-3)     # the limit load, not beyond


def test_lee_frame_passes_its_first_limit_point_at_the_published_load():
    shipped = load_scene(scenes.path("lee_frame"))
    assert shipped.static.method == "arc_length"
    # up to just past the first limit point (at load_v = -48 with 20 elements per member)
    settings = dataclasses.replace(shipped.static, stop_sensor="load_v", stop_value=-55.0)
    result = run_scene(dataclasses.replace(shipped, static=settings), progress=False)
    factors = result.path["load_factor"]
    assert factors.max() == pytest.approx(18.5, rel=1.5e-2)      # 18.69: 1 % high at 20
    assert factors[-1] < factors.max() - 0.2                      # past it, going down


def test_the_deep_arch_passes_its_limit_point_at_the_published_load():
    # Da Deppo and Schmidt's clamped-hinged arch (scenes/deep_arch.toml), up to just past its
    # limit point (at crown_v = -114 with 160 elements; the crown goes on down as the load
    # falls)
    shipped = load_scene(scenes.path("deep_arch"))
    settings = dataclasses.replace(shipped.static, stop_value=-118.0)
    result = run_scene(dataclasses.replace(shipped, static=settings), progress=False)
    factors = result.path["load_factor"]
    assert factors.max() == pytest.approx(8.97, rel=1e-2)       # 9.00 with 160 elements
    assert factors[-1] < factors.max() - 0.1


def test_load_stepping_stays_the_default_and_its_summary_unchanged():
    settings = Static()
    assert settings.method == "load_stepping" and "method" not in settings.to_dict()
    result = run_scene(truss(settings, 0.5 * LIMIT), progress=False)
    assert set(result.summary["static"]) == {"sensors", "iterations", "load_steps"}
    assert result.path == {}


def test_ancf_run_writes_the_path_csv_and_plot(tmp_path):
    from runtime.app.run import run

    settings = Static(method="arc_length", arc_length=0.02, max_steps=40, max_load_factor=0.9)
    summary, code = run(truss(settings, LIMIT), tmp_path, quiet=True)
    assert code == 0
    assert {"static_path.csv", "static_path.png"} <= set(summary["files"])
    rows = (tmp_path / "static_path.csv").read_text().splitlines()
    assert rows[0] == "load_factor,apex_v,apex_u"
    assert len(rows) - 1 == summary["static"]["path_points"]
    last = [float(x) for x in rows[-1].split(",")]
    assert last[0] == summary["static"]["load_factor"] >= 0.9
    assert last[0] * LIMIT == pytest.approx(truss_load(RISE + last[1]), abs=1e-6 * LIMIT)


def _static_table(**keys) -> dict:
    data = truss(Static(), LIMIT).to_dict()
    data["analysis"]["static"] = keys
    return data


@pytest.mark.parametrize("keys, message", [
    ({"method": "riks"}, "analysis.static.method: unknown static method"),
    ({"arc_length": 0.1}, 'analysis.static.arc_length: only meaningful with method = '
                          '"arc_length"'),
    ({"method": "arc_length", "arc_length": -1.0}, "analysis.static.arc_length: expected a "
                                                   "positive number"),
    ({"method": "arc_length", "stop_sensor": "apex_v"}, "analysis.static.stop_value: expected "
                                                        "with stop_sensor"),
    ({"method": "arc_length", "stop_sensor": "tip", "stop_value": 1.0},
     "analysis.static.stop_sensor: no sensor called"),
    ({"method": "arc_length", "max_steps": 0}, "analysis.static.max_steps"),
])
def test_bad_arc_length_keys_name_their_path(keys, message):
    with pytest.raises(SceneError, match=message.replace("(", r"\(")):
        parse_scene(_static_table(**keys))


def test_path_points_times_elements_are_bounded_before_anything_is_built():
    data = _static_table(method="arc_length", max_steps=10**8)
    data["body"][0]["elements"] = 1000
    with pytest.raises(SceneError, match="analysis.static.max_steps: 100000000 path points of "
                                         "1002 elements exceed the limit of 1e"):
        parse_scene(data)


def test_arc_length_with_a_follower_moment_follows_the_roll_up_circles():
    # scenes/rollup.toml (M = 2 pi EI / L, following) by arc length: at load factor lambda
    # the beam is a circular arc of angle 2 pi lambda, the tip at
    # L (sin(2 pi lambda), 1 - cos(2 pi lambda)) / (2 pi lambda)
    shipped = load_scene(scenes.path("rollup"))
    settings = Static(method="arc_length", load_steps=10, max_steps=200)
    result = run_scene(dataclasses.replace(shipped, static=settings), progress=False)
    assert result.status == "ok" and result.summary["static"]["load_factor"] >= 1.0
    turn = 2 * math.pi * result.path["load_factor"][1:]
    np.testing.assert_allclose(result.path["tip_x"][1:], np.sin(turn) / turn, atol=5e-3)
    np.testing.assert_allclose(result.path["tip_y"][1:], (1 - np.cos(turn)) / turn, atol=5e-3)
