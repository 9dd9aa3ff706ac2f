"""The outputs of an error-vs-time study from its measured rows: ``error_vs_time.csv``,
the work-precision plot ``error_vs_time.png`` and ``error_vs_time.md`` (the table and the
paragraph on which choice is cheapest for a given accuracy).
"""

from __future__ import annotations

import csv
import itertools
import math
from pathlib import Path
from typing import Any

from runtime.studies.error_vs_time.plan import Plan

CSV_COLUMNS = ("elements", "step", "integrator", "method", "backend", "error", "simulate_s",
               "total_s", "status", "measure", "value", "exact", "newton_iterations", "role",
               "message")
ANNOTATE_ALL = 30       # annotate every point of the plot up to this many
CLOSE = 1.1             # times within this factor of the best are called a tie


def write_csv(rows: list[dict], path: Path) -> None:
    """error_vs_time.csv: CSV_COLUMNS, numbers with repr precision, absent values empty."""
    with path.open("w", newline="", encoding="utf-8") as f:
        writer = csv.writer(f, lineterminator="\n")
        writer.writerow(CSV_COLUMNS)
        for row in rows:
            writer.writerow(["" if row[c] is None or (isinstance(row[c], float)
                                                      and math.isnan(row[c])) else row[c]
                             for c in CSV_COLUMNS])



def _label(row: dict, plan: Plan) -> str:
    """The line a run belongs to: its method, and its integrator when several are swept."""
    if len(plan.integrators) > 1:
        return f"{row['method']} / {row['integrator']}"
    return row["method"]


def _lines(rows: list[dict], plan: Plan) -> list[str]:
    """The lines of the sweep's runs (``_label``), in the order of the runs."""
    return list(dict.fromkeys(_label(r, plan) for r in rows if r["role"] == "sweep"))


def _point(row: dict) -> str:
    return f"{row['elements']}" if row["step"] is None else f"{row['elements']}, {row['step']:g}"


def _usable(rows: list[dict]) -> list[dict]:
    return [r for r in rows if r["role"] == "sweep" and r["status"] == "ok"
            and math.isfinite(r["error"]) and r["error"] > 0 and r["simulate_s"] > 0]


def _front(points: list[dict]) -> list[dict]:
    """Runs not beaten by a faster run with a smaller error (sorted by time)."""
    best, front = math.inf, []
    for row in sorted(points, key=lambda r: (r["simulate_s"], r["error"])):
        if row["error"] < best:
            front.append(row)
            best = row["error"]
    return front


def _describe_measure(plan: Plan) -> str:
    if plan.measure == "static_tip":
        c = plan.cantilever
        return (f"relative error of the static tip displacement (sensor `{plan.sensor}`) "
                f"against P L^3 / 3EI = {abs(plan.exact):.6g} m (P = {c.load:g} N, "
                f"L = {c.length:g} m, I = {c.inertia:.6g} m^4)")
    if plan.measure == "frequency":
        return (f"relative error of the response frequency of sensor `{plan.sensor}` after "
                f"t = {plan.frequency_after:g} s (sinusoid fit, not timed) against "
                f"1.8751^2 sqrt(EI / (rho A L^4)) = {plan.exact:.6g} rad/s")
    n, h, integ, meth = plan.reference
    return (f"max |difference| of sensor `{plan.sensor}` over 0..{plan.t_end:g} s against a "
            f"reference run ({n} elements, step {h:g} s, {integ}, {meth}), divided by the "
            "reference's max |value|")


