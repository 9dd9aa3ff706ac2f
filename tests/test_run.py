"""``ancf run``: summary.json, timeseries.csv and plots (DESIGN.md section 7), exit codes,
overrides, bad scenes and diverging runs."""

from __future__ import annotations

import csv
import json
import math
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
from scenes_small import cantilever

from runtime.app.run import run
from runtime.cli import main
from runtime.model.toml_io import toml_text

ROOT = Path(__file__).resolve().parent.parent
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"

SENSORS = [
    {"name": "tip_y", "type": "displacement", "node": "beam:-1", "component": "y"},
    {"name": "strain", "type": "strain_energy"},
    {"name": "kinetic", "type": "kinetic_energy"},
]
ENERGIES = ("strain", "kinetic")

# the keys DESIGN.md section 7 documents
TOP_KEYS = {"scene", "status", "message", "static", "modal", "dynamic", "timing", "kernels"}
STATIC_KEYS = {"sensors", "iterations"}
MODAL_KEYS = {"frequencies_rad_s", "frequencies_hz"}
DYNAMIC_KEYS = {"t_end", "steps", "newton_iterations", "force_evaluations",
                "jacobian_evaluations", "sensors_final"}
TIMING_KEYS = {"generate_s", "compile_s", "preprocess_s", "simulate_s", "total_s"}


def small_scene(analyses=("static", "modal", "dynamic"), **changes) -> dict:
    tables = {"static": {}, "modal": {"modes": 3},
              "dynamic": {"t_end": 0.05, "step": 2.5e-3, "output_every": 5e-3}}
    data = cantilever(elements=2, force=[0.0, -1000.0],
                      law={"type": "cosine_ramp", "duration": 0.02}, sensors=SENSORS,
                      **{k: tables[k] for k in analyses}).to_dict()
    data.update(changes)
    return data


def write(folder: Path, data: dict | str, name: str = "scene.toml") -> Path:
    path = folder / name
    path.write_text(data if isinstance(data, str) else toml_text(data))
    return path


def read_csv(path: Path) -> tuple[list[str], list[list[float]]]:
    with path.open(newline="") as f:
        rows = list(csv.reader(f))
    return rows[0], [[float(x) for x in row] for row in rows[1:]]


def no_temporary_files(folder: Path) -> bool:
    return not [name for name in os.listdir(folder) if name.endswith(".tmp")]


@pytest.fixture(scope="module")
def full_run(tmp_path_factory):
    folder = tmp_path_factory.mktemp("full")
    scene = write(folder, small_scene())
    out = folder / "out"
    summary, code = run(scene, out, quiet=True)
    return scene, out, summary, code


# --------------------------------------------------------------------------- a full run

def test_full_run_succeeds_and_writes_its_summary(full_run):
    scene, out, summary, code = full_run
    assert code == 0
    assert summary["status"] == "ok"
    assert isinstance(summary["message"], str)
    assert summary["scene"] == str(scene)
    on_disk = json.loads((out / "summary.json").read_text())
    assert on_disk == json.loads(json.dumps(summary))
    assert no_temporary_files(out)


def test_summary_holds_the_documented_keys(full_run):
    _, out, _, _ = full_run
    summary = json.loads((out / "summary.json").read_text())
    assert TOP_KEYS <= set(summary)
    assert STATIC_KEYS <= set(summary["static"])
    assert MODAL_KEYS <= set(summary["modal"])
    assert DYNAMIC_KEYS <= set(summary["dynamic"])
    assert TIMING_KEYS <= set(summary["timing"])
    names = [s["name"] for s in SENSORS]
    assert set(summary["static"]["sensors"]) == set(names)
    assert set(summary["dynamic"]["sensors_final"]) == set(names)
    assert isinstance(summary["kernels"], list) and summary["kernels"]
    assert all(isinstance(k, str) and k for k in summary["kernels"])


