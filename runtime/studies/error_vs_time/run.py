"""An error-vs-time study from end to end: plan it, run every case (through
``runtime.studies.sweep``), measure the rows and write the outputs into the study folder.
"""

from __future__ import annotations

import itertools
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from runtime.model.errors import SceneError
from runtime.studies.error_vs_time.measure import (
    case_scene,
    check_scheduler,
    measured_rows,
    run_case,
)
from runtime.studies.error_vs_time.plan import StudyError, plan_study
from runtime.studies.error_vs_time.report import markdown, plot, write_csv
from runtime.studies.options import default_out as command_out
from runtime.studies.sweep import run_cases


def study(scene_path: str | Path, out_dir: str | Path | None = None, *,
          elements: Sequence[Any] | None = None, step: Sequence[Any] | None = None,
          integrator: Sequence[Any] | None = None, method: Sequence[Any] | None = None,
          backend: str | None = None, error: str | None = None, sensor: str | None = None,
          reference: dict | Sequence[Any] | None = None, t_end: float | None = None,
          repeat: int | None = None, targets: Sequence[Any] | None = None,
          scheduler: str | None = None, workers: int | None = None,
          serial: bool = False,
          on_start: Callable[[Path], None] | None = None) -> list[dict]:
    """Run the work-precision study of a scene; returns one row per run (CSV_COLUMNS; the
    reference run last, with role "reference").

    Overrides (None: from the ``[study]`` table, else from the scene) win over the table:
    elements (ints), step (s), integrator, method (lists), backend, error (a MEASURES),
    sensor (a sensor name), reference ({elements, step[, integrator, method]} or
    [elements, step]), t_end (s), repeat (runs per case), targets (accuracies of the summary).
    scheduler / workers / serial: see ``runtime.studies.sweep.run_cases``.  out_dir (default
    ``results/error-vs-time/<scene stem>``) receives error_vs_time.csv, .png and .md;
    ``on_start(out_dir)`` is called once the input is valid, before the first run.
    Raises StudyError / SceneError for invalid input and SchedulerError for an unreachable
    scheduler, all before any run starts.
    """
    start = time.perf_counter()
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int)
                                or workers <= 0):
        raise StudyError(f"--workers: expected a positive integer, got {workers!r}")
    plan = plan_study(scene_path, elements=elements, step=step, integrator=integrator,
                      method=method, backend=backend, error=error, sensor=sensor,
                      reference=reference, t_end=t_end, repeat=repeat, targets=targets)
    out = Path(out_dir) if out_dir is not None else default_out(plan.path)
    runs = list(itertools.product(plan.elements, plan.steps, plan.integrators, plan.methods))
    if plan.reference is not None:
        runs.append(plan.reference)
    cases = []
    for i, (n, h, integ, meth) in enumerate(runs):
        try:
            text = case_scene(plan, n, h, integ, meth).to_toml()
        except SceneError as scene_error:
            what = "the reference run" if plan.reference is not None and i == len(runs) - 1 \
                else "a run"
            raise StudyError(f"study: {what} with {n} elements is not a valid scene: "
                             f"{scene_error}") from None
        cases.append({"scene_text": text, "repeat": plan.repeat,
                      "series": None if plan.measure == "static_tip" else plan.sensor})
    if scheduler is not None:
        check_scheduler(scheduler)
    if on_start is not None:
        on_start(out)
    results = run_cases(run_case, cases, scheduler=scheduler, workers=workers, serial=serial,
                        label="error-vs-time study")
    rows = measured_rows(plan, runs, results)
    out.mkdir(parents=True, exist_ok=True)
    write_csv(rows, out / "error_vs_time.csv")
    plot(plan, rows, out / "error_vs_time.png")
    wall = time.perf_counter() - start
    where = f"dask at {scheduler}" if scheduler else "this process" if serial or \
        len(cases) == 1 else f"a local dask cluster ({workers or 'one per core'} workers)"
    (out / "error_vs_time.md").write_text(markdown(plan, rows, wall, where), encoding="utf-8")
    reference_row = rows[-1] if plan.reference is not None else None
    if reference_row is not None and reference_row["status"] != "ok":
        raise StudyError(f"study.reference: the reference run ({reference_row['elements']} "
                         f"elements, step {reference_row['step']!r} s) {reference_row['status']}"
                         f": {reference_row['message']} (outputs in {out})")
    return rows


def default_out(scene_path: str | Path) -> Path:
    """The default study folder: ``results/error-vs-time/<scene stem>``."""
    return command_out("error-vs-time", Path(scene_path).stem)
