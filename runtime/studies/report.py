"""``ancf report``: measure everything on this machine and write ``docs/report.md``.

The page is generated, never edited by hand: kernel costs, invariants, the paper's Tables I
and II, the shipped scenes, the cost of a step against model size, the work-precision
studies and the stability table, with the machine and the date.
"""

from __future__ import annotations

import datetime
import os
import platform
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import scipy
import sympy

import scenes
from runtime.app.run import run
from runtime.catalog import METHODS, NEWTON_MODES, generated_kinds
from runtime.kernels import naming
from runtime.kernels.kind import element_kind
from runtime.studies import bench_kernels as bench
from runtime.studies import bench_solvers, bench_steps, error_vs_time, paper, precision, stability
from runtime.studies import invariant_comparison as invariant_report

#: the shipped scenes run for section 4
SCENES = tuple(scenes.names())
#: the scenes of section 4 in ``--quick`` (a smoke test of the page: a dynamic beam, a
#: rotating one, a mechanism with rigid bodies and joints and a static analysis; every
#: shipped scene is run in the tests anyway)
QUICK_SCENES = ("cantilever", "rotating_beam", "slider_crank_2d", "deep_arch")


def machine() -> str:
    """One paragraph describing this machine and software."""
    cpu = platform.processor() or platform.machine()
    cpuinfo = Path("/proc/cpuinfo")
    if cpuinfo.exists():
        for line in cpuinfo.read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    memory = ""
    meminfo = Path("/proc/meminfo")
    if meminfo.exists():
        kib = int(meminfo.read_text().split()[1])
        memory = f", {kib / 2**20:.0f} GiB memory"
    try:
        compiler = subprocess.run([os.environ.get("CC", "gcc"), "--version"], capture_output=True,
                                  text=True, check=False).stdout.splitlines()[0]
    except (OSError, IndexError):
        compiler = "no C compiler"
    return (f"{cpu}, {os.cpu_count()} cores{memory}; {platform.system()} {platform.release()}; "
            f"Python {platform.python_version()}, NumPy {np.__version__}, SciPy "
            f"{scipy.__version__}, SymPy {sympy.__version__}; {compiler} with "
            f"`{' '.join(naming.COMPILE_FLAGS)}` (pre-processing families at "
            f"`{naming.compile_flags(0)[0]}`: element.json `optimization`).")


def _scenes(out: Path, figures: Path, names: tuple[str, ...] = SCENES,
            warm: bool = True) -> str:
    """Section 4: the shipped scenes ``names`` run (after a warm-up run when ``warm``:
    kernels compiled and imports done before the timed run)."""
    lines = ["| scene | status | key results | steps | Newton iterations | compile s | "
             "pre-processing s | simulation s | post-processing s | total s |",
             "|---|---|---|---:|---:|---:|---:|---:|---:|---:|"]
    for name in names:
        folder = out / "scenes" / name
        if warm:
            run(scenes.path(name), folder, quiet=True)  # kernels compiled, imports done
        summary, _ = run(scenes.path(name), folder, quiet=True)
        key = []
        if "static" in summary:
            key += [f"static {k} = {v:.5g}" for k, v in summary["static"]["sensors"].items()
                    if "energy" not in k]
        if "modal" in summary:
            key.append(f"omega1 = {summary['modal']['frequencies_rad_s'][0]:.4g} rad/s")
        dyn = summary.get("dynamic", {})
        if "response_frequency_rad_s" in dyn:
            key.append(f"response {dyn['response_frequency_rad_s']:.4g} rad/s")
        if "static" not in summary and dyn:
            key += [f"final {k} = {v:.4g}" for k, v in dyn["sensors_final"].items()]
        timing = summary["timing"]
        lines.append(
            f"| {name} | {summary['status']} | {'; '.join(key)} | {dyn.get('steps', '-')} | "
            f"{dyn.get('newton_iterations', '-')} | {timing['compile_s']:.2f} | "
            f"{timing['preprocess_s']:.3f} | {timing['simulate_s']:.2f} | "
            f"{timing.get('postprocess_s', 0):.2f} | {timing['total_s']:.2f} |")
        for png in folder.glob("*.png"):
            shutil.copy(png, figures / f"{name}_{png.name}")
    return "\n".join(lines) + "\n"


