"""Run outputs: the time-series CSV (readable as it is written), the atomic JSON summary, the
plots and the progress bar."""

from __future__ import annotations

import csv
import json
import math

import pytest

from runtime import output
from runtime.output import Progress, TimeSeriesWriter, plot_timeseries, write_json_atomic


def read_rows(path) -> list[list[str]]:
    with open(path, newline="") as f:
        return list(csv.reader(f))


def test_csv_is_readable_after_each_write_without_close(tmp_path):
    path = tmp_path / "run" / "timeseries.csv"
    writer = TimeSeriesWriter(path, ["tip_y", "energy"])
    assert read_rows(path) == [["t", "tip_y", "energy"]]
    writer.write(0.0, [0.0, 0.0])
    assert read_rows(path)[1:] == [["0.0", "0.0", "0.0"]]
    value = 0.1 + 0.2  # repr keeps every digit
    writer.write(0.001, {"energy": 2.0, "tip_y": value})
    rows = read_rows(path)
    assert len(rows) == 3
    assert float(rows[2][1]) == value and float(rows[2][0]) == 0.001
    writer.write(0.002, [math.nan, math.inf])
    assert math.isnan(float(read_rows(path)[3][1]))
    writer.close()
    writer.close()
    with pytest.raises(ValueError):
        writer.write(1.0, [1.0, 2.0])


def test_csv_rejects_wrong_row_lengths_and_works_as_context_manager(tmp_path):
    path = tmp_path / "ts.csv"
    with TimeSeriesWriter(path, ["a"]) as writer:
        with pytest.raises(ValueError):
            writer.write(0.0, [1.0, 2.0])
        writer.write(0.0, [1.5])
    assert read_rows(path) == [["t", "a"], ["0.0", "1.5"]]
    with pytest.raises(ValueError):
        TimeSeriesWriter(tmp_path / "bad.csv", ["t"])


def test_json_is_written_with_nan_as_null(tmp_path):
    path = tmp_path / "summary.json"
    write_json_atomic(path, {"status": "ok", "x": math.nan, "y": [1.0, -math.inf], "n": 3,
                             "t": (1, 2)})
    assert json.loads(path.read_text()) == {"status": "ok", "x": None, "y": [1.0, None],
                                            "n": 3, "t": [1, 2]}
    assert list(tmp_path.iterdir()) == [path]


def test_json_write_is_atomic(tmp_path, monkeypatch):
    path = tmp_path / "summary.json"
    write_json_atomic(path, {"status": "ok"})
    before = path.read_text()

    def broken_dump(obj, f, **kwargs):
        f.write('{"status": "fai')  # half a document, then a crash
        raise RuntimeError("disk full")

    monkeypatch.setattr(output.json, "dump", broken_dump)
    with pytest.raises(RuntimeError, match="disk full"):
        write_json_atomic(path, {"status": "failed"})
    assert path.read_text() == before
    assert json.loads(path.read_text()) == {"status": "ok"}
    assert list(tmp_path.iterdir()) == [path]  # no temporary file left behind


def test_json_accepts_numpy_values(tmp_path):
    np = pytest.importorskip("numpy")
    path = tmp_path / "s.json"
    write_json_atomic(path, {"a": np.float64(np.nan), "b": np.arange(3), "c": np.int64(4)})
    assert json.loads(path.read_text()) == {"a": None, "b": [0, 1, 2], "c": 4}


def test_plots_are_written(tmp_path):
    csv_path = tmp_path / "timeseries.csv"
    with TimeSeriesWriter(csv_path, ["tip_y", "strain_energy", "kinetic_energy"]) as writer:
        for i in range(20):
            t = 0.1 * i
            writer.write(t, [math.sin(t), t * t, 1.0 - t])
    out = tmp_path / "plots"
    paths = plot_timeseries(csv_path, out, ["strain_energy", "kinetic_energy", "absent"])
    names = sorted(p.name for p in paths)
    assert names == ["energies.png", "kinetic_energy.png", "strain_energy.png", "tip_y.png"]
    for p in paths:
        assert p.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert plot_timeseries(csv_path, tmp_path / "no_energy", []) != []
    assert not (tmp_path / "no_energy" / "energies.png").exists()


def test_plot_of_empty_csv_writes_nothing(tmp_path):
    csv_path = tmp_path / "timeseries.csv"
    TimeSeriesWriter(csv_path, ["tip_y"]).close()
    assert plot_timeseries(csv_path, tmp_path / "plots", ["tip_y"]) == []
    assert not (tmp_path / "plots").exists()


def test_progress_disabled_prints_nothing(capsys):
    bar = Progress(4.0, enabled=False)
    for i in range(5):
        bar.update(float(i))
    bar.close()
    captured = capsys.readouterr()
    assert captured.err == "" and captured.out == ""


def test_progress_enabled_draws_a_bar(capsys):
    with Progress(4.0, enabled=True) as bar:
        bar.update(1.68)
        for i in range(1000):  # rate-limited: these do not all redraw
            bar.update(1.68 + i * 1e-3)
    err = capsys.readouterr().err
    assert err.startswith("\r[") and err.endswith("\n")
    assert "42% t=1.68 s" in err
    assert err.count("\r") < 100
    assert "100%" not in err


def test_progress_defaults_to_disabled_when_stderr_is_not_a_tty(capsys):
    bar = Progress(1.0)
    bar.update(0.5)
    bar.close()
    assert capsys.readouterr().err == ""
