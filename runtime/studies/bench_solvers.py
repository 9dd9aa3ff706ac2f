"""``ancf bench solvers``: the cost of whole dynamic runs, engine against engine and against
Exudyn, measured in one process with the cases interleaved (the machine is shared: only
ratios inside one run mean something).

Tables (Markdown):

1. the paper's cantilever (2/5/10 beam3d, 4 s, trapezoidal, h = 1e-3), rotating beam
   (10 beam2d, 20 s, generalized-alpha rho_inf = 0.8, h = 1e-3) and the shipped
   slider-crank (rigid crank, 8-element beam3d or cable3d rod, slider, nonlinear joints;
   and its 2D scene, cable2d rod):
   simulate time of each engine and Newton mode, the same run with the quadrature method
   (the paper's "without invariants"), and Exudyn (``runtime.studies.peers``, when
   installed) with modified and full Newton; min and median of the repeats, and ratios to
   Exudyn's default (modified Newton);
2. the cost of a step from 10 to 100,000 beam3d elements: microseconds per step and per
   element-step, Newton iterations per step, and the shares of the element kernels and of
   the factorisations in the step;
3. the cost of a Python load (``type = "python"``: a tip spring-damper f(t, q, v) on the
   cantilever, with its exact Jacobian or by finite differences) in both engines: calls of
   the function per step, microseconds per call and its share of the run.

Simulate time is the engine's ``run`` from the initial state to ``t_end`` (the models are
built and the stepper compiled before; sensors are not evaluated), as Exudyn's solve time.
"""

from __future__ import annotations

import dataclasses
import itertools
import statistics
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

import scenes
from runtime.catalog import ENGINES, NEWTON_MODES
from runtime.model.items.body_joints import BodyRevolute, BodySpherical
from runtime.model.items.loads import PythonLoad
from runtime.model.items.sensors import Sensors
from runtime.model.model import Model
from runtime.model.scene import Scene, load_scene
from runtime.model.time_laws import Constant
from runtime.progress import Bar, enabled
from runtime.solve import engines
from runtime.studies import peers
from runtime.studies.repeats import interleave


@dataclass
class Case:
    """One timed configuration: ``prepare()`` builds it (untimed) and returns a function
    that runs it and returns (simulate seconds, Newton iterations, Jacobians, tip value)."""

    table: str
    label: str
    prepare: Callable[[], Callable[[], tuple[float, int, int, float]]]
    times: list[float] = dataclasses.field(default_factory=list)
    counts: tuple[int, int] = (0, 0)
    tip: float = float("nan")


def _scene(name: str, elements: int | None = None, grow: bool = False, **dynamic) -> Scene:
    """A shipped scene with ``elements`` per body (``grow``: the body lengthens with them,
    same element length), only its dynamic analysis (``dynamic`` overrides), one output at
    the end and no frequency fit."""
    scene = load_scene(scenes.path(name))
    bodies = scene.bodies
    if elements is not None:
        def meshed(body):
            end = body.end
            if grow:
                end = (body.start[0] + (body.end[0] - body.start[0]) * elements / body.elements,
                       *body.end[1:])
            return dataclasses.replace(body, elements=elements, end=end)
        bodies = tuple(meshed(body) for body in bodies)
    settings = dataclasses.replace(scene.dynamic, frequency_of=None, frequency_after=0.0,
                                   **dynamic)
    settings = dataclasses.replace(settings, output_every=settings.t_end)
    return dataclasses.replace(scene, bodies=bodies, static=None, modal=None,
                               dynamic=settings)


def _ours(scene: Scene, engine: str, newton: str, method: str = "gram",
          tip: str | None = None):
    """A case of the project: builds the model and the engine, returns the timed run."""

    def prepare():
        settings = dataclasses.replace(scene.dynamic, newton=newton)
        model = Model(scene, method=method)
        sensors = Sensors(model)

        def go():
            runner = engines.make(engine, model, settings, model.reference)
            final = {}

            def observe(t, q, v):
                final["q"] = q

            start = time.perf_counter()
            runner.run(settings.t_end, settings.step, observe)
            seconds = time.perf_counter() - start
            value = sensors.values(final["q"], None, settings.t_end)[tip] if tip else float("nan")
            c = runner.counters
            return seconds, c.newton_iterations, c.jacobian_evaluations, value

        return go

    return prepare


