"""``ancf bench steps``: the cost of a dynamic step against model size, per body type and
linear solver.

Cases (trapezoidal, h = 1e-3, gram method, C kernels, loaded from the first step):

* ``plate``: a square 1 m steel plate3d (10 mm) of N x N elements clamped on one edge under
  a line load on the opposite edge ramped up over 0.2 s (``scenes/plate_cantilever.toml``);
* ``beam chain``: the paper's cantilever of beam3d elements of the same length (the beam
  grows with them);
* ``joint chain``: a mechanism of N joints, N + 1 beam3d bodies of one element each (the
  cantilever's section and material, 0.1 m long) in a line, the first pinned to the
  ground, each to the next by a spherical joint (3 N + 3 constraint rows), swinging under
  gravity (generalized-alpha, as mechanisms are run);
* ``free links``: the joint chain's links without their joints, falling freely: what its
  step costs without constraints (the constraint share of a KKT step is measured against
  it).
* ``brick block``: a 1 m steel cube of N x N x N brick3d_3843 elements (Chrono's ANCF-3843,
  96 coordinates each) clamped on its face x = 0 under gravity (``scenes/brick_cantilever.toml``'s
  body and material), loaded from the first step.

Each case runs ``repeats`` times on one model (min and median per step), its Newton modes
interleaved.  For each case and
linear solver (``runtime.catalog.LINEAR_SOLVERS``; ``auto`` is the model's
automatic choice) and Newton mode: milliseconds per step, microseconds per element-step,
Newton iterations per step and the shares of the step spent in the element kernels (with
assembly), in factorisations and in solves, and on the joints (constraint share: the
Schur complement's time, or, on the KKT path, the difference to the free links).  The model
is built and the stepper compiled before the timed run (``build_s``); only the steps are
timed, by the engine itself.
"""

from __future__ import annotations

import dataclasses
import math
import statistics
import time

import scenes
from runtime.catalog import LINEAR_SOLVERS, NEWTON_MODES
from runtime.model.bodies import Body
from runtime.model.items.constraints import Clamp, Pin, Spherical
from runtime.model.items.loads import Gravity, LineForce
from runtime.model.model import Model
from runtime.model.scene import Scene, load_scene
from runtime.model.settings import Dynamic
from runtime.model.time_laws import Constant, CosineRamp
from runtime.progress import Bar, enabled
from runtime.solve import engines

#: the choice of the model, besides the catalog's solvers
AUTO = "auto"
#: the plate's load law (the shipped plate scene's): two Newton iterations a step at first
RAMP = CosineRamp(0.2)


def plate_scene(grid: int, steps: int) -> Scene:
    """The plate case with ``grid`` x ``grid`` elements, ``steps`` steps."""
    scene = load_scene(scenes.path("plate_cantilever"))
    body = scene.bodies[0]
    body = dataclasses.replace(body, elements=None, rectangle=dataclasses.replace(
        body.rectangle, size=(1.0, 1.0), grid=(grid, grid)))
    return _dynamic(dataclasses.replace(
        scene, bodies=(body,), constraints=(Clamp(edge="plate:x=0"),),
        loads=(LineForce("plate:x=-1", (0.0, 0.0, -100.0), time_law=RAMP),)), steps)


def chain_scene(elements: int, steps: int) -> Scene:
    """The beam chain case with ``elements`` beam3d elements, ``steps`` steps."""
    scene = load_scene(scenes.path("cantilever"))
    body = scene.bodies[0]
    end = (body.start[0] + (body.end[0] - body.start[0]) * elements / body.elements,
           *body.end[1:])
    body = dataclasses.replace(body, elements=elements, end=end)
    loads = tuple(dataclasses.replace(load, time_law=Constant()) for load in scene.loads)
    return _dynamic(dataclasses.replace(scene, bodies=(body,), loads=loads), steps)


def joint_chain_scene(joints: int, steps: int) -> Scene:
    """The joint chain case with ``joints`` spherical joints, ``steps`` steps."""
    scene = load_scene(scenes.path("cantilever"))
    beam = scene.bodies[0]
    bodies = tuple(Body(f"link{i}", "beam3d", beam.material, beam.height, beam.width, 1,
                        start=(0.1 * i, 0.0, 0.0), end=(0.1 * (i + 1), 0.0, 0.0))
                   for i in range(joints + 1))
    constraints = (Pin("link0:0"),) + tuple(Spherical((f"link{i}:-1", f"link{i + 1}:0"))
                                            for i in range(joints))
    dynamic = _dynamic(scene, steps).dynamic
    return dataclasses.replace(
        scene, bodies=bodies, constraints=constraints, loads=(Gravity((0.0, -9.81, 0.0)),),
        sensors=(), static=None, modal=None,
        dynamic=dataclasses.replace(dynamic, integrator="generalized_alpha"))