def test_summary_values_are_consistent(full_run):
    _, out, summary, _ = full_run
    static = summary["static"]
    assert isinstance(static["iterations"], int) and static["iterations"] >= 1
    # tip deflection of the 1 m, 0.1 m square steel cantilever: P L^3 / 3EI = 0.19 mm,
    # 2 elements are ~6 % stiff
    assert -static["sensors"]["tip_y"] == pytest.approx(1000 / (3 * 2.1e11 * 0.1**4 / 12),
                                                        rel=0.1)
    assert static["sensors"]["kinetic"] == 0.0
    modal = summary["modal"]
    assert len(modal["frequencies_rad_s"]) == len(modal["frequencies_hz"]) == 3
    assert all(w > 0 for w in modal["frequencies_rad_s"])
    assert modal["frequencies_rad_s"] == sorted(modal["frequencies_rad_s"])
    for w, f in zip(modal["frequencies_rad_s"], modal["frequencies_hz"], strict=True):
        assert f == pytest.approx(w / (2 * math.pi), rel=1e-12)
    dynamic = summary["dynamic"]
    assert dynamic["t_end"] == 0.05
    assert dynamic["steps"] == 20
    assert dynamic["newton_iterations"] >= dynamic["steps"]
    assert dynamic["force_evaluations"] >= dynamic["newton_iterations"]
    assert 0 < dynamic["jacobian_evaluations"] <= dynamic["force_evaluations"]
    timing = summary["timing"]
    assert all(isinstance(timing[k], float) and timing[k] >= 0 for k in TIMING_KEYS)
    assert timing["total_s"] >= timing["simulate_s"]
    assert timing["total_s"] >= timing["preprocess_s"]


def test_timeseries_has_t_then_one_column_per_sensor(full_run):
    _, out, summary, _ = full_run
    header, rows = read_csv(out / "timeseries.csv")
    assert header == ["t"] + [s["name"] for s in SENSORS]
    times = [row[0] for row in rows]
    assert len(rows) == 11  # t = 0, 0.005, ..., 0.05
    assert times[0] == 0.0 and times[-1] == pytest.approx(0.05)
    assert all(b > a for a, b in zip(times, times[1:], strict=False))
    assert rows[0][1:] == [0.0, 0.0, 0.0]  # at rest at the reference
    final = dict(zip(header, rows[-1], strict=True))
    for name, value in summary["dynamic"]["sensors_final"].items():
        assert final[name] == value


def test_one_plot_per_sensor_and_one_for_the_energies(full_run):
    _, out, summary, _ = full_run
    expected = {f"{s['name']}.png" for s in SENSORS if s["name"] not in ENERGIES}
    expected |= {"energies.png"}
    assert {p.name for p in out.glob("*.png")} == expected  # energies are not plotted twice
    for name in expected:
        assert (out / name).read_bytes()[:8] == PNG_SIGNATURE
    assert summary["files"] == sorted(expected | {"summary.json", "timeseries.csv"})
    assert summary["warnings"] == []


@pytest.mark.parametrize("analyses, absent", [
    (("static",), {"modal", "dynamic"}),
    (("modal",), {"static", "dynamic"}),
    (("static", "modal"), {"dynamic"}),
])
def test_keys_of_analyses_that_did_not_run_are_absent(analyses, absent, tmp_path):
    summary, code = run(write(tmp_path, small_scene(analyses)), tmp_path / "out", quiet=True)
    assert code == 0
    on_disk = json.loads((tmp_path / "out" / "summary.json").read_text())
    for key in absent:
        assert key not in summary and key not in on_disk
    for key in analyses:
        assert key in on_disk
    assert not (tmp_path / "out" / "timeseries.csv").exists()


# --------------------------------------------------------------------------- the CLI