def _exudyn(function, **arguments):
    def prepare():
        def go():
            run = function(**arguments)
            return (run.simulate_s, run.newton_iterations, run.jacobian_evaluations,
                    run.tip_displacement)
        return go
    return prepare


def whole_run_cases(quick: bool = False) -> list[Case]:
    """The cases of table 1 (``quick``: short runs, for tests)."""
    t_cantilever, t_rotating = (0.2, 0.5) if quick else (4.0, 20.0)
    cases: list[Case] = []
    with_peer = peers.exudyn_available()
    for elements in ((2,) if quick else (2, 5, 10)):
        table = f"cantilever, {elements} beam3d, {t_cantilever:g} s"
        scene = _scene("cantilever", elements=elements, t_end=t_cantilever)
        for engine, newton, method in (("compiled", "full", "gram"),
                                       ("compiled", "modified", "gram"),
                                       ("compiled", "full", "quadrature"),
                                       ("python", "full", "gram")):
            cases.append(Case(table, f"{engine} {newton} {method}",
                              _ours(scene, engine, newton, method, "tip_y")))
        if with_peer:
            for newton in peers.NEWTON:
                cases.append(Case(table, f"Exudyn ANCFBeam {newton}", _exudyn(
                    peers.exudyn_cantilever, elements=elements, t_end=t_cantilever,
                    step=1e-3, newton=newton)))
    table = f"rotating beam, 10 beam2d, {t_rotating:g} s, generalized-alpha, h = 1e-3"
    scene = _scene("rotating_beam", t_end=t_rotating, step=1e-3, integrator="generalized_alpha",
                  rho_inf=0.8)
    for engine, newton in itertools.product(ENGINES, NEWTON_MODES):
        cases.append(Case(table, f"{engine} {newton} gram",
                          _ours(scene, engine, newton, tip="tip_transverse")))
    if with_peer:
        for newton in peers.NEWTON:
            cases.append(Case(table, f"Exudyn ANCFCable2D {newton}", _exudyn(
                peers.exudyn_rotating_beam, elements=10, t_end=t_rotating, step=1e-3,
                newton=newton, integrator="generalized_alpha", rho_inf=0.8)))
    return cases + _slider_crank_cases(quick, with_peer) + _four_bar_cases(quick, with_peer)


def cable_rod(scene: Scene, name: str = "rod") -> Scene:
    """The mechanism with its flexible body ``name`` (the slider-crank's rod, the four-bar's
    coupler) of cable3d elements (the peer's element kind, in 3D), hinged to the rigid
    bodies by spherical joints (a cable node has no frame for the revolute's axis; the
    planar motion needs none)."""
    def pin(joint):
        if isinstance(joint, BodyRevolute) and joint.node is not None:
            return BodySpherical(body=joint.body, point=joint.point, node=joint.node)
        return joint
    return dataclasses.replace(
        scene, bodies=tuple(dataclasses.replace(b, element="cable3d") if b.name == name
                            else b for b in scene.bodies),
        constraints=tuple(pin(joint) for joint in scene.constraints))


