"""Second audit, run level: ParaView files carry the reference with the motion as point data;
an output the user asked for that the environment keeps out is exit 3; the Python API names
misused arguments; a reused VtkSeries starts afresh; the summary is the record of the rows
written when an interrupt stops a run, which still draws the plots of those rows; the
locking warning is said once."""

from __future__ import annotations

import csv
import errno
import json
import os

import meshio
import numpy as np
import pytest
from test_shapes import read_pvd, small

from runtime.app import writers as output
from runtime.app.run import RunInterrupted, run
from runtime.app.shapes import Shape, VtkSeries
from runtime.app.simulation import run_scene
from runtime.cli import main
from runtime.model.scene import parse_scene
from runtime.model.toml_io import toml_text


def rows(path) -> list[list[float]]:
    with open(path, newline="") as f:
        return [[float(x) for x in row] for row in list(csv.reader(f))[1:]]


def full_disk(*args, **kwargs):
    raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))


# --------------------------------------------------------------------------- item 1

def test_vtu_points_are_the_reference_and_the_motion_is_point_data(tmp_path):
    series = VtkSeries(tmp_path / "vtk")
    result = run_scene(parse_scene(small()), observers=[series], store_states=True,
                       progress=False)
    model = result.model
    shape = Shape(model)
    reference = shape.sample(model.reference)
    for k, (_, name) in enumerate(read_pvd(tmp_path / "vtk" / "dynamic.pvd")):
        mesh = meshio.read(tmp_path / "vtk" / name)
        assert mesh.points == pytest.approx(reference, abs=1e-15)
        # Warp By Vector (points + displacement) gives the deformed shape, applied once
        warped = mesh.points + mesh.point_data["displacement"]
        assert warped == pytest.approx(shape.sample(result.states.q[k]), rel=1e-12, abs=1e-15)
    static = meshio.read(tmp_path / "vtk" / "static.vtu")
    assert static.points == pytest.approx(reference, abs=1e-15)
    assert static.point_data["displacement"][-1, 1] == pytest.approx(
        result.summary["static"]["sensors"]["tip_y"], rel=1e-12)


# --------------------------------------------------------------------------- item 5

def test_a_full_disk_while_writing_the_gif_is_exit_3_with_a_valid_summary(tmp_path,
                                                                         monkeypatch):
    from matplotlib.animation import PillowWriter

    monkeypatch.setattr(PillowWriter, "finish", full_disk)
    out = tmp_path / "out"
    summary, code = run(parse_scene(small(analyses=("dynamic",))), out, quiet=True,
                        animation=True)
    assert code == 3
    assert summary["status"] == "failed"
    assert summary["message"].startswith(f"not written: {output.ANIMATION_FILE}: ")
    assert "No space left on device" in summary["message"]
    written = json.loads((out / "summary.json").read_text())
    assert written == json.loads(json.dumps(summary))
    assert output.ANIMATION_FILE not in written["files"]
    assert sorted(written["files"]) == sorted(p.name for p in out.iterdir())
    assert "tip_y.png" in written["files"]


def test_a_full_disk_while_drawing_a_plot_is_exit_3(tmp_path, monkeypatch):
    from matplotlib.figure import Figure

    monkeypatch.setattr(Figure, "savefig", full_disk)
    out = tmp_path / "out"
    summary, code = run(parse_scene(small(analyses=("dynamic",))), out, quiet=True)
    assert code == 3 and summary["status"] == "failed"
    assert "tip_y.png: not written" in summary["message"]
    assert not [w for w in summary["warnings"] if "not written" in w]   # said once
    assert sorted(summary["files"]) == ["summary.json", "timeseries.csv"]


# --------------------------------------------------------------------------- item 6

@pytest.mark.parametrize("call, message", [
    (lambda: run_scene(None), "scene: expected a runtime.Scene or the path of a TOML scene "
                              "file (str or pathlib.Path), got NoneType None"),
    (lambda: VtkSeries(None), "folder: expected the path of the output folder"),
    (lambda: run_scene(parse_scene(small(analyses=("static",))), observers=None),
     "observers: expected a sequence (list or tuple) of runtime.app.result.Observer objects, "
     "got NoneType None"),
    (lambda: run_scene(parse_scene(small(analyses=("static",))), observers=[object()]),
     "observers[0]: expected a runtime.app.result.Observer"),
])
def test_python_api_misuse_names_the_argument(call, message):
    with pytest.raises(TypeError) as info:
        call()
    assert str(info.value).startswith(message), str(info.value)


