"""``ancf run``: a scene from file to results (summary.json, timeseries.csv, plots).

Exit codes (:class:`ExitCode`): 0 ok, 1 diverged, 2 invalid scene or options, 3 environment
(output folder or files, C compiler, kernel cache, memory), 4 internal error (a bug),
130 interrupted (SIGINT, or SIGTERM as the CLI maps it).
"""

from __future__ import annotations

import time
import traceback
from enum import IntEnum
from pathlib import Path

import numpy as np

from runtime import analysis, engines, output
from runtime.integrators import Divergence
from runtime.jit import CacheError, JitEnvironmentError
from runtime.model import Model
from runtime.scene import Scene, SceneError, Static, load_scene
from runtime.sensors import ENERGY_TYPES, Sensors
from runtime.signal import dominant_frequency

CSV = "timeseries.csv"
SUMMARY = "summary.json"
# y-axis units of the plots, by sensor type
UNITS = {"displacement": "m", "position": "m", "constraint_violation": "m",
         **dict.fromkeys(ENERGY_TYPES, "J")}


class ExitCode(IntEnum):
    """Exit codes of ``ancf run`` (README, DESIGN.md section 5)."""

    OK = 0
    DIVERGED = 1
    INVALID = 2
    ENVIRONMENT = 3
    INTERNAL = 4
    INTERRUPTED = 130


class RunInterrupted(KeyboardInterrupt):
    """A KeyboardInterrupt stopped a run after its summary (status "interrupted") was written,
    if the output folder allowed; ``summary`` is that summary."""

    def __init__(self, summary: dict) -> None:
        super().__init__(summary["message"])
        self.summary = summary


class _Stop(Exception):
    """Ends a run early: exit code, status and message."""

    def __init__(self, code: ExitCode, message: str, status: str = "failed") -> None:
        super().__init__(message)
        self.code, self.status = code, status


def run(scene_path, out_dir: str | Path, method: str | None = None,
        backend: str | None = None, quiet: bool = False,
        plots: bool = True, engine: str | None = None) -> tuple[dict, int]:
    """Run every analysis of a scene (a TOML path or a parsed Scene) into the folder
    ``out_dir``; returns (summary, exit code) - see :class:`ExitCode`.

    Order: the scene is validated; ``out_dir`` is created, checked writable and cleared of a
    previous run's outputs (only those); the model is built (kernels compiled); the analyses
    run.  summary.json is written atomically when the analyses end, then the plots are drawn
    (unless ``plots`` is False) and the summary rewritten with their time in
    ``timing.postprocess_s``, their files and warnings.  ``summary["message"]`` explains any
    code but 0; its first line is the one-line report.  If ``out_dir`` cannot be written the
    message says that no summary.json was written.  A KeyboardInterrupt writes the summary
    with status "interrupted" and raises :class:`RunInterrupted`.
    """
    job = _Job(scene_path, Path(out_dir))
    try:
        code = job.execute(method, backend, quiet, plots, engine)
    except _Stop as stop:
        job.summary.update(status=stop.status, message=str(stop))
        code = job.save(stop.code)
    except KeyboardInterrupt as interrupt:
        job.summary.update(status="interrupted", message=job.interrupted(interrupt))
        job.save(ExitCode.INTERRUPTED)
        raise RunInterrupted(job.summary) from None
    except MemoryError:
        job.summary.update(status="failed", message=f"out of memory during the {job.phase}")
        code = job.save(ExitCode.ENVIRONMENT)
    except Exception as error:  # a bug: still leave a summary that says what happened
        job.summary.update(status="failed", traceback=traceback.format_exc(),
                           message=f"internal error during the {job.phase}: "
                                   f"{type(error).__name__}: {error}")
        code = job.save(ExitCode.INTERNAL)
    return job.summary, code


