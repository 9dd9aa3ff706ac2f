"""``ancf bench precision``: the plan covers what the catalog and the generated kinds say, the
error measures are right on synthetic data, the exact elastica matches Mattiasson's table
two independent ways, and the quick run completes with and without Exudyn."""

from __future__ import annotations

import csv
import math

import numpy as np
import pytest

from runtime.catalog import INTEGRATORS, NEWTON_MODES, generated_kinds
from runtime.kernels.kind import element_kind
from runtime.studies import peers
from runtime.studies.precision import elastica, plan
from runtime.studies.precision.measure import history_error, static_error
from runtime.studies.precision.run import study


def test_line_kinds_are_every_generated_kind_meshed_along_one_axis():
    for dim in (2, 3):
        kinds = plan.line_kinds(dim)
        assert kinds
        for kind in generated_kinds():
            meta = element_kind(kind)
            line = sum(axis.meshed for axis in meta.domain.axes) == 1
            assert (kind in kinds) == (line and meta.dim == dim)
    assert "plate3d" not in plan.line_kinds(3)
    for cable in ("cable2d", "cable3d"):   # picked up as soon as they are generated
        if cable in generated_kinds():
            assert cable in plan.line_kinds(element_kind(cable).dim)


@pytest.mark.parametrize("quick", [False, True])
def test_plan_covers_kinds_integrators_newton_modes(quick):
    for problem in plan.problems(quick):
        configs = plan.configurations(problem, with_peer=True)
        ours = {(c.kind, c.elements, c.step, c.load_steps, c.integrator, c.newton)
                for c in configs if c.code == "project"}
        steps = [(h, None) for h in problem.steps] if not problem.static else \
            [(None, n) for n in problem.steps]
        integrators = (None,) if problem.static else INTEGRATORS
        newtons = (plan.STATIC_NEWTON,) if problem.static else NEWTON_MODES
        assert ours == {(k, n, h, s, i, m) for k in plan.line_kinds(problem.dim)
                        for n in problem.elements for h, s in steps
                        for i in integrators for m in newtons}
        peer = [c for c in configs if c.code == "exudyn"]
        assert {c.newton for c in peer} == set(peers.NEWTON)
        assert {c.elements for c in peer} == set(problem.elements)
        assert not any(c.reference for c in configs)
        assert not [c for c in plan.configurations(problem, with_peer=False)
                    if c.code == "exudyn"]
        refs = plan.references(problem, with_peer=True)
        assert [c.code for c in refs][-1] == "exudyn" and all(c.reference for c in refs)
        ours = [c for c in refs if c.code == "project"]
        assert all(c.kind in plan.line_kinds(problem.dim) for c in ours)
        # one reference per model the project's kinds discretise (the static elastica's
        # reference is exact: one finest run)
        models = ({element_kind(plan.reference_kind(problem)).energy.name} if problem.static
                  else {element_kind(k).energy.name for k in plan.line_kinds(problem.dim)})
        assert sorted(plan.model(c) for c in ours) == sorted(models)
    full = {p.name: p for p in plan.problems()}
    assert full["elastica"].steps[0] == 20 and full["rotating_beam"].t_end == 20.0
    assert full["cantilever"].t_end == 4.0 and plan.reference_kind(full["cantilever"]) == "beam3d"


def test_history_error_on_synthetic_data():
    t = np.linspace(0.0, 2.0, 41)
    ref = np.cos(t) * 2.0   # max |ref| = 2, at t = 0
    assert history_error(t, ref, t, ref) == 0.0
    bumped = ref.copy()
    bumped[10] += 0.02
    assert history_error(t, bumped, t, ref) == pytest.approx(0.01)   # 0.02 / max |ref| = 2
    fine = np.linspace(0.0, 2.0, 401)   # a run with more outputs is read at the reference's
    assert history_error(fine, 2.0 * np.cos(fine) + 1e-3, t, ref) == pytest.approx(5e-4)
    assert math.isnan(history_error(t[:20], ref[:20], t, ref))       # stopped early


def test_static_error_is_the_larger_component_over_length():
    assert static_error((-0.5, -0.8), (-0.55, -0.81), 1.0) == pytest.approx(0.05)
    assert static_error((-1.0, -1.7), (-1.1, -1.62), 2.0) == pytest.approx(0.05)


@pytest.mark.parametrize("alpha", sorted(elastica.MATTIASSON))
def test_elastica_two_ways_and_mattiasson(alpha):
    quad = elastica.by_quadrature(alpha)
    bvp = elastica.by_bvp(alpha)
    assert quad == pytest.approx(bvp, abs=1e-9)
    assert quad == pytest.approx(elastica.MATTIASSON[alpha], abs=5e-6)   # 5 decimals


def test_elastica_of_the_study():
    u, w = elastica.by_quadrature(plan.ELASTICA["alpha"])
    assert (round(u, 5), round(w, 5)) == (0.55500, 0.81061)   # Mattiasson, PL^2/EI = 10


def _quick(tmp_path, peer):
    text = study(quick=True, out=tmp_path, repeats=1, peer=peer, progress=False)
    with (tmp_path / "precision.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert (tmp_path / "precision.png").stat().st_size > 0
    assert (tmp_path / "precision.md").read_text() == text
    assert {r["problem"] for r in rows} == {p.name for p in plan.problems(True)}
    assert "| rotating_beam | 0.01 |" in text and "Which element" in text
    ours = [r for r in rows if r["code"] == "project" and r["role"] == "sweep"]
    assert ours and all(r["status"] == "ok" or r["status"] == "diverged" for r in ours)
    return text, rows


def test_quick_run_without_the_peer(tmp_path):
    text, rows = _quick(tmp_path, peer=False)
    assert "Exudyn skipped" in text
    assert {r["code"] for r in rows} == {"project"}


def test_quick_run_with_exudyn(tmp_path):
    pytest.importorskip("exudyn")
    text, rows = _quick(tmp_path, peer=True)
    assert f"Exudyn {peers.exudyn_version()}" in text
    peer = [r for r in rows if r["code"] == "exudyn" and r["role"] == "sweep"]
    assert peer and any(r["error"] and float(r["error"]) < 1e-2 for r in peer)
    assert "Distance between them" in text
