"""Issue 19, the pinched hemisphere of Sze, Liu and Lo (2004, Finite Elements in Analysis and
Design 40, 1551-1569) as shipped (``scenes/hemisphere.toml``: a quarter of 16 x 16
ANCF-3833 shells from ``scenes/hemisphere.vtu`` with two symmetry planes, law svk_sri),
against the published load-deflection table at its first load level.

With the law svk (Gauss orders 3 x 3 x 2) this mesh locked at R / t = 250 and came out
16-17 % short at A and 17-23 % at B along the whole path.  svk_sri (the plane-stress and
shear part at 2 x 2 Gauss points of the surface, docs/laws.md) frees it: its linear
flexibility at A is 0.0935 per unit quarter force against MacNeal and Harder's 0.094, and the
first load level is within 1 % of the table (measured -0.3 % at A, -0.6 % at B); hence the
band of 2 %.  The whole path to Pmax (``python -m runtime.cli run scenes/hemisphere.toml``,
45 s) stays within 2.5 % (1.8 % at A and 2.5 % at B at Pmax).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest

from runtime import Static, load_scene, run_scene

SCENE = Path(__file__).resolve().parent.parent / "scenes" / "hemisphere.toml"

#: Sze, Liu and Lo's table: P / Pmax, u_A (outward at A), -u_B (inward at B)
PUBLISHED = {0.05: (0.855, 0.955), 0.5: (3.406, 5.902), 1.0: (4.067, 8.178)}


def test_hemisphere_against_the_published_table_at_the_first_load_level():
    scene = load_scene(SCENE)
    level = 0.05
    loads = [dataclasses.replace(load, force=tuple(level * f for f in load.force))
             for load in scene.loads]
    result = run_scene(dataclasses.replace(scene, loads=loads, static=Static(load_steps=1)),
                       progress=False)
    assert result.status == "ok", result.summary["message"]
    sensors = result.summary["static"]["sensors"]
    u_a, u_b = sensors["u_A"], -sensors["u_B"]
    published_a, published_b = PUBLISHED[level]
    for ours, published in ((u_a, published_a), (u_b, published_b)):
        assert ours == pytest.approx(published, rel=0.02)


def test_the_shipped_scene_holds_the_quarter_by_symmetry_alone():
    """Its constraints: the two symmetry planes and z at one node, nothing else held; the
    loads on the planes (the halves of the full model's forces)."""
    scene = load_scene(SCENE)
    assert [c.type for c in scene.constraints] == ["symmetry", "symmetry", "fix"]
    assert [c.normal for c in scene.constraints[:2]] == [(0.0, 1.0, 0.0), (1.0, 0.0, 0.0)]
    assert [load.force for load in scene.loads] == [(200.0, 0.0, 0.0), (0.0, -200.0, 0.0)]