def free_links_scene(joints: int, steps: int) -> Scene:
    """The joint chain's links without their joints (each falls freely): what the chain's
    step costs without its constraints."""
    return dataclasses.replace(joint_chain_scene(joints, steps), constraints=())


def block_scene(grid: int, steps: int) -> Scene:
    """The brick block case with ``grid`` x ``grid`` x ``grid`` elements, ``steps`` steps."""
    scene = load_scene(scenes.path("brick_cantilever"))
    body = scene.bodies[0]
    body = dataclasses.replace(body, elements=None, box=dataclasses.replace(
        body.box, size=(1.0, 1.0, 1.0), grid=(grid, grid, grid)))
    return _dynamic(dataclasses.replace(
        scene, bodies=(body,), constraints=(Clamp(edge=f"{body.name}:x=0"),),
        loads=(Gravity((0.0, 0.0, -9.81)),), sensors=(),
        dynamic=Dynamic(t_end=steps * 1e-3, step=1e-3)), steps)


def _dynamic(scene: Scene, steps: int) -> Scene:
    dynamic = dataclasses.replace(scene.dynamic, t_end=steps * 1e-3, step=1e-3,
                                  integrator="trapezoidal", output_every=steps * 1e-3,
                                  frequency_of=None, frequency_after=0.0)
    return dataclasses.replace(scene, static=None, modal=None, dynamic=dynamic)


def step_costs(scene: Scene, case: str, linear_solver: str = AUTO,
               newtons: tuple[str, ...] = ("full",), engine: str = "compiled",
               method: str = "gram", repeats: int = 3) -> list[dict]:
    """One row per Newton mode of ``newtons``: the cost of the steps of ``scene`` with
    ``linear_solver`` (``AUTO``: the model's choice) and ``engine``, run ``repeats`` times
    on one model, the modes interleaved (repeat 1 of every mode, then repeat 2, ...: a
    shared machine's load falls on all of them alike); min and median per step, the
    shares those of the fastest run."""
    solver = dataclasses.replace(scene.solver, method=method,
                                 linear_solver=None if linear_solver == AUTO else linear_solver)
    scene = dataclasses.replace(scene, solver=solver)
    start = time.perf_counter()
    model = Model(scene, method=method)
    settings = {newton: dataclasses.replace(scene.dynamic, newton=newton) for newton in newtons}
    for newton in newtons:                        # compiled once, untimed
        engines.make(engine, model, settings[newton], model.reference)
    build = time.perf_counter() - start
    runs: dict[str, list] = {newton: [] for newton in newtons}
    for _ in range(repeats):
        for newton in newtons:
            runner = engines.make(engine, model, settings[newton], model.reference)
            runner.run(settings[newton].t_end, settings[newton].step, lambda t, q, v: None)
            runs[newton].append((runner.timing["steps_s"] / runner.counters.steps, runner))
    elements = sum(body.elements for body in model.bodies.values())
    return [_row(case, model, elements, linear_solver, newton, engine, build, runs[newton])
            for newton in newtons]


def _row(case: str, model: Model, elements: int, linear_solver: str, newton: str,
         engine: str, build: float, runs: list) -> dict:
    """The table row of one Newton mode's ``runs`` ((seconds per step, runner) each)."""
    per_step, runner = min(runs, key=lambda run: run[0])
    timing, counters = runner.timing, runner.counters
    # the KKT path factorises the joints with the matrix: no time of their own
    kkt = getattr(runner, "kkt", None) not in (None, False)
    return {"case": case, "elements": elements, "coordinates": model.free.size,
            "linear_solver": runner.linear_solver, "requested": linear_solver,
            "newton": newton, "engine": engine, "build_s": build,
            "step_ms": per_step * 1e3,
            "median_ms": statistics.median(run[0] for run in runs) * 1e3,
            "element_step_us": per_step * 1e6 / elements,
            "newton_per_step": counters.newton_iterations / counters.steps,
            "factorisations_per_step": counters.factorisations / counters.steps,
            "kernel_share": timing["kernel_s"] / timing["steps_s"],
            "factorisation_share": timing["factorisation_s"] / timing["steps_s"],
            "solve_share": timing["solve_s"] / timing["steps_s"],
            "constraint_share": (float("nan") if kkt else
                                 timing.get("constraint_s", float("nan")) / timing["steps_s"])}


def _steps(elements: int) -> int:
    """Steps timed for a model of ``elements``: fewer for large ones (seconds per case)."""
    return 50 if elements <= 100 else 10 if elements <= 1000 else 3


#: banded brick blocks up to this many elements a side (a block of N^3 bricks has a band of
#: about 12 (N + 1)^2 coordinates: beyond, seconds per factorisation)
BANDED_BLOCK_LIMIT = 4


