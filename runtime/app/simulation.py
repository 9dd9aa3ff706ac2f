"""``run_scene``: every analysis of a scene in memory, with no file I/O, into a ``Result``
(``runtime.app.result``), what it did recorded in a ``Summary`` (``runtime.app.summary``).

``ancf run`` (``runtime.app.run``) is ``run_scene`` plus writers: they are ``Observer``
objects that receive the results as they are computed (the time-series CSV and the VTU
series stream rows and files while the dynamic analysis goes on).
"""

from __future__ import annotations

import contextlib
import os
import time
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from runtime.app.result import Modes, Observer, Result, States
from runtime.app.signal import dominant_frequency
from runtime.app.summary import DynamicSummary, Summary
from runtime.catalog import INTEGRATORS, POISSON_LOCKING_LAWS
from runtime.kernels.kind import element_kind
from runtime.model.dae import StateLoads
from runtime.model.items.python_loads import load_notes
from runtime.model.items.sensors import Samples, Sensors
from runtime.model.model import Model
from runtime.model.scene import Scene, load_scene
from runtime.model.settings import Static
from runtime.progress import Bar, enabled, warn
from runtime.solve import arc_length, engines
from runtime.solve import static as analysis
from runtime.solve.modal import modal_shapes
from runtime.solve.python_engine import Divergence, OutputDynamics, StateLimits

__all__ = ["Simulation", "requested", "run_scene"]


def requested(scene: Scene, name: str) -> bool:
    """Whether the scene's ``[output]`` table asks for ``name`` (vtk, animation, states);
    False for a scene without one."""
    return bool(getattr(getattr(scene, "output", None), name, False))