def build(out_dir: str | Path = "docs", quick: bool = False, scheduler: str | None = None,
          workers: int | None = None) -> Path:
    """Run every measurement and write ``<out_dir>/report.md`` (figures in ``figures/``).
    ``quick``: the small versions (a smoke test of the page), their sweeps in this process
    unless a ``scheduler`` is given, and each kernel figure timed for a tenth of the budget."""
    start = time.perf_counter()
    serial = quick and scheduler is None
    out = Path(out_dir)
    figures = out / "figures"
    figures.mkdir(parents=True, exist_ok=True)
    work = out / "runs"
    date = datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M UTC")
    parts = [
        "# Measured on this machine", "",
        f"Generated by `ancf report{' --quick' if quick else ''}` on {date}. Machine: "
        f"{machine()}", "",
        "Every number below was measured by the command named in its section; nothing is "
        "copied by hand. Timings are wall-clock seconds on a machine that may run other work.",
        "",
        "## 1. Kernel cost per element (`ancf bench kernels`)", "",
        bench.run(["beam3d"] if quick else None, batch=1000 if quick else 10_000,
                  budget_s=0.02 if quick else 0.2),
        "## 2. Closed-form against quadrature invariants (`ancf invariants`)", "",
    ]
    for kind, reference in ([("beam3d", "straight")] if quick else
                            [(kind, reference) for kind in generated_kinds()
                             for reference in ("straight", "curved")
                             if reference == "straight"
                             or "general" in element_kind(kind).energy.variants]):
        parts.append(invariant_report.report(invariant_report.compare(kind, reference)))
    results = paper.bench_paper(quick, scheduler, workers, serial=serial)
    paper.write(results, work / "paper")
    parts += ["## 3. The paper's Tables I and II (`ancf bench paper`)", "",
              "With invariants: `gram` (this project's compressed form) and `cij` (the "
              "paper's); without: `quadrature`. The ratio column is quadrature total over the "
              "method's total, the paper's in parentheses. Simulation times here include the "
              "integrator's own work (Newton loop, banded solves), which does not depend on "
              "the method; the `in kernels` column isolates the element forces and Jacobians.",
              "", paper.markdown(results)]
    scene_names = QUICK_SCENES if quick else SCENES
    parts += ["## 4. Shipped scenes (`ancf run`)", "",
              _scenes(work, figures, scene_names, warm=not quick),
              "![rotating beam tip](figures/rotating_beam_tip_transverse.png)", "",
              "![rotating beam energies](figures/rotating_beam_energies.png)", ""]
    parts += ["## 5. Whole runs and the cost of a step: engines, Newton modes, Exudyn "
              "(`ancf bench solvers`)", "",
              "Simulate time of the dynamic analysis alone (models built and the stepper "
              "compiled before), min and median of interleaved repeats in this process; "
              "`/ Exudyn modified` divides by Exudyn's default (modified Newton) on the same "
              "problem. Exudyn's elements are the closest it has, not ours: see "
              "`runtime/studies/peers.py`.", "",
              _demote(bench_solvers.run(quick=quick, repeats=1 if quick else 3,
                                        progress=False), 1)]
    parts += ["## 6. Error against run time (`ancf study error-vs-time`)", ""]
    parts += _error_vs_time(work, figures, quick, scheduler, workers, serial)
    parts += ["## 7. Stability on stiff and extreme cases (`ancf study stability`)", ""]
    rows = stability.stability_study(scheduler=scheduler, workers=workers, quick=quick,
                                     serial=serial)
    stability.write(rows, work / "stability")
    parts.append(_failures(rows))
    parts.append(_demote(stability.markdown(rows), 2))
    parts += ["## 8. Fastest to a given accuracy, beside Exudyn (`ancf bench precision`)", "",
              _demote(precision.study(quick, work / "precision", repeats=1 if quick else 3,
                                      progress=False), 1),
              "![work precision](figures/precision.png)", ""]
    shutil.copyfile(work / "precision" / "precision.png", figures / "precision.png")
    parts += step_scaling(figures, quick)
    parts.append(f"\nReport generated in {time.perf_counter() - start:.0f} s.\n")
    path = out / "report.md"
    path.write_text("\n".join(parts))
    return path


