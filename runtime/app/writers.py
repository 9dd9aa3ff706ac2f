"""Run outputs (docs/design.md section 9): the output folder, the time-series CSV written as the
run goes, the atomic ``summary.json`` and PNG plots (shapes: ``runtime.app.shapes``; progress:
``runtime.progress``).

Every file is created with the ordinary permissions of ``open`` (0666 less the umask).  A
write error (full disk, read-only folder) raises :class:`OutputError` and never leaves a
partial file: the CSV is cut back to its last whole row, other files are replaced atomically.
"""

from __future__ import annotations

import contextlib
import csv
import hashlib
import io
import json
import math
import os
import re
import secrets
import warnings
from collections.abc import Iterable, Iterator, Mapping, Sequence
from pathlib import Path
from types import TracebackType
from typing import IO, Any

import numpy as np

__all__ = ["ENERGIES_FILE", "OutputError", "PATH_CSV", "PATH_PLOT", "RESERVED_FILES",
           "TimeSeriesWriter", "VTK_FOLDER", "atomic_file", "atomic_path", "plot_file_name",
           "plot_path", "plot_series", "prepare_folder", "write_json_atomic", "write_path"]

ENERGIES_FILE = "energies.png"
#: the snapshot of the static state and the animation (runtime.app.shapes)
SHAPE_FILE, ANIMATION_FILE = "shape_static.png", "shape_animation.gif"
#: the arc-length path of a static analysis: its CSV and its load-displacement plot
PATH_CSV, PATH_PLOT = "static_path.csv", "static_path.png"
#: PNG names of a run that no sensor plot may take
RESERVED_FILES = (ENERGIES_FILE, SHAPE_FILE, PATH_PLOT)
#: subfolder of the VTU/PVD files of a run (runtime.app.shapes), owned by the run
VTK_FOLDER = "vtk"
# longest plot file stem: room for the temporary-file decoration within 255 bytes
MAX_STEM = 100
# what a run may have written, hence may remove when it reuses a folder
OUTPUT_SUFFIXES = (".json", ".csv", ".png", ".vtu", ".pvd")


class OutputError(OSError):
    """The output folder or an output file cannot be written (exit code 3, environment)."""


def _reason(error: OSError) -> str:
    return error.strerror or str(error)


def prepare_folder(folder: str | Path, owned: Iterable[str] = ()) -> None:
    """Make ``folder`` ready for a run: create it if needed, check that files can be created
    in it, then remove the outputs of a previous run there - ``summary.json``,
    ``timeseries.csv``, the ``owned`` file names and the files listed under ``files`` in the
    old ``summary.json``, the VTU and PVD files of its ``vtk`` subfolder - and nothing
    else.  Raises OutputError, with a one-line message."""
    folder = Path(folder)
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except FileExistsError:
        raise OutputError(f"{folder}: exists and is not a folder") from None
    except NotADirectoryError:
        raise OutputError(f"{folder}: cannot create the folder: part of the path is a file") \
            from None
    except OSError as error:
        raise OutputError(f"{folder}: cannot create the folder ({_reason(error)})") from None
    probe = folder / f".ancf-probe-{os.getpid()}-{secrets.token_hex(4)}"
    try:
        os.close(os.open(probe, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600))
        os.unlink(probe)
    except OSError as error:
        raise OutputError(f"{folder}: cannot write in the folder ({_reason(error)})") from None
    names = {"summary.json", "timeseries.csv", *owned, *_previous_files(folder)}
    vtk = folder / VTK_FOLDER
    paths = [folder / name for name in sorted(names)]
    if vtk.is_dir() and not vtk.is_symlink():
        paths += sorted(p for p in vtk.iterdir() if p.suffix in (".vtu", ".pvd"))
    for path in paths:
        try:
            path.unlink(missing_ok=True)
        except IsADirectoryError:
            raise OutputError(f"{path}: is a folder; expected an output file of a "
                              f"previous run") from None
        except OSError as error:
            raise OutputError(f"{path}: cannot remove the output of a previous run "
                              f"({_reason(error)})") from None
    with contextlib.suppress(OSError):  # gone when it held nothing else
        vtk.rmdir()


