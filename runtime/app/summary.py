"""The summary of a run, typed: what ``summary.json`` holds (docs/design.md section 9).

A :class:`Summary` is filled as the run goes by methods that say what happened
(:meth:`Summary.record_static`, :meth:`Summary.diverged`, ...), so it tells what was done
whenever the run stops; :meth:`Summary.to_dict` gives the JSON document: the keys in the
order of the fields, a field still None left out.
"""

from __future__ import annotations

import copy
from collections.abc import Collection
from dataclasses import dataclass, field, fields
from typing import Any, Protocol

import numpy as np

from runtime.model.settings import Dynamic
from runtime.solve.python_engine import Counters

__all__ = ["DynamicSummary", "ModalSummary", "StaticSummary", "Summary", "Timing"]

DAMPING_IGNORED = ("ignored: undamped natural frequencies (Kelvin-Voigt damping gives mode k "
                   "the damping ratio alpha omega_k / 2)")


def _document(record: Any, omit: Collection[str] = ()) -> dict[str, Any]:
    """The JSON object of a dataclass ``record``: its fields but ``omit`` in order, those that
    are None left out, records as their documents, containers copied."""
    out = {}
    for item in fields(record):
        value = getattr(record, item.name)
        if item.name in omit or value is None:
            continue
        out[item.name] = value.to_dict() if hasattr(value, "to_dict") else copy.deepcopy(value)
    return out


@dataclass
class Timing:
    """Wall times (s) of a run's phases."""

    generate_s: float = 0.0
    compile_s: float = 0.0
    preprocess_s: float = 0.0
    simulate_s: float = 0.0
    postprocess_s: float = 0.0
    total_s: float = 0.0

    def to_dict(self) -> dict[str, float]:
        """``summary["timing"]``."""
        return _document(self)


@dataclass
class StaticSummary:
    """The static analysis: sensor values at equilibrium, Newton iterations, load steps (arc
    length: the steps of the path), and with arc length the method, the load factor of the
    last point, the points of the path (the start included) and why it stopped."""

    sensors: dict[str, float]
    iterations: int
    load_steps: int
    method: str | None = None
    load_factor: float | None = None
    path_points: int | None = None
    stopped: str | None = None

    def to_dict(self) -> dict[str, Any]:
        """``summary["static"]``."""
        return _document(self)


@dataclass
class ModalSummary:
    """The modal analysis: linearisation point (``reference`` or ``static``), natural
    frequencies ascending, and how damping was treated (None: the model is undamped)."""

    about: str
    frequencies_rad_s: list[float]
    frequencies_hz: list[float]
    damping: str | None = None

    def to_dict(self) -> dict[str, Any]:
        """``summary["modal"]``."""
        return _document(self)


class EngineReport(Protocol):
    """What a dynamic engine (``runtime.solve.engines``) tells of its run."""

    engine: str
    newton: str
    linear_solver: str
    counters: Counters
    timing: dict[str, float]


@dataclass
class DynamicSummary:
    """The dynamic analysis however it ended: settings, engine, Newton mode, linear solver
    (``runtime.catalog.LINEAR_SOLVERS``), time reached, work counters,
    engine times (s), last sensor values and, once measured, the response frequency (rad/s;
    None when the signal allowed no measure)."""

    t_end: float
    step: float
    integrator: str
    engine: str
    newton: str
    linear_solver: str
    t_reached: float
    steps: int
    newton_iterations: int
    force_evaluations: int
    jacobian_evaluations: int
    factorisations: int
    kernel_s: float
    steps_s: float
    sensors_final: dict[str, float]
    frequency_measured: bool = False
    response_frequency_rad_s: float | None = None

    @classmethod
    def of(cls, settings: Dynamic, engine: EngineReport, t_reached: float,
           sensors_final: dict[str, float]) -> DynamicSummary:
        """The summary of a run of ``engine`` with ``settings`` that reached ``t_reached``."""
        counters = engine.counters
        return cls(settings.t_end, settings.step, settings.integrator, engine.engine,
                   engine.newton, engine.linear_solver, t_reached, counters.steps,
                   counters.newton_iterations, counters.force_evaluations,
                   counters.jacobian_evaluations, counters.factorisations,
                   engine.timing["kernel_s"],
                   engine.timing["steps_s"], sensors_final)

    def to_dict(self) -> dict[str, Any]:
        """``summary["dynamic"]``: ``response_frequency_rad_s`` only once measured."""
        out = _document(self, omit=("frequency_measured", "response_frequency_rad_s"))
        if self.frequency_measured:
            out["response_frequency_rad_s"] = self.response_frequency_rad_s
        return out