def _slider_crank_cases(quick: bool, with_peer: bool) -> list[Case]:
    """The shipped slider-crank (rigid flywheel crank, 8 beam3d rod, point-mass slider, the
    nonlinear joints), the same with a cable3d rod, its 2D scene (planar rigid crank, 8
    cable2d rod, 2D slider: ``scenes/slider_crank_2d.toml``), and Exudyn's (RigidBody2D,
    ANCFCable2D rod, MassPoint2D)."""
    t_end = 0.05 if quick else 0.7
    scene, planar = (dataclasses.replace(s, sensors=tuple(
        x for x in s.sensors if x.name == "slider_x"))
        for s in (_scene(name, t_end=t_end) for name in ("slider_crank", "slider_crank_2d")))
    settings = scene.dynamic
    table = (f"slider-crank, rigid crank, 8-element rod, slider, {t_end:g} s, "
             f"generalized-alpha rho_inf = {settings.rho_inf:g}, h = {settings.step:g}")
    cases = [Case(table, f"{engine} {newton} gram", _ours(scene, engine, newton,
                                                          tip="slider_x"))
             for engine, newton in (("compiled", "full"), ("compiled", "modified"),
                                    ("compiled", "auto"), ("python", "full"))]
    cables = cable_rod(scene)
    cases += [Case(table, f"compiled {newton} gram, cable3d rod",
                   _ours(cables, "compiled", newton, tip="slider_x"))
              for newton in NEWTON_MODES]
    cases += [Case(table, f"compiled {newton} gram, 2D cable2d rod",
                   _ours(planar, "compiled", newton, tip="slider_x"))
              for newton in NEWTON_MODES]
    if with_peer:
        cases += [Case(table, f"Exudyn RigidBody2D + ANCFCable2D {newton}", _exudyn(
            peers.exudyn_slider_crank, elements=8, t_end=t_end, step=settings.step,
            newton=newton, integrator=settings.integrator, rho_inf=settings.rho_inf))
            for newton in peers.NEWTON]
    return cases


def _four_bar_cases(quick: bool, with_peer: bool) -> list[Case]:
    """The shipped four-bar (rigid crank driven by a prescribed angle, 8 beam3d coupler,
    rigid rocker), the same with a cable3d coupler, and Exudyn's (RigidBody2D crank and
    rocker, ANCFCable2D coupler)."""
    t_end = 0.05 if quick else 1.5
    scene = _scene("four_bar", t_end=t_end)
    scene = dataclasses.replace(scene, sensors=tuple(s for s in scene.sensors
                                                     if s.name == "rocker_tip_y"))
    settings = scene.dynamic
    table = (f"four-bar, driven rigid crank, 8-element coupler, rigid rocker, {t_end:g} s, "
             f"generalized-alpha rho_inf = {settings.rho_inf:g}, h = {settings.step:g}")
    cases = [Case(table, f"compiled {newton} gram", _ours(scene, "compiled", newton,
                                                          tip="rocker_tip_y"))
             for newton in NEWTON_MODES]
    cables = cable_rod(scene, "coupler")
    cases += [Case(table, f"compiled {newton} gram, cable3d coupler",
                   _ours(cables, "compiled", newton, tip="rocker_tip_y"))
              for newton in NEWTON_MODES]
    if with_peer:
        cases += [Case(table, f"Exudyn RigidBody2D + ANCFCable2D {newton}", _exudyn(
            peers.exudyn_four_bar, elements=8, t_end=t_end, step=settings.step,
            newton=newton, integrator=settings.integrator, rho_inf=settings.rho_inf))
            for newton in peers.NEWTON]
    return cases


def measure(cases: list[Case], repeats: int, progress: bool = True) -> None:
    """Run every case ``repeats`` times, interleaved (round after round)."""

    def timed(go):
        def run():
            seconds, *rest = go()
            return seconds, rest
        return run

    runs = [(f"{case.table}: {case.label}", timed(case.prepare())) for case in cases]
    for case, (times, (iterations, jacobians, tip)) in zip(
            cases, interleave(runs, repeats, "bench solvers", progress), strict=True):
        case.times, case.counts, case.tip = times, (iterations, jacobians), tip


