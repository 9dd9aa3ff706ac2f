"""``ancf bench paper``: the paper's Tables I and II reproduced on this machine.

Table I: the cantilever of section 7 with 2, 5 and 10 beam3d elements for 4 s (t_c = 3.5 s);
Table II: 5 elements for 10, 20 and 30 s (t_c = 8.75 % of the simulated time).  Every row is
run with the invariants (``gram`` and the paper's ``cij``) and without (``quadrature``), as
independent cases on dask.  The paper's CPU times (Pentium 4, 3.06 GHz) are printed beside.
"""

from __future__ import annotations

import csv
import dataclasses
import json
import math
import tempfile
from pathlib import Path

import scenes
from runtime.catalog import DEFAULT_LAW, METHODS, family_name
from runtime.kernels.kind import element_kind
from runtime.model.scene import Scene, load_scene

SCENE = scenes.path("cantilever")

#: Published figures: (table, elements, t_end) -> force evaluations, CPU s with invariants
#: (pre-processing, simulation, total) and without (total); section 7 of the paper.
PAPER = {
    ("I", 2, 4.0): {"evaluations": 301, "pre": 40.2, "sim": 68.7, "total": 108.9,
                    "without": 312.4, "delta_cm": 1.07, "omega": 16.89},
    ("I", 5, 4.0): {"evaluations": 301, "pre": 100.6, "sim": 136.4, "total": 237.0,
                    "without": 910.4, "delta_cm": 1.13, "omega": 16.41},
    ("I", 10, 4.0): {"evaluations": 301, "pre": 201.3, "sim": 296.2, "total": 497.5,
                     "without": 2930.8, "delta_cm": 1.14, "omega": 16.28},
    ("II", 5, 10.0): {"evaluations": 754, "pre": 100.6, "sim": 372.4, "total": 473.0,
                      "without": 2466.2},
    ("II", 5, 20.0): {"evaluations": 1450, "pre": 100.6, "sim": 1226.0, "total": 1326.6,
                      "without": 8446.0},
    ("II", 5, 30.0): {"evaluations": 2039, "pre": 100.6, "sim": 1570.5, "total": 1671.1,
                      "without": 10424.1},
}
PAPER_OPERATIONS = {"with": 5.52e4, "without": 9.16e6}


def paper_scene(elements: int, t_end: float, step: float | None = None) -> Scene:
    """The shipped cantilever scene meshed and timed for one row of the tables (the load's
    cosine ramp lasts 3.5 s of 4 s as in the paper, the same fraction otherwise)."""
    scene = load_scene(SCENE)
    t_c = 3.5 if t_end == 4.0 else 0.0875 * t_end
    load = scene.loads[0]
    dynamic = scene.dynamic
    step = dynamic.step if step is None else step
    # outputs at a whole number of steps, at most 2000 of them
    every = max(dynamic.output_every, t_end / 2000, step)
    return dataclasses.replace(
        scene, title=f"cantilever[{elements} el, {t_end:g} s]",
        bodies=(dataclasses.replace(scene.bodies[0], elements=elements),),
        loads=(dataclasses.replace(load, time_law=dataclasses.replace(load.time_law,
                                                                      duration=t_c)),),
        dynamic=dataclasses.replace(dynamic, t_end=t_end, step=step, frequency_after=t_c,
                                    output_every=step * math.ceil(every / step - 1e-9)))


def paper_case(table: str, elements: int, t_end: float, method: str, backend: str = "c",
               step: float | None = None) -> dict:
    """Run one row with one method; returns the measured figures (module-level for dask)."""
    from runtime.app.run import run

    scene = paper_scene(elements, t_end, step)
    with tempfile.TemporaryDirectory() as folder:
        # warm-up: a 0.1 s run loads kernels and libraries, so the timed run measures work
        short = dataclasses.replace(scene, dynamic=dataclasses.replace(
            scene.dynamic, t_end=0.1, frequency_after=0.0, output_every=scene.dynamic.step))
        run(short, folder, method=method, backend=backend, quiet=True)
        summary, code = run(scene, folder, method=method, backend=backend, quiet=True)
    if code:
        raise RuntimeError(f"paper row {table}/{elements}/{t_end}/{method}: "
                           f"{summary['message']}")
    timing = summary["timing"]
    family = family_name(method, DEFAULT_LAW, "straight")
    return {
        "table": table, "elements": elements, "t_end": t_end, "method": method,
        "backend": backend, "step": scene.dynamic.step,
        "delta_cm": abs(summary["static"]["sensors"]["tip_y"]) * 100,
        "omega_modal": summary["modal"]["frequencies_rad_s"][0],
        "omega_response": summary["dynamic"]["response_frequency_rad_s"],
        "force_evaluations": summary["dynamic"]["force_evaluations"],
        "jacobian_evaluations": summary["dynamic"]["jacobian_evaluations"],
        "preprocess_s": timing["preprocess_s"], "simulate_s": timing["simulate_s"],
        "kernel_s": summary["kernel_s"],
        "total_s": timing["preprocess_s"] + timing["simulate_s"],
        "operations_per_element_force": element_kind("beam3d").operations(family, "force"),
    }


