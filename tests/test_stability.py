"""``ancf study stability`` (quick form): rows and their fields, the default method's kernel
accuracy, Newton's quadratic rate, the written reports, the CLI entry, a tiny sweep on a
two-worker local dask cluster and an unreachable scheduler."""

from __future__ import annotations

import argparse
import csv
import functools
import json
import math
from dataclasses import fields

import pytest

from runtime.catalog import generated_kinds
from runtime.kernels.kind import element_kind
from runtime.studies import stability, sweep
from runtime.studies.stability.locking import beam_theory, euler_bernoulli
from runtime.studies.sweep import SchedulerError

FIELDS = {"group", "case", "method", "measured", "tolerance", "passed", "detail", "cause"}


@pytest.fixture(scope="module")
def quick_rows() -> list[stability.Row]:
    return stability.stability_study(quick=True, serial=True)


def test_rows_have_the_fields(quick_rows):
    assert FIELDS <= {f.name for f in fields(stability.Row)}
    assert {r.group for r in quick_rows} == set(stability.GROUPS)
    for row in quick_rows:
        assert isinstance(row.measured, float)
        assert row.case and row.method and row.detail
        if row.passed is None:          # informational: no tolerance, says what it shows
            assert row.tolerance is None and row.cause
        else:
            assert row.tolerance is not None
        if row.passed is False:         # a failing row states its cause
            assert row.cause


def test_default_method_passes_the_kernel_accuracy_rows(quick_rows):
    rows = [r for r in quick_rows if r.group == "kernel_accuracy"]
    assert {r.method for r in rows} == {"gram"}
    assert len(rows) == 2 * len(generated_kinds()) * 2   # scenarios x kinds x (force, energy)
    assert {r.case.split()[1] for r in rows} == set(generated_kinds())
    for row in rows:
        assert row.tolerance == 1e-6
        assert row.passed and row.measured <= 1e-6, row


def test_cij_rows_state_their_cause_only_when_the_estimate_explains_them():
    """At a strain of 1e-9 the cij energy fails for every kind; beam2d's error is within a
    few times eps U0/U, the plate's is over 1e3 times it: reported as unexplained."""
    rows = {r["case"]: r for r in stability.kernel_accuracy_case(
        "strain_1e-9", "cij", ("beam2d", "plate3d"))}
    beam, plate = rows["strain_1e-9 beam2d energy"], rows["strain_1e-9 plate3d energy"]
    assert beam["passed"] is False and beam["cause"].startswith("cij energy by eq. 39")
    assert plate["passed"] is False and plate["cause"].startswith("unexplained: ")


def test_analytic_newton_converges_quadratically(quick_rows):
    row = next(r for r in quick_rows if r.group == "newton" and r.method == "analytic")
    assert row.measured > 1.8 and row.passed


def test_convergence_order_of_a_quadratic_sequence():
    order, _ = stability.convergence_order([1e-1, 1e-2, 1e-4, 1e-8, 3e-15, 2e-15, 4e-15])
    assert abs(order - 2.0) < 1e-9
    linear, _ = stability.convergence_order([1e-1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-15])
    assert abs(linear - 1.0) < 1e-9


def test_poisson_locking_is_shown_failing_with_its_cause(quick_rows):
    row = next(r for r in quick_rows if r.group == "poisson_locking" and "svk" in r.case)
    # nu = 0.3: the locked limit is bending with lam + 2G = 1.346 E: about 25 % short
    assert row.passed is False and -0.30 < row.measured < -0.20
    assert "Poisson locking" in row.cause


def test_ecm_law_removes_the_locking(quick_rows):
    # the same 4-element mesh within the discretisation error (2 %), not 25 % short
    row = next(r for r in quick_rows if r.group == "poisson_locking" and "ecm" in r.case)
    assert abs(row.measured) < 0.02
    # Chrono's aluminium beam at nu = 0.33: tip load within 2 % of P L^3 / 3EI
    chrono = next(r for r in quick_rows if r.group == "chrono_beam")
    assert chrono.passed is True and abs(chrono.measured) < 0.02


