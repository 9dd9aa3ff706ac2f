"""``ancf run``: a scene from file to results (summary.json, timeseries.csv, plots, shapes):
``runtime.app.simulation.run_scene``'s machinery plus writers.

Exit codes (:class:`ExitCode`): 0 ok, 1 diverged, 2 invalid scene or options, 3 environment
(output folder or files, C compiler, kernel cache, memory), 4 internal error (a bug),
130 interrupted (SIGINT, or SIGTERM as the CLI maps it).
"""

from __future__ import annotations

import contextlib
import time
import traceback
from enum import IntEnum
from pathlib import Path

import numpy as np

from runtime import progress
from runtime.app import shapes
from runtime.app import writers as output
from runtime.app.result import Observer
from runtime.app.simulation import Simulation, requested
from runtime.app.summary import Summary
from runtime.kernels.errors import CacheError, JitEnvironmentError
from runtime.model.errors import SceneError
from runtime.model.scene import Scene, load_scene

CSV = "timeseries.csv"
SUMMARY = "summary.json"
# y-axis units of the plots, by sensor type


class ExitCode(IntEnum):
    """Exit codes of ``ancf run`` (README, docs/design.md section 8)."""

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
    """Ends a run early (status "failed"): exit code and message."""

    def __init__(self, code: ExitCode, message: str) -> None:
        super().__init__(message)
        self.code = code


def run(scene_path, out_dir: str | Path, method: str | None = None,
        backend: str | None = None, quiet: bool = False, plots: bool = True,
        engine: str | None = None, vtk: bool | None = None, animation: bool | None = None,
        plane: str = "auto") -> tuple[dict, int]:
    """Run every analysis of a scene (a TOML path or a parsed Scene) into the folder
    ``out_dir``; returns (summary, exit code) - see :class:`ExitCode`.

    Order: the scene is validated; ``out_dir`` is created, checked writable and cleared of a
    previous run's outputs (only those); the model is built (kernels compiled); the analyses
    run (:func:`runtime.app.simulation.run_scene`'s machinery), timeseries.csv and, if asked, the
    VTU series written as they go.  summary.json is written atomically when the analyses
    end, then the plots are drawn (unless ``plots`` is False) with, if asked, the shape
    snapshot and animation, and the summary rewritten with their time in
    ``timing.postprocess_s``, their files and warnings.  ``summary["message"]`` explains any
    code but 0; its first line is the one-line report.  If ``out_dir`` cannot be written the
    message says that no summary.json was written.  A KeyboardInterrupt writes the summary
    with status "interrupted" and raises :class:`RunInterrupted`.

    vtk, animation: write ``vtk/`` (static.vtu, mode_K.vtu, dynamic.pvd) and the snapshot
    ``shape_static.png`` / animation ``shape_animation.gif`` projected on ``plane`` (xy,
    xz, yz, or auto: ``shapes.view_plane``); None: as the scene's ``[output]`` table says.
    quiet: no progress on stderr.
    """
    job = _Job(scene_path, Path(out_dir))
    try:
        with progress.enabled(not quiet):
            code = job.execute(method, backend, plots, engine, vtk, animation, plane)
    except _Stop as stop:
        job.summary.failed(str(stop))
        code = job.save(stop.code)
    except KeyboardInterrupt as interrupt:
        job.summary.interrupted(job.interrupted(interrupt))
        job.save(ExitCode.INTERRUPTED)
        if plots:
            job.plots_of_kept_rows()
        raise RunInterrupted(job.summary.to_dict()) from None
    except MemoryError:
        job.summary.failed(f"out of memory during the {job.phase}")
        code = job.save(ExitCode.ENVIRONMENT)
    except Exception as error:  # a bug: still leave a summary that says what happened
        job.summary.failed(f"internal error during the {job.phase}: "
                           f"{type(error).__name__}: {error}", traceback.format_exc())
        code = job.save(ExitCode.INTERNAL)
    return job.summary.to_dict(), code


class _CsvWriter(Observer):
    """timeseries.csv of the dynamic analysis, a whole row at every output time."""

    def __init__(self, job: _Job) -> None:
        self.job = job
        self.writer: output.TimeSeriesWriter | None = None

    def dynamic_start(self, names: list[str]) -> None:
        self.names = names
        self.job.files.add(CSV)
        self.writer = output.TimeSeriesWriter(self.job.out / CSV, names)

    def samples(self, times: np.ndarray, q: np.ndarray, v: np.ndarray,
                values: dict[str, np.ndarray]) -> None:
        self.writer.write_rows(times, np.column_stack([values[name] for name in self.names])
                               if self.names else np.empty((len(times), 0)))

    def dynamic_end(self) -> None:
        if self.writer is not None:
            self.writer.close()