class Simulation:
    """One in-memory run of ``scene``: :meth:`build`, then :meth:`analyses`, then
    :meth:`result`.  ``summary`` (the :class:`Summary` given, or a new one) is filled as the
    run goes, so it says what was done when an exception stops it; ``phase`` names the
    current step.

    method, backend, engine: overrides of the scene's ``[solver]``; store_states: keep
    :class:`States`; observers: :class:`Observer` objects, called in order.
    """

    def __init__(self, scene: Scene, method: str | None = None, backend: str | None = None,
                 engine: str | None = None, store_states: bool = False,
                 observers: Sequence[Observer] = (), summary: Summary | None = None) -> None:
        self.scene, self.method, self.backend = scene, method, backend
        self.engine_name = engine
        self.store_states = store_states
        self.observers = _observers(observers)
        self.summary = summary if summary is not None else Summary(scene.source)
        self.summary.record_title(scene.title)
        self.phase = "model build"
        self.model: Model | None = None
        self.static_q: np.ndarray | None = None
        self._static_multipliers: np.ndarray | None = None
        self.modes: Modes | None = None
        self.path: dict[str, np.ndarray] = {}   # arc length: load_factor and sensors
        self.history: dict[str, list[float]] = {}
        self._states: tuple[list, list] = ([], [])
        self._built: set[str] = set()   # modules built for this run beyond the kernels
        self._setup_s = 0.0   # seconds building engines during the analyses (not simulating)
        self._dynamics: OutputDynamics | None = None   # equations of motion at the outputs

    def build(self) -> Model:
        """Build the model (kernels compiled or loaded) and its sensors; choose the engine.
        Raises ValueError (invalid options), JitEnvironmentError and OSError (kernels)."""
        self.phase = "model build"
        solver = self.scene.solver
        if self.engine_name is None and solver.engine == "compiled" and \
                (self.backend or solver.backend) != "c":
            # the scene's engine (an engine option is checked by engines.choose)
            given = (f'solver.backend = "{solver.backend}"' if self.backend is None
                     else f'the backend option "{self.backend}"')
            raise ValueError(f'solver.engine: the compiled engine needs backend "c", got '
                             f'{given}; use engine = "python" or backend = "c"')
        model = Model(self.scene, self.method, self.backend)
        self.engine_name = engines.choose(self.engine_name or solver.engine, model.backend)
        self.summary.record_build(model.method, model.backend, model.timing["compile_s"],
                                  model.timing["preprocess_s"])
        self.sensors = Sensors(model)
        self.model = model
        if self.scene.static is not None or (self.scene.modal is not None
                                             and self.scene.modal.about == "static"):
            analysis.check_held(model)   # before any work: a free body has no equilibrium
        self.summary.loads = load_notes(self.scene.loads) or None
        for text in locking_warnings(self.scene):
            self.summary.warn(text)
        for observer in self.observers:
            observer.begin(model)
        return model

    def analyses(self) -> int:
        """Static, modal and dynamic analyses, those the scene declares, in that order.
        Returns 0, or 1 when one diverged (status "diverged"; the later ones do not run).
        Other exceptions propagate (``summary`` keeps what was done)."""
        scene, model, summary = self.scene, self.model, self.summary
        timing = summary.timing
        start = time.perf_counter()
        try:
            if scene.static is not None:
                self.phase = "static analysis"
                found = self._solve_static(scene.static)
                self.static_q, self._static_multipliers = found.q, found.multipliers
                if self.path:
                    for observer in self.observers:
                        observer.static_path(self.path)
                else:
                    summary.record_static(self._static_sensors(found), found.iterations,
                                          found.load_steps)
                for observer in self.observers:
                    observer.static(found.q)
            if scene.modal is not None:
                self.phase = "modal analysis"
                self._modal()
            if scene.dynamic is not None:
                return self._dynamic(scene.dynamic)
        except analysis.ConvergenceError as error:
            summary.diverged(str(error))
            return 1
        finally:
            # post-processing (frequency fit) is timed apart from the simulation
            timing.simulate_s = (time.perf_counter() - start - timing.postprocess_s
                                 - self._setup_s)
            # the Python engine's kernel calls go through the model, the compiled one's not
            dynamic = summary.dynamic
            compiled = dynamic is not None and dynamic.engine == "compiled"
            summary.record_kernels(
                model.kernel_seconds + (dynamic.kernel_s if compiled else 0.0),
                sorted(self._built | {
                    f"{b.element.kind.name}/{f}/{model.backend}" for b in model.bodies.values()
                    for f in b.element.loaded_families}))
        return 0

    def _static_sensors(self, found: analysis.StaticResult) -> dict[str, float]:
        """The sensors at the static equilibrium: at rest, loads at their nominal value, the
        joint multipliers of the solution (reactions)."""
        angles = found.spring_angles
        if not self.sensors.dynamics:
            return self.sensors.values(found.q, t=None, spring_angles=angles)
        model = self.model
        force = model.internal_forces(found.q, jacobian=False)[0] + model.nominal_load()
        followers = StateLoads(model)
        if followers:
            if angles is not None:
                followers.count_turns(angles)
            force += followers.evaluate(found.q, np.ones(len(self.scene.loads)), False)[0]
        return self.sensors.values(found.q, t=None, a=np.zeros(model.size),
                                   multipliers=found.multipliers, force=force,
                                   spring_angles=angles)

    def _solve_static(self, settings) -> analysis.StaticResult:
        """The static equilibrium with the chosen engine's Newton solve, or the end of the
        arc-length path (its load factors and sensors into ``path``, the summary's static
        record filled)."""
        if settings.method == "arc_length":
            return self._trace_path(settings)
        dynamic = self.scene.dynamic
        start = time.perf_counter()
        newton = engines.static_newton(self.engine_name, self.model, settings,
                                       dynamic.integrator if dynamic else INTEGRATORS[0])
        if newton is not None:
            self._charge_setup(newton, time.perf_counter() - start)
        return analysis.solve_static(self.model, settings, newton)

    def _trace_path(self, settings) -> analysis.StaticResult:
        """The arc-length path (``runtime.solve.arc_length``, through the Python solves
        whatever the engine), stopped by ``settings``' load factor or sensor criterion."""
        values = lambda q: self.sensors.values(q, t=None)  # noqa: E731
        start = values(self.model.reference)
        name, target = settings.stop_sensor, settings.stop_value

        def stop(q: np.ndarray, load_factor: float) -> str | None:
            if load_factor >= settings.max_load_factor:
                return f"load factor {load_factor:.6g} >= max_load_factor"
            if name is not None:
                value = values(q)[name]
                if (value - target) * (start[name] - target) <= 0.0:
                    return f"sensor {name} = {value:.6g} passed stop_value = {target:g}"
            return None

        found = arc_length.trace_path(self.model, settings, stop)
        rows = [self.sensors.values(q, t=None, spring_angles=angles)
                for q, angles in zip(found.states, found.spring_angles, strict=True)]
        self.path = {"load_factor": found.load_factors,
                     **{n: np.array([row[n] for row in rows]) for n in self.sensors.names}}
        self.summary.record_path(rows[-1], found.iterations, found.steps, found.load_factor,
                                 len(rows), found.stopped)
        return analysis.StaticResult(found.q, found.multipliers, found.iterations,
                                     found.steps, found.spring_angles[-1])

    def _charge_setup(self, engine, seconds: float) -> None:
        """An engine built in ``seconds`` (its generated step compiled or loaded): its
        compile time is compile_s, the rest pre-processing; neither is simulate_s."""
        timing = self.summary.timing
        timing.compile_s += engine.compile_s
        timing.preprocess_s += seconds - engine.compile_s
        self._setup_s += seconds
        self._built.update(engine.modules)

    def _modal(self) -> None:
        model, settings = self.model, self.scene.modal
        about, multipliers = model.reference, None
        if settings.about == "static":
            if self.static_q is None:
                found = self._solve_static(self.scene.static or Static())
                self.static_q, self._static_multipliers = found.q, found.multipliers
            about, multipliers = self.static_q, self._static_multipliers
        found = modal_shapes(model, about, settings.modes, multipliers)
        self.modes = Modes(found.frequencies, found.shapes, np.array(about))
        self.summary.record_modal(settings.about, found.frequencies, model.damped)
        for observer in self.observers:
            observer.modal(self.modes)

    def _observe(self, times: np.ndarray, q: np.ndarray, v: np.ndarray,
                 dissipated: np.ndarray, angles: np.ndarray) -> None:
        """A block of output times (k,): states (k, size), dissipated energy (k,), the
        torsional springs' joint angles (k, loads; ``Samples.spring_angles``).  Raises
        Divergence at the first output whose state or sensors are non-finite or absurd
        (``StateLimits``), after observing those before it."""
        dynamics = self._dynamics(times, q, v, angles) if self._dynamics is not None else ()
        values = self.sensors.block(Samples(times, q, v, dissipated, *dynamics,
                                            spring_angles=angles))
        insane = self._first_insane(q, v, values)
        if insane is not None:
            row, cause = insane
            if row:
                self._record(times[:row], q[:row], v[:row],
                             {name: x[:row] for name, x in values.items()})
            raise Divergence(float(times[row]), cause)
        self._record(times, q, v, values)

    def _first_insane(self, q: np.ndarray, v: np.ndarray, values: dict[str, np.ndarray]
                      ) -> tuple[int, str] | None:
        """(row, cause) of the first output of a block whose state (``StateLimits``) or
        sensor values are not sane, or None."""
        found = self._limits.first_insane(q, v, self.model.reference)
        for name, value in values.items():
            bad = ~np.isfinite(value)
            if bad.any() and (found is None or int(np.argmax(bad)) < found[0]):
                row = int(np.argmax(bad))
                found = (row, f"non-finite sensor {name} ({value[row]})")
        return found

    def _record(self, times: np.ndarray, q: np.ndarray, v: np.ndarray,
                values: dict[str, np.ndarray]) -> None:
        """Sane output times (k,) with their states (k, size) and sensor values (k,) into the
        history and to the observers."""
        # the history first: it is never behind what an observer wrote (``keep_outputs``
        # cuts it back to what they did write)
        self.history["t"].extend(times.tolist())
        for name in self.sensors.names:
            self.history[name].extend(values[name].tolist())
        if self.store_states:
            self._states[0].extend(np.array(q))
            self._states[1].extend(np.array(v))
        if all(type(o).samples is not Observer.samples for o in self.observers):
            for observer in self.observers:
                observer.samples(times, q, v, values)
            return
        # an observer takes one output time at a time: every observer sees each time before
        # any sees the next (as the order of the hooks promises)
        for row in range(len(times)):
            rows = slice(row, row + 1)
            one = {name: value[rows] for name, value in values.items()}
            for observer in self.observers:
                observer.samples(times[rows], q[rows], v[rows], one)

    def keep_outputs(self, count: int) -> None:
        """Keep the first ``count`` output times of the dynamic analysis only (those a writer
        did write when the run stopped): history, states and the summary's ``t_reached``
        and ``sensors_final`` follow."""
        history, dynamic = self.history, self.summary.dynamic
        if not history or len(history["t"]) <= count:
            return
        for values in (*history.values(), *self._states):
            del values[count:]
        if dynamic is not None:
            dynamic.t_reached = history["t"][-1] if count else 0.0
            dynamic.sensors_final = {name: history[name][-1] for name in self.sensors.names
                                     if history[name]}

    def _dynamic(self, settings) -> int:
        """The dynamic analysis with the chosen engine (``runtime.solve.engines``); fills
        the summary's ``dynamic`` however it ends."""
        self.phase = "dynamic analysis"
        names = self.sensors.names
        start = time.perf_counter()
        engine = engines.make(self.engine_name, self.model, settings, self.model.reference)
        self._dynamics = OutputDynamics(engine.dae, engine.mass) if self.sensors.dynamics else None
        self._limits = StateLimits.of(engine.dae, settings.t_end)
        self._charge_setup(engine, time.perf_counter() - start)
        self.history = {name: [] for name in ["t", *names]}
        for observer in self.observers:
            observer.dynamic_start(list(names))
        code, failed = 0, True
        bar = Bar("dynamic analysis", settings.t_end, "s")
        try:
            engine.run(settings.t_end, settings.step, progress=bar,
                       observe_block=self._observe)
            failed = False
        except Divergence as error:
            self.summary.diverged(str(error))
            code, failed = 1, False
        finally:
            bar.close()
            history = self.history
            self.summary.record_dynamic(DynamicSummary.of(
                settings, engine, history["t"][-1] if history["t"] else 0.0,
                {name: history[name][-1] for name in names if history[name]}))
            for observer in self.observers:
                with contextlib.suppress(Exception) if failed else contextlib.nullcontext():
                    observer.dynamic_end()
        if settings.frequency_of is not None and code == 0:
            self._frequency(settings)
        return code

    def _frequency(self, settings) -> None:
        """The response frequency of ``settings.frequency_of`` (timed as post-processing)."""
        start = time.perf_counter()
        t = np.asarray(self.history["t"])
        keep = t >= settings.frequency_after
        try:
            frequency, warning = dominant_frequency(
                t[keep], np.asarray(self.history[settings.frequency_of])[keep]), None
        except ValueError as error:  # too few samples, a constant signal
            frequency, warning = None, f"analysis.dynamic.frequency_of: {error}"
        self.summary.record_frequency(frequency, warning)
        self.summary.timing.postprocess_s += time.perf_counter() - start

    def result(self, exit_code: int) -> Result:
        """The :class:`Result` of the run so far."""
        sensors = {name: np.asarray(values, float) for name, values in self.history.items()}
        states = None
        if self.store_states and self.history:
            size = self.model.size
            q, v = (np.array(x).reshape(-1, size) for x in self._states)
            states = States(np.asarray(self.history["t"], float), q, v)
        return Result(self.summary.to_dict(), sensors, self.static_q, self.modes, states,
                      self.model, exit_code, dict(self.path))


