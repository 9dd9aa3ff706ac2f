"""Running the configurations of ``ancf bench precision`` and measuring their errors: the
project's scene of a configuration (run in memory with ``run_scene``, simulate time from its
summary), the matching Exudyn run (its solve timed alone), both interleaved through
``runtime.studies.repeats``, and the error measures against the reference.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

import scenes
from runtime import Body, Clamp, Displacement, Material, PointForce, Scene, Static, run_scene
from runtime.model.scene import load_scene
from runtime.studies import peers
from runtime.studies.precision import elastica
from runtime.studies.precision.plan import ELASTICA, PEER_MODEL, Config, Problem, model
from runtime.studies.repeats import best, interleave


@dataclass
class Outcome:
    """What one run computed: ``status`` (ok, diverged, failed) and ``message``, Newton
    ``iterations``, the sensor's history (``t``, ``y``) of a dynamic run or the ``tip``
    displacement (x, y) of a static one."""

    status: str
    message: str = ""
    iterations: int | None = None
    t: np.ndarray | None = None
    y: np.ndarray | None = None
    tip: tuple[float, float] | None = None


def history_error(t: np.ndarray, y: np.ndarray, ref_t: np.ndarray,
                  ref_y: np.ndarray) -> float:
    """max over the reference's output times of |y - reference| over max |reference|; NaN
    when the run does not reach the reference's last time."""
    t, y, ref_t, ref_y = (np.asarray(a, dtype=float) for a in (t, y, ref_t, ref_y))
    if t.size == 0 or t[-1] < ref_t[-1] - 1e-9 * max(1.0, abs(ref_t[-1])):
        return math.nan
    return float(np.abs(np.interp(ref_t, t, y) - ref_y).max() / np.abs(ref_y).max())


def static_error(tip: tuple[float, float], exact: tuple[float, float], length: float) -> float:
    """max(|x - exact x|, |y - exact y|) / length of a tip displacement."""
    return max(abs(tip[0] - exact[0]), abs(tip[1] - exact[1])) / length


def exact_tip() -> tuple[float, float]:
    """The elastica's tip displacement (x, y) (m) under the load in -y (``by_quadrature``;
    ``by_bvp`` agrees to 1e-13)."""
    u, w = elastica.by_quadrature(ELASTICA["alpha"])
    return -u * ELASTICA["length"], -w * ELASTICA["length"]


def elastica_load(problem: Problem) -> tuple[Material, float]:
    """The elastica's material (the scene's) and its tip force P (N) with P L^2 / EI =
    alpha for ELASTICA's section (EI = E w h^3 / 12)."""
    material = next(iter(load_scene(scenes.path(problem.scene)).materials.values()))
    inertia = ELASTICA["width"] * ELASTICA["height"] ** 3 / 12.0
    return material, ELASTICA["alpha"] * material.E * inertia / ELASTICA["length"] ** 2


def elastica_scene(problem: Problem, kind: str, elements: int, load_steps: int) -> Scene:
    """The elastica: a cantilever of ELASTICA's length and section, clamped at the origin,
    tip force -P y (``elastica_load``), static in ``load_steps`` increments."""
    material, force = elastica_load(problem)
    length, h, w = ELASTICA["length"], ELASTICA["height"], ELASTICA["width"]
    return Scene(title="elastica", materials=[material],
                 bodies=[Body("beam", kind, material.name, h, w, elements, (0.0, 0.0),
                              (length, 0.0))],
                 constraints=[Clamp("beam:0")], loads=[PointForce("beam:-1", (0.0, -force))],
                 sensors=[Displacement("tip_x", "beam:-1", "x"),
                          Displacement("tip_y", "beam:-1", "y")],
                 static=Static(load_steps=load_steps))


def project_scene(problem: Problem, config: Config) -> Scene:
    """The project's scene of a configuration: the elastica, or the shipped scene with the
    kind, mesh, step, integrator and Newton set, only the dynamic analysis and the sensor
    kept, outputs every ``problem.every`` s."""
    if problem.static:
        return elastica_scene(problem, config.kind, config.elements, config.load_steps)
    scene = load_scene(scenes.path(problem.scene))
    dynamic = dataclasses.replace(scene.dynamic, t_end=problem.t_end, step=config.step,
                                  integrator=config.integrator, newton=config.newton,
                                  output_every=problem.every, frequency_of=None,
                                  frequency_after=0.0)
    return dataclasses.replace(
        scene, bodies=tuple(dataclasses.replace(b, element=config.kind,
                                                elements=config.elements)
                            for b in scene.bodies),
        sensors=tuple(s for s in scene.sensors if s.name == problem.sensor),
        static=None, modal=None, dynamic=dynamic)


