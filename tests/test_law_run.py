"""Material laws in runs: Poisson locking is never silent, modal analysis says it ignores
damping, and the kernels a law or damping needs are listed as built."""

from __future__ import annotations

import pytest
from scenes_small import cantilever

from runtime import Material, Modal, Static, run_scene


def _scene(law: str, nu: float, damping: float = 0.0, modal: bool = False):
    material = Material("m", E=2.1e11, nu=nu, rho=7800.0, law=law, damping=damping)
    return cantilever(elements=2, force=[0.0, -100.0], material=material, static=Static(),
                      modal=Modal(modes=2) if modal else None)


def test_svk_with_poisson_ratio_warns_once_naming_material_and_remedy(capsys):
    result = run_scene(_scene("svk", 0.3))
    warnings = [w for w in result.summary["warnings"] if "Poisson locking" in w]
    assert len(warnings) == 1
    assert warnings[0].startswith("material.m:") and 'law = "ecm"' in warnings[0]
    assert "35%" in warnings[0]   # (lam + 2G) / E = 1.346 at nu = 0.3
    assert capsys.readouterr().err.count("Poisson locking") == 1


@pytest.mark.parametrize("law,nu", [("ecm", 0.3), ("svk", 0.0)])
def test_no_locking_warning_without_locking(law, nu):
    result = run_scene(_scene(law, nu))
    assert not any("Poisson locking" in w for w in result.summary["warnings"])


def test_modal_analysis_says_it_ignores_damping_and_kernels_are_listed():
    result = run_scene(_scene("ecm", 0.3, damping=1e-4, modal=True))
    assert result.summary["modal"]["damping"].startswith("ignored")
    kernels = result.summary["kernels"]
    assert "beam2d/laws/c" in kernels and "beam2d/damping_straight/c" in kernels
    undamped = run_scene(_scene("ecm", 0.3, modal=True))
    assert "damping" not in undamped.summary["modal"]