def test_a_reused_vtk_series_starts_a_fresh_series(tmp_path):
    series = VtkSeries(tmp_path / "vtk")
    scene = parse_scene(small(analyses=("dynamic",)))
    for _ in range(2):
        result = run_scene(scene, observers=[series], progress=False)
        entries = read_pvd(tmp_path / "vtk" / "dynamic.pvd")
        assert [t for t, _ in entries] == result.sensors["t"].tolist()
    assert series.files == ["vtk/dynamic.pvd"]
    assert len(os.listdir(tmp_path / "vtk")) == len(entries) + 1


# --------------------------------------------------------------------------- items 7 and 9

def test_an_interrupt_while_writing_vtk_leaves_the_summary_at_the_last_csv_row(tmp_path,
                                                                              monkeypatch):
    real = VtkSeries.sample
    calls = []

    def sample(self, *args):
        calls.append(1)
        if len(calls) == 4:      # after the CSV row of the fourth output time
            raise KeyboardInterrupt("SIGINT")
        return real(self, *args)

    monkeypatch.setattr(VtkSeries, "sample", sample)
    out = tmp_path / "out"
    with pytest.raises(RunInterrupted) as info:
        run(parse_scene(small(analyses=("dynamic",))), out, quiet=True, vtk=True)
    summary = json.loads((out / "summary.json").read_text())
    assert summary == json.loads(json.dumps(info.value.summary))
    last = rows(out / "timeseries.csv")[-1]
    assert summary["dynamic"]["t_reached"] == last[0]
    assert [summary["dynamic"]["sensors_final"][name] for name in ("tip_y", "tip_x")] == \
        last[1:]
    # item 9: the plots of what was computed are drawn from the kept rows
    assert {"tip_y.png", "tip_x.png"} <= set(summary["files"])
    assert (out / "tip_y.png").read_bytes()[:4] == b"\x89PNG"


def test_ancf_run_says_the_locking_warning_once(tmp_path, capsys):
    data = small(analyses=("static",))
    data["material"]["m"]["nu"] = 0.3
    scene = tmp_path / "scene.toml"
    scene.write_text(toml_text(data))
    assert main(["run", str(scene), "--out", str(tmp_path / "out"), "--quiet"]) == 0
    err = capsys.readouterr().err
    assert err.count("Poisson locking") == 1, err
    assert "35% too stiff in bending (bending modulus lam + 2G = 1.35 E instead of E, 2D and " \
           "3D beams alike: deflections up to 26% too small)" in err


def test_run_scene_says_the_locking_warning_once_on_stderr(capsys):
    data = small(analyses=("static",))
    data["material"]["m"]["nu"] = 0.3
    result = run_scene(parse_scene(data))
    assert len(result.summary["warnings"]) == 1
    assert capsys.readouterr().err.count("Poisson locking") == 1


def test_energy_panels_show_the_change_from_the_initial_value(tmp_path, monkeypatch):
    from matplotlib.figure import Figure

    saved = []
    real = Figure.savefig
    monkeypatch.setattr(Figure, "savefig",
                        lambda self, *a, **k: (saved.append(self), real(self, *a, **k))[1])
    t = [0.01 * i for i in range(50)]
    energy = [7.4127 + 1e-5 * np.sin(x) for x in t]
    output.plot_series(t, {"E_total": energy}, tmp_path, {"E_total": "J"}, ["E_total"])
    (fig,) = saved
    (ax,) = fig.axes
    y = ax.lines[0].get_ydata()
    assert y[0] == 0.0 and max(y) == pytest.approx(1e-5 * np.sin(0.49), rel=1e-6)
    assert ax.yaxis.get_major_formatter().offset == 0     # no offset hiding the curve
    assert "change from its initial value 7.4127 J" in ax.get_title(loc="left")
