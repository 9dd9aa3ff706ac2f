"""Run outputs: the output folder, the time-series CSV (readable as it is written, whole rows
only, even on a full disk), the atomic JSON summary and plots, file permissions and plot
names (the progress bar: tests/test_progress.py)."""

from __future__ import annotations

import csv
import errno
import json
import math
import os

import pytest

from runtime.app import writers as output
from runtime.app.writers import (
    OutputError,
    TimeSeriesWriter,
    plot_file_name,
    plot_series,
    prepare_folder,
    write_json_atomic,
)

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


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


# --------------------------------------------------------------------------- full disk

class FullDisk:
    """A file object that accepts ``budget`` more bytes, writes part of the next write and
    then raises ENOSPC, like a disk that fills up."""

    def __init__(self, file, budget: int, error: BaseException | None = None) -> None:
        self._file, self.budget = file, budget
        self.error = error or OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    def write(self, data) -> int:
        if len(data) <= self.budget:
            self.budget -= len(data)
            return self._file.write(data)
        written = self._file.write(data[:self.budget])  # the disk takes what it can ...
        self.budget = 0
        if written:
            return written  # ... as a short write; the next call fails
        raise self.error

    def __getattr__(self, name):
        return getattr(self._file, name)


def test_full_disk_keeps_the_csv_valid_up_to_the_last_whole_row(tmp_path):
    path = tmp_path / "timeseries.csv"
    writer = TimeSeriesWriter(path, ["tip_y", "energy"])
    writer.write(0.0, [0.0, 0.0])
    writer.write(0.001, [-1.2345678901234567e-05, 3.0e-7])
    whole = path.read_bytes()
    writer._file = FullDisk(writer._file, budget=10)  # the next row is cut after 10 bytes
    with pytest.raises(OutputError, match="No space left on device") as caught:
        writer.write(0.002, [-2.345678901234567e-05, 4.0e-7])
    assert "2 whole rows, up to t = 0.001 s" in str(caught.value)
    assert path.read_bytes() == whole  # the partial row is gone
    assert read_rows(path)[1:] == [["0.0", "0.0", "0.0"],
                                   ["0.001", repr(-1.2345678901234567e-05), "3e-07"]]
    assert writer.rows == 2 and writer.last_t == 0.001
    with pytest.raises(ValueError, match="after close"):  # it stopped writing
        writer.write(0.003, [0.0, 0.0])
    writer.close()


def test_full_disk_at_the_header_leaves_an_empty_file(tmp_path, monkeypatch):
    real_open = open

    def full_open(path, *args, **kwargs):
        return FullDisk(real_open(path, *args, **kwargs), budget=3)

    monkeypatch.setattr(output, "open", full_open, raising=False)
    with pytest.raises(OutputError, match="keeps no row"):
        TimeSeriesWriter(tmp_path / "ts.csv", ["tip_y"])
    assert (tmp_path / "ts.csv").read_bytes() == b""


def test_interrupted_write_keeps_whole_rows_and_propagates(tmp_path):
    path = tmp_path / "timeseries.csv"
    writer = TimeSeriesWriter(path, ["a"])
    writer.write(0.0, [1.0])
    writer._file = FullDisk(writer._file, budget=4, error=KeyboardInterrupt())
    with pytest.raises(KeyboardInterrupt):
        writer.write(0.5, [2.0])  # 4 bytes accepted ("0.5,"), then the interrupt
    assert read_rows(path) == [["t", "a"], ["0.0", "1.0"]]


def test_unwritable_csv_is_an_output_error(tmp_path):
    (tmp_path / "ts.csv").mkdir()
    with pytest.raises(OutputError, match="cannot create"):
        TimeSeriesWriter(tmp_path / "ts.csv", ["a"])


# --------------------------------------------------------------------------- permissions

@pytest.fixture
def umask_022():
    old = os.umask(0o022)
    yield
    os.umask(old)


def mode(path) -> int:
    return os.stat(path).st_mode & 0o777


def test_outputs_get_ordinary_permissions(tmp_path, umask_022):
    write_json_atomic(tmp_path / "summary.json", {"status": "ok"})
    TimeSeriesWriter(tmp_path / "timeseries.csv", ["a"]).close()
    paths, problems = plot_series([0.0, 1.0], {"a": [0.0, 1.0]}, tmp_path)
    assert problems == [] and [p.name for p in paths] == ["a.png"]
    for name in ("summary.json", "timeseries.csv", "a.png"):
        assert mode(tmp_path / name) == 0o644, name


# --------------------------------------------------------------------------- output folder

def test_prepare_folder_creates_nested_folders(tmp_path):
    prepare_folder(tmp_path / "a" / "b")
    assert (tmp_path / "a" / "b").is_dir()
    assert os.listdir(tmp_path / "a" / "b") == []  # the write probe is gone


def test_prepare_folder_rejects_a_file_and_a_path_under_a_file(tmp_path):
    (tmp_path / "file").write_text("x")
    with pytest.raises(OutputError, match="exists and is not a folder"):
        prepare_folder(tmp_path / "file")
    with pytest.raises(OutputError, match="part of the path is a file"):
        prepare_folder(tmp_path / "file" / "sub")
    assert (tmp_path / "file").read_text() == "x"


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into read-only folders")
def test_prepare_folder_rejects_a_read_only_folder(tmp_path):
    folder = tmp_path / "ro"
    folder.mkdir()
    folder.chmod(0o555)
    try:
        with pytest.raises(OutputError, match="cannot write in the folder"):
            prepare_folder(folder)
    finally:
        folder.chmod(0o755)