class _PathWriter(Observer):
    """static_path.csv of an arc-length static analysis, a row per converged point."""

    def __init__(self, job: _Job) -> None:
        self.job = job

    def static_path(self, path: dict[str, np.ndarray]) -> None:
        self.job.files.add(output.PATH_CSV)
        output.write_path(self.job.out / output.PATH_CSV, path)


class _Job:
    """One run: its summary, output folder and the files it wrote there."""

    def __init__(self, scene_path, out: Path) -> None:
        self.start = time.perf_counter()
        self.scene_path, self.out = scene_path, out
        given = isinstance(scene_path, Scene)
        self.summary = Summary(scene_path.source if given else str(scene_path))
        self.folder_error: str | None = "the output folder is not ready"
        self.files: set[str] = set()
        self.unwritten: list[str] = []   # outputs asked for that the environment kept out
        self.csv = _CsvWriter(self)
        self.simulation: Simulation | None = None
        self._phase: str | None = "scene validation"

    @property
    def phase(self) -> str:
        """The step under way: the job's own, or the simulation's while it runs."""
        return self._phase or self.simulation.phase

    def execute(self, method: str | None, backend: str | None, plots: bool,
                engine: str | None, vtk: bool | None, animation: bool | None,
                plane: str) -> ExitCode:
        scene, invalid = None, None
        if isinstance(self.scene_path, Scene):
            scene = self.scene_path
        else:
            try:
                scene = load_scene(self.scene_path)
            except SceneError as error:
                invalid = str(error)
        self._phase = "output folder check"
        try:
            output.prepare_folder(self.out, _owned_files(scene))
            self.folder_error = None
        except output.OutputError as error:
            self.folder_error = str(error)
        if invalid is not None:
            raise _Stop(ExitCode.INVALID, invalid)
        if self.folder_error is not None:
            raise _Stop(ExitCode.ENVIRONMENT, self.folder_error)
        if plane not in (shapes.AUTO_PLANE, *shapes.PLANES):
            raise _Stop(ExitCode.INVALID, f"plane: expected {shapes.AUTO_PLANE} or one of "
                                          f"{', '.join(shapes.PLANES)}, got {plane!r}")
        vtk = requested(scene, "vtk") if vtk is None else vtk
        animation = requested(scene, "animation") if animation is None else animation
        observers: list[Observer] = [self.csv, _PathWriter(self)]
        series = shapes.VtkSeries(self.out / output.VTK_FOLDER) if vtk else None
        frames = shapes.Frames() if animation else None
        observers += [o for o in (series, frames) if o is not None]
        self.simulation = simulation = Simulation(scene, method, backend, engine,
                                                  observers=observers, summary=self.summary)
        self._phase = None
        try:
            simulation.build()
        except (JitEnvironmentError, output.OutputError) as error:
            raise _environment_stop(error) from None
        except OSError as error:  # kernel cache folder or generated kernels unusable
            where = f"{error.filename}: " if error.filename else ""
            raise _Stop(ExitCode.ENVIRONMENT, f"{where}{error.strerror or error} while "
                        f"preparing the kernels; check ANCF_CACHE_DIR, the kernel cache "
                        f"folder") from None
        except ValueError as error:
            raise _Stop(ExitCode.INVALID, str(error)) from None
        try:
            code = ExitCode(simulation.analyses())
        except (JitEnvironmentError, output.OutputError) as error:  # a dynamic engine
            raise _environment_stop(error) from None                # compiled on demand
        finally:
            if series is not None:
                self.files.update(series.files)
            if self.csv.writer is not None:   # the summary says what the CSV holds
                simulation.keep_outputs(self.csv.writer.rows)
        self._phase = "summary writing"
        code = self.save(code)
        if code in (ExitCode.OK, ExitCode.DIVERGED):
            self._phase = "plots"
            post_start = time.perf_counter()
            drawn = self._plots(scene, simulation) if plots else False
            if animation:
                drawn = self._shapes(scene, simulation, frames, plane) or drawn
            if drawn:
                self.summary.timing.postprocess_s += time.perf_counter() - post_start
                if self.unwritten:
                    self.summary.add_problem(f"not written: {'; '.join(self.unwritten)}")
                    code = ExitCode.ENVIRONMENT
                code = self.save(code)
        return code

    def plots_of_kept_rows(self) -> None:
        """After an interrupt of the dynamic analysis, the plots of the rows it kept, and the
        summary again with their files (a second interrupt leaves them undrawn)."""
        simulation = self.simulation
        if self.phase != "dynamic analysis" or self.folder_error is not None:
            return
        with contextlib.suppress(KeyboardInterrupt):
            if self._plots(simulation.scene, simulation):
                self.save(ExitCode.INTERRUPTED)

    def _plots(self, scene: Scene, simulation: Simulation) -> bool:
        """The sensor plots of the dynamic analysis and the plot of the arc-length path;
        whether any was attempted."""
        history = simulation.history
        units = {s.name: s.unit for s in scene.sensors}
        if simulation.path:
            energies = simulation.sensors.energy_names
            series = {name: values for name, values in simulation.path.items()
                      if name != "load_factor" and name not in energies}
            written, warnings = output.plot_path(simulation.path["load_factor"], series,
                                                 self.out, units)
            self.files.update(path.name for path in written)
            for text in warnings:
                self.summary.warn(text)
        if not history.get("t"):
            return bool(simulation.path)
        sensors = simulation.sensors
        series = {name: history[name] for name in sensors.names}
        unwritten: list[str] = []
        written, warnings = output.plot_series(history["t"], series, self.out, units,
                                               sensors.energy_names, unwritten=unwritten)
        self.files.update(path.name for path in written)
        self.unwritten += unwritten
        for text in warnings:
            if text not in unwritten:
                self.summary.warn(text)
        return True

    def _shapes(self, scene: Scene, simulation: Simulation, frames: shapes.Frames | None,
                plane: str) -> bool:
        """The static snapshot and the animation, those that have data; whether any was
        attempted.  A failure is a warning, as for the plots."""
        drawn = []
        if simulation.static_q is not None:
            line = shapes.Shape(simulation.model)
            drawn.append((output.SHAPE_FILE, lambda path: shapes.write_snapshot(
                path, line, simulation.model.reference, simulation.static_q, scene.title,
                plane=plane)))
        if frames is not None and frames.frames:
            drawn.append((output.ANIMATION_FILE, lambda path: shapes.write_animation(
                path, frames, scene.title, plane)))
        for name, draw in drawn:
            try:
                draw(self.out / name)
                self.files.add(name)
            except Exception as error:
                text = f"{name}: not written ({type(error).__name__}: {error})"
                if isinstance(error, OSError):   # a full disk: exit 3, not a warning
                    self.unwritten.append(text)
                else:
                    self.summary.warn(text)
        return bool(drawn)

    def save(self, code: ExitCode) -> ExitCode:
        """Write summary.json (total time and files updated); returns ``code``, or 3
        (environment) if the summary cannot be written and the code was not 2 or 130."""
        summary = self.summary
        summary.timing.total_s = time.perf_counter() - self.start
        problem = None
        if self.folder_error is not None:
            problem = f"no {SUMMARY} written"
            if summary.message != self.folder_error:
                problem = f"{self.folder_error}; {problem}"
        else:
            summary.record_files(sorted(self.files | {SUMMARY}))
            try:
                output.write_json_atomic(self.out / SUMMARY, summary.to_dict())
            except OSError as error:
                summary.record_files(sorted(self.files))
                problem = f"{SUMMARY} not written ({error.strerror or error})"
        if problem is None:
            return code
        summary.add_problem(problem)
        if code in (ExitCode.INVALID, ExitCode.INTERRUPTED):
            return code
        return ExitCode.ENVIRONMENT

    def interrupted(self, interrupt: KeyboardInterrupt) -> str:
        """The message of a run stopped by ``interrupt`` (its argument names the signal)."""
        by = f" by {interrupt.args[0]}" if interrupt.args else ""
        if self.phase == "plots":
            return f"interrupted{by} while drawing the plots; the results are complete"
        message = f"interrupted{by} during the {self.phase}"
        dynamic = self.summary.dynamic
        if self.phase == "dynamic analysis" and dynamic is not None:
            message += (f" at t = {dynamic.t_reached:.6g} s; {CSV} keeps the rows up to "
                        f"then")
        return message


def _owned_files(scene: Scene | None) -> list[str]:
    """Files a run of ``scene`` owns in its folder beside summary.json: the time series,
    the energy plot, the shape snapshot and animation, and a plot named after each sensor
    (energies had one before they shared energies.png: a folder of an earlier version loses
    those too)."""
    if scene is None:
        return []
    return [CSV, output.PATH_CSV, *output.RESERVED_FILES, output.ANIMATION_FILE,
            *(output.plot_file_name(s.name) for s in scene.sensors)]


def _environment_stop(error: JitEnvironmentError | output.OutputError) -> _Stop:
    """Exit 3 for an unusable output file or C backend; for the latter the first line of the
    message ends with what to do."""
    if isinstance(error, output.OutputError):
        return _Stop(ExitCode.ENVIRONMENT, str(error))
    first, *rest = str(error).split("\n", 1)
    if isinstance(error, CacheError):
        hint = "set ANCF_CACHE_DIR to a writable folder of yours"
    else:
        hint = "--backend numpy needs no C compiler"
    return _Stop(ExitCode.ENVIRONMENT, "\n".join([f"{first.rstrip('.')}; {hint}", *rest]))