def whole_run_table(cases: list[Case]) -> str:
    """Markdown table of measured whole-run cases, ratios against Exudyn's default and
    against the compiled gram run of the same problem."""
    lines = ["| problem | run | simulate s (min) | median | Newton iterations | Jacobians | "
             "tip (m) | / compiled full gram | / Exudyn modified |",
             "|---|---|---:|---:|---:|---:|---:|---:|---:|"]
    for table in dict.fromkeys(c.table for c in cases):
        group = [c for c in cases if c.table == table]
        ours = next(c for c in group if c.label == "compiled full gram")
        peer = next((c for c in group if "Exudyn" in c.label and "modified" in c.label), None)
        for case in group:
            best, median = min(case.times), statistics.median(case.times)
            to_peer = f"{best / min(peer.times):.3g}" if peer else "-"
            lines.append(f"| {table} | {case.label} | {best:.4g} | {median:.4g} | "
                         f"{case.counts[0]} | {case.counts[1]} | {case.tip:.6g} | "
                         f"{best / min(ours.times):.3g} | {to_peer} |")
    return "\n".join(lines) + "\n"


def step_cost(elements: int, engine: str, steps: int = 10, method: str = "gram") -> dict:
    """Cost of a trapezoidal step of the paper cantilever meshed with ``elements`` beam3d
    elements of the same length (the beam grows with them), loaded from the first step."""
    scene = _scene("cantilever", elements=elements, grow=True, t_end=steps * 1e-3, step=1e-3)
    scene = dataclasses.replace(scene, loads=tuple(dataclasses.replace(
        load, time_law=Constant()) for load in scene.loads))
    start = time.perf_counter()
    model = Model(scene, method=method)
    runner = engines.make(engine, model, scene.dynamic, model.reference)
    build = time.perf_counter() - start
    runner.run(scene.dynamic.t_end, scene.dynamic.step, lambda t, q, v: None)
    timing, counters = runner.timing, runner.counters
    per_step = timing["steps_s"] / counters.steps
    return {"elements": elements, "engine": engine, "coordinates": model.free.size,
            "build_s": build, "step_us": per_step * 1e6,
            "element_step_us": per_step * 1e6 / elements,
            "newton_per_step": counters.newton_iterations / counters.steps,
            "kernel_share": timing["kernel_s"] / timing["steps_s"],
            "factorisation_share": timing["factorisation_s"] / timing["steps_s"]}


def step_table(sizes=(10, 100, 1000, 10_000, 100_000), python_limit: int = 10_000,
               method: str = "gram", progress: bool = True) -> str:
    """Markdown table of ``step_cost`` for both engines (Python up to ``python_limit``)."""
    lines = ["| beam3d elements | engine | free coordinates | us per step | "
             "us per element-step | Newton per step | kernel share | factorisation share |",
             "|---:|---|---:|---:|---:|---:|---:|---:|"]
    runs = [(size, engine) for size in sizes for engine in ENGINES
            if engine == "compiled" or size <= python_limit]
    with enabled(progress), Bar("step cost", len(runs), "cases") as bar:
        rows = []
        for size, engine in runs:
            rows.append(step_cost(size, engine, method=method))
            bar.advance(f"{size} elements, {engine} engine")
    for r in rows:
        lines.append(f"| {r['elements']} | {r['engine']} | {r['coordinates']} | "
                     f"{r['step_us']:.4g} | {r['element_step_us']:.3g} | "
                     f"{r['newton_per_step']:.1f} | {r['kernel_share']:.0%} | "
                     f"{r['factorisation_share']:.0%} |")
    return "\n".join(lines) + "\n"


#: stiffness (N/m) and damping (N s/m) of the tip spring-damper of the Python-load case
TIP_SPRING, TIP_DAMPER = 1e5, 50.0