def cases(quick: bool = False, methods=METHODS, backend: str = "c") -> list[dict]:
    """Keyword arguments of every run (quick: two short rows, for tests)."""
    rows = [("I", 2, 4.0), ("I", 5, 4.0), ("I", 10, 4.0), ("II", 5, 10.0), ("II", 5, 20.0),
            ("II", 5, 30.0)]
    if quick:
        return [{"table": "I", "elements": 2, "t_end": 4.0, "method": m, "backend": backend,
                 "step": 4e-3} for m in methods]
    return [{"table": t, "elements": n, "t_end": te, "method": m, "backend": backend}
            for t, n, te in rows for m in methods]


def markdown(results: list[dict]) -> str:
    """Tables I and II side by side with the paper."""
    by = {(r["table"], r["elements"], r["t_end"], r["method"]): r for r in results}
    lines = []
    for table in ("I", "II"):
        keys = sorted({(r["elements"], r["t_end"]) for r in results if r["table"] == table})
        if not keys:
            continue
        lines += [f"### Table {table}", "",
                  "| elements | t_end s | method | delta cm | omega rad/s (modal / response) | "
                  "evaluations of Fe (paper) | pre-processing s | simulation s | "
                  "in kernels s | total s | ops/element force | paper total s | "
                  "quadrature/method total (paper without/with) |",
                  "|---:|---:|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|"]
        for elements, t_end in keys:
            paper = PAPER.get((table, elements, t_end), {})
            quad = by.get((table, elements, t_end, "quadrature"))
            for method in METHODS:
                r = by.get((table, elements, t_end, method))
                if r is None:
                    continue
                with_invariants = method != "quadrature"
                paper_total = paper.get("total" if with_invariants else "without")
                ratio = ""
                if quad is not None and with_invariants:
                    ratio = (f"{quad['total_s'] / r['total_s']:.2f}"
                             f" ({paper['without'] / paper['total']:.2f})" if paper else
                             f"{quad['total_s'] / r['total_s']:.2f}")
                lines.append(
                    f"| {elements} | {t_end:g} | {method} | {r['delta_cm']:.3f} | "
                    f"{r['omega_modal']:.2f} / {r['omega_response']:.2f} | "
                    f"{r['force_evaluations']} ({paper.get('evaluations', '-')}) | "
                    f"{r['preprocess_s']:.4f} | {r['simulate_s']:.3f} | {r['kernel_s']:.3f} | "
                    f"{r['total_s']:.3f} | {r['operations_per_element_force']} | "
                    f"{paper_total if paper_total is not None else '-'} | {ratio} |")
        lines.append("")
    lines.append(f"Paper: {PAPER_OPERATIONS['with']:.3g} operations per element force with "
                 f"invariants, {PAPER_OPERATIONS['without']:.3g} without; paper CPU: Pentium 4, "
                 "3.06 GHz, variable step (301 force evaluations in 4 s); here the scene's "
                 "fixed step and the trapezoidal rule.")
    return "\n".join(lines) + "\n"


def write(results: list[dict], out_dir: str | Path) -> dict[str, Path]:
    """paper.md, paper.json and paper.csv in ``out_dir``."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = {"md": out / "paper.md", "json": out / "paper.json", "csv": out / "paper.csv"}
    paths["md"].write_text(markdown(results))
    paths["json"].write_text(json.dumps({"results": results, "paper": {
        "/".join(map(str, k)): v for k, v in PAPER.items()}}, indent=1))
    with paths["csv"].open("w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=list(results[0]))
        writer.writeheader()
        writer.writerows(results)
    return paths


def bench_paper(quick: bool = False, scheduler: str | None = None, workers: int | None = None,
                serial: bool = False, backend: str = "c") -> list[dict]:
    """Every row of Tables I and II with every method, in parallel on dask."""
    from runtime.studies.sweep import run_cases

    return run_cases(paper_case, cases(quick, backend=backend), scheduler=scheduler,
                     workers=workers, serial=serial, label="paper tables")