def _observers(observers: Sequence[Observer]) -> list[Observer]:
    """``observers`` as a list; TypeError naming the argument unless it is a sequence of
    :class:`Observer` objects."""
    if not isinstance(observers, Sequence) or isinstance(observers, str):
        raise TypeError(f"observers: expected a sequence (list or tuple) of "
                        f"runtime.app.result.Observer objects, got {type(observers).__name__} "
                        f"{observers!r}")
    for k, observer in enumerate(observers):
        if not isinstance(observer, Observer):
            raise TypeError(f"observers[{k}]: expected a runtime.app.result.Observer (subclass "
                            f"it and override the hooks you need), got "
                            f"{type(observer).__name__} {observer!r}")
    return list(observers)


def locking_warnings(scene: Scene) -> list[str]:
    """A warning per material and kind of domain (beams, plates) that uses a law of
    ``catalog.POISSON_LOCKING_LAWS`` with nu != 0 (Poisson locking, by the amount
    ``ElementKind.svk_locking`` states)."""
    out = []
    for name in sorted({body.material for body in scene.bodies}):
        material = scene.materials[name]
        if material.law not in POISSON_LOCKING_LAWS:
            continue
        nu = material.nu
        locking = dict(filter(None, (element_kind(b.element).svk_locking(nu)
                                     for b in scene.bodies if b.material == name)))
        if "beams" in locking:
            excess = locking["beams"]
            out.append(f"material.{name}: law \"svk\" with nu = {nu:g} locks in bending "
                       f"(Poisson locking): its beams come out up to {excess:.0%} too stiff "
                       f"in bending (bending modulus lam + 2G = {1 + excess:.3g} E instead of "
                       f"E, 2D and 3D beams alike: deflections up to {excess / (1 + excess):.0%}"
                       f" too small); use law = \"ecm\" (docs/laws.md)")
        if "plates" in locking:
            out.append(f"material.{name}: law \"{material.law}\" with nu = {nu:g} locks in "
                       f"bending (Poisson thickness locking): its plates come out about "
                       f"{locking['plates']:.0%} too stiff in bending (their thickness strain "
                       f"is constant across the thickness; no law removes that, ecm needs a "
                       f"beam axis); shell3d_3833 (r_zz) does not lock, nor do plates at "
                       f"nu = 0")
    return out


