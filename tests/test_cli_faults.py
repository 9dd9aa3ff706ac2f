"""The exit-code contract of ``ancf run`` (0 ok, 1 diverged, 2 invalid scene or options,
3 environment, 4 internal error, 130 interrupted): every failure is one line on stderr, never
a traceback, and leaves a summary.json that says what happened whenever the output folder
allows it.  Environment faults and signals are exercised in real subprocesses."""

from __future__ import annotations

import csv
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from scenes_small import cantilever

from runtime import cli
from runtime.cli import main
from runtime.kernels import errors
from runtime.model.toml_io import toml_text

ROOT = Path(__file__).resolve().parent.parent


def scene_file(folder: Path, analyses: dict | None = None, backend: str = "numpy",
               **changes) -> Path:
    data = cantilever(elements=2, force=[0.0, -1000.0], **(analyses or {"static": {}}),
                      solver={"backend": backend}).to_dict()
    data.update(changes)
    path = folder / "scene.toml"
    path.write_text(toml_text(data))
    return path


def one_line(err: str) -> str:
    """The single line of stderr (asserted single, without a traceback)."""
    assert "Traceback" not in err
    lines = err.strip("\n").split("\n")
    assert len(lines) == 1, err
    return lines[0]


def read_rows(path: Path) -> list[list[float]]:
    with path.open(newline="") as f:
        rows = list(csv.reader(f))
    return [[float(x) for x in row] for row in rows[1:]]


# --------------------------------------------------------------------------- options

@pytest.mark.parametrize("argv, words", [
    (["run", "SCENE", "--out", "OUT", "--method", "magic"], "invalid choice: 'magic'"),
    (["run", "SCENE", "--out", "OUT", "--backend", "fortran"], "invalid choice: 'fortran'"),
    (["run", "SCENE"], "--out"),
    (["run", "SCENE", "--out", "OUT", "--frobnicate"], "--frobnicate"),
    (["runn"], "invalid choice: 'runn'"),
])
def test_option_errors_are_exit_2_in_one_line(argv, words, tmp_path, capsys):
    argv = [a.replace("SCENE", str(tmp_path / "s.toml")).replace("OUT", str(tmp_path / "o"))
            for a in argv]
    assert main(argv) == 2
    line = one_line(capsys.readouterr().err)
    assert line.startswith("ancf") and words in line
    assert not (tmp_path / "o").exists()


def test_help_is_exit_0(capsys):
    assert main(["run", "--help"]) == 0
    assert "--no-plots" in capsys.readouterr().out


def test_missing_scene_is_exit_2_in_one_line(tmp_path, capsys):
    assert main(["run", str(tmp_path / "missing.toml"), "--out", str(tmp_path / "o")]) == 2
    assert "missing.toml: cannot read the scene file" in one_line(capsys.readouterr().err)
    assert json.loads((tmp_path / "o" / "summary.json").read_text())["status"] == "failed"


@pytest.mark.parametrize("out", ["file", "file/sub"])
def test_unusable_out_is_exit_3_in_one_line(out, tmp_path, capsys):
    (tmp_path / "file").write_text("x")
    assert main(["run", str(scene_file(tmp_path)), "--out", str(tmp_path / out)]) == 3
    line = one_line(capsys.readouterr().err)
    assert str(tmp_path / "file") in line and "no summary.json written" in line


def test_invalid_scene_with_unusable_out_is_still_exit_2(tmp_path, capsys):
    (tmp_path / "file").write_text("x")
    scene = scene_file(tmp_path, title=3)
    assert main(["run", str(scene), "--out", str(tmp_path / "file")]) == 2
    line = one_line(capsys.readouterr().err)
    assert line.startswith("ancf run: title: expected a non-empty string")
    assert "no summary.json written" in line


def test_no_plots_option(tmp_path, capsys):
    scene = scene_file(tmp_path, {"dynamic": {"t_end": 0.01, "step": 2.5e-3}})
    assert main(["run", str(scene), "--out", str(tmp_path / "o"), "--quiet", "--no-plots"]) == 0
    assert sorted(os.listdir(tmp_path / "o")) == ["summary.json", "timeseries.csv"]
    assert capsys.readouterr().err == ""


# --------------------------------------------------------------------------- in process