def test_prepare_folder_rejects_a_read_only_file_system(tmp_path, monkeypatch):
    real_open = os.open

    def read_only(path, flags, *args):
        if flags & os.O_CREAT:
            raise OSError(errno.EROFS, os.strerror(errno.EROFS), str(path))
        return real_open(path, flags, *args)

    monkeypatch.setattr(output.os, "open", read_only)
    with pytest.raises(OutputError, match="cannot write in the folder.*Read-only"):
        prepare_folder(tmp_path)


def test_prepare_folder_removes_only_the_outputs_of_a_previous_run(tmp_path):
    previous = ["summary.json", "timeseries.csv", "old_sensor.png", "notes.txt",
                "../outside.png", ".hidden.png"]
    (tmp_path / "summary.json").write_text(json.dumps({"status": "ok", "files": previous}))
    for name in ("timeseries.csv", "tip_y.png", "old_sensor.png", "notes.txt", "mine.png",
                 ".hidden.png", "data.csv"):
        (tmp_path / name).write_text("x")
    (tmp_path.parent / "outside.png").write_text("x")
    prepare_folder(tmp_path, ["tip_y.png", "energies.png"])
    assert sorted(os.listdir(tmp_path)) == [".hidden.png", "data.csv", "mine.png", "notes.txt"]
    assert (tmp_path.parent / "outside.png").exists()
    (tmp_path.parent / "outside.png").unlink()


def test_prepare_folder_ignores_a_damaged_old_summary(tmp_path):
    (tmp_path / "summary.json").write_text('{"files": ["a.png"')
    (tmp_path / "a.png").write_text("x")
    prepare_folder(tmp_path)
    assert os.listdir(tmp_path) == ["a.png"]


# --------------------------------------------------------------------------- plots

def test_plot_file_names_are_safe_short_and_distinct():
    assert plot_file_name("tip_y") == "tip_y.png"
    assert plot_file_name("a-b.c") == "a-b.c.png"
    long_a, long_b = "a" * 300, "a" * 299 + "b"
    for name in (long_a, long_b, "x/../y z", "..", "", "energies", "é" * 200):
        file = plot_file_name(name)
        assert file.endswith(".png") and len(file.encode()) <= output.MAX_STEM + 4
        assert not file.startswith((".", "-")) and "/" not in file
    assert plot_file_name(long_a) != plot_file_name(long_b)
    assert plot_file_name("a b") != plot_file_name("a_b")
    assert plot_file_name("energies") != "energies.png"


@pytest.fixture
def figures(monkeypatch):
    """The matplotlib figures plot_series saves, in order."""
    from matplotlib.figure import Figure

    saved = []
    real = Figure.savefig

    def savefig(self, *args, **kwargs):
        saved.append(self)
        return real(self, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", savefig)
    return saved


def test_plots_have_units_and_separate_energy_panels(tmp_path, figures):
    t = [0.01 * i for i in range(50)]
    series = {"tip_y": [-1e-3 * x for x in t], "strain": [1.7 * x for x in t],
              "kinetic": [1e-5 * x for x in t]}
    units = {"tip_y": "m", "strain": "J", "kinetic": "J"}
    paths, problems = plot_series(t, series, tmp_path, units, ["strain", "kinetic", "absent"])
    assert problems == []
    assert [p.name for p in paths] == ["tip_y.png", "energies.png"]  # no duplicate energy plots
    for p in paths:
        assert p.read_bytes()[:8] == PNG_SIGNATURE
    assert sorted(os.listdir(tmp_path)) == ["energies.png", "tip_y.png"]  # no temporary files
    single, energies = figures
    assert [ax.get_ylabel() for ax in single.axes] == ["tip_y (m)"]
    assert [ax.get_ylabel() for ax in energies.axes] == ["strain (J)", "kinetic (J)"]
    # each energy on its own scale: the 1e-5 J curve fills its panel
    assert energies.axes[1].get_ylim()[1] == pytest.approx(0.49e-5, rel=0.2)
    assert energies.axes[0].get_ylim()[1] == pytest.approx(1.7 * 0.49, rel=0.2)
    for fig in figures:
        assert type(fig.get_layout_engine()).__name__ == "ConstrainedLayoutEngine"
        assert fig.axes[-1].get_xlabel() == "t (s)"


def test_a_very_long_name_is_plotted(tmp_path):
    name = "s" * 300
    paths, problems = plot_series([0.0, 1.0], {name: [0.0, 1.0]}, tmp_path, {name: "m"})
    assert problems == []
    assert [p.name for p in paths] == [plot_file_name(name)]


def test_a_failing_plot_is_a_warning_and_leaves_no_partial_file(tmp_path, monkeypatch):
    from matplotlib.figure import Figure

    (tmp_path / "tip_y.png").write_bytes(b"previous")

    def full_disk(self, f, **kwargs):
        f.write(b"\x89PNG half")
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))

    monkeypatch.setattr(Figure, "savefig", full_disk)
    paths, problems = plot_series([0.0, 1.0], {"tip_y": [0.0, 1.0], "e": [1.0, 2.0]},
                                  tmp_path, energies=["e"])
    assert paths == []
    assert len(problems) == 2 and "tip_y.png: not written" in problems[0]
    assert "No space left on device" in problems[0]
    assert (tmp_path / "tip_y.png").read_bytes() == b"previous"  # atomic: old file kept
    assert sorted(os.listdir(tmp_path)) == ["tip_y.png"]


def test_plot_of_no_data_writes_nothing(tmp_path):
    assert plot_series([], {"tip_y": []}, tmp_path / "plots", energies=["tip_y"]) == ([], [])
    assert not (tmp_path / "plots").exists()