def _previous_files(folder: Path) -> list[str]:
    """Output file names listed by the summary.json of a previous run in ``folder``."""
    try:
        files = json.loads((folder / "summary.json").read_text(encoding="utf-8"))["files"]
    except (OSError, ValueError, TypeError, KeyError):
        return []
    if not isinstance(files, list):
        return []
    return [name for name in files if isinstance(name, str) and name == Path(name).name
            and not name.startswith(".") and name.endswith(OUTPUT_SUFFIXES)]


def _temporary(path: Path, suffix: str = "") -> Path:
    """A fresh hidden name beside ``path``, ending in ``.tmp`` and ``suffix``."""
    return path.with_name(f".{path.name}.{os.getpid()}.{secrets.token_hex(4)}.tmp{suffix}")


@contextlib.contextmanager
def atomic_file(path: str | Path, mode: str = "wb") -> Iterator[IO[Any]]:
    """Open a temporary file beside ``path`` (``mode`` "wb" or "w", UTF-8) that replaces
    ``path`` when the block ends normally, after fsync; on any exception (KeyboardInterrupt
    included) it is removed and ``path`` is untouched.  Readers never see a partial file."""
    path = Path(path)
    tmp = _temporary(path)
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
    try:
        with os.fdopen(fd, mode, encoding=None if "b" in mode else "utf-8") as f:
            yield f
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


@contextlib.contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """A temporary path beside ``path`` (same suffix, for writers that choose the format by
    it) for a writer that wants a file name (meshio, matplotlib animations): it replaces
    ``path`` when the block ends normally; on any exception it is removed and ``path`` is
    untouched.  A write error raises OutputError."""
    path = Path(path)
    tmp = _temporary(path, path.suffix)
    try:
        yield tmp
        os.replace(tmp, path)
    except OSError as error:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise OutputError(f"{path}: cannot write ({_reason(error)})") from None
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


class TimeSeriesWriter:
    """CSV of sensor values against time: header ``t,<columns...>``, one row per ``write``.

    Each row is built whole and handed to the operating system at once (unbuffered), so the
    file is readable while the run goes on and keeps what was computed if the run stops.  A
    write that fails (full disk) or is interrupted cuts the file back to its last whole row
    and closes it; the failure raises OutputError.  Numbers are written with ``repr``
    precision (round-trip exact; ``nan``/``inf`` as Python spells them).
    """

    def __init__(self, path: str | Path, columns: Sequence[str]) -> None:
        self.path = Path(path)
        self.columns = list(columns)
        if "t" in self.columns or len(set(self.columns)) != len(self.columns):
            raise ValueError(f"columns: expected unique names other than 't', got {columns!r}")
        self.rows = 0  # data rows on disk
        self.last_t: float | None = None  # time of the last row on disk
        self._size = 0  # bytes of whole lines on disk
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self._file: IO[bytes] | None = open(self.path, "wb", buffering=0)
        except OSError as error:
            raise OutputError(f"{self.path}: cannot create ({_reason(error)})") from None
        header = io.StringIO()
        csv.writer(header, lineterminator="\n").writerow(["t", *self.columns])
        self._append(header.getvalue().encode("utf-8"))

    def write(self, t: float, values: Sequence[float] | Mapping[str, float]) -> None:
        """Append the row at time t (s): ``values`` in column order, or by column name."""
        if self._file is None:
            raise ValueError(f"{self.path}: write after close")
        if isinstance(values, Mapping):
            row = [values[name] for name in self.columns]
        else:
            row = list(values)
        if len(row) != len(self.columns):
            raise ValueError(f"expected {len(self.columns)} values, got {len(row)}")
        line = ",".join([repr(float(t)), *(repr(float(v)) for v in row)]) + "\n"
        self._append(line.encode("ascii"))
        self.rows += 1
        self.last_t = float(t)

    def write_rows(self, times: Sequence[float], values: np.ndarray) -> None:
        """Append one row per time (s), ``values`` (rows, columns) in column order, in one
        write (whole rows: a failure cuts the file back to the rows before them)."""
        if self._file is None:
            raise ValueError(f"{self.path}: write after close")
        values = np.asarray(values, float).reshape(len(times), -1)
        if values.shape[1] != len(self.columns):
            raise ValueError(f"expected {len(self.columns)} values, got {values.shape[1]}")
        if not len(times):
            return
        lines = "".join(",".join([repr(float(t)), *map(repr, row)]) + "\n"
                        for t, row in zip(times, values.tolist(), strict=True))
        self._append(lines.encode("ascii"))
        self.rows += len(times)
        self.last_t = float(times[-1])

    def _append(self, data: bytes) -> None:
        """Write ``data`` whole, or cut the file back to its last whole line and close it."""
        assert self._file is not None
        view, done = memoryview(data), 0
        try:
            while done < len(data):
                done += self._file.write(view[done:])  # an OS write may be partial
        except BaseException as error:
            with contextlib.suppress(OSError):
                self._file.truncate(self._size)
            self.close()
            if isinstance(error, OSError):
                kept = "no row" if self.last_t is None else \
                    f"{self.rows} whole rows, up to t = {self.last_t:.6g} s"
                raise OutputError(f"{self.path}: cannot write ({_reason(error)}); the file "
                                  f"keeps {kept}") from error
            raise
        self._size += len(data)

    def close(self) -> None:
        """Close the file (idempotent)."""
        if self._file is not None:
            with contextlib.suppress(OSError):
                self._file.close()
            self._file = None

    def __enter__(self) -> TimeSeriesWriter:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        self.close()