def step_scaling(figures: Path, quick: bool = False) -> list[str]:
    """Section 9: the cost of a step against model size per body type and Newton mode, with
    the linear solver each model chose (``ancf bench steps``), its table and its plot
    ``figures/step_scaling.png``; dated, so that it can be measured on its own."""
    cases = bench_steps.plan(
        plates=(2, 4) if quick else (4, 8, 16, 32, 64), chains=(10,) if quick else
        (1000, 10_000), solvers=(bench_steps.AUTO,), newtons=NEWTON_MODES,
        joints=(3,) if quick else (50, 200), blocks=(1,) if quick else (2, 4))
    rows = bench_steps.measure(cases, repeats=1 if quick else 2, progress=False)
    bench_steps.plot(rows, figures / "step_scaling.png")
    date = datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M UTC")
    return ["## 9. The cost of a step against model size (`ancf bench steps`)", "",
            f"Measured on {date}: each model with the linear solver it chooses, every Newton "
            "mode, min of the repeats; the constraint share of a KKT step (many joints) is "
            "measured against the same links without joints (`free links`), per step and per "
            "Newton iteration (the free links fall in one iteration a step, the swinging "
            "chain takes more whatever handles its joints).", "",
            bench_steps.table(rows), "![cost per element-step](figures/step_scaling.png)", ""]


def _demote(markdown: str, levels: int) -> str:
    """Push the headings of an embedded Markdown document ``levels`` levels down."""
    return "\n".join("#" * levels + line if line.startswith("#") else line
                     for line in markdown.splitlines()) + "\n"


def _failures(rows) -> str:
    """The failing rows of the stability table grouped by cause, with their counts."""
    failing: dict[tuple[str, str, str], list] = {}
    for row in rows:
        if row.passed is False:
            # same cause up to its numbers: one line
            key = (row.group, row.method, re.sub(r"[-+]?\d[\d.e+-]*", "#", row.cause))
            failing.setdefault(key, []).append(row)
    if not failing:
        return "Every row passes its stated tolerance.\n"
    lines = [f"{sum(len(v) for v in failing.values())} of {len(rows)} rows fail their "
             "stated tolerance; grouped by cause (every row is in the tables below):", ""]
    for (group, method, _), cases in sorted(failing.items()):
        names = [c.case for c in cases]
        shown = ", ".join(names[:3]) + (f" and {len(names) - 3} more" if len(names) > 3 else "")
        lines.append(f"- **{group}**, {method}, {len(cases)} row(s) ({shown}): "
                     f"{cases[0].cause}")
    return "\n".join(lines) + "\n"


def _error_vs_time(work: Path, figures: Path, quick: bool, scheduler, workers,
                   serial: bool = False) -> list[str]:
    """The work-precision studies of the cantilever and the rotating beam."""
    parts = []
    # (label, scene, sweep overrides of the scene's [study] table)
    studies = [("cantilever_static", "cantilever",
                {"error": "static_tip", "elements": [2, 3] if quick else [2, 5, 10, 20, 40],
                 "method": ["gram"] if quick else list(METHODS)})]
    if not quick:
        studies += [("cantilever_frequency", "cantilever", {}),
                    ("rotating_beam", "rotating_beam", {})]
    for label, scene, sweep in studies:
        folder = work / "error_vs_time" / label
        error_vs_time.study(scenes.path(scene), folder, scheduler=scheduler,
                            workers=workers, serial=serial, **sweep)
        parts.append(_demote((folder / "error_vs_time.md").read_text(), 2))
        png = folder / "error_vs_time.png"
        if png.exists():
            shutil.copy(png, figures / f"error_vs_time_{label}.png")
            parts.append(f"![error against run time, {label}](figures/"
                         f"error_vs_time_{label}.png)\n")
    return parts


if __name__ == "__main__":  # pragma: no cover
    print(build(*sys.argv[1:2]))
