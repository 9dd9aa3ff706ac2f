"""The outputs of ``ancf bench precision``: ``precision.csv`` (every run), ``precision.png``
(error against simulate time, log-log, a panel per problem, one marker set per code), and
the Markdown: for each problem and target the fastest configuration of each code reaching
it and the ratio of their times, the distance between the references, and which element
and how many elements to use for an accuracy.
"""

from __future__ import annotations

import csv
import math
from pathlib import Path

from runtime.studies.precision.plan import CODES, TARGETS, Problem

CSV_COLUMNS = ("problem", "code", "kind", "elements", "step", "integrator", "newton",
               "load_steps", "role", "status", "error", "simulate_min_s", "simulate_median_s",
               "repeats", "newton_iterations", "message")
#: Marker of each code in the plot (colours tell the element kinds apart).
MARKERS = {"project": "o", "exudyn": "x"}


def write_csv(rows: list[dict], path: Path) -> None:
    """precision.csv: one row per run (CSV_COLUMNS); a reference row's ``error`` is its
    distance to the other code's reference (dynamic) or to the exact elastica (static)."""
    with path.open("w", newline="", encoding="utf-8") as f:
        writer = csv.DictWriter(f, CSV_COLUMNS)
        writer.writeheader()
        writer.writerows(rows)


def _usable(rows: list[dict]) -> list[dict]:
    return [r for r in rows if r["role"] == "sweep" and r["status"] == "ok"
            and math.isfinite(r["error"]) and math.isfinite(r["simulate_min_s"])]


def fastest(rows: list[dict], code: str, target: float) -> dict | None:
    """The sweep run of ``code`` that reaches ``target`` in the least simulate time."""
    reaching = [r for r in _usable(rows) if r["code"] == code and r["error"] <= target]
    return min(reaching, key=lambda r: r["simulate_min_s"]) if reaching else None


def describe(row: dict) -> str:
    """A run's configuration in words."""
    how = (f"{row['load_steps']} load steps" if row["load_steps"] is not None
           else f"h {row['step']:g} s, {row['integrator']}")
    return f"{row['kind']} x {row['elements']}, {how}, {row['newton']} Newton"


def _time(row: dict) -> str:
    return f"{row['simulate_min_s']:.3g} s (median {row['simulate_median_s']:.3g})"


def target_table(problem: Problem, rows: list[dict]) -> list[str]:
    """Markdown rows: per target the fastest run of each code reaching it, the ratio."""
    lines = []
    for target in TARGETS:
        best = {code: fastest(rows, code, target) for code in CODES}
        cells = [f"{describe(r)}: {_time(r)}, error {r['error']:.2g}" if r else "not reached"
                 for r in best.values()]
        ours, peer = best["project"], best["exudyn"]
        ratio = f"{ours['simulate_min_s'] / peer['simulate_min_s']:.3g}" if ours and peer else "-"
        lines.append(f"| {problem.name} | {target:g} | {cells[0]} | {cells[1]} | {ratio} |")
    return lines


def reference_lines(problem: Problem, rows: list[dict]) -> list[str]:
    """Sentences on the references of a problem and how far apart they are."""
    refs = [r for r in rows if r["role"] == "reference"]
    if problem.static:
        return [f"- {problem.name}: the finest run of {r['code']} ({describe(r)}) is "
                f"{r['error']:.2g} L from the exact elastica." for r in refs
                if r["status"] == "ok"] or [f"- {problem.name}: no finest run succeeded."]
    words = "; ".join(f"{r['code']}: {describe(r)} ({r['status']})" for r in refs)
    line = f"- {problem.name}: references (one per code and model) {words}."
    for r in refs:
        if r["code"] == "project" and math.isfinite(r["error"]):
            verdict = ("they agree to 1e-4" if r["error"] <= 1e-4 else "they differ by more "
                       "than 1e-4: the two models, not only their discretisations, differ")
            line += (f" Distance between them ({r['kind']} against the peer's): "
                     f"{r['error']:.2g} of the reference's max |value|; {verdict}.")
    return [line]


def advice(problems: tuple[Problem, ...], rows: list[dict]) -> list[str]:
    """'Which element and how many for my accuracy': the fastest project run per target,
    for the problems from shipped scenes."""
    lines = []
    for problem in problems:
        if problem.static:
            continue
        picks = []
        for target in TARGETS:
            r = fastest([r for r in rows if r["problem"] == problem.name], "project", target)
            picks.append(f"{target:g}: {describe(r)} ({r['simulate_min_s']:.3g} s)" if r
                         else f"{target:g}: not reached by the sweep")
        lines.append(f"- `scenes/{problem.scene}.toml`: " + "; ".join(picks) + ".")
    return lines


def markdown(problems: tuple[Problem, ...], rows: list[dict], header: str) -> str:
    """The whole Markdown: header, target table, references, advice."""
    lines = [header, "",
             "| problem | target | project: fastest reaching it | Exudyn: fastest reaching it "
             "| project / Exudyn |", "|---|---:|---|---|---:|"]
    for problem in problems:
        lines += target_table(problem, [r for r in rows if r["problem"] == problem.name])
    lines += ["", "References:", ""]
    for problem in problems:
        lines += reference_lines(problem, [r for r in rows if r["problem"] == problem.name])
    lines += ["", "Which element and how many for an accuracy (the fastest project run):", ""]
    lines += advice(problems, rows)
    return "\n".join(lines) + "\n"


def plot(problems: tuple[Problem, ...], rows: list[dict], path: Path) -> None:
    """precision.png: error against simulate time (min of the repeats), log-log, a panel
    per problem, one marker per code, the targets dashed."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.ticker import NullFormatter

    fig = Figure(figsize=(5.0 * len(problems), 4.6))
    FigureCanvasAgg(fig)
    for k, problem in enumerate(problems):
        ax = fig.add_subplot(1, len(problems), k + 1)
        points = _usable([r for r in rows if r["problem"] == problem.name])
        kinds = list(dict.fromkeys((r["code"], r["kind"]) for r in points))
        for i, (code, kind) in enumerate(kinds):
            mine = [r for r in points if (r["code"], r["kind"]) == (code, kind)]
            ax.loglog([r["simulate_min_s"] for r in mine], [r["error"] for r in mine],
                      MARKERS[code], color=f"C{i % 10}", ms=4, alpha=0.6,
                      label=f"{code} {kind}")
        for target in TARGETS:
            ax.axhline(target, color="grey", lw=0.7, ls="--")
        ax.set_title(problem.title, fontsize=8)
        ax.set_xlabel("simulate time (s, min of repeats)")
        ax.set_ylabel("error" if problem.static else "error (max over outputs, relative)")
        ax.grid(True, which="both", alpha=0.3)
        ax.xaxis.set_minor_formatter(NullFormatter())   # decade labels only: no overlaps
        if points:
            ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