class _Job:
    """One run: its summary, output folder and the files it wrote there."""

    def __init__(self, scene_path, out: Path) -> None:
        self.start = time.perf_counter()
        self.scene_path, self.out = scene_path, out
        given = isinstance(scene_path, Scene)
        self.summary: dict = {"scene": scene_path.source if given else str(scene_path),
                              "status": "ok", "message": "", "warnings": []}
        self.timing = dict.fromkeys(("generate_s", "compile_s", "preprocess_s", "simulate_s",
                                     "postprocess_s", "total_s"), 0.0)
        self.summary["timing"] = self.timing
        self.folder_error: str | None = "the output folder is not ready"
        self.files: set[str] = set()
        self.phase = "scene validation"
        self.engine = "python"
        self.built: set[str] = set()   # modules built for this run beyond the kernels

    def execute(self, method: str | None, backend: str | None, quiet: bool,
                plots: bool, engine: str | None = None) -> ExitCode:
        summary, timing = self.summary, self.timing
        scene, invalid = None, None
        if isinstance(self.scene_path, Scene):
            scene = self.scene_path
        else:
            try:
                scene = load_scene(self.scene_path)
            except SceneError as error:
                invalid = str(error)
        self.phase = "output folder check"
        try:
            output.prepare_folder(self.out, _owned_files(scene))
            self.folder_error = None
        except output.OutputError as error:
            self.folder_error = str(error)
        if invalid is not None:
            raise _Stop(ExitCode.INVALID, invalid)
        if self.folder_error is not None:
            raise _Stop(ExitCode.ENVIRONMENT, self.folder_error)
        summary["title"] = scene.title
        self.phase = "model build"
        try:
            model = Model(scene, method, backend)
            self.engine = engines.choose(engine or scene.solver.engine, model.backend)
        except JitEnvironmentError as error:
            raise _Stop(ExitCode.ENVIRONMENT, _environment_message(error)) from None
        except OSError as error:  # kernel cache folder or generated kernels unusable
            where = f"{error.filename}: " if error.filename else ""
            raise _Stop(ExitCode.ENVIRONMENT, f"{where}{error.strerror or error} while "
                        f"preparing the kernels; check ANCF_CACHE_DIR, the kernel cache "
                        f"folder") from None
        except ValueError as error:
            raise _Stop(ExitCode.INVALID, str(error)) from None
        summary["method"], summary["backend"] = model.method, model.backend
        timing["compile_s"] = model.timing["compile_s"]
        timing["preprocess_s"] = model.timing["preprocess_s"]
        sensors = Sensors(model)
        simulate_start = time.perf_counter()
        code, history = ExitCode.OK, None
        try:
            code, history = self._analyses(scene, model, sensors, quiet)
        finally:
            # post-processing (frequency fit) is timed apart from the simulation
            timing["simulate_s"] = time.perf_counter() - simulate_start - timing["postprocess_s"]
            # the Python engine's kernel calls go through the model, the compiled one's not
            compiled = summary.get("dynamic", {}).get("engine") == "compiled"
            summary["kernel_s"] = model.kernel_seconds + (
                summary["dynamic"]["kernel_s"] if compiled else 0.0)
            summary["kernels"] = sorted(self.built | {
                f"{b.element.kind.name}/{f}/{model.backend}" for b in model.bodies.values()
                for f in ("invariants", b.element.family)})
        self.phase = "summary writing"
        code = self.save(code)
        if plots and history and code in (ExitCode.OK, ExitCode.DIVERGED):
            self.phase = "plots"
            post_start = time.perf_counter()
            units = {s.name: UNITS[s.type] for s in scene.sensors}
            series = {name: history[name] for name in sensors.names}
            written, warnings = output.plot_series(history["t"], series, self.out, units,
                                                   sensors.energy_names)
            self.files.update(path.name for path in written)
            summary["warnings"] += warnings
            timing["postprocess_s"] += time.perf_counter() - post_start
            code = self.save(code)
        return code

    def _analyses(self, scene: Scene, model: Model, sensors: Sensors,
                  quiet: bool) -> tuple[ExitCode, dict | None]:
        summary = self.summary
        static_q = None
        try:
            if scene.static is not None:
                self.phase = "static analysis"
                result = analysis.solve_static(model, scene.static)
                static_q = result.q
                summary["static"] = {"sensors": sensors.values(result.q, t=None),
                                     "iterations": result.iterations,
                                     "load_steps": result.load_steps}
            if scene.modal is not None:
                self.phase = "modal analysis"
                about = model.reference
                if scene.modal.about == "static":
                    about = static_q if static_q is not None else \
                        analysis.solve_static(model, scene.static or Static()).q
                omega = analysis.modal(model, about, scene.modal.modes)
                summary["modal"] = {"about": scene.modal.about,
                                    "frequencies_rad_s": omega.tolist(),
                                    "frequencies_hz": (omega / (2 * np.pi)).tolist()}
            if scene.dynamic is not None:
                self.phase = "dynamic analysis"
                self.files.add(CSV)
                engine = engines.make(self.engine, model, scene.dynamic, model.reference)
                self.timing["compile_s"] += getattr(engine, "compile_s", 0.0)
                self.built.update(getattr(engine, "modules", ()))
                return _dynamic(engine, scene.dynamic, sensors, self.out, summary, quiet)
        except analysis.ConvergenceError as error:
            raise _Stop(ExitCode.DIVERGED, str(error), "diverged") from None
        except output.OutputError as error:
            raise _Stop(ExitCode.ENVIRONMENT, str(error)) from None
        except JitEnvironmentError as error:  # a dynamic engine compiled on demand
            raise _Stop(ExitCode.ENVIRONMENT, _environment_message(error)) from None
        return ExitCode.OK, None

    def save(self, code: ExitCode) -> ExitCode:
        """Write summary.json (total time and files updated); returns ``code``, or 3
        (environment) if the summary cannot be written and the code was not 2 or 130."""
        summary = self.summary
        self.timing["total_s"] = time.perf_counter() - self.start
        problem = None
        if self.folder_error is not None:
            problem = f"no {SUMMARY} written"
            if summary["message"] != self.folder_error:
                problem = f"{self.folder_error}; {problem}"
        else:
            summary["files"] = sorted(self.files | {SUMMARY})
            try:
                output.write_json_atomic(self.out / SUMMARY, summary)
            except OSError as error:
                summary["files"] = sorted(self.files)
                problem = f"{SUMMARY} not written ({error.strerror or error})"
        if problem is None:
            return code
        if summary["status"] == "ok":
            summary.update(status="failed", message=problem)
        else:
            first, *rest = summary["message"].split("\n", 1)
            summary["message"] = "\n".join([f"{first}; {problem}", *rest])
        if code in (ExitCode.INVALID, ExitCode.INTERRUPTED):
            return code
        return ExitCode.ENVIRONMENT

    def interrupted(self, interrupt: KeyboardInterrupt) -> str:
        """The message of a run stopped by ``interrupt`` (its argument names the signal)."""
        by = f" by {interrupt.args[0]}" if interrupt.args else ""
        if self.phase == "plots":
            return f"interrupted{by} while drawing the plots; the results are complete"
        message = f"interrupted{by} during the {self.phase}"
        dynamic = self.summary.get("dynamic")
        if self.phase == "dynamic analysis" and dynamic is not None:
            message += (f" at t = {dynamic['t_reached']:.6g} s; {CSV} keeps the rows up to "
                        f"then")
        return message