def plan(plates=(4, 8, 16, 32), chains=(1000, 10_000), solvers=(AUTO, *LINEAR_SOLVERS),
         newtons=("full",), banded_limit: int = 32, joints=(50, 200),
         blocks=(2, 4, 6)) -> list[tuple]:
    """The cases: (scene maker, size, case label, solver, newton); banded plates up to
    ``banded_limit`` elements a side (beyond, its band costs seconds per factorisation),
    banded brick blocks up to ``BANDED_BLOCK_LIMIT``."""
    cases = []
    for grid in plates:
        for solver in solvers:
            if solver == "banded" and grid > banded_limit:
                continue
            cases += [(plate_scene, grid, f"plate {grid} x {grid}", solver, newton)
                      for newton in newtons]
    for elements in chains:
        cases += [(chain_scene, elements, f"beam chain {elements}", solver, newton)
                  for solver in solvers for newton in newtons]
    for count in joints:
        cases += [(joint_chain_scene, count, f"joint chain {count}", solver, newton)
                  for solver in solvers for newton in newtons]
        cases += [(free_links_scene, count, f"free links {count}", AUTO, newton)
                  for newton in newtons]
    for grid in blocks:
        cases += [(block_scene, grid, f"brick block {grid} x {grid} x {grid}", solver, newton)
                  for solver in solvers for newton in newtons
                  if solver != "banded" or grid <= BANDED_BLOCK_LIMIT]
    return cases


def measure(cases: list[tuple], method: str = "gram", repeats: int = 3,
            progress: bool = True) -> list[dict]:
    """Run every case ``repeats`` times with ``method`` (in this process, one case after
    the other; the Newton modes of a case, consecutive in ``cases``, interleaved:
    ``step_costs``)."""
    groups: list[tuple[tuple, list[str]]] = []
    for make, size, label, solver, newton in cases:
        if groups and groups[-1][0] == (make, size, label, solver):
            groups[-1][1].append(newton)
        else:
            groups.append(((make, size, label, solver), [newton]))
    rows = []
    with enabled(progress), Bar("bench steps", len(groups), "cases") as bar:
        for (make, size, label, solver), newtons in groups:
            elements = (size * size if make is plate_scene else size**3
                        if make is block_scene else size + (
                            make in (joint_chain_scene, free_links_scene)))
            rows += step_costs(make(size, _steps(elements)), label, solver, tuple(newtons),
                               method=method, repeats=repeats)
            bar.advance(f"{label}, {solver}, {'/'.join(newtons)}")
    return rows


def constraint_share(row: dict, rows: list[dict], per_iteration: bool = False) -> float:
    """The share of ``row``'s step spent on its joints: the Schur complement's time where the
    step has one; on the KKT path (the joints factorised with the matrix) 1 - the step of
    the same links without joints (``free links``, same Newton mode) over its step, or with
    ``per_iteration`` 1 - the ratio of their costs per Newton iteration (the free links fall
    in one iteration a step; the swinging chain's large rotations take more, whatever
    handles its joints)."""
    if row["case"].startswith("joint chain") and math.isnan(row["constraint_share"]):
        count = row["case"].rsplit(" ", 1)[1]
        free = next((r for r in rows if r["case"] == f"free links {count}"
                     and r["newton"] == row["newton"]), None)
        if free is not None:
            if per_iteration:
                return 1.0 - (free["step_ms"] / free["newton_per_step"]) / (
                    row["step_ms"] / row["newton_per_step"])
            return 1.0 - free["step_ms"] / row["step_ms"]
    return row["constraint_share"]


