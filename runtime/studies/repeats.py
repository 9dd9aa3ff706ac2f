"""Timed repeats of benchmark runs, interleaved: every run once, round after round, so that a
shared machine's slow spells spread over all the runs instead of falling on one (``ancf bench
solvers``, ``ancf bench precision``).  Only the minimum and the median of a run's times are
reported.
"""

from __future__ import annotations

import math
import statistics
from collections.abc import Callable, Sequence
from typing import Any

from runtime.progress import Bar, enabled

#: A prepared run: called, it runs once and returns (seconds, what it computed); seconds NaN
#: says it failed, and a failed run is not repeated.
Run = Callable[[], tuple[float, Any]]


def interleave(runs: Sequence[tuple[str, Run]], repeats: int, title: str,
               progress: bool = True) -> list[tuple[list[float], Any]]:
    """Run each (label, run) ``repeats`` times, round after round; returns per run its
    times (s, one per repeat done) and what its last repeat computed."""
    times: list[list[float]] = [[] for _ in runs]
    values: list[Any] = [None] * len(runs)
    with enabled(progress), Bar(title, repeats * len(runs), "runs") as bar:
        for _ in range(repeats):
            for i, (label, run) in enumerate(runs):
                if times[i] and math.isnan(times[i][-1]):
                    bar.advance(f"{label}: failed, not repeated")
                    continue
                seconds, values[i] = run()
                times[i].append(seconds)
                bar.advance(f"{label} {seconds:.3f} s")
    return list(zip(times, values, strict=True))


def best(times: Sequence[float]) -> tuple[float, float]:
    """(min, median) of a run's times; NaN for a run that failed or never ran."""
    if not times or any(math.isnan(t) for t in times):
        return math.nan, math.nan
    return min(times), statistics.median(times)