def _tip_spring(t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """A spring-damper holding the position of the last beam3d node (its first 3 of 12
    coordinates) toward (1, 0, 0): the generalised force (size,) in N."""
    force = np.zeros(q.size)
    tip = slice(q.size - 12, q.size - 9)
    force[tip] = -TIP_SPRING * (q[tip] - (1.0, 0.0, 0.0)) - TIP_DAMPER * v[tip]
    return force


def _tip_spring_jacobian(t: float, q: np.ndarray, v: np.ndarray):
    """(df/dq, df/dv) of ``_tip_spring``, dense (size, size)."""
    d_q, d_v = np.zeros((q.size, q.size)), np.zeros((q.size, q.size))
    tip = np.arange(q.size - 12, q.size - 9)
    d_q[tip, tip], d_v[tip, tip] = -TIP_SPRING, -TIP_DAMPER
    return d_q, d_v


def python_load_cost(engine: str, exact: bool, t_end: float = 0.2) -> dict:
    """A dynamic run of the paper cantilever (2 beam3d, h = 1e-3, full Newton) with the tip
    spring-damper as a Python load (``exact``: its Jacobian given, else finite differences):
    simulate seconds, calls of the load function, seconds in them and steps."""
    scene = _scene("cantilever", elements=2, t_end=t_end)
    load = PythonLoad(_tip_spring, _tip_spring_jacobian if exact else None, nodes=["beam:-1"])
    scene = Scene(**{f.name: getattr(scene, f.name) for f in dataclasses.fields(scene)
                     if f.name != "loads"}, loads=(*scene.loads, load))
    model = Model(scene)
    runner = engines.make(engine, model, scene.dynamic, model.reference)
    start = time.perf_counter()
    runner.run(scene.dynamic.t_end, scene.dynamic.step, lambda t, q, v: None)
    seconds = time.perf_counter() - start
    force = runner.dae.state_loads.python_loads[0]
    return {"engine": engine, "jacobian": "exact" if exact else "finite differences",
            "simulate_s": seconds, "calls": force.calls, "call_s": force.seconds,
            "steps": runner.counters.steps, "iterations": runner.counters.newton_iterations}


def python_load_table(repeats: int = 3, t_end: float = 0.2, progress: bool = True) -> str:
    """Markdown table of ``python_load_cost`` for both engines and both Jacobians: min and
    median simulate time of ``repeats`` runs, calls per step and per Newton iteration,
    microseconds per call (min over the repeats) and the share of the run in the calls."""
    lines = ["| engine | Jacobian | simulate s (min) | median | calls per step | "
             "calls per Newton iteration | us per call | share of the run |",
             "|---|---|---:|---:|---:|---:|---:|---:|"]
    runs = list(itertools.product(ENGINES, (True, False)))
    with enabled(progress), Bar("Python load cost", len(runs) * repeats, "runs") as bar:
        for engine, exact in runs:
            rows = []
            for _ in range(repeats):
                rows.append(python_load_cost(engine, exact, t_end))
                bar.advance(f"{engine}, {rows[-1]['jacobian']}")
            times = [r["simulate_s"] for r in rows]
            best = min(rows, key=lambda r: r["simulate_s"])
            per_call = min(r["call_s"] / r["calls"] for r in rows)
            lines.append(f"| {engine} | {best['jacobian']} | {min(times):.4g} | "
                         f"{statistics.median(times):.4g} | {best['calls'] / best['steps']:.3g} "
                         f"| {best['calls'] / best['iterations']:.3g} | {per_call * 1e6:.3g} | "
                         f"{best['call_s'] / best['simulate_s']:.0%} |")
    return "\n".join(lines) + "\n"


def run(quick: bool = False, repeats: int = 3, progress: bool = True) -> str:
    """Both tables as Markdown (``quick``: short runs and small sizes, for tests)."""
    cases = whole_run_cases(quick)
    measure(cases, repeats, progress)
    peer = (f"Exudyn {peers.exudyn_version()}" if peers.exudyn_available()
            else "Exudyn not installed (pip install -e \".[peers]\")")
    sizes = (10, 100) if quick else (10, 100, 1000, 10_000, 100_000)
    return (f"## Whole runs ({repeats} interleaved repeats; peer: {peer})\n\n"
            + whole_run_table(cases)
            + "\n## Cost of a step (trapezoidal, full Newton, gram, C kernels)\n\n"
            + step_table(sizes, progress=progress)
            + "\n## Cost of a Python load (tip spring-damper f(t, q, v) on the cantilever, "
            "2 beam3d, h = 1e-3)\n\n"
            + python_load_table(repeats, 0.02 if quick else 0.2, progress))