def _project(problem: Problem, config: Config) -> Callable[[], tuple[float, Outcome]]:
    scene = project_scene(problem, config)

    def run() -> tuple[float, Outcome]:
        try:
            result = run_scene(scene, progress=False)
        except Exception as error:  # a failing configuration is a result, not the end
            return math.nan, Outcome("failed", f"{type(error).__name__}: {error}")
        summary = result.summary
        if result.status != "ok":
            return math.nan, Outcome(result.status, summary.get("message", ""))
        seconds = summary["timing"]["simulate_s"]
        if problem.static:
            values = summary["static"]["sensors"]
            return seconds, Outcome("ok", iterations=summary["static"]["iterations"],
                                    tip=(values["tip_x"], values["tip_y"]))
        return seconds, Outcome("ok", iterations=summary["dynamic"]["newton_iterations"],
                                t=result.sensors["t"], y=result.sensors[problem.sensor])

    return run


#: The Exudyn model of each dynamic problem.
PEER_DYNAMIC = {"rotating_beam": peers.exudyn_rotating_beam,
                "cantilever": peers.exudyn_cantilever_cable}


def _exudyn(problem: Problem, config: Config) -> Callable[[], tuple[float, Outcome]]:
    rho_inf = load_scene(scenes.path(problem.scene)).dynamic.rho_inf

    def run() -> tuple[float, Outcome]:
        try:
            if problem.static:
                material, force = elastica_load(problem)
                solve = peers.exudyn_elastica(
                    config.elements, config.load_steps, config.newton,
                    length=ELASTICA["length"], height=ELASTICA["height"],
                    width=ELASTICA["width"], E=material.E, force=(0.0, -force))
                return solve.simulate_s, Outcome("ok", iterations=solve.newton_iterations,
                                                 tip=solve.tip)
            peer = PEER_DYNAMIC[problem.name](
                config.elements, t_end=problem.t_end, step=config.step, newton=config.newton,
                integrator=config.integrator, rho_inf=rho_inf, every=problem.every)
        except RuntimeError as error:
            return math.nan, Outcome("failed", str(error))
        return peer.simulate_s, Outcome("ok", iterations=peer.newton_iterations,
                                        t=peer.history[0], y=peer.history[1])

    return run


def prepare(problem: Problem, config: Config) -> Callable[[], tuple[float, Outcome]]:
    """The run of a configuration: called, it runs once and returns (simulate seconds, NaN
    when it failed; its Outcome)."""
    return (_project if config.code == "project" else _exudyn)(problem, config)


def measure(problem: Problem, configs: list[Config], references: list[Config],
            repeats: int, progress: bool = True) -> list[dict]:
    """Run the references once, then every configuration ``repeats`` times interleaved;
    returns one row per run (``report.CSV_COLUMNS``) with its error against its code's
    reference (the exact elastica for the static problem)."""
    timed = interleave([(f"{problem.name} reference: {c.code} {c.label()}", prepare(problem, c))
                        for c in references], 1, f"{problem.name} references", progress)
    timed += interleave([(f"{problem.name}: {c.code} {c.label()}", prepare(problem, c))
                         for c in configs], repeats, f"bench precision {problem.name}",
                        progress)
    runs = list(zip([*references, *configs], timed, strict=True))
    own = {(c.code, model(c)): outcome for c, (_, outcome) in runs if c.reference}
    exact = exact_tip() if problem.static else None
    rows = []
    for config, (times, outcome) in runs:
        error = math.nan
        if outcome.status == "ok":
            if problem.static:
                error = static_error(outcome.tip, exact, ELASTICA["length"])
            elif not config.reference and own[config.code, model(config)].status == "ok":
                ref = own[config.code, model(config)]
                error = history_error(outcome.t, outcome.y, ref.t, ref.y)
        fastest, median = best(times)
        fields = {k: v for k, v in dataclasses.asdict(config).items() if k != "reference"}
        rows.append({**fields, "role": "reference" if config.reference else "sweep",
                     "status": outcome.status, "error": error,
                     "simulate_min_s": fastest, "simulate_median_s": median,
                     "repeats": len(times), "newton_iterations": outcome.iterations,
                     "message": outcome.message.splitlines()[0] if outcome.message else ""})
    peer = own.get(("exudyn", PEER_MODEL))
    if not problem.static and peer is not None and peer.status == "ok":
        # each project reference's distance to the peer's (like models should agree)
        for config, row in zip([c for c, _ in runs], rows, strict=True):
            ours = own.get(("project", model(config)))
            if row["role"] == "reference" and ours is not None and ours.status == "ok":
                row["error"] = history_error(peer.t, peer.y, ours.t, ours.y)
    return rows