def test_integrator_rows_report_runs_and_failures(quick_rows):
    rows = [r for r in quick_rows if r.group == "integrator"]
    scan = [r for r in rows if r.case.startswith("step")]
    assert {r.case for r in scan} == {"step 0.002 s", "step 0.02 s"}
    for row in scan:
        assert row.tolerance == 0.01 and "Newton" in row.detail
        if row.passed is False:
            assert "diverged" in row.cause or "drift" in row.cause or "energy" in row.cause
    ran = [float(r.case.split()[1]) for r in scan if "ran to" in r.detail]
    summary = next(r for r in rows if r.case == "stable step range")
    assert summary.passed is None
    if ran:
        assert summary.measured == max(ran)


def test_written_reports(quick_rows, tmp_path):
    paths = stability.write(quick_rows, tmp_path / "out", wall_s=1.5)
    assert all(path.exists() for path in paths.values())
    text = paths["md"].read_text()
    assert "| case | method | measured | criterion | result | detail | cause |" in text
    assert "| --- | --- | --- | --- | --- | --- | --- |" in text
    for title in stability.GROUPS.values():
        assert f"## {title}" in text
    data = json.loads(paths["json"].read_text())
    assert len(data["rows"]) == len(quick_rows) and data["wall_s"] == 1.5
    with paths["csv"].open() as handle:
        records = list(csv.DictReader(handle))
    assert len(records) == len(quick_rows) and FIELDS <= set(records[0])


def test_cli_entry_prints_and_writes(tmp_path, capsys):
    parser = argparse.ArgumentParser(prog="ancf")
    study = parser.add_subparsers(dest="command", required=True).add_parser("study")
    stability.add_cli(study.add_subparsers(dest="what", required=True))
    args = parser.parse_args(["study", "stability", "--quick", "--serial", "--out",
                              str(tmp_path)])
    assert args.run(args) == 0    # exit 0 even though rows fail: the table reports them
    out = capsys.readouterr().out
    assert "# Numerical stability study" in out and "| case | method |" in out
    assert (tmp_path / "stability.md").exists()
    defaults = parser.parse_args(["study", "stability"])
    assert defaults.out == "results/stability" and defaults.scheduler is None


@pytest.mark.slow
def test_tiny_sweep_on_a_two_worker_local_cluster(quick_rows):
    rows = stability.stability_study(quick=True, workers=2)
    assert [(r.group, r.case, r.method, r.passed) for r in rows] == \
        [(r.group, r.case, r.method, r.passed) for r in quick_rows]
    for parallel, serial in zip(rows, quick_rows, strict=True):
        if parallel.group in ("kernel_accuracy", "poisson_locking"):
            assert parallel.measured == serial.measured or (
                math.isnan(parallel.measured) and math.isnan(serial.measured))


def test_unreachable_scheduler_is_named(monkeypatch):
    # the study hands its scheduler to the sweep (whose own tests wait out the default 10 s)
    monkeypatch.setattr(sweep, "run_cases", functools.partial(sweep.run_cases,
                                                              connect_timeout_s=1.0))
    with pytest.raises(SchedulerError, match="tcp://127.0.0.1:9"):
        stability.stability_study(quick=True, scheduler="tcp://127.0.0.1:9")


def test_full_study_runs_each_law_of_its_beams_and_the_elastic_line_against_euler_bernoulli():
    # the full study's locking rows once took every law of every kind (the cables' and
    # shells'), and `ancf study stability` stopped at a scene error
    locking = [c for c in stability.cases(quick=False) if c["study"] in ("poisson",
                                                                          "chrono_beam")]
    kind = {"poisson": "beam2d", "chrono_beam": "beam3d"}
    assert all(c["law"] in element_kind(kind[c["study"]]).laws for c in locking)
    assert {c["law"] for c in locking} >= {"svk", "ecm", "elastic_line"}
    row, = stability.run_case(study="poisson", nu=0.3, elements=2, law="elastic_line")
    assert row["passed"] and abs(row["measured"]) < 1e-6     # P L^3 / 3EI, shear-free
    assert euler_bernoulli() < beam_theory(0.3)