def write_path(path: str | Path, columns: Mapping[str, Sequence[float]]) -> None:
    """The arc-length path as CSV, atomically: header ``load_factor,<sensors...>`` (the
    ``columns`` in order), one row per converged point, numbers with ``repr`` precision.
    Raises OutputError."""
    names = list(columns)
    lines = io.StringIO()
    csv.writer(lines, lineterminator="\n").writerow(names)
    for row in zip(*(columns[name] for name in names), strict=True):
        lines.write(",".join(repr(float(v)) for v in row) + "\n")
    try:
        with atomic_file(path, "w") as f:
            f.write(lines.getvalue())
    except OSError as error:
        raise OutputError(f"{path}: cannot write ({_reason(error)})") from None


def _json_ready(data: Any) -> Any:
    """``data`` with NaN/inf floats replaced by None, tuples by lists, NumPy values by Python
    ones (anything with ``tolist``) and paths by strings."""
    if isinstance(data, float):
        return data if math.isfinite(data) else None
    if isinstance(data, Mapping):
        return {str(k): _json_ready(v) for k, v in data.items()}
    if isinstance(data, list | tuple):
        return [_json_ready(v) for v in data]
    if isinstance(data, Path):
        return str(data)
    if hasattr(data, "tolist") and not isinstance(data, str | bytes):
        return _json_ready(data.tolist())
    return data