def test_keyboard_interrupt_anywhere_is_exit_130_in_one_line(tmp_path, monkeypatch, capsys):
    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(cli, "parser", interrupted)
    assert main(["run", "x", "--out", "y"]) == 130
    assert one_line(capsys.readouterr().err) == "ancf: interrupted"
    monkeypatch.undo()
    monkeypatch.setattr(cli, "cmd_generate", interrupted)
    assert main(["generate", "--check"]) == 130
    assert one_line(capsys.readouterr().err) == "ancf generate: interrupted"


def test_environment_error_of_any_command_is_exit_3_in_one_line(monkeypatch, capsys):
    def no_compiler(args):
        raise errors.CompilerNotFoundError("no C compiler\nmore detail")

    monkeypatch.setattr(cli, "cmd_bench", no_compiler)
    assert main(["bench", "kernels"]) == 3
    assert one_line(capsys.readouterr().err) == "ancf bench: no C compiler"


def test_interrupted_dynamic_run_writes_its_summary(tmp_path, monkeypatch, capsys):
    from runtime.model.items.sensors import Sensors

    real = Sensors.block
    seen: list[list[float]] = []     # the output times of each block the sensors evaluated

    def block(self, samples):
        if samples.t is not None:
            seen.append(samples.t.tolist())
            if samples.t[-1] > 0.011:   # the block past t = 0.01 s is interrupted
                raise KeyboardInterrupt("SIGINT")
        return real(self, samples)

    monkeypatch.setattr(Sensors, "block", block)
    scene = scene_file(tmp_path, {"dynamic": {"t_end": 0.05, "step": 2.5e-3}})
    out = tmp_path / "o"
    assert main(["run", str(scene), "--out", str(out), "--quiet"]) == 130
    kept = [t for times in seen[:-1] for t in times]    # the blocks before the interrupt
    assert kept[:5] == [0.0, 0.0025, 0.005, 0.0075, 0.01][:len(kept)] and kept[-1] <= 0.01
    line = one_line(capsys.readouterr().err)
    assert line == ("ancf run: interrupted by SIGINT during the dynamic analysis at t = "
                    f"{kept[-1]:g} s; timeseries.csv keeps the rows up to then")
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "interrupted" and summary["message"] == line[len("ancf run: "):]
    assert summary["dynamic"]["t_reached"] == kept[-1]
    assert summary["dynamic"]["steps"] >= len(kept) - 1
    assert [row[0] for row in read_rows(out / "timeseries.csv")] == kept
    # the plots of what was computed are drawn (from the kept rows): the tip sensor's and
    # the energies' panels
    assert {"tip_y.png", "energies.png"} <= {p.name for p in out.glob("*.png")}


def test_interrupted_plots_keep_the_results(tmp_path, monkeypatch, capsys):
    from runtime.app import writers as output

    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(output, "plot_series", interrupted)
    scene = scene_file(tmp_path, {"dynamic": {"t_end": 0.01, "step": 2.5e-3}})
    assert main(["run", str(scene), "--out", str(tmp_path / "o"), "--quiet"]) == 130
    assert "while drawing the plots" in one_line(capsys.readouterr().err)
    summary = json.loads((tmp_path / "o" / "summary.json").read_text())
    assert summary["status"] == "interrupted" and summary["dynamic"]["steps"] == 4


def test_internal_error_is_exit_4_with_a_hint_to_report_it(tmp_path, monkeypatch, capsys):
    def bug(*args, **kwargs):
        raise ZeroDivisionError("division by zero")

    monkeypatch.setattr("runtime.app.simulation.Sensors", bug)
    out = tmp_path / "o"
    assert main(["run", str(scene_file(tmp_path)), "--out", str(out), "--quiet"]) == 4
    line = one_line(capsys.readouterr().err)
    assert "internal error" in line and "ZeroDivisionError: division by zero" in line
    assert "bug" in line and str(out / "summary.json") in line
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "failed" and "ZeroDivisionError" in summary["traceback"]


# --------------------------------------------------------------------------- subprocesses

def ancf(args: list[str], env: dict | None = None, **popen) -> subprocess.Popen:
    environment = dict(os.environ, **(env or {}))
    environment["PYTHONPATH"] = os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])
    return subprocess.Popen([sys.executable, "-m", "runtime.cli", *args], cwd=ROOT,
                            env=environment, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, **popen)


def finish(process: subprocess.Popen) -> tuple[int, str]:
    _, err = process.communicate(timeout=120)
    return process.returncode, err


