"""Running the cases of an error-vs-time study and measuring their errors: the scene of
each case, one case run with ``ancf run`` (module-level, for dask), the scheduler checked
before the sweep, and one row per run with its error against the closed form or the
reference run.
"""

from __future__ import annotations

import csv
import dataclasses
import math
import socket
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from runtime.model.scene import Scene
from runtime.model.settings import Static
from runtime.studies.error_vs_time.plan import Plan
from runtime.studies.sweep import SchedulerError


def case_scene(plan: Plan, elements: int, step: float | None, integrator: str | None,
               method: str) -> Scene:
    """The scene of one run (validated: SceneError otherwise): the sweep values set, only
    the analysis and the sensor the error needs kept."""
    scene = plan.scene
    changes: dict[str, Any] = {
        "bodies": tuple(dataclasses.replace(body, elements=elements) for body in scene.bodies),
        "sensors": tuple(s for s in scene.sensors if s.name == plan.sensor),
        "modal": None,
        "solver": dataclasses.replace(scene.solver, method=method, backend=plan.backend)}
    if plan.measure == "static_tip":
        changes.update(static=scene.static or Static(), dynamic=None)
    else:
        dynamic = scene.dynamic
        every = dynamic.output_every
        # outputs at a whole number of steps; the response frequency is fitted here, after
        # the run, so that simulate_s stays the time of the integration alone
        changes.update(static=None, dynamic=dataclasses.replace(
            dynamic, t_end=plan.t_end, step=step, integrator=integrator,
            output_every=None if every is None else step * max(1, round(every / step)),
            frequency_of=None, frequency_after=0.0))
    return dataclasses.replace(scene, **changes)


def run_case(scene_text: str, repeat: int = 1, series: str | None = None) -> dict:
    """Run one scene (TOML text) ``repeat`` times in a temporary folder with ``ancf run``.

    Returns {status, message, simulate_s, total_s (s, the fastest repeat), summary (the last
    run's), t and y (the time series of sensor ``series``, if asked)}.  An exception in the
    run gives status "failed" with its message: one case never stops the study.
    Module-level, so that dask can ship it to its workers.
    """
    from runtime.app.run import run

    result: dict = {"status": "failed", "message": "", "simulate_s": math.nan,
                    "total_s": math.nan, "summary": {}}
    with tempfile.TemporaryDirectory(prefix="ancf_error_vs_time_") as tmp:
        path = Path(tmp) / "scene.toml"
        path.write_text(scene_text, encoding="utf-8")
        simulate, total = [], []
        for i in range(repeat):
            out = Path(tmp) / f"run{i}"
            try:
                summary, _ = run(path, out, quiet=True)
            except Exception as error:  # a failing case is a result, not the study's end
                result.update(status="failed", message=f"{type(error).__name__}: {error}")
                return result
            result.update(status=summary["status"], message=summary.get("message", ""),
                          summary=summary)
            if summary["status"] != "ok":
                break
            simulate.append(summary["timing"]["simulate_s"])
            total.append(summary["timing"]["total_s"])
        if simulate:
            result.update(simulate_s=min(simulate), total_s=min(total))
        if series is not None and (out / "timeseries.csv").exists():
            with (out / "timeseries.csv").open(newline="") as f:
                rows = list(csv.reader(f))
            column = rows[0].index(series)
            values = np.array([[float(r[0]), float(r[column])] for r in rows[1:]]).reshape(-1, 2)
            result["t"], result["y"] = values[:, 0].tolist(), values[:, 1].tolist()
    return result


def check_scheduler(address: str, timeout: float = 3.0) -> None:
    """Fail fast (SchedulerError naming ``address``) when nothing listens at a tcp/tls
    scheduler address; other protocols are left to dask."""
    scheme, sep, rest = address.partition("://")
    if not sep:
        scheme, rest = "tcp", address
    if scheme not in ("tcp", "tls"):
        return
    host, colon, port = rest.rstrip("/").rpartition(":")
    if not colon:
        host, port = rest.rstrip("/"), "8786"
    if not host or not port.isdigit():
        raise SchedulerError(f"--scheduler {address}: expected an address like "
                             "tcp://HOST:8786")
    try:
        socket.create_connection((host.strip("[]"), int(port)), timeout=timeout).close()
    except OSError as error:
        raise SchedulerError(f"--scheduler {address}: cannot connect to a dask scheduler "
                             f"there ({error.strerror or error})") from None



def measured_rows(plan: Plan, runs: list[tuple], results: list[dict]) -> list[dict]:
    """One CSV row per run, errors measured."""
    ref_t = ref_y = None
    if plan.reference is not None and results[-1]["status"] == "ok":
        ref_t = np.asarray(results[-1].get("t", []))
        ref_y = np.asarray(results[-1].get("y", []))
        if ref_y.size == 0:
            ref_t = ref_y = None
    rows = []
    for i, ((n, h, integ, meth), result) in enumerate(zip(runs, results, strict=True)):
        is_reference = plan.reference is not None and i == len(runs) - 1
        row = {"elements": n, "step": h, "integrator": integ, "method": meth,
               "backend": plan.backend, "error": math.nan, "simulate_s": result["simulate_s"],
               "total_s": result["total_s"], "status": result["status"],
               "measure": plan.measure, "value": math.nan, "exact": plan.exact,
               "newton_iterations": _iterations(result["summary"]),
               "role": "reference" if is_reference else "sweep", "message": result["message"]}
        summary = result["summary"]
        if result["status"] == "ok" and not is_reference:
            try:
                value, error = _measure(plan, summary, result, ref_t, ref_y)
                row.update(value=value, error=error)
            except (KeyError, ValueError, TypeError) as failure:
                row.update(status="failed", message=f"error measure: {failure}")
        elif is_reference and ref_y is not None:
            row.update(value=float(np.abs(ref_y).max()))
        rows.append(row)
    return rows


def _iterations(summary: dict) -> int | None:
    """Newton iterations of a run (static or dynamic): a machine-independent measure of work."""
    for key in ("dynamic", "static"):
        if key in summary:
            return summary[key].get("newton_iterations", summary[key].get("iterations"))
    return None


def _measure(plan: Plan, summary: dict, result: dict, ref_t, ref_y) -> tuple[float, float]:
    """(measured value, error) of one run."""
    if plan.measure == "static_tip":
        value = float(summary["static"]["sensors"][plan.sensor])
        return value, abs(value - plan.exact) / abs(plan.exact)
    t, y = np.asarray(result.get("t", [])), np.asarray(result.get("y", []))
    if t.size == 0:
        raise ValueError(f"the run wrote no time series of sensor {plan.sensor!r}")
    if plan.measure == "frequency":
        from runtime.app.signal import dominant_frequency

        keep = t >= plan.frequency_after
        value = dominant_frequency(t[keep], y[keep])
        return value, abs(value - plan.exact) / plan.exact
    if ref_y is None:
        raise ValueError("no reference run to compare with")
    scale = float(np.abs(ref_y).max())
    if scale == 0.0:
        raise ValueError(f"the reference run's sensor {plan.sensor!r} is zero throughout")
    difference = float(np.abs(np.interp(ref_t, t, y) - ref_y).max())
    return difference, difference / scale