def write_json_atomic(path: str | Path, data: Any) -> None:
    """Write ``data`` as JSON to ``path`` atomically (see :func:`atomic_file`); NaN and
    infinities become null."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    ready = _json_ready(data)
    with atomic_file(path, "w") as f:
        json.dump(ready, f, indent=2, allow_nan=False)
        f.write("\n")


def plot_file_name(name: str) -> str:
    """File name of the plot of the series ``name``: ``<name>.png`` when that is a safe, short
    file name other than the ``RESERVED_FILES``; otherwise the name with unsafe characters
    replaced by ``_``, cut to ``MAX_STEM`` characters and followed by a short hash of the
    whole name, so that different names never share a file."""
    safe = re.sub(r"[^A-Za-z0-9_.\-]", "_", name).lstrip(".-")
    if name and safe == name and len(name) <= MAX_STEM and f"{name}.png" not in RESERVED_FILES:
        return f"{name}.png"
    digest = hashlib.sha1(name.encode("utf-8", "surrogatepass")).hexdigest()[:8]
    return f"{safe[:MAX_STEM - 9] or 'series'}-{digest}.png"


def plot_path(load_factors: Sequence[float], series: Mapping[str, Sequence[float]],
              out_dir: str | Path, units: Mapping[str, str] | None = None
              ) -> tuple[list[Path], list[str]]:
    """``static_path.png``: the load factor against each of ``series`` (the
    load-displacement curves of the arc-length path, a panel each), written atomically.
    Returns (written paths, warnings) as :func:`plot_series`; nothing without series."""
    if not series:
        return [], []
    try:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure
    except Exception as error:
        return [], [f"plots: cannot import matplotlib ({type(error).__name__}: {error})"]
    units = units or {}
    target = Path(out_dir) / PATH_PLOT
    try:
        names = list(series)
        fig = Figure(figsize=(6.4, 1.2 + 3.0 * len(names)), layout="constrained")
        axes = fig.subplots(len(names), 1, squeeze=False)[:, 0]
        for ax, name in zip(axes, names, strict=True):
            ax.plot(series[name], load_factors, lw=1.2, marker=".", ms=3)
            ax.set_xlabel(_label(name, units.get(name)))
            ax.set_ylabel("load factor")
            ax.grid(True, alpha=0.3)
        fig.suptitle("static equilibrium path (arc length)")
        FigureCanvasAgg(fig)
        with atomic_file(target) as f:
            fig.savefig(f, format="png", dpi=100)
    except Exception as error:
        return [], [f"{PATH_PLOT}: not written ({type(error).__name__}: {error})"]
    return [target], []


def _label(name: str, unit: str | None, width: int = 40) -> str:
    short = name if len(name) <= width else name[:width - 3] + "..."
    return f"{short} ({unit})" if unit else short


def plot_series(t: Sequence[float], series: Mapping[str, Sequence[float]],
                out_dir: str | Path, units: Mapping[str, str] | None = None,
                energies: Sequence[str] = (), *,
                unwritten: list[str] | None = None) -> tuple[list[Path], list[str]]:
    """Plot each series against t (s) into ``out_dir``: one PNG per series not in
    ``energies`` (:func:`plot_file_name`), and ``energies.png`` with one panel per series of
    ``energies``, each on its own scale (a 1e-5 J curve stays visible beside a 1.7 J one),
    as the change from its initial value (the value at t = 0 in the panel's label).
    y axes carry ``units[name]``.  Each PNG is written atomically.

    A plot that fails is a warning, never an exception (except KeyboardInterrupt): returns
    the written paths and the warnings.  Nothing is drawn when t is empty.  ``unwritten``,
    if given, also receives the warnings of the files that the environment kept from being
    written (an OSError: a full disk, a read-only folder).
    """
    units = units or {}
    if len(t) == 0 or not series:
        return [], []
    try:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure
    except Exception as error:  # a broken matplotlib costs the plots, not the run
        return [], [f"plots: cannot import matplotlib ({type(error).__name__}: {error})"]
    out = Path(out_dir)
    written: list[Path] = []
    problems: list[str] = []

    def save(file: str, draw) -> None:
        target = out / file
        try:
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter("always")
                fig = draw()
                FigureCanvasAgg(fig)
                with atomic_file(target) as f:
                    fig.savefig(f, format="png", dpi=100)
            problems.extend(f"{file}: {w.message}" for w in caught)
            written.append(target)
        except Exception as error:
            problems.append(f"{file}: not written ({type(error).__name__}: {error})")
            if isinstance(error, OSError) and unwritten is not None:
                unwritten.append(problems[-1])

    def single(name: str):
        fig = Figure(figsize=(6.4, 4.0), layout="constrained")
        ax = fig.add_subplot()
        ax.plot(t, series[name], lw=1.2)
        ax.set_title(_label(name, None, 60))
        ax.set_xlabel("t (s)")
        ax.set_ylabel(_label(name, units.get(name)))
        ax.grid(True, alpha=0.3)
        return fig

    def energy_panels(names: list[str]):
        fig = Figure(figsize=(6.4, 1.2 + 1.8 * len(names)), layout="constrained")
        axes = fig.subplots(len(names), 1, sharex=True, squeeze=False)[:, 0]
        for ax, name in zip(axes, names, strict=True):
            unit = units.get(name, "J")
            first = float(series[name][0])
            ax.plot(t, [float(v) - first for v in series[name]], lw=1.2)
            ax.set_ylabel(_label(name, unit, 24))
            ax.set_title(f"{_label(name, None)}: change from its initial value {first:.7g} "
                         f"{unit} (t = {float(t[0]):g} s)", fontsize=9, loc="left")
            ax.grid(True, alpha=0.3)
        fig.suptitle("energies")
        axes[-1].set_xlabel("t (s)")
        return fig

    for name in series:
        if name not in energies:
            save(plot_file_name(name), lambda name=name: single(name))
    present = [name for name in series if name in energies]
    if present:
        save(ENERGIES_FILE, lambda: energy_panels(present))
    return written, problems