def table(rows: list[dict]) -> str:
    """Markdown table of measured rows (constraint shares: ``constraint_share``, per step and
    per Newton iteration)."""
    lines = ["| case | elements | free coordinates | linear solver | Newton | ms per step "
             "(min) | median | us per element-step | Newton per step | factorisations per "
             "step | kernel share | factorisation share | solve share | constraint share | "
             "constraint share per Newton iteration |",
             "|---|---:|---:|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        solver = r["linear_solver"] + (" (auto)" if r["requested"] == AUTO else "")
        lines.append(f"| {r['case']} | {r['elements']} | {r['coordinates']} | {solver} | "
                     f"{r['newton']} | {r['step_ms']:.4g} | {r['median_ms']:.4g} | "
                     f"{r['element_step_us']:.3g} | {r['newton_per_step']:.2f} | "
                     f"{r['factorisations_per_step']:.2f} | {r['kernel_share']:.0%} | "
                     f"{r['factorisation_share']:.0%} | {r['solve_share']:.0%} | "
                     f"{constraint_share(r, rows):.0%} | "
                     f"{constraint_share(r, rows, per_iteration=True):.0%} |")
    return "\n".join(lines) + "\n"


def _body_type(case: str) -> str:
    """The body type of a case label (``plate 8 x 8`` -> ``plate3d``, ``joint chain 50`` ->
    ``joint chain (beam3d)``): one colour of the plot per type."""
    if case.startswith("plate"):
        return "plate3d"
    if case.startswith("brick block"):
        return "brick3d_3843 block"
    name = case.rsplit(" ", 1)[0]
    return "beam3d chain" if name == "beam chain" else f"{name} (beam3d)"


def plot(rows: list[dict], path) -> None:
    """Cost per element-step against elements (log-log), one line per body type and Newton
    mode with the solver each model chose (``AUTO`` rows; without them one line per solver
    too), and the n^1.5 growth of a 2D sparse factorisation from the first plate point."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    chosen = [r for r in rows if r["requested"] == AUTO]
    figure, axes = plt.subplots(figsize=(10, 4.8))
    lines = {}
    for r in chosen or rows:
        solver = "solver chosen" if chosen else r["linear_solver"]
        key = (_body_type(r["case"]), r["newton"], solver)
        lines.setdefault(key, []).append((r["elements"], r["element_step_us"]))
    colours = {body: f"C{i}" for i, body in enumerate(sorted({k[0] for k in lines}))}
    styles = {newton: style for newton, style in zip(NEWTON_MODES, ("-", "--", ":"),
                                                      strict=True)}
    for (body, newton, solver), points in sorted(lines.items()):
        points.sort()
        x, y = zip(*points, strict=True)
        axes.loglog(x, y, marker="o", linestyle=styles.get(newton, "-"), color=colours[body],
                    label=f"{body}, {newton} Newton, {solver}")
    plates = sorted(p for (body, _, _), pts in lines.items() if body == "plate3d" for p in pts)
    if plates:
        x0, y0 = min(plates)
        x1 = max(p[0] for p in plates)
        axes.loglog([x0, x1], [y0, y0 * (x1 / x0) ** 0.5], "k:",
                    label="n^1.5 total (2D nested dissection)")
    axes.set_xlabel("elements")
    axes.set_ylabel("us per element-step")
    axes.set_title("Cost of a step (compiled engine, gram, h = 1e-3; joint chains "
                   "generalized-alpha, the rest trapezoidal)", fontsize=10)
    axes.grid(True, which="both", alpha=0.3)
    axes.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0))
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)


def scene_runs(names, newtons=NEWTON_MODES, repeats: int = 3,
               progress: bool = True) -> list[dict]:
    """Whole dynamic runs of the shipped scenes ``names`` (``scenes/*.toml``, as shipped,
    no sensors nor outputs evaluated) per Newton mode, compiled engine, the modes
    interleaved in each repeat: simulate seconds (min and median of ``repeats``), steps,
    Newton iterations and factorisations."""
    rows = []
    with enabled(progress), Bar("bench steps: scenes", len(names) * len(newtons),
                                "runs") as bar:
        for name in names:
            scene = load_scene(scenes.path(name))
            if scene.dynamic is None:
                continue
            model = Model(scene)
            times: dict[str, list[float]] = {newton: [] for newton in newtons}
            last = {}
            for _ in range(repeats):         # the modes interleaved: a drift hits them alike
                for newton in newtons:
                    settings = dataclasses.replace(scene.dynamic, newton=newton)
                    runner = engines.make("compiled", model, settings, model.reference)
                    start = time.perf_counter()
                    runner.run(settings.t_end, settings.step, lambda t, q, v: None)
                    times[newton].append(time.perf_counter() - start)
                    last[newton] = runner
            for newton in newtons:
                runner = last[newton]
                c = runner.counters
                rows.append({"scene": name, "newton": newton, "seconds": min(times[newton]),
                             "median_s": statistics.median(times[newton]), "steps": c.steps,
                             "newton_iterations": c.newton_iterations,
                             "factorisations": c.factorisations,
                             "linear_solver": runner.linear_solver})
                bar.advance(f"{name}, {newton}")
    return rows


def scene_table(rows: list[dict]) -> str:
    """Markdown table of ``scene_runs``, each run against the faster Newton mode."""
    lines = ["| scene | linear solver | Newton | simulate s (min) | median | steps | Newton "
             "iterations | factorisations | / faster mode |",
             "|---|---|---|---:|---:|---:|---:|---:|---:|"]
    for r in rows:
        best = min(o["seconds"] for o in rows if o["scene"] == r["scene"])
        lines.append(f"| {r['scene']} | {r['linear_solver']} | {r['newton']} | "
                     f"{r['seconds']:.4g} | {r['median_s']:.4g} | {r['steps']} | "
                     f"{r['newton_iterations']} | {r['factorisations']} | "
                     f"{r['seconds'] / best:.2f} |")
    return "\n".join(lines) + "\n"