def plot(plan: Plan, rows: list[dict], path: Path) -> None:
    """error_vs_time.png: log-log error against simulate time, one line (the runs no faster
    run beats) per method (and integrator); points annotated with elements[, step] (every
    point up to ANNOTATE_ALL points, else the points on the lines; the points on the lines
    first), each label beside its point where it overlaps no other label, else left out."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(9.5, 5.6))
    canvas = FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    usable = _usable(rows)
    annotate_all = len(usable) <= ANNOTATE_ALL
    labels = _lines(rows, plan)
    markers = "osD^vP*X"
    fronts, others = [], []    # (row, colour) to label: points on the lines first
    for k, label in enumerate(labels):
        points = [r for r in usable if _label(r, plan) == label]
        if not points:
            continue
        color = f"C{k % 10}"
        ax.loglog([r["simulate_s"] for r in points], [r["error"] for r in points],
                  markers[k % len(markers)], color=color, alpha=0.5, ms=5)
        front = _front(points)
        ax.loglog([r["simulate_s"] for r in front], [r["error"] for r in front], "-",
                  marker=markers[k % len(markers)], color=color, lw=1.4, ms=5, label=label)
        fronts += [(r, color) for r in front]
        if annotate_all:
            others += [(r, color) for r in points if r not in front]
    ax.set_xlabel("simulate time (s)")
    ax.set_ylabel(f"error ({plan.measure})")
    title = plan.scene.title if len(plan.scene.title) < 60 else plan.scene.title[:57] + "..."
    ax.set_title(f"{title}\n{plan.measure} error against run time; labels: elements"
                 f"{'' if plan.measure == 'static_tip' else ', step (s)'}"
                 f"{'' if annotate_all else ' (points on the lines)'}", fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    if usable:
        _label_ticks(ax.xaxis, [r["simulate_s"] for r in usable])
        _label_ticks(ax.yaxis, [r["error"] for r in usable])
        ax.legend(fontsize=8, title="line: best error\nfor the time", title_fontsize=7,
                  loc="upper left", bbox_to_anchor=(1.01, 1.0))
    else:
        ax.text(0.5, 0.5, "no run with a finite error", transform=ax.transAxes, ha="center")
    fig.subplots_adjust(left=0.09, right=0.75, bottom=0.1, top=0.89)
    canvas.draw()  # final limits and layout: label boxes in pixels from here on
    renderer = canvas.get_renderer()
    placed = []    # pixel boxes of the labels kept
    # right-above, right-below, left-above, left-below of the point (points, alignment)
    spots = [((4, 3), "left", "bottom"), ((4, -3), "left", "top"),
             ((-4, 3), "right", "bottom"), ((-4, -3), "right", "top")]
    for row, color in fronts + others:
        for offset, ha, va in spots:
            note = ax.annotate(_point(row), (row["simulate_s"], row["error"]),
                               textcoords="offset points", xytext=offset, ha=ha, va=va,
                               fontsize=6, color=color)
            box = note.get_window_extent(renderer)
            if not any(box.overlaps(other) for other in placed):
                placed.append(box)
                break
            note.remove()
    fig.savefig(path, dpi=110)


def _log_ticks(low: float, high: float) -> list[float]:
    """Labelled ticks of a log axis holding [low, high] (> 0) between its first and last:
    1-2-5 steps, or decades beyond three decades; at least two."""
    steps = (1,) if high / low > 1e3 else (1, 2, 5)
    k0, k1 = math.floor(math.log10(low)) - 1, math.ceil(math.log10(high)) + 1
    candidates = [m * 10.0**k for k in range(k0, k1 + 1) for m in steps]
    first = max(i for i, t in enumerate(candidates) if t <= low * (1 + 1e-12))
    last = min(i for i, t in enumerate(candidates) if t >= high * (1 - 1e-12))
    if first == last:
        first, last = first - 1, last + 1
    return candidates[first:last + 1]


def _label_ticks(axis: Any, values: list[float]) -> None:
    """Put the limits of a log ``axis`` on labelled ticks holding every value."""
    from matplotlib.ticker import NullFormatter

    ticks = _log_ticks(min(values), max(values))
    axis.axes.autoscale(False, axis=axis.axis_name)
    axis.set_view_interval(ticks[0], ticks[-1], ignore=True)
    axis.set_ticks(ticks, labels=[f"{t:g}" for t in ticks])
    axis.set_minor_formatter(NullFormatter())


def default_targets(rows: list[dict]) -> list[float]:
    """Accuracy levels of the summary: the finest four of 1e-k and 3e-k between the smallest
    and the largest error, or the level just above every error."""
    errors = [r["error"] for r in _usable(rows)]
    if not errors:
        return []
    low, high = min(errors), max(errors)
    levels = [m * 10.0**k for k in range(math.ceil(math.log10(high)), -17, -1) for m in (3, 1)]
    inside = [t for t in levels if low <= t < high]
    return inside[-4:] if inside else [min(t for t in levels if t >= high)]


def _run_words(row: dict, plan: Plan) -> str:
    words = f"{row['method']} with {row['elements']} elements"
    if row["step"] is not None:
        words += f", step {row['step']:g} s, {row['integrator']}"
    return words


def _join(words: list[str]) -> str:
    """'a', 'a and b', 'a, b and c'."""
    return words[0] if len(words) == 1 else ", ".join(words[:-1]) + " and " + words[-1]


def _level(target: float) -> str:
    """An accuracy level as 3e-2, 1e-3, 2.5e-4."""
    mantissa, exponent = f"{target:.1e}".split("e")
    return f"{mantissa.rstrip('0').rstrip('.')}e{int(exponent)}"


def summary_paragraph(plan: Plan, rows: list[dict]) -> str:
    """One paragraph: for each accuracy target, the run that reaches it at the least
    simulate time and its speed-up over the best run of the slowest line reaching it."""
    usable = _usable(rows)
    if not usable:
        return "No run produced a finite error, so no choice can be recommended."
    targets = plan.targets or default_targets(rows)
    labels = _lines(rows, plan)
    findings: list[tuple[float, str]] = []     # (target, what holds at that accuracy)
    wins: dict[str, int] = {}
    for target in targets:
        reaching = [r for r in usable if r["error"] <= target]
        if not reaching:
            findings.append((target, "no run reaches it"))
            continue
        best = min(reaching, key=lambda r: r["simulate_s"])
        fastest: dict[str, float] = {}
        for r in reaching:
            label = _label(r, plan)
            fastest[label] = min(fastest.get(label, math.inf), r["simulate_s"])
        slowest = max(fastest, key=fastest.get)
        wins[_label(best, plan)] = wins.get(_label(best, plan), 0) + 1
        text = (f"the cheapest run is {_run_words(best, plan)} ({best['simulate_s']:.3g} s, "
                f"error {best['error']:.2g})")
        if slowest != _label(best, plan):
            text += (f", {fastest[slowest] / best['simulate_s']:.1f}x faster than the "
                     f"cheapest {slowest} run ({fastest[slowest]:.3g} s)")
        elif len(fastest) == 1 and len(labels) > 1:
            text += f", the only {'line' if len(plan.integrators) > 1 else 'method'} to reach it"
        missing = [label for label in labels if label not in fastest]
        if missing and len(fastest) > 1:
            text += f" ({', '.join(missing)} never reach it)"
        close = [f"{label} ({t:.3g} s)" for label, t in sorted(fastest.items(), key=lambda x: x[1])
                 if label != _label(best, plan) and t <= CLOSE * best["simulate_s"]]
        if close:
            text += (f"; {_join(close)} {'is' if len(close) == 1 else 'are'} within "
                     f"{round(100 * (CLOSE - 1))} %, a tie within timing noise")
        findings.append((target, text))
    sentences = []
    for text, group in itertools.groupby(findings, key=lambda finding: finding[1]):
        levels = [_level(target) for target, _ in group]
        if len(levels) == 1:
            sentences.append(f"for an error of {levels[0]} {text}")
        else:
            sentences.append(f"for errors of {_join(levels)} {text}")
    paragraph = "; ".join(sentences)
    paragraph = paragraph[0].upper() + paragraph[1:] + "."
    if wins:
        leader = max(wins, key=wins.get)
        reached = sum(1 for t in targets if any(r["error"] <= t for r in usable))
        paragraph += (f" Overall, {leader} is the cheapest choice at {wins[leader]} of "
                      f"{reached} accuracy level{'s' if reached != 1 else ''} reached.")
    return paragraph


def _cell(value: Any, spec: str = ".3g") -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "-"
    return format(value, spec) if isinstance(value, float) else str(value)


def markdown(plan: Plan, rows: list[dict], wall: float, where: str) -> str:
    """error_vs_time.md: what was measured, the table of runs and the summary paragraph."""
    ok = sum(1 for r in rows if r["role"] == "sweep" and r["status"] == "ok")
    sweep = sum(1 for r in rows if r["role"] == "sweep")
    lines = [f"# Error against run time: {plan.scene.title}", "",
             f"Scene `{plan.path}`; error: {_describe_measure(plan)}. {sweep} runs ({ok} ok)"
             f"{' plus the reference run' if plan.reference else ''}, backend {plan.backend}"
             f"{f', best of {plan.repeat} repeats' if plan.repeat > 1 else ''}; run in {where}, "
             f"study wall time {wall:.1f} s. Times: `simulate_s` is the analyses alone, "
             "`total_s` the whole run (kernel loading and plots included).", ""]
    lines += [f"Note: {note}." for note in plan.notes]
    if plan.notes:
        lines.append("")
    value_head = {"static_tip": "tip (m)", "frequency": "frequency (rad/s)",
                  "reference": "max diff"}[plan.measure]
    lines += [f"| elements | step (s) | integrator | method | {value_head} | error | "
              "Newton iterations | simulate (s) | total (s) | status |",
              "| ---: | ---: | --- | --- | ---: | ---: | ---: | ---: | ---: | --- |"]
    order = sorted(rows, key=lambda r: (r["role"] != "sweep", r["method"], r["integrator"] or "",
                                        r["elements"], -(r["step"] or 0.0)))
    for r in order:
        status = r["status"] if r["role"] == "sweep" else f"reference ({r['status']})"
        if r["status"] != "ok" and r["message"]:
            status += f": {r['message'].splitlines()[0][:80]}"
        lines.append(f"| {r['elements']} | {_cell(r['step'], 'g')} | {_cell(r['integrator'])} "
                     f"| {r['method']} | {_cell(r['value'], '.6g')} | {_cell(r['error'], '.3e')}"
                     f" | {_cell(r['newton_iterations'])} | {_cell(r['simulate_s'])} "
                     f"| {_cell(r['total_s'])} | {status} |")
    lines += ["", "## Summary", "", summary_paragraph(plan, rows), ""]
    return "\n".join(lines)