@dataclass
class Summary:
    """What a run did: ``scene`` (its source), ``status`` (ok, diverged, failed,
    interrupted) with ``message`` explaining any but ok, warnings, timing, then as the run
    goes the scene title, method and backend, each analysis, the kernel time (s) and the
    kernels used, the traceback of an internal error and the files written."""

    scene: str
    status: str = "ok"
    message: str = ""
    warnings: list[str] = field(default_factory=list)
    timing: Timing = field(default_factory=Timing)
    title: str | None = None
    method: str | None = None
    backend: str | None = None
    static: StaticSummary | None = None
    modal: ModalSummary | None = None
    dynamic: DynamicSummary | None = None
    kernel_s: float | None = None
    kernels: list[str] | None = None
    traceback: str | None = None
    files: list[str] | None = None
    #: notes on how loads are evaluated (Python loads whose Jacobians are finite differences)
    loads: list[str] | None = None

    def to_dict(self) -> dict[str, Any]:
        """The document of ``summary.json`` (a copy: later records do not change it)."""
        return _document(self)

    def record_title(self, title: str) -> None:
        """The scene is valid; its title."""
        self.title = title

    def record_build(self, method: str, backend: str, compile_s: float,
                     preprocess_s: float) -> None:
        """The model is built with ``method`` and ``backend``, in these times (s)."""
        self.method, self.backend = method, backend
        self.timing.compile_s, self.timing.preprocess_s = compile_s, preprocess_s

    def warn(self, text: str) -> None:
        """A warning (the run goes on)."""
        self.warnings.append(text)

    def record_static(self, sensors: dict[str, float], iterations: int,
                      load_steps: int) -> None:
        """The static equilibrium was found."""
        self.static = StaticSummary(sensors, iterations, load_steps)

    def record_path(self, sensors: dict[str, float], iterations: int, steps: int,
                    load_factor: float, points: int, stopped: str) -> None:
        """The static equilibrium path was traced by arc length to the point of
        ``load_factor`` (``sensors`` there), ``points`` of them, the start included."""
        self.static = StaticSummary(sensors, iterations, steps, "arc_length", load_factor,
                                    points, stopped)

    def record_modal(self, about: str, frequencies_rad_s: np.ndarray, damped: bool) -> None:
        """The natural frequencies (rad/s, ascending) about ``about``; ``damped``: whether
        the model has damping (which they ignore)."""
        self.modal = ModalSummary(about, frequencies_rad_s.tolist(),
                                  (frequencies_rad_s / (2 * np.pi)).tolist(),
                                  DAMPING_IGNORED if damped else None)

    def record_dynamic(self, dynamic: DynamicSummary) -> None:
        """The dynamic analysis ended (completed, diverged, interrupted or failed)."""
        self.dynamic = dynamic

    def record_frequency(self, rad_s: float | None, warning: str | None = None) -> None:
        """The response frequency of the dynamic analysis (rad/s), or None with the
        ``warning`` that says why it could not be measured."""
        self.dynamic.frequency_measured = True
        self.dynamic.response_frequency_rad_s = rad_s
        if warning is not None:
            self.warn(warning)

    def record_kernels(self, kernel_s: float, kernels: list[str]) -> None:
        """Time spent in kernels (s) and the kernels used, as ``kind/family/backend``."""
        self.kernel_s, self.kernels = kernel_s, kernels

    def record_files(self, files: list[str]) -> None:
        """The files written in the output folder (summary.json included once written)."""
        self.files = files

    def diverged(self, message: str) -> None:
        """An analysis diverged (the later ones do not run)."""
        self.status, self.message = "diverged", message

    def failed(self, message: str, traceback: str | None = None) -> None:
        """The run failed; ``traceback`` of an internal error."""
        self.status, self.message = "failed", message
        if traceback is not None:
            self.traceback = traceback

    def interrupted(self, message: str) -> None:
        """The run was interrupted (SIGINT, SIGTERM)."""
        self.status, self.message = "interrupted", message

    def add_problem(self, problem: str) -> None:
        """A problem on top of what happened: it fails a run that was ok, else ends the
        first line of the message."""
        if self.status == "ok":
            self.failed(problem)
        else:
            first, *rest = self.message.split("\n", 1)
            self.message = "\n".join([f"{first}; {problem}", *rest])