@pytest.mark.parametrize("case", ["cc_false", "no_compiler", "cache_is_a_file",
                                  "cache_read_only"])
def test_environment_faults_are_exit_3_in_one_line(case, tmp_path):
    if case == "cache_read_only" and os.geteuid() == 0:
        pytest.skip("root writes into read-only folders")
    cache = tmp_path / "cache"  # empty: the kernels must be compiled
    cache.mkdir()
    env = {"ANCF_CACHE_DIR": str(cache)}
    if case == "cc_false":
        env["CC"] = "/bin/false"
    elif case == "no_compiler":
        (tmp_path / "bin").mkdir()
        env.update(CC="", PATH=str(tmp_path / "bin"))
    elif case == "cache_is_a_file":
        cache.rmdir()
        cache.write_text("not a folder")
    else:
        cache.chmod(0o555)
    out = tmp_path / "o"
    code, err = finish(ancf(["run", str(scene_file(tmp_path, backend="c")), "--out", str(out),
                             "--quiet"], env))
    assert code == 3, err
    line = one_line(err)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "failed"
    assert line == f"ancf run: {summary['message'].splitlines()[0]}"
    if case in ("cc_false", "no_compiler"):
        assert "--backend numpy" in line
    else:
        assert "ANCF_CACHE_DIR" in line and str(cache) in line


def long_run(folder: Path) -> tuple[Path, Path]:
    """A dynamic run of minutes, a row every step: stopped by a signal long before its end."""
    scene = scene_file(folder, {"dynamic": {"t_end": 100.0, "step": 1e-3}},
                       sensor=[{"name": "tip_y", "type": "displacement", "node": "beam:-1",
                                "component": "y"}, {"name": "kinetic", "type": "kinetic_energy"}])
    return scene, folder / "o"


def rows_on_disk(path: Path) -> int:
    try:
        return path.read_text().count("\n") - 1
    except OSError:
        return -1


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_signal_during_a_run_is_exit_130_with_a_summary(sig, tmp_path):
    scene, out = long_run(tmp_path)
    # as from an interactive shell: SIGINT not ignored whoever started the tests
    process = ancf(["run", str(scene), "--out", str(out), "--quiet"],
                   preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    deadline = time.monotonic() + 90
    while rows_on_disk(out / "timeseries.csv") < 5 and process.poll() is None:
        assert time.monotonic() < deadline, "no rows appeared"
        time.sleep(0.05)
    process.send_signal(sig)
    code, err = finish(process)
    assert code == 130
    line = one_line(err)
    assert line.startswith(f"ancf run: interrupted by {sig.name} during the dynamic analysis")
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "interrupted"
    assert summary["message"] == line[len("ancf run: "):]
    rows = read_rows(out / "timeseries.csv")  # every row whole
    assert len(rows) >= 5 and all(len(row) == 3 for row in rows)
    assert (out / "timeseries.csv").read_text().endswith("\n")
    assert summary["dynamic"]["t_reached"] == rows[-1][0] < 100.0
    assert not [name for name in os.listdir(out) if name.endswith(".tmp")]


# --------------------------------------------------------------------------- report --quick

def test_report_quick_writes_to_a_scratch_folder_never_into_docs(tmp_path, monkeypatch,
                                                                  capsys):
    import shutil

    from runtime.studies import report

    docs = ROOT / "docs"
    before = {p: p.read_bytes() for p in docs.rglob("*") if p.is_file()}
    seen = []

    def build(out, quick, **kwargs):
        seen.append((Path(out), quick))
        return Path(out) / "report.md"

    monkeypatch.setattr(report, "build", build)
    monkeypatch.chdir(ROOT)
    assert main(["report", "--quick"]) == 0
    scratch, quick = seen[-1]
    try:
        assert quick and scratch.is_dir() and not os.listdir(scratch)
        assert docs.resolve() not in [scratch.resolve(), *scratch.resolve().parents]
        assert str(scratch / "report.md") in capsys.readouterr().out
    finally:
        shutil.rmtree(scratch)
    assert main(["report", "--quick", "--out", str(tmp_path / "mine")]) == 0
    assert seen[-1] == (tmp_path / "mine", True)
    assert main(["report"]) == 0  # the full report is the tracked one
    assert seen[-1] == (Path("docs"), False)
    assert {p: p.read_bytes() for p in docs.rglob("*") if p.is_file()} == before
