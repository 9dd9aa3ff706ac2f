"""Run outputs (DESIGN.md section 7): the time-series CSV written as the run goes, the atomic
``summary.json``, the PNG plots and a progress bar on stderr.
"""

from __future__ import annotations

import csv
import json
import math
import os
import re
import sys
import tempfile
import time
from collections.abc import Mapping, Sequence
from pathlib import Path
from types import TracebackType
from typing import Any, TextIO

__all__ = ["Progress", "TimeSeriesWriter", "plot_timeseries", "write_json_atomic"]


class TimeSeriesWriter:
    """CSV of sensor values against time: header ``t,<columns...>``, one row per ``write``.

    Each row is flushed at once, so the file is readable while the run goes on and keeps
    what was computed if the run stops early.  Numbers are written with ``repr`` precision
    (round-trip exact; ``nan``/``inf`` as Python spells them).
    """

    def __init__(self, path: str | Path, columns: Sequence[str]) -> None:
        self.path = Path(path)
        self.columns = list(columns)
        if "t" in self.columns or len(set(self.columns)) != len(self.columns):
            raise ValueError(f"columns: expected unique names other than 't', got {columns!r}")
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._file: TextIO | None = self.path.open("w", newline="", encoding="utf-8")
        self._writer = csv.writer(self._file, lineterminator="\n")
        self._writer.writerow(["t", *self.columns])
        self._file.flush()

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
        self._writer.writerow([repr(float(t)), *(repr(float(v)) for v in row)])
        self._file.flush()

    def close(self) -> None:
        """Close the file (idempotent)."""
        if self._file is not None:
            self._file.close()
            self._file = None

    def __enter__(self) -> TimeSeriesWriter:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        self.close()


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
    """Write ``data`` as JSON to ``path`` atomically: to a temporary file in the same folder,
    then ``os.replace``, so readers see the old file or the new one, never a half-written one.
    NaN and infinities become null."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    ready = _json_ready(data)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            json.dump(ready, f, indent=2, allow_nan=False)
            f.write("\n")
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        raise


def _read_csv(csv_path: Path) -> tuple[list[str], list[list[float]]]:
    with csv_path.open(newline="", encoding="utf-8") as f:
        rows = list(csv.reader(f))
    if not rows:
        return [], []
    header, data = rows[0], []
    for row in rows[1:]:
        if len(row) == len(header):  # a row cut short by a crash is skipped
            try:
                data.append([float(x) for x in row])
            except ValueError:
                continue
    return header, data


def _file_name(column: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.\-]", "_", column).lstrip(".") or "column"


def plot_timeseries(csv_path: str | Path, out_dir: str | Path,
                    energy_columns: Sequence[str] = ()) -> list[Path]:
    """One PNG per sensor column of the time-series CSV against t (``<column>.png``), plus
    ``energies.png`` with the ``energy_columns`` present in the CSV on one plot, when any.

    Uses the Agg canvas directly (no pyplot, no global backend switch).  Returns the written
    paths; [] when the CSV has no data rows.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    header, rows = _read_csv(Path(csv_path))
    if not rows or len(header) < 2:
        return []
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    t = [r[0] for r in rows]
    columns = {name: [r[j] for r in rows] for j, name in enumerate(header) if j > 0}
    written: list[Path] = []

    def save(fig: Figure, name: str) -> None:
        FigureCanvasAgg(fig)
        # fixed margins: tight_layout would render every figure twice
        fig.subplots_adjust(left=0.16, right=0.97, bottom=0.12, top=0.92)
        target = out / name
        fig.savefig(target, dpi=100)
        written.append(target)

    for name, values in columns.items():
        fig = Figure(figsize=(6.4, 4.0))
        ax = fig.add_subplot()
        ax.plot(t, values, lw=1.2)
        ax.set_title(name)
        ax.set_xlabel("t (s)")
        ax.set_ylabel(name)
        ax.grid(True, alpha=0.3)
        save(fig, f"{_file_name(name)}.png")

    energies = [name for name in energy_columns if name in columns]
    if energies:
        fig = Figure(figsize=(6.4, 4.0))
        ax = fig.add_subplot()
        for name in energies:
            ax.plot(t, columns[name], lw=1.2, label=name)
        ax.set_title("energies")
        ax.set_xlabel("t (s)")
        ax.set_ylabel("energy (J)")
        ax.grid(True, alpha=0.3)
        ax.legend()
        save(fig, "energies.png")
    return written


class Progress:
    """Progress bar of a run on stderr: ``\\r[#####.....] 42% t=1.68 s``.

    total_time: the end time (s).  enabled: None -> only when stderr is a terminal.
    ``update(t)`` redraws at most every ``interval`` s (0.1 s); ``close()`` draws the last
    state and ends the line.  Disabled, it prints nothing.
    """

    def __init__(self, total_time: float, enabled: bool | None = None, width: int = 30,
                 interval: float = 0.1) -> None:
        if enabled is None:
            try:
                enabled = bool(sys.stderr is not None and sys.stderr.isatty())
            except (AttributeError, ValueError):
                enabled = False
        self.total_time = float(total_time)
        self.enabled = enabled
        self.width = width
        self.interval = interval
        self._t = 0.0
        self._last_draw: float | None = None
        self._closed = False

    def _draw(self) -> None:
        total = self.total_time
        fraction = 1.0 if total <= 0 else min(max(self._t / total, 0.0), 1.0)
        filled = int(round(fraction * self.width))
        bar = "#" * filled + "." * (self.width - filled)
        sys.stderr.write(f"\r[{bar}] {fraction * 100:3.0f}% t={self._t:.2f} s")
        sys.stderr.flush()
        self._last_draw = time.monotonic()

    def update(self, t: float) -> None:
        """Record progress up to time t (s); redraw when the last draw is old enough."""
        if not self.enabled or self._closed:
            return
        self._t = float(t)
        now = time.monotonic()
        if self._last_draw is None or now - self._last_draw >= self.interval:
            self._draw()

    def close(self) -> None:
        """Draw the final state and end the line (idempotent)."""
        if self.enabled and not self._closed:
            self._draw()
            sys.stderr.write("\n")
            sys.stderr.flush()
        self._closed = True

    def __enter__(self) -> Progress:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        self.close()
