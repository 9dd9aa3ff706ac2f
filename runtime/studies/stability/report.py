"""The stability study's outputs from its rows: the Markdown tables (one per group, each
with a one-line summary), the per-group counts, and stability.md, .json and .csv.
"""

from __future__ import annotations

import csv
import json
import math
from dataclasses import asdict, fields
from pathlib import Path

from runtime.studies.stability.plan import GROUPS, Row


def _number(value: float | None) -> str:
    if value is None:
        return "-"
    if isinstance(value, float) and not math.isfinite(value):
        return str(value)
    magnitude = abs(value)
    if magnitude != 0 and (magnitude < 1e-3 or magnitude >= 1e4):
        return f"{value:.2e}"
    return f"{value:.4g}"


def _result(row: Row) -> str:
    return {True: "pass", False: "**FAIL**", None: "info"}[row.passed]


def _criterion(row: Row) -> str:
    if row.tolerance is None:
        return "-"
    return f"{row.compare} {_number(row.tolerance)}"


def _cell(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")


def summary(rows: list[Row]) -> dict[str, dict]:
    """Per group: rows, passed, failed, informational, and the failing methods' counts."""
    out: dict[str, dict] = {}
    for row in rows:
        entry = out.setdefault(row.group, {"rows": 0, "passed": 0, "failed": 0,
                                           "informational": 0, "failing": {}})
        entry["rows"] += 1
        key = {True: "passed", False: "failed", None: "informational"}[row.passed]
        entry[key] += 1
        if row.passed is False:
            entry["failing"][row.method] = entry["failing"].get(row.method, 0) + 1
    return out


def _headline(group: str, rows: list[Row], entry: dict) -> str:
    text = (f"{entry['rows']} rows: {entry['passed']} pass, {entry['failed']} fail, "
            f"{entry['informational']} informational")
    if entry["failing"]:
        text += " (failing: " + ", ".join(f"{m} x{n}" for m, n in entry["failing"].items()) + ")"
    if group == "kernel_accuracy":
        gram = [r for r in rows if r.method == "gram"]
        if gram:
            worst = max(r.measured for r in gram)
            verdict = "passes every row" if all(r.passed for r in gram) else "FAILS some rows"
            text += f". Default method gram {verdict}; worst error {worst:.1e}"
    return text + "."


def markdown(rows: list[Row], wall_s: float | None = None) -> str:
    """The study as Markdown: one table per group, each with a one-line summary."""
    counts = summary(rows)
    lines = ["# Numerical stability study", ""]
    total = sum(c["failed"] for c in counts.values())
    head = (f"{len(rows)} rows, {total} failing; every failing row states its cause. "
            f"Criterion: `<=` the measured value must not exceed the tolerance, `>=` must "
            f"reach it, `|x| <=` in magnitude; `info`: informational.")
    if wall_s is not None:
        head += f" Study wall time {wall_s:.1f} s."
    lines += [head, ""]
    for group, title in GROUPS.items():
        selected = [r for r in rows if r.group == group]
        if not selected:
            continue
        lines += [f"## {title}", "", _headline(group, selected, counts[group]), "",
                  "| case | method | measured | criterion | result | detail | cause |",
                  "| --- | --- | --- | --- | --- | --- | --- |"]
        for r in selected:
            lines.append(f"| {_cell(r.case)} | {_cell(r.method)} | {_number(r.measured)} | "
                         f"{_criterion(r)} | {_result(r)} | {_cell(r.detail)} | "
                         f"{_cell(r.cause)} |")
        lines.append("")
    return "\n".join(lines)


def _finite(value):
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def write(rows: list[Row], out_dir: str | Path, wall_s: float | None = None) -> dict[str, Path]:
    """Write stability.md, stability.json and stability.csv into ``out_dir``; their paths."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = {"md": out / "stability.md", "json": out / "stability.json",
             "csv": out / "stability.csv"}
    paths["md"].write_text(markdown(rows, wall_s) + "\n")
    records = [{k: _finite(v) for k, v in asdict(r).items()} for r in rows]
    paths["json"].write_text(json.dumps({"wall_s": wall_s, "summary": summary(rows),
                                         "rows": records}, indent=1) + "\n")
    names = [f.name for f in fields(Row)]
    with paths["csv"].open("w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=names)
        writer.writeheader()
        writer.writerows(asdict(r) for r in rows)
    return paths