def _owned_files(scene: Scene | None) -> list[str]:
    """Files a run of ``scene`` owns in its folder beside summary.json: the time series,
    the energy plot and a plot named after each sensor (energies had one before they shared
    energies.png: a folder of an earlier version loses those too)."""
    if scene is None:
        return []
    return [CSV, output.ENERGIES_FILE, *(output.plot_file_name(s.name) for s in scene.sensors)]


def _environment_message(error: JitEnvironmentError) -> str:
    """The message of an unusable C backend, first line ending with what to do."""
    first, *rest = str(error).split("\n", 1)
    if isinstance(error, CacheError):
        hint = "set ANCF_CACHE_DIR to a writable folder of yours"
    else:
        hint = "--backend numpy needs no C compiler"
    return "\n".join([f"{first.rstrip('.')}; {hint}", *rest])


def _dynamic(integrator, settings, sensors: Sensors, out: Path, summary: dict,
             quiet: bool) -> tuple[ExitCode, dict[str, list[float]]]:
    """The dynamic analysis with an engine (``runtime.engines``): timeseries.csv written as
    it goes and the time series kept in memory ({"t" or sensor name: values}); fills
    summary["dynamic"] even when interrupted."""
    history: dict[str, list[float]] = {name: [] for name in ["t", *sensors.names]}
    progress = output.Progress(settings.t_end, enabled=False if quiet else None)
    code = ExitCode.OK
    with output.TimeSeriesWriter(out / CSV, sensors.names) as writer:

        def observe(t, q, v):
            values = sensors.values(q, v, t)
            writer.write(t, [values[name] for name in sensors.names])
            history["t"].append(t)
            for name in sensors.names:
                history[name].append(values[name])

        try:
            integrator.run(settings.t_end, settings.step, observe, progress)
        except Divergence as error:
            summary.update(status="diverged", message=str(error))
            code = ExitCode.DIVERGED
        finally:
            progress.close()
            counters = integrator.counters
            summary["dynamic"] = {
                "t_end": settings.t_end, "step": settings.step,
                "integrator": settings.integrator, "engine": integrator.engine,
                "newton": integrator.newton,
                "t_reached": history["t"][-1] if history["t"] else 0.0,
                "steps": counters.steps, "newton_iterations": counters.newton_iterations,
                "force_evaluations": counters.force_evaluations,
                "jacobian_evaluations": counters.jacobian_evaluations,
                "factorisations": counters.factorisations,
                "kernel_s": integrator.timing["kernel_s"],
                "steps_s": integrator.timing["steps_s"],
                "sensors_final": {name: history[name][-1] for name in sensors.names
                                  if history[name]},
            }
    if settings.frequency_of is not None and code == ExitCode.OK:
        post_start = time.perf_counter()
        t = np.asarray(history["t"])
        keep = t >= settings.frequency_after
        try:
            frequency = dominant_frequency(t[keep],
                                           np.asarray(history[settings.frequency_of])[keep])
        except ValueError as error:  # too few samples, a constant signal
            frequency = None
            summary["warnings"].append(f"analysis.dynamic.frequency_of: {error}")
        summary["dynamic"]["response_frequency_rad_s"] = frequency
        summary["timing"]["postprocess_s"] += time.perf_counter() - post_start
    return code, history
