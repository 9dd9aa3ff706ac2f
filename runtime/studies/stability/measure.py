"""Running the stability study: one case dispatched by name (module-level, so that dask can
ship it) and every case of ``plan.cases`` run through ``runtime.studies.sweep.run_cases``,
the results collected into rows in the order of the groups.
"""

from __future__ import annotations

from typing import Any

from runtime.studies.stability.integrators import (
    integrator_case,
    integrator_rows,
    slender_frequencies,
)
from runtime.studies.stability.kernel_accuracy import kernel_accuracy_case
from runtime.studies.stability.locking import chrono_beam_case, poisson_case
from runtime.studies.stability.newton import newton_case
from runtime.studies.stability.plan import GROUPS, Row, cases

CASE_FUNCTIONS = {
    "kernel": kernel_accuracy_case,
    "integrator": integrator_case,
    "newton": newton_case,
    "poisson": poisson_case,
    "chrono_beam": chrono_beam_case,
}


def run_case(study: str, **arguments: Any) -> dict | list[dict]:
    """Dispatch one case of the sweep (module-level, picklable): ``study`` names the case
    function (a key of ``CASE_FUNCTIONS``)."""
    return CASE_FUNCTIONS[study](**arguments)


def stability_study(scheduler: str | None = None, workers: int | None = None,
                    quick: bool = False, serial: bool = False) -> list[Row]:
    """Every case through ``runtime.studies.sweep.run_cases`` (dask: a local cluster of ``workers``
    processes, or the scheduler at ``scheduler``); ``quick``: a small subset (tests)."""
    from runtime.studies.sweep import run_cases

    todo = cases(quick)
    results = run_cases(run_case, todo, scheduler=scheduler, workers=workers, serial=serial,
                        label="stability study")
    rows: list[dict] = []
    integrator_results = []
    for case, result in zip(todo, results, strict=True):
        if case["study"] == "integrator":
            integrator_results.append(result)
        else:
            rows.extend(result)
    frequencies = None if quick else slender_frequencies()
    rows.extend(integrator_rows(integrator_results, frequencies))
    order = list(GROUPS)
    rows.sort(key=lambda r: order.index(r["group"]))   # stable: case order kept in a group
    return [Row(**r) for r in rows]
