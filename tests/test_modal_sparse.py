"""Modes of slender and large models: the dense path (its inverse form) and, beyond the dense
limit, the shift-invert iterations with CHOLMOD's Cholesky of K give beam theory's
frequencies to the discretisation's error, and the latter SciPy's own SuperLU path's."""

from __future__ import annotations

import numpy as np
import pytest

from runtime.model.model import Model
from runtime.solve import modal
from runtime.solve.linear import DENSE_LIMIT
from runtime.studies.bench_steps import chain_scene


def _beam_theory(scene) -> np.ndarray:
    """The clamped-free beam's first two bending frequencies, twice each (square section:
    both planes alike), Euler-Bernoulli: omega_k = (beta_k L)^2 sqrt(EI / (rho A L^4))."""
    body, material = scene.bodies[0], scene.materials[scene.bodies[0].material]
    length, area = body.end[0] - body.start[0], body.height * body.width
    scale = np.sqrt(material.E * body.width * body.height ** 3 / 12
                    / (material.rho * area * length ** 4))
    return np.repeat(np.array([1.8751040687, 4.6940911330]) ** 2 * scale, 2)


def test_the_dense_path_resolves_a_slender_beams_lowest_frequency():
    # 120 elements, L/h = 600 (1440 coordinates, dense): 1.18e-5 above beam theory, the
    # element's discretisation error; eigh(K, M) resolved the lowest eigenvalue only to
    # round-off times the largest and was 5.4e-5 off
    scene = chain_scene(120, 1)
    model = Model(scene)
    assert model.free.size <= DENSE_LIMIT
    found = modal.modal(model, model.reference, 2)
    assert found == pytest.approx(_beam_theory(scene)[:2], rel=2e-5)


def test_cholmod_shift_invert_gives_the_superlu_and_beam_theory_frequencies(monkeypatch):
    scene = chain_scene(160, 1)                 # 160 beam3d elements: 1920 coordinates
    model = Model(scene)
    assert model.free.size > DENSE_LIMIT
    stiffness = -model.jacobian_matrix(model.internal_forces(model.reference)[1])
    assert modal._inverse(stiffness) is not None     # CHOLMOD's factor is the path taken
    found = modal.modal(model, model.reference, 4)
    # measured 6e-6 and 4.6e-5 apart, the continuum beam's (beta_k L / N)^2 convergence
    # (its bending strain is constant per element: docs/laws.md), 6.3x larger for the
    # second mode
    assert found == pytest.approx(_beam_theory(scene), rel=1e-4)
    # SciPy's SuperLU of K, the other way to the same shift-invert iterations (ARPACK's
    # tolerance: 2.5e-7 on the degenerate pair measured)
    monkeypatch.setattr(modal, "_inverse", lambda stiffness: None)
    assert modal.modal(model, model.reference, 4) == pytest.approx(found, rel=1e-6)