def run_scene(scene: Scene | str | Path, method: str | None = None,
              backend: str | None = None, engine: str | None = None, *,
              progress: bool = True, store_states: bool | None = None,
              observers: Sequence[Observer] = ()) -> Result:
    """Run every analysis of ``scene`` (a Scene, or a TOML file path) in memory.

    method, backend, engine: overrides of the scene's ``[solver]``; progress: show the
    progress of long phases on stderr (``runtime.progress``); store_states: keep the states
    at every output time in ``result.states`` (default: the scene's ``[output] states``);
    observers: receive results as they are computed (see :class:`Observer`).

    Returns a :class:`Result` with exit code 0 (ok) or 1 (a diverged analysis: the results
    up to then are kept).  Raises SceneError / ValueError for an invalid scene or option,
    ``runtime.kernels.errors.JitEnvironmentError`` or OSError when the kernels cannot be built, and
    KeyboardInterrupt as it comes.
    """
    start = time.perf_counter()
    if not isinstance(scene, Scene | str | os.PathLike):
        raise TypeError(f"scene: expected a runtime.Scene or the path of a TOML scene file "
                        f"(str or pathlib.Path), got {type(scene).__name__} {scene!r}")
    if not isinstance(scene, Scene):
        scene = load_scene(scene)
    if store_states is None:
        store_states = requested(scene, "states")
    simulation = Simulation(scene, method, backend, engine, store_states, observers)
    with enabled(progress):
        simulation.build()
        for text in simulation.summary.warnings:   # ``ancf run`` reports them at the end
            warn(text)
        code = simulation.analyses()
    simulation.summary.timing.total_s = time.perf_counter() - start
    return simulation.result(code)
