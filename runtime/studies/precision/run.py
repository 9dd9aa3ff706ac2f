"""``ancf bench precision`` from end to end: plan each problem, measure its runs, write the
CSV, the plot and the Markdown into the output folder (said before anything is written).
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from pathlib import Path

from runtime.studies import peers
from runtime.studies.precision import plan
from runtime.studies.precision.measure import measure
from runtime.studies.precision.report import markdown, plot, write_csv

#: Where the results go by default (under the current folder's results/).
DEFAULT_OUT = Path("results") / "precision"


def study(quick: bool = False, out: str | Path | None = None, repeats: int = 3,
          only: Sequence[str] | None = None, peer: bool = True,
          progress: bool = True) -> str:
    """Run the work-precision comparison; returns the Markdown (also in ``precision.md``).

    quick: the small subset (CI-fast); out: output folder (default DEFAULT_OUT); repeats:
    interleaved timed repeats per run (min and median kept); only: problem names to run
    (default all); peer: run Exudyn when installed (without it the peer is skipped and the
    output says so).
    """
    if repeats < 1:
        raise ValueError(f"--repeats: expected at least 1, got {repeats}")
    problems = plan.problems(quick)
    names = [p.name for p in problems]
    unknown = [name for name in only or () if name not in names]
    if unknown:
        raise ValueError(f"--problem: unknown {', '.join(unknown)}; known: {', '.join(names)}")
    problems = tuple(p for p in problems if not only or p.name in only)
    with_peer = peer and peers.exudyn_available()
    folder = Path(out) if out is not None else DEFAULT_OUT
    print(f"ancf bench precision: writing into {folder}/", flush=True)
    start = time.perf_counter()
    rows = []
    for problem in problems:
        rows += measure(problem, plan.configurations(problem, with_peer),
                        plan.references(problem, with_peer), repeats, progress)
    peer_words = (f"Exudyn {peers.exudyn_version()} ({peers.PEER_ELEMENT})" if with_peer else
                  "Exudyn skipped (not installed: pip install -e \".[peers]\")"
                  if not peers.exudyn_available() else "Exudyn skipped (asked)")
    header = (f"## Work precision: project against {peer_words}\n\n"
              f"{'Quick subset. ' if quick else ''}Simulate time: min of {repeats} interleaved "
              f"repeats (median in brackets); project: `summary.timing.simulate_s` of "
              f"`run_scene`, compiled engine; Exudyn: its solve alone. Errors: dynamic, max "
              f"over the output times of |tip - reference| over the reference's max |tip|, "
              f"each code against its own converged reference; elastica, max of the x and y "
              f"tip errors over L against the exact elastica. {len(rows)} runs in "
              f"{time.perf_counter() - start:.0f} s.")
    text = markdown(problems, rows, header)
    folder.mkdir(parents=True, exist_ok=True)
    write_csv(rows, folder / "precision.csv")
    plot(problems, rows, folder / "precision.png")
    (folder / "precision.md").write_text(text, encoding="utf-8")
    return text
