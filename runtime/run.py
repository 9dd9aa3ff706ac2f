"""``ancf run``: a scene from file to results (summary.json, timeseries.csv, plots)."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from runtime import analysis, engines, output
from runtime.integrators import Divergence
from runtime.model import Model
from runtime.scene import Scene, SceneError, load_scene
from runtime.sensors import Sensors
from runtime.signal import dominant_frequency


def run(scene_path, out_dir: str | Path, method: str | None = None,
        backend: str | None = None, quiet: bool = False,
        engine: str | None = None) -> tuple[dict, int]:
    """Run every analysis of a scene (a TOML path or a parsed Scene); returns (summary, code).

    Exit code 0: ok; 1: a run diverged (results up to that point are written); 2: the scene
    or the options are invalid.  summary.json is always written, atomically.
    """
    start = time.perf_counter()
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    given = isinstance(scene_path, Scene)
    summary: dict = {"scene": scene_path.source if given else str(scene_path),
                     "status": "ok", "message": ""}
    timing = {"generate_s": 0.0, "compile_s": 0.0, "preprocess_s": 0.0, "simulate_s": 0.0,
              "total_s": 0.0}
    summary["timing"] = timing
    code = 0
    try:
        scene = scene_path if given else load_scene(scene_path)
        summary["title"] = scene.title
        model = Model(scene, method, backend)
        engine = engines.choose(engine or getattr(scene.solver, "engine", None),
                                model.backend)
    except (SceneError, ValueError) as error:
        summary.update(status="failed", message=str(error))
        timing["total_s"] = time.perf_counter() - start
        output.write_json_atomic(out / "summary.json", summary)
        return summary, 2
    summary["method"], summary["backend"] = model.method, model.backend
    built: set[str] = set()
    timing["compile_s"] = model.timing["compile_s"]
    timing["preprocess_s"] = model.timing["preprocess_s"]
    sensors = Sensors(model)
    simulate_start = time.perf_counter()
    static_q = None
    try:
        if scene.static is not None:
            result = analysis.solve_static(model, scene.static)
            static_q = result.q
            summary["static"] = {"sensors": sensors.values(result.q, t=None),
                                 "iterations": result.iterations,
                                 "load_steps": result.load_steps}
        if scene.modal is not None:
            about = model.reference
            if scene.modal.about == "static":
                about = static_q if static_q is not None else \
                    analysis.solve_static(model, scene.static or _default_static()).q
            omega = analysis.modal(model, about, scene.modal.modes)
            summary["modal"] = {"about": scene.modal.about,
                                "frequencies_rad_s": omega.tolist(),
                                "frequencies_hz": (omega / (2 * np.pi)).tolist()}
        if scene.dynamic is not None:
            code = _dynamic(model, scene.dynamic, sensors, out, summary, quiet, engine, built)
    except analysis.ConvergenceError as error:
        summary.update(status="diverged", message=str(error))
        code = 1
    # plots are outputs, not simulation: their time is reported apart (and in total_s)
    timing["simulate_s"] = time.perf_counter() - simulate_start - timing.get("postprocess_s", 0.0)
    summary["kernel_s"] = model.kernel_seconds + summary.get("dynamic", {}).get("kernel_s", 0)
    summary["kernels"] = sorted(built | {f"{b.element.kind.name}/{f}/{model.backend}"
                                         for b in model.bodies.values()
                                         for f in ("invariants", b.element.family)})
    timing["total_s"] = time.perf_counter() - start
    output.write_json_atomic(out / "summary.json", summary)
    return summary, code


def _default_static():
    from runtime.scene import Static

    return Static()


def _dynamic(model: Model, settings, sensors: Sensors, out: Path, summary: dict,
             quiet: bool, engine: str, built: set[str]) -> int:
    integrator = engines.make(engine, model, settings, model.reference)
    summary["timing"]["compile_s"] += getattr(integrator, "compile_s", 0.0)
    built.update(getattr(integrator, "modules", ()))
    csv_path = out / "timeseries.csv"
    final: dict = {}
    progress = output.Progress(settings.t_end, enabled=False if quiet else None)
    code = 0
    with output.TimeSeriesWriter(csv_path, sensors.names) as writer:

        def observe(t, q, v):
            values = sensors.values(q, v, t)
            writer.write(t, [values[name] for name in sensors.names])
            final.clear()
            final.update(values)
            final["t"] = t

        try:
            integrator.run(settings.t_end, settings.step, observe, progress)
        except Divergence as error:
            summary.update(status="diverged", message=str(error))
            code = 1
        finally:
            progress.close()
    counters = integrator.counters
    summary["dynamic"] = {
        "t_end": settings.t_end, "step": settings.step, "integrator": settings.integrator,
        "engine": engine, "newton": integrator.newton,
        "t_reached": final.get("t", 0.0), "steps": counters.steps,
        "newton_iterations": counters.newton_iterations,
        "force_evaluations": counters.force_evaluations,
        "jacobian_evaluations": counters.jacobian_evaluations,
        "factorisations": counters.factorisations,
        "kernel_s": getattr(integrator, "kernel_seconds", 0.0),
        "sensors_final": {k: v for k, v in final.items() if k != "t"},
    }
    # post-processing (frequency fit, plots) is timed apart from the simulation
    post_start = time.perf_counter()
    if settings.frequency_of is not None and code == 0:
        data = np.genfromtxt(csv_path, delimiter=",", names=True)
        keep = data["t"] >= settings.frequency_after
        summary["dynamic"]["response_frequency_rad_s"] = dominant_frequency(
            data["t"][keep], data[settings.frequency_of][keep])
    output.plot_timeseries(csv_path, out, sensors.energy_names)
    summary["timing"]["postprocess_s"] = time.perf_counter() - post_start
    return code
