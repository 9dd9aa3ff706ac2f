"""``ancf bench steps`` on tiny cases: one row per case, solver and Newton mode, the solver
the model chose named, shares of the step between 0 and 1, the table and the plot written."""

from __future__ import annotations

from runtime.cli import main
from runtime.studies import bench_steps


def test_bench_steps_rows_name_the_solver_and_split_the_step(tmp_path):
    cases = bench_steps.plan(plates=(2,), chains=(4,), solvers=(bench_steps.AUTO, "sparse"),
                             newtons=("full", "modified"), joints=(3,), blocks=(1,))
    rows = bench_steps.measure(cases, repeats=1, progress=False)
    assert [(r["case"], r["requested"], r["newton"]) for r in rows] == [
        (label, solver, newton) for _, _, label, solver, newton in cases]
    for r in rows:
        assert r["linear_solver"] == ("sparse" if r["requested"] == "sparse" else "banded")
        shares = r["kernel_share"] + r["factorisation_share"] + r["solve_share"]
        assert 0.0 < shares <= 1.0 and r["step_ms"] > 0
        # the joints' Schur complement is a part of the factorisations and solves
        joints = r["case"].startswith("joint chain")     # "free links": the same, no joints
        assert (r["constraint_share"] > 0.0) == joints
        assert r["constraint_share"] <= r["factorisation_share"] + r["solve_share"]
        assert r["factorisations_per_step"] <= r["newton_per_step"]
    full = next(r for r in rows if r["newton"] == "full" and r["case"].startswith("plate"))
    assert full["factorisations_per_step"] == full["newton_per_step"]
    text = bench_steps.table(rows)
    assert text.count("\n") == len(rows) + 2 and "banded (auto)" in text
    bench_steps.plot(rows, tmp_path / "steps.png")
    assert (tmp_path / "steps.png").stat().st_size > 1000


def test_constraint_share_of_a_kkt_step_is_measured_against_the_free_links():
    def row(case, step_ms, share=float("nan"), newton="full", iterations=1.0):
        return {"case": case, "step_ms": step_ms, "constraint_share": share, "newton": newton,
                "newton_per_step": iterations}
    kkt = row("joint chain 200", 20.0, iterations=1.25)
    rows = [kkt, row("free links 200", 15.0), row("free links 200", 5.0, newton="auto")]
    assert bench_steps.constraint_share(kkt, rows) == 0.25
    # per Newton iteration: 16 ms an iteration with the joints, 15 without
    assert bench_steps.constraint_share(kkt, rows, per_iteration=True) == 0.0625
    schur = row("joint chain 50", 10.0, share=0.6)
    assert bench_steps.constraint_share(schur, rows) == 0.6
    assert bench_steps.constraint_share(schur, rows, per_iteration=True) == 0.6
    # no free links measured: nothing to compare with
    assert bench_steps.constraint_share(kkt, [kkt]) != bench_steps.constraint_share(kkt, [kkt])


def test_bench_steps_refuses_a_bad_size(capsys):
    assert main(["bench", "steps", "--plates", "0"]) == 2
    assert "--plates" in capsys.readouterr().err


def test_bench_steps_scenes_compares_the_newton_modes_of_a_shipped_scene(tmp_path, capsys):
    out = tmp_path / "scenes.md"
    assert main(["bench", "steps", "--scenes", "cable_cantilever", "--newton", "full",
                 "modified", "--repeats", "1", "--quiet", "--out", str(out)]) == 0
    rows = [line for line in out.read_text().splitlines() if line.startswith("| cable")]
    assert [row.split("|")[3].strip() for row in rows] == ["full", "modified"]
    # full Newton factorises at every iteration, modified keeps its factorisation
    iterations, factorisations = ([int(row.split("|")[k]) for row in rows] for k in (7, 8))
    assert factorisations[0] == iterations[0] and factorisations[1] < iterations[1]
    assert min(float(row.split("|")[9]) for row in rows) == 1.0


def test_bench_steps_scenes_refuses_an_unknown_scene(capsys):
    assert main(["bench", "steps", "--scenes", "nope"]) == 2
    assert "--scenes" in capsys.readouterr().err
