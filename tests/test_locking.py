"""Locking of the fully parameterised beams and the ``ecm_sri`` remedy (docs/laws.md):
the law as data, where it applies, the cantilever convergence against beam theory (the
elastica solved independently, checked against Mattiasson's table), and scenes using it."""

from __future__ import annotations

import json

import numpy as np
import pytest
from conftest import E_MODULUS, HEIGHT, LENGTH, NU, RHO, WIDTH, lame, rel_diff

from runtime import Element
from runtime.studies import locking

SRI_KINDS = ["beam2d", "beam3d"]


@pytest.mark.parametrize("kind", SRI_KINDS)
def test_ecm_sri_is_ecm_split_over_reduced_rules(kind):
    """D0's E11 and transverse shears on the 2-point Gauss rule along x, its cross-section
    strains on the ends (Lobatto), ecm's Poisson part on the axis ends: per Voigt entry the
    domains add up to ecm's."""
    sri = Element(kind, LENGTH, HEIGHT, WIDTH, E_MODULUS, NU, RHO, law="ecm_sri",
                  backend="numpy").law_coefficients()
    ecm = Element(kind, LENGTH, HEIGHT, WIDTH, E_MODULUS, NU, RHO, law="ecm",
                  backend="numpy").law_coefficients()
    k = 10 * (1 + NU) / (12 + 11 * NU)
    _, G = lame()
    if kind == "beam3d":   # [D11, D12, D13, D22, D23, D33, D44, D55, D66]
        gauss = [E_MODULUS, 0, 0, 0, 0, 0, 0, k * G, k * G]
        ends = [0, 0, 0, E_MODULUS, 0, E_MODULUS, G, 0, 0]
    else:                  # [D11, D12, D22, D33]
        gauss, ends = [E_MODULUS, 0, 0, k * G], [0, 0, E_MODULUS, 0]
    assert rel_diff(sri["volume_gauss2"], np.array(gauss)) <= 1e-15
    assert rel_diff(sri["volume_lobatto2"], np.array(ends)) <= 1e-15
    assert rel_diff(sri["axis_lobatto2"], ecm["axis"]) <= 1e-15
    assert not sri["volume"].any() and not sri["axis"].any()
    assert rel_diff(sri["volume_gauss2"] + sri["volume_lobatto2"], ecm["volume"]) <= 1e-15


@pytest.mark.parametrize("kind", ["beam2d_3node", "beam3d_3node"])
def test_ecm_sri_is_refused_where_the_ends_are_not_all_the_nodes(kind):
    """Sampling the cross-section at the ends only would leave the middle node's free."""
    with pytest.raises(ValueError, match="the nodes sit at x = 0, l/2, l"):
        Element(kind, LENGTH, HEIGHT, WIDTH, E_MODULUS, NU, RHO, law="ecm_sri",
                backend="numpy")


def test_elastica_matches_mattiasson():
    """Mattiasson (1981), tip load P L^2 / EI = 10: v/L = 0.81061, u/L = 0.55500."""
    v, u = locking.elastica(10.0)
    assert v == pytest.approx(0.81061, abs=1e-5) and u == pytest.approx(0.55500, abs=1e-5)
    assert locking.elastica(1e-4)[0] == pytest.approx(1e-4 / 3, rel=1e-6)  # P L^3 / 3EI


def test_ecm_sri_removes_the_locking_of_the_elastica():
    """beam2d, 8 elements, P L^2 / EI = 10, L/h = 100: ecm is 10 % too stiff, ecm_sri is
    within 0.5 % (from above: what remains is the element's constant curvature)."""
    exact = locking.reference("elastica")
    errors = {law: locking.tip_deflection("beam2d", law, "elastica", 8) / exact - 1
              for law in ("ecm", "ecm_sri")}
    assert errors["ecm"] < -0.05
    assert 0 < errors["ecm_sri"] < 5e-3


@pytest.mark.parametrize("elements", [2, 4])
def test_small_deflection_keeps_the_constant_curvature_limit(elements):
    """Linear cantilever: the bending strain of the element is y r_x . r_yx with r_y linear
    along x, so the curvature is constant per element and the tip deflection is the
    trapezoid rule of the rotation, -1 / (4 N^2) of P L^3 / 3EI, with either law."""
    exact = locking.reference("linear")
    for law in ("ecm", "ecm_sri"):
        error = locking.tip_deflection("beam2d", law, "linear", elements) / exact - 1
        assert error == pytest.approx(-1 / (4 * elements**2), abs=1e-3)


def test_report_is_a_markdown_table():
    rows = [locking.Row("beam3d", "ecm_sri", "linear", (0.01, -0.002))]
    text = locking.report(rows, elements=(2, 4))
    assert text.splitlines()[0] == "| case | kind | law | 2 el. | 4 el. |"
    assert "| P L^3/3EI, L/h = 50, nu = 0 | beam3d | ecm_sri | +1.00e-02 | -2.00e-03 |" in text


@pytest.mark.parametrize("engine", ["python", "compiled"])
def test_scene_with_ecm_sri_runs_with_both_engines(tmp_path, engine):
    """``[material.NAME] law = "ecm_sri"`` needs no scene code (the parser takes the laws of
    element.json): a beam3d cantilever runs statics and a short dynamic analysis."""
    from runtime.cli import main

    scene = tmp_path / "sri.toml"
    scene.write_text("""title = "ecm_sri cantilever"
[material.steel]
E = 2.1e11
nu = 0.3
rho = 7800.0
law = "ecm_sri"
[[body]]
name = "beam"
element = "beam3d"
material = "steel"
section = { height = 0.02, width = 0.02 }
elements = 4
start = [0.0, 0.0, 0.0]
end = [1.0, 0.0, 0.0]
[[constraint]]
type = "clamp"
node = "beam:0"
[[load]]
type = "point_force"
node = "beam:-1"
force = [0.0, -1.0, 0.0]
[[sensor]]
name = "tip_y"
type = "displacement"
node = "beam:-1"
component = "y"
[analysis.static]
[analysis.dynamic]
t_end = 0.002
step = 0.001
""")
    out = tmp_path / "out"
    assert main(["run", str(scene), "--out", str(out), "--engine", engine, "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    inertia = 0.02**4 / 12
    theory = 1.0 / (3 * 2.1e11 * inertia)
    assert summary["static"]["sensors"]["tip_y"] == pytest.approx(-theory, rel=0.03)
    assert any("gram_general" in kernel for kernel in summary["kernels"])