def test_cli_module_runs_a_scene_quietly(tmp_path):
    scene = write(tmp_path, small_scene(("static",)))
    out = tmp_path / "cli"
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(ROOT), os.environ.get("PYTHONPATH", "")]))
    done = subprocess.run([sys.executable, "-m", "runtime.cli", "run", str(scene), "--out",
                           str(out), "--quiet"], cwd=ROOT, env=env, capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout == ""
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "ok"
    assert summary["static"]["sensors"]["tip_y"] < 0


def test_cli_method_and_backend_override_the_scene(tmp_path):
    data = small_scene(("static",), solver={"method": "gram", "backend": "c"})
    scene = write(tmp_path, data)
    assert main(["run", str(scene), "--out", str(tmp_path / "default"), "--quiet"]) == 0
    assert main(["run", str(scene), "--out", str(tmp_path / "override"), "--method", "cij",
                 "--backend", "numpy", "--quiet"]) == 0
    default = json.loads((tmp_path / "default" / "summary.json").read_text())
    override = json.loads((tmp_path / "override" / "summary.json").read_text())
    assert "beam2d/cij/numpy" in override["kernels"]
    assert all(k.endswith("/numpy") for k in override["kernels"])
    assert not any("cij" in k for k in default["kernels"])
    # kernel families in C; the static solve of the compiled engine builds the stepper too
    assert all(k.endswith("/c") for k in default["kernels"] if not k.startswith("stepper/"))
    assert "stepper/trapezoidal" in default["kernels"]
    # the same physics whichever way the force is evaluated
    assert override["static"]["sensors"]["tip_y"] == pytest.approx(
        default["static"]["sensors"]["tip_y"], rel=1e-9)


def test_run_arguments_override_the_scene_solver(tmp_path):
    scene = write(tmp_path, small_scene(("static",), solver={"method": "cij"}))
    summary, code = run(scene, tmp_path / "out", method="quadrature", backend="numpy",
                        quiet=True)
    assert code == 0
    assert "beam2d/quadrature/numpy" in summary["kernels"]
    assert not any("cij" in k for k in summary["kernels"])


def test_cli_prints_a_summary_line_unless_quiet(tmp_path, capsys):
    scene = write(tmp_path, small_scene(("static",)))
    assert main(["run", str(scene), "--out", str(tmp_path / "out")]) == 0
    assert "ok" in capsys.readouterr().out


# --------------------------------------------------------------------------- bad scenes

def test_unknown_key_fails_with_exit_2_naming_the_key_path(tmp_path, capsys):
    data = small_scene()
    data["body"][0]["sectoin"] = data["body"][0].pop("section")
    scene = write(tmp_path, data)
    out = tmp_path / "out"
    summary, code = run(scene, out, quiet=True)
    assert code == 2
    on_disk = json.loads((out / "summary.json").read_text())
    for s in (summary, on_disk):
        assert s["status"] == "failed"
        assert "body[0].sectoin" in s["message"]
        assert s["scene"] == str(scene)
        assert not {"static", "modal", "dynamic"} & set(s)
    assert no_temporary_files(out)
    # the command line: exit 2 and the message on stderr
    assert main(["run", str(scene), "--out", str(tmp_path / "cli"), "--quiet"]) == 2
    assert "body[0].sectoin" in capsys.readouterr().err


def test_unknown_top_level_key_and_toml_errors_fail(tmp_path):
    summary, code = run(write(tmp_path, toml_text(small_scene()) + "\nsolverr = 1\n"),
                        tmp_path / "a", quiet=True)
    assert code == 2 and summary["status"] == "failed" and "solverr" in summary["message"]
    summary, code = run(write(tmp_path, "title = \n", "broken.toml"), tmp_path / "b",
                        quiet=True)
    assert code == 2 and summary["status"] == "failed"
    summary, code = run(tmp_path / "missing.toml", tmp_path / "c", quiet=True)
    assert code == 2 and summary["status"] == "failed" and "missing.toml" in summary["message"]
    assert (tmp_path / "c" / "summary.json").exists()


def test_static_analysis_of_a_body_hinged_in_3d_names_its_free_rotation(tmp_path):
    # a 3D revolute joint (quadratic rows) leaves the second beam free to turn about z only
    data = cantilever(elements=2, element="beam3d", static={}).to_dict()
    second = dict(data["body"][0], name="other", start=[1.0, 0.0, 0.0], end=[2.0, 0.0, 0.0])
    data["body"].append(second)
    data["constraint"].append({"type": "revolute", "nodes": ["beam:-1", "other:0"]})
    summary, code = run(write(tmp_path, data), tmp_path / "out", quiet=True)
    assert code == 2
    assert summary["status"] == "failed"
    assert "body 'other' is free to rotate about z:" in summary["message"]


# --------------------------------------------------------------------------- divergence

def diverging_scene() -> dict:
    # quiet until t = 0.05 s, then a 1e12 N tip load: Newton cannot follow
    return cantilever(elements=2, force=[0.0, -1e12], sensors=SENSORS,
                      law={"type": "table", "points": [[0.0, 0.0], [0.05, 0.0], [0.06, 1.0]]},
                      dynamic={"t_end": 0.2, "step": 5e-3}).to_dict()


def test_diverging_run_keeps_what_it_computed(tmp_path, capsys):
    scene = write(tmp_path, diverging_scene())
    out = tmp_path / "out"
    summary, code = run(scene, out, quiet=True)
    assert code == 1
    on_disk = json.loads((out / "summary.json").read_text())
    for s in (summary, on_disk):
        assert s["status"] == "diverged"
        assert "t = " in s["message"]
    when = float(re.search(r"t = ([0-9.eE+-]+)", summary["message"]).group(1))
    assert 0.05 < when <= 0.2
    header, rows = read_csv(out / "timeseries.csv")
    assert header == ["t"] + [s["name"] for s in SENSORS]
    times = [row[0] for row in rows]
    # every step before the failure is there (output at every step), none after it
    assert times[0] == 0.0
    assert len(rows) >= 11  # 0 ... 0.05 s
    assert times[-1] < when
    assert times[-1] == pytest.approx(when - 5e-3)
    assert all(math.isfinite(x) for row in rows for x in row)
    dynamic = on_disk["dynamic"]
    assert DYNAMIC_KEYS <= set(dynamic)
    assert dynamic["steps"] == len(rows) - 1
    assert dynamic["sensors_final"] == dict(zip(header[1:], rows[-1][1:], strict=True))
    assert no_temporary_files(out)
    # the command line: exit 1 and the message on stderr
    assert main(["run", str(scene), "--out", str(tmp_path / "cli"), "--quiet"]) == 1
    assert "t = " in capsys.readouterr().err


def test_static_that_does_not_converge_is_reported_as_diverged(tmp_path):
    data = small_scene(("static",))
    data["analysis"]["static"] = {"max_iterations": 1}
    summary, code = run(write(tmp_path, data), tmp_path / "out", quiet=True)
    assert code == 1
    assert summary["status"] == "diverged"
    assert "static" in summary["message"]
    assert "static" not in summary
    assert no_temporary_files(tmp_path / "out")


# --------------------------------------------------------------------------- issue 10

def numpy_dynamic(sensors: list[dict], t_end: float = 0.3, **dynamic) -> dict:
    """A 2-element cantilever shaken at 5 Hz, numpy backend (no compiler), dynamic only."""
    return cantilever(elements=2, force=[0.0, -1000.0], sensors=sensors,
                      law={"type": "sine", "amplitude": 1.0, "frequency_hz": 5.0},
                      dynamic={"t_end": t_end, "step": 2.5e-3, **dynamic},
                      solver={"backend": "numpy"}).to_dict()


def csv_column(path: Path, name: str) -> tuple[list[float], list[float]]:
    header, rows = read_csv(path)
    j = header.index(name)
    return [row[0] for row in rows], [row[j] for row in rows]


TRICKY_SENSORS = [
    {"name": "a-b", "type": "kinetic_energy"},
    {"name": "ab", "type": "displacement", "node": "beam:-1", "component": "y"},
    {"name": "tip-y", "type": "displacement", "node": "beam:-1", "component": "y"},
    {"name": "return", "type": "displacement", "node": "beam:-1", "component": "x"},
]


@pytest.mark.parametrize("name", ["ab", "tip-y", "return"])
def test_response_frequency_is_of_the_sensor_named_exactly(name, tmp_path):
    from runtime.app.signal import dominant_frequency

    data = numpy_dynamic(TRICKY_SENSORS, frequency_of=name, frequency_after=0.05)
    summary, code = run(write(tmp_path, data), tmp_path / "out", quiet=True)
    assert code == 0, summary["message"]
    on_disk = json.loads((tmp_path / "out" / "summary.json").read_text())
    t, y = csv_column(tmp_path / "out" / "timeseries.csv", name)
    keep = [i for i, x in enumerate(t) if x >= 0.05]
    expected = dominant_frequency([t[i] for i in keep], [y[i] for i in keep])
    assert on_disk["dynamic"]["response_frequency_rad_s"] == pytest.approx(expected, rel=1e-12)
    if name == "ab":  # not the frequency of "a-b", which genfromtxt also calls "ab"
        t, y = csv_column(tmp_path / "out" / "timeseries.csv", "a-b")
        other = dominant_frequency([t[i] for i in keep], [y[i] for i in keep])
        assert abs(other - expected) > 0.1 * expected


def test_frequency_of_a_constant_signal_is_a_warning(tmp_path):
    sensors = [{"name": "still", "type": "displacement", "node": "beam:0", "component": "y"}]
    data = numpy_dynamic(sensors, frequency_of="still")
    summary, code = run(write(tmp_path, data), tmp_path / "out", quiet=True, plots=False)
    assert code == 0 and summary["status"] == "ok"
    assert summary["dynamic"]["response_frequency_rad_s"] is None
    assert any("constant" in w for w in summary["warnings"])


class Refuse:
    """Stands in for Model: a test fails if the run gets as far as building the model."""

    calls = 0

    def __init__(self, *args, **kwargs):
        Refuse.calls += 1
        raise AssertionError("the model must not be built")


@pytest.mark.parametrize("where", ["file", "under_file"])
def test_unusable_output_folder_is_exit_3_before_any_work(where, tmp_path, monkeypatch):
    monkeypatch.setattr("runtime.app.simulation.Model", Refuse)
    Refuse.calls = 0
    scene = write(tmp_path, small_scene())
    (tmp_path / "file").write_text("not a folder")
    out = tmp_path / "file" if where == "file" else tmp_path / "file" / "out"
    summary, code = run(scene, out, quiet=True)
    assert code == 3 and Refuse.calls == 0
    assert summary["status"] == "failed"
    assert str(tmp_path / "file") in summary["message"]
    assert "no summary.json written" in summary["message"]
    assert "\n" not in summary["message"]
    assert (tmp_path / "file").read_text() == "not a folder"


def test_read_only_output_folder_is_exit_3(tmp_path, monkeypatch):
    from runtime.app import writers as output

    real_open = os.open

    def read_only(path, flags, *args):
        if flags & os.O_CREAT and str(tmp_path / "out") in str(path):
            raise OSError(13, "Permission denied", str(path))
        return real_open(path, flags, *args)

    monkeypatch.setattr(output.os, "open", read_only)
    monkeypatch.setattr("runtime.app.simulation.Model", Refuse)
    (tmp_path / "out").mkdir()
    summary, code = run(write(tmp_path, small_scene()), tmp_path / "out", quiet=True)
    assert code == 3
    assert "cannot write in the folder (Permission denied)" in summary["message"]
    assert os.listdir(tmp_path / "out") == []


def test_invalid_scene_and_unusable_folder_is_exit_2_saying_no_summary(tmp_path):
    data = small_scene()
    data["body"][0]["sectoin"] = data["body"][0].pop("section")
    (tmp_path / "file").write_text("x")
    summary, code = run(write(tmp_path, data), tmp_path / "file", quiet=True)
    assert code == 2 and summary["status"] == "failed"
    first = summary["message"].split("\n")[0]
    assert first.startswith("body[0].sectoin")
    assert "exists and is not a folder" in first and "no summary.json written" in first


def test_full_disk_during_the_run_is_exit_3_with_whole_csv_rows(tmp_path, monkeypatch):
    from test_output import FullDisk

    from runtime.app.writers import TimeSeriesWriter

    real_init = TimeSeriesWriter.__init__

    def init(self, *args, **kwargs):
        real_init(self, *args, **kwargs)
        self._file = FullDisk(self._file, budget=300)  # a few rows, then a cut row

    monkeypatch.setattr(TimeSeriesWriter, "__init__", init)
    out = tmp_path / "out"
    summary, code = run(write(tmp_path, small_scene(("dynamic",))), out, quiet=True)
    assert code == 3
    on_disk = json.loads((out / "summary.json").read_text())
    assert on_disk["status"] == "failed"
    assert "timeseries.csv: cannot write (No space left on device)" in on_disk["message"]
    header, rows = read_csv(out / "timeseries.csv")  # every row whole and readable
    assert header == ["t"] + [s["name"] for s in SENSORS]
    assert 1 <= len(rows) < 11 and all(len(row) == len(header) for row in rows)
    assert (out / "timeseries.csv").read_bytes().endswith(b"\n")
    assert on_disk["dynamic"]["t_reached"] == rows[-1][0]
    assert f"up to t = {rows[-1][0]:.6g} s" in on_disk["message"]
    assert not list(out.glob("*.png")) and no_temporary_files(out)


@pytest.mark.parametrize("error, hint", [
    ("CompilerNotFoundError", "--backend numpy"),
    ("CompilationError", "--backend numpy"),
    ("CacheError", "ANCF_CACHE_DIR"),
])
def test_jit_environment_errors_are_exit_3_with_a_hint(error, hint, tmp_path, monkeypatch):
    from runtime.kernels import errors

    def broken(*args, **kwargs):
        raise getattr(errors, error)(f"{error} first line\ndetails: compiler output")

    monkeypatch.setattr("runtime.app.simulation.Model", broken)
    out = tmp_path / "out"
    summary, code = run(write(tmp_path, small_scene()), out, quiet=True)
    assert code == 3
    on_disk = json.loads((out / "summary.json").read_text())
    assert on_disk["status"] == "failed"
    first, rest = on_disk["message"].split("\n", 1)
    assert first.startswith(f"{error} first line") and hint in first
    assert rest == "details: compiler output"


def test_long_sensor_name_keeps_results_and_plot(tmp_path):
    from runtime.app.writers import plot_file_name

    # the longest name a scene accepts (300 characters are a scene error: tests/test_scene*)
    name = "s" * 64
    sensors = [{"name": name, "type": "displacement", "node": "beam:-1", "component": "y"}]
    out = tmp_path / "out"
    summary, code = run(write(tmp_path, numpy_dynamic(sensors, t_end=0.02)), out, quiet=True)
    assert code == 0, summary["message"]
    assert summary["warnings"] == []
    assert (out / plot_file_name(name)).read_bytes()[:8] == PNG_SIGNATURE
    assert name in json.loads((out / "summary.json").read_text())["dynamic"]["sensors_final"]


def test_failing_plots_are_warnings_not_failures(tmp_path, monkeypatch):
    from matplotlib.figure import Figure

    def broken(self, *args, **kwargs):
        raise RuntimeError("renderer exploded")

    monkeypatch.setattr(Figure, "savefig", broken)
    out = tmp_path / "out"
    summary, code = run(write(tmp_path, small_scene(("dynamic",))), out, quiet=True)
    assert code == 0 and summary["status"] == "ok"
    assert len(summary["warnings"]) == 2  # tip_y.png and energies.png
    assert all("renderer exploded" in w for w in summary["warnings"])
    assert json.loads((out / "summary.json").read_text())["warnings"] == summary["warnings"]
    assert not list(out.glob("*.png")) and no_temporary_files(out)


def test_plots_are_drawn_after_the_summary_is_written(tmp_path, monkeypatch):
    import time

    from runtime.app import writers as output

    real = output.plot_series
    seen = {}

    def slow_plots(*args, **kwargs):
        seen.update(json.loads((tmp_path / "out" / "summary.json").read_text()))
        time.sleep(0.3)
        return real(*args, **kwargs)

    monkeypatch.setattr(output, "plot_series", slow_plots)
    summary, code = run(write(tmp_path, small_scene(("dynamic",))), tmp_path / "out",
                        quiet=True)
    assert code == 0
    assert seen["status"] == "ok" and seen["dynamic"]["steps"] == 20  # results already there
    assert summary["timing"]["postprocess_s"] >= 0.3 > seen["timing"]["postprocess_s"]
    assert summary["timing"]["simulate_s"] == seen["timing"]["simulate_s"]
    assert summary["timing"]["total_s"] >= summary["timing"]["simulate_s"] + 0.3


def test_no_plots(tmp_path):
    summary, code = run(write(tmp_path, small_scene(("dynamic",))), tmp_path / "out",
                        quiet=True, plots=False)
    assert code == 0
    assert not list((tmp_path / "out").glob("*.png"))
    assert summary["files"] == ["summary.json", "timeseries.csv"]


def test_reused_output_folder_loses_stale_outputs_only(tmp_path):
    out = tmp_path / "out"
    other = [{"name": "old_sensor", "type": "displacement", "node": "beam:-1",
              "component": "x"}] + SENSORS
    assert run(write(tmp_path, small_scene(("dynamic",), sensor=other)), out, quiet=True)[1] == 0
    assert (out / "old_sensor.png").exists()
    (out / "notes.txt").write_text("mine")
    (out / "picture.png").write_text("mine")
    # a newer run of another scene: no old_sensor.png next to its results
    assert run(write(tmp_path, small_scene(("dynamic",))), out, quiet=True)[1] == 0
    assert not (out / "old_sensor.png").exists()
    assert (out / "notes.txt").read_text() == "mine" == (out / "picture.png").read_text()
    # a plot of an earlier version, when energies had one plot each
    (out / "kinetic.png").write_text("old")
    assert run(write(tmp_path, small_scene(("static",))), out, quiet=True)[1] == 0
    assert not (out / "kinetic.png").exists() and not (out / "timeseries.csv").exists()
    # a newer run that fails: no stale results beside its summary
    data = small_scene()
    data["body"][0]["sectoin"] = data["body"][0].pop("section")
    assert run(write(tmp_path, data), out, quiet=True)[1] == 2
    assert sorted(os.listdir(out)) == ["notes.txt", "picture.png", "summary.json"]
    assert json.loads((out / "summary.json").read_text())["status"] == "failed"


def test_outputs_have_ordinary_permissions(tmp_path):
    old = os.umask(0o022)
    try:
        run(write(tmp_path, small_scene(("dynamic",))), tmp_path / "out", quiet=True)
    finally:
        os.umask(old)
    for path in (tmp_path / "out").iterdir():
        assert path.stat().st_mode & 0o777 == 0o644, path.name


def test_internal_error_still_writes_a_failed_summary(tmp_path, monkeypatch):
    def bug(*args, **kwargs):
        raise ZeroDivisionError("a bug")

    monkeypatch.setattr("runtime.app.simulation.Sensors", bug)
    out = tmp_path / "out"
    summary, code = run(write(tmp_path, small_scene()), out, quiet=True)
    assert code == 4
    on_disk = json.loads((out / "summary.json").read_text())
    assert on_disk["status"] == "failed"
    assert on_disk["message"] == "internal error during the model build: ZeroDivisionError: a bug"
    assert "Traceback" in on_disk["traceback"]


def test_out_of_memory_is_exit_3(tmp_path, monkeypatch):
    def huge(*args, **kwargs):
        raise MemoryError

    monkeypatch.setattr("runtime.app.simulation.Model", huge)
    summary, code = run(write(tmp_path, small_scene()), tmp_path / "out", quiet=True)
    assert code == 3
    assert summary["message"] == "out of memory during the model build"
    assert json.loads((tmp_path / "out" / "summary.json").read_text())["status"] == "failed"


def test_summary_that_cannot_be_written_is_exit_3(tmp_path, monkeypatch):
    from runtime.app import writers as output

    def full_disk(path, data):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(output, "write_json_atomic", full_disk)
    summary, code = run(write(tmp_path, small_scene(("static",))), tmp_path / "out",
                        quiet=True)
    assert code == 3 and summary["status"] == "failed"
    assert summary["message"] == "summary.json not written (No space left on device)"
    assert "summary.json" not in summary["files"]
    assert "static" in summary  # the results are still returned


def test_compiler_fault_when_the_dynamic_engine_is_built_is_exit_3(tmp_path, monkeypatch):
    from runtime.kernels import errors
    from runtime.solve import engines

    def no_compiler(*args, **kwargs):
        raise errors.CompilerNotFoundError("no C compiler for the stepper")

    monkeypatch.setitem(engines.ENGINES, "compiled", no_compiler)
    summary, code = run(write(tmp_path, small_scene()), tmp_path / "out", quiet=True)
    assert code == 3 and summary["status"] == "failed"
    assert summary["message"] == ("no C compiler for the stepper; --backend numpy needs no C "
                                  "compiler")
    assert "static" in summary and "modal" in summary  # what ran before is kept
