"""``ancf study error-vs-time SCENE``: a work-precision study of a scene.

Every combination of mesh size (elements per body), time step (s), integrator and elastic
force method is run as an independent case (in parallel through ``runtime.studies.sweep``);
each run's error is measured

* ``static_tip``: against the Euler-Bernoulli tip deflection ``P L^3 / (3 E I)`` of a
  cantilever (relative error of the static value of a displacement sensor of the loaded tip);
* ``frequency``: against the first bending frequency ``1.8751^2 sqrt(E I / (rho A L^4))``
  (rad/s) of a cantilever (relative error of the dynamic response frequency of a sensor);
* ``reference``: against a converged reference run on a finer mesh and step (max abs
  difference of the sensor's time series on the reference's output times, divided by the
  reference's max abs value);

and its wall time is taken from the run's summary (``simulate_s``: the analyses, without
compilation and plots; ``total_s``: the whole run).  Outputs in the study folder:
``error_vs_time.csv`` (one row per run), ``error_vs_time.png`` (log-log error against
simulate time, one line per method and integrator) and ``error_vs_time.md`` (the table and a
paragraph on which choice is cheapest for a given accuracy).

The sweep comes from a ``[study]`` table of the scene and/or from command-line options, which
override the table::

    [study]
    elements = [2, 5, 10]                  # elements per body
    step = [1e-3, 5e-4]                    # s (dynamic errors only)
    integrator = ["trapezoidal", "generalized_alpha"]
    method = ["gram", "cij", "quadrature"]
    backend = "c"
    error = "frequency"                    # static_tip | frequency | reference
    sensor = "tip_y"                       # the sensor the error is computed from
    reference = { elements = 40, step = 2.5e-4 }   # reference runs (error = "reference")
    t_end = 4.0                            # s, overrides [analysis.dynamic].t_end
    repeat = 1                             # runs per case, the fastest kept (static: 5)
    targets = [1e-2, 1e-3]                 # accuracies of the summary (default: decades)

Every run keeps only the analysis and the sensor its error needs (the static analysis for
``static_tip``, the dynamic one otherwise), so the times measure what the error measures.
"""

from __future__ import annotations

import argparse
import copy
import csv
import dataclasses
import itertools
import math
import re
import socket
import sys
import tempfile
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from runtime.catalog import BACKENDS, INTEGRATORS, METHODS
from runtime.model.errors import SceneError
from runtime.model.scene import Scene, parse_scene
from runtime.model.settings import Static
from runtime.model.toml_io import read_scene_file
from runtime.studies.sweep import SchedulerError, run_cases

__all__ = [
    "CSV_COLUMNS",
    "MEASURES",
    "StudyError",
    "add_cli",
    "plan_study",
    "run_case",
    "study",
]

MEASURES = ("static_tip", "frequency", "reference")
STUDY_KEYS = ("elements", "step", "integrator", "method", "backend", "error", "sensor",
              "reference", "t_end", "repeat", "targets")
REFERENCE_KEYS = ("elements", "step", "integrator", "method")
CSV_COLUMNS = ("elements", "step", "integrator", "method", "backend", "error", "simulate_s",
               "total_s", "status", "measure", "value", "exact", "newton_iterations", "role",
               "message")
# first root of 1 + cos(x) cosh(x) = 0: omega_1 = BETA_L^2 sqrt(E I / (rho A L^4))
BETA_L = 1.8751040687119611
POSITION_SENSORS = ("displacement", "position")
ANNOTATE_ALL = 30       # annotate every point of the plot up to this many
CLOSE = 1.1             # times within this factor of the best are called a tie


class StudyError(ValueError):
    """An invalid study: the message starts with the key (``study.step[1]``) or the option
    (``--step``) at fault and says what was expected and what was found."""


# --------------------------------------------------------------------------- validation

def _show(value: Any) -> str:
    return repr(value)


def _is_number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool) and \
        math.isfinite(value)


def _items(value: Any, label: str) -> list:
    """A sweep list (a scalar counts as a list of one); an empty one is an error."""
    items = list(value) if isinstance(value, list | tuple) else [value]
    if not items:
        raise StudyError(f"{label}: the study has no runs: expected at least one value, "
                         "got an empty list")
    return items


def _unique(values: list) -> list:
    out: list = []
    for value in values:
        if value not in out:
            out.append(value)
    return out


def _positive_int(value: Any, label: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value <= 0:
        raise StudyError(f"{label}: expected a positive integer, got {_show(value)}")
    return value


def _positive_number(value: Any, label: str) -> float:
    if not _is_number(value) or value <= 0:
        raise StudyError(f"{label}: expected a positive number, got {_show(value)}")
    return float(value)


def _choice(value: Any, label: str, choices: Sequence[str], what: str) -> str:
    if not isinstance(value, str) or value not in choices:
        raise StudyError(f"{label}: unknown {what} {_show(value)}; expected one of "
                         f"{', '.join(choices)}")
    return value


def _sweep(value: Any, label: str, check) -> list:
    return _unique([check(item, f"{label}[{i}]") for i, item in enumerate(_items(value, label))])


# --------------------------------------------------------------------------- cantilever physics

@dataclass(frozen=True)
class Cantilever:
    """Closed-form data of a straight clamped beam with a tip force.

    deflection: Euler-Bernoulli static tip displacement (dim,) in m (bending ``P L^3 / 3EI``
    about each principal axis of the section plus the axial ``P L / EA``); frequency: first
    bending angular frequency (rad/s) in the plane of the load, None when the load is not
    along a principal axis of a non-square section; tip: the loaded node; clamp: the clamped
    node; frame: the section's local axes (dim, dim), columns x (along the beam), y (height),
    z (width); load (N), length (m), inertia (m^4, about the bending axis of the load).
    """

    tip: str
    clamp: str
    deflection: np.ndarray
    frequency: float | None
    frame: np.ndarray
    load: float
    length: float
    inertia: float


def cantilever(scene: Scene, label: str, measure: str) -> Cantilever:
    """The closed-form data of ``scene``, or a StudyError (naming ``label``) saying why the
    scene is not a cantilever: one straight body, one clamp at an end, one point force at the
    other end."""

    def fail(reason: str) -> StudyError:
        return StudyError(f"{label}: error {measure!r} needs a cantilever scene (one straight "
                          f"body clamped at one end, one point force at the other): {reason}")

    if len(scene.bodies) != 1:
        raise fail(f"the scene has {len(scene.bodies)} bodies")
    body = scene.bodies[0]
    if body.start is None or body.end is None:
        raise fail(f"body {body.name!r} is not straight")
    last = body.n_nodes - 1
    ends = (0, last)
    clamps = [c for c in scene.constraints if c.type == "clamp"]
    if len(scene.constraints) != 1 or not clamps or clamps[0].node.index not in ends:
        raise fail("expected exactly one constraint, a clamp at an end node")
    forces = [x for x in scene.loads if x.type == "point_force"]
    if len(scene.loads) != 1 or not forces:
        raise fail("expected exactly one load, a point_force")
    clamp, force = clamps[0].node, forces[0]
    if force.node.index != last - clamp.index:
        raise fail(f"the point force acts on {force.node}, not on the free end")
    from runtime.element.reference import gradient_frame, straight_reference
    from runtime.kernels.kind import element_kind

    kind = element_kind(body.element)
    dim = kind.dim
    e0 = straight_reference(kind, body.start, body.end).reshape(-1, len(kind.vectors), dim)[0]
    frame = gradient_frame({name: e0[k] for k, name in enumerate(kind.vectors)
                            if name != "r"}, dim)
    material = scene.material_of(body)
    E, rho = material.E, material.rho
    h, w = body.height, body.width
    area = h * w
    length = float(np.linalg.norm(np.subtract(body.end, body.start)))
    load = np.asarray(force.force, float)
    local = frame.T @ load                      # axial, along height (y), along width (z)
    inertias = [w * h**3 / 12, h * w**3 / 12][: dim - 1]   # bending towards y, towards z
    local_deflection = [local[0] * length / (E * area)]
    local_deflection += [local[1 + a] * length**3 / (3 * E * i) for a, i in enumerate(inertias)]
    deflection = frame @ np.array(local_deflection)
    transverse = np.abs(local[1:])
    frequency = None
    inertia = inertias[0]
    if transverse.max() > 0:
        loaded = transverse > 1e-9 * transverse.max()
        if loaded.sum() == 1 or math.isclose(h, w):
            inertia = inertias[int(np.argmax(transverse))]
            frequency = BETA_L**2 * math.sqrt(E * inertia / (rho * area * length**4))
    return Cantilever(str(force.node), str(clamp), deflection, frequency, frame,
                      float(np.linalg.norm(load)), length, inertia)


# --------------------------------------------------------------------------- the plan

@dataclass
class Plan:
    """A validated study: the scene (``data`` without ``[study]``), the sweep and the error.

    elements: mesh sizes; steps (s) and integrators: [None] for static errors; exact: the
    closed-form value of the measured quantity (m or rad/s) or None (reference runs);
    reference: (elements, step, integrator, method) of the reference run or None.
    """

    path: Path
    scene: Scene
    data: dict
    measure: str
    sensor: str
    elements: list[int]
    steps: list[float | None]
    integrators: list[str | None]
    methods: list[str]
    backend: str
    t_end: float | None
    repeat: int
    targets: list[float] | None
    exact: float | None = None
    cantilever: Cantilever | None = None
    reference: tuple[int, float, str, str] | None = None
    frequency_after: float = 0.0
    notes: list[str] = field(default_factory=list)


def _read(scene_path: str | Path) -> tuple[dict, dict]:
    """(scene data without [study], the [study] table) of a TOML file."""
    data = read_scene_file(scene_path)
    table = data.pop("study", {})
    if not isinstance(table, dict):
        raise StudyError(f"study: expected a table [study], got {_show(table)}")
    for key in table:
        if key not in STUDY_KEYS:
            raise StudyError(f"study.{key}: unknown key; expected one of {', '.join(STUDY_KEYS)}")
    return data, table


def _option(name: str) -> str:
    return "--" + name.replace("_", "-")


def plan_study(scene_path: str | Path, **overrides: Any) -> Plan:
    """Read the scene and its ``[study]`` table, apply ``overrides`` (the keys of the table;
    None: not given; named in messages as the command-line options) and validate it all.

    Raises StudyError (or SceneError for the scene itself) before any run starts.
    """
    path = Path(scene_path)
    data, table = _read(path)
    scene = parse_scene(copy.deepcopy(data), str(path))
    for key in overrides:
        if key not in STUDY_KEYS:
            raise TypeError(f"plan_study: unknown override {key!r}")

    def pick(key: str, default: Any) -> tuple[Any, str]:
        if overrides.get(key) is not None:
            return overrides[key], _option(key)
        if key in table:
            return table[key], f"study.{key}"
        return default, f"study.{key}"

    value, label = pick("error", None)
    if value is None:
        try:
            cantilever(scene, "study.error", "static_tip")
            value = "static_tip"
        except StudyError:
            value = "reference"
    measure = _choice(value, label, MEASURES, "error measure")
    error_label = label

    value, label = pick("elements", [b.elements for b in scene.bodies][:1])
    elements = _sweep(value, label, _positive_int)
    value, label = pick("method", scene.solver.method)
    methods = _sweep(value, label, lambda v, p: _choice(v, p, METHODS, "method"))
    value, label = pick("backend", scene.solver.backend)
    backend = _choice(value, label, BACKENDS, "backend")
    value, label = pick("repeat", 5 if measure == "static_tip" else 1)
    repeat = _positive_int(value, label)
    value, label = pick("targets", None)
    targets = None if value is None else sorted(_sweep(value, label, _positive_number),
                                                reverse=True)

    dynamic = scene.dynamic
    value, t_end_label = pick("t_end", None)
    t_end = None if value is None else _positive_number(value, t_end_label)
    static = measure == "static_tip"
    step_value, step_label = pick("step", None if dynamic is None else dynamic.step)
    integrator_value, integrator_label = pick(
        "integrator", "trapezoidal" if dynamic is None else dynamic.integrator)
    # validated even where they do not apply (a static error), so typos never pass silently
    steps: list = [] if step_value is None else _sweep(step_value, step_label, _positive_number)
    integrators: list = _sweep(integrator_value, integrator_label,
                               lambda v, p: _choice(v, p, INTEGRATORS, "integrator"))
    plan = Plan(path, scene, data, measure, "", elements, steps, integrators, methods, backend,
                t_end, repeat, targets)
    if static:
        plan.steps, plan.integrators = [None], [None]
        if any(overrides.get(k) is not None or k in table for k in ("step", "integrator")):
            plan.notes.append("step and integrator do not apply to the static error: each "
                              "(elements, method) is run once")
    else:
        if dynamic is None and (t_end is None or not steps):
            raise StudyError(f"{t_end_label if t_end is None else step_label}: error "
                             f"{measure!r} needs a dynamic analysis, and the scene has no "
                             "[analysis.dynamic]; give t_end and step in [study]")
        t_end = t_end if t_end is not None else dynamic.t_end
        plan.t_end = t_end
        for i, step in enumerate(steps):
            if step > t_end:
                raise StudyError(f"{step_label}[{i}]: expected a step of at most t_end = "
                                 f"{t_end!r} s, got {step!r}")
        after = dynamic.frequency_after if dynamic is not None else 0.0
        plan.frequency_after = after
        if measure == "frequency" and after >= t_end:
            raise StudyError(f"{t_end_label}: expected a time after frequency_after = "
                             f"{after!r} s, got {t_end!r}")

    sensors = {s.name: s for s in scene.sensors}
    available = ", ".join(f"{s.name} ({s.type})" for s in scene.sensors) or "none"
    sensor_value, sensor_label = pick("sensor", None)
    if sensor_value is not None:
        if not isinstance(sensor_value, str) or sensor_value not in sensors:
            raise StudyError(f"{sensor_label}: no sensor {_show(sensor_value)} in the scene; "
                             f"available sensors: {available}")

    if measure in ("static_tip", "frequency"):
        info = cantilever(scene, error_label, measure)
        plan.cantilever = info
        candidates = [s for s in scene.sensors if s.type == "displacement"
                      and str(s.node) == info.tip
                      and (s.frame is None or str(s.frame) == info.clamp)
                      and _expected(info, s.component, s.frame is not None) != 0.0]
        if measure == "frequency" and dynamic is not None and dynamic.frequency_of \
                and dynamic.frequency_of in {s.name for s in candidates}:
            candidates.insert(0, sensors[dynamic.frequency_of])
        if sensor_value is None:
            if not candidates:
                raise StudyError(f"{sensor_label}: error {measure!r} needs a displacement "
                                 f"sensor of the loaded node {info.tip} along the load "
                                 f"(none in the scene); available sensors: {available}")
            sensor_value = candidates[0].name
        chosen = sensors[sensor_value]
        if chosen not in candidates:
            raise StudyError(f"{sensor_label}: sensor {sensor_value!r} ({chosen.type}) cannot "
                             f"give error {measure!r}: expected a displacement sensor of the "
                             f"loaded node {info.tip} with a component the load deflects "
                             f"(frame none or the clamp); available sensors: {available}")
        if measure == "static_tip":
            plan.exact = _expected(info, chosen.component, chosen.frame is not None)
        else:
            if info.frequency is None:
                raise StudyError(f"{error_label}: error 'frequency' needs a load along a "
                                 "principal axis of the section (or a square section)")
            plan.exact = info.frequency
    else:
        if sensor_value is None:
            ordered = sorted(scene.sensors, key=lambda s: s.type not in POSITION_SENSORS)
            if not ordered:
                raise StudyError(f"{sensor_label}: error 'reference' needs a sensor to compare "
                                 "runs with, and the scene has no [[sensor]]")
            sensor_value = ordered[0].name
        plan.reference = _reference(pick("reference", None), plan)
    plan.sensor = sensor_value
    return plan


def _expected(info: Cantilever, component: str, local: bool) -> float:
    """Closed-form static value (m) of a tip displacement sensor's component."""
    vector = info.frame.T @ info.deflection if local else info.deflection
    if component == "norm":
        return float(np.linalg.norm(vector))
    return float(vector["xyz".index(component)])


def _reference(picked: tuple[Any, str], plan: Plan) -> tuple[int, float, str, str]:
    """(elements, step, integrator, method) of the reference run: by default twice the
    finest mesh and half the finest step, trapezoidal (when swept) and gram (when swept)."""
    value, label = picked
    if value is None:
        value = {}
    if isinstance(value, list | tuple):   # --reference ELEMENTS,STEP
        if len(value) != 2:
            raise StudyError(f"{label}: expected ELEMENTS,STEP, got {_show(value)}")
        value = {"elements": value[0], "step": value[1]}
    if not isinstance(value, dict):
        raise StudyError(f"{label}: expected a table {{elements = N, step = h}}, got "
                         f"{_show(value)}")
    for key in value:
        if key not in REFERENCE_KEYS:
            raise StudyError(f"{label}.{key}: unknown key; expected one of "
                             f"{', '.join(REFERENCE_KEYS)}")
    elements = _positive_int(value.get("elements", 2 * max(plan.elements)), f"{label}.elements")
    step = _positive_number(value.get("step", min(plan.steps) / 2), f"{label}.step")
    if step > plan.t_end:
        raise StudyError(f"{label}.step: expected a step of at most t_end = {plan.t_end!r} s, "
                         f"got {step!r}")
    integrator = _choice(value.get("integrator", "trapezoidal" if "trapezoidal" in
                                   plan.integrators else plan.integrators[0]),
                         f"{label}.integrator", INTEGRATORS, "integrator")
    method = _choice(value.get("method", "gram" if "gram" in plan.methods else plan.methods[0]),
                     f"{label}.method", METHODS, "method")
    return elements, step, integrator, method


# --------------------------------------------------------------------------- cases

def case_scene(plan: Plan, elements: int, step: float | None, integrator: str | None,
               method: str) -> Scene:
    """The scene of one run (validated: SceneError otherwise): the sweep values set, only
    the analysis and the sensor the error needs kept."""
    scene = plan.scene
    changes: dict[str, Any] = {
        "bodies": tuple(dataclasses.replace(body, elements=elements) for body in scene.bodies),
        "sensors": tuple(s for s in scene.sensors if s.name == plan.sensor),
        "modal": None,
        "solver": dataclasses.replace(scene.solver, method=method, backend=plan.backend)}
    if plan.measure == "static_tip":
        changes.update(static=scene.static or Static(), dynamic=None)
    else:
        dynamic = scene.dynamic
        every = dynamic.output_every
        # outputs at a whole number of steps; the response frequency is fitted here, after
        # the run, so that simulate_s stays the time of the integration alone
        changes.update(static=None, dynamic=dataclasses.replace(
            dynamic, t_end=plan.t_end, step=step, integrator=integrator,
            output_every=None if every is None else step * max(1, round(every / step)),
            frequency_of=None, frequency_after=0.0))
    return dataclasses.replace(scene, **changes)


def run_case(scene_text: str, repeat: int = 1, series: str | None = None) -> dict:
    """Run one scene (TOML text) ``repeat`` times in a temporary folder with ``ancf run``.

    Returns {status, message, simulate_s, total_s (s, the fastest repeat), summary (the last
    run's), t and y (the time series of sensor ``series``, if asked)}.  An exception in the
    run gives status "failed" with its message: one case never stops the study.
    Module-level, so that dask can ship it to its workers.
    """
    from runtime.app.run import run

    result: dict = {"status": "failed", "message": "", "simulate_s": math.nan,
                    "total_s": math.nan, "summary": {}}
    with tempfile.TemporaryDirectory(prefix="ancf_error_vs_time_") as tmp:
        path = Path(tmp) / "scene.toml"
        path.write_text(scene_text, encoding="utf-8")
        simulate, total = [], []
        for i in range(repeat):
            out = Path(tmp) / f"run{i}"
            try:
                summary, _ = run(path, out, quiet=True)
            except Exception as error:  # a failing case is a result, not the study's end
                result.update(status="failed", message=f"{type(error).__name__}: {error}")
                return result
            result.update(status=summary["status"], message=summary.get("message", ""),
                          summary=summary)
            if summary["status"] != "ok":
                break
            simulate.append(summary["timing"]["simulate_s"])
            total.append(summary["timing"]["total_s"])
        if simulate:
            result.update(simulate_s=min(simulate), total_s=min(total))
        if series is not None and (out / "timeseries.csv").exists():
            with (out / "timeseries.csv").open(newline="") as f:
                rows = list(csv.reader(f))
            column = rows[0].index(series)
            values = np.array([[float(r[0]), float(r[column])] for r in rows[1:]]).reshape(-1, 2)
            result["t"], result["y"] = values[:, 0].tolist(), values[:, 1].tolist()
    return result


def check_scheduler(address: str, timeout: float = 3.0) -> None:
    """Fail fast (SchedulerError naming ``address``) when nothing listens at a tcp/tls
    scheduler address; other protocols are left to dask."""
    scheme, sep, rest = address.partition("://")
    if not sep:
        scheme, rest = "tcp", address
    if scheme not in ("tcp", "tls"):
        return
    host, colon, port = rest.rstrip("/").rpartition(":")
    if not colon:
        host, port = rest.rstrip("/"), "8786"
    if not host or not port.isdigit():
        raise SchedulerError(f"--scheduler {address}: expected an address like "
                             "tcp://HOST:8786")
    try:
        socket.create_connection((host.strip("[]"), int(port)), timeout=timeout).close()
    except OSError as error:
        raise SchedulerError(f"--scheduler {address}: cannot connect to a dask scheduler "
                             f"there ({error.strerror or error})") from None


# --------------------------------------------------------------------------- the study

def study(scene_path: str | Path, out_dir: str | Path | None = None, *,
          elements: Sequence[Any] | None = None, step: Sequence[Any] | None = None,
          integrator: Sequence[Any] | None = None, method: Sequence[Any] | None = None,
          backend: str | None = None, error: str | None = None, sensor: str | None = None,
          reference: dict | Sequence[Any] | None = None, t_end: float | None = None,
          repeat: int | None = None, targets: Sequence[Any] | None = None,
          scheduler: str | None = None, workers: int | None = None,
          serial: bool = False) -> list[dict]:
    """Run the work-precision study of a scene; returns one row per run (CSV_COLUMNS; the
    reference run last, with role "reference").

    Overrides (None: from the ``[study]`` table, else from the scene) win over the table:
    elements (ints), step (s), integrator, method (lists), backend, error (a MEASURES),
    sensor (a sensor name), reference ({elements, step[, integrator, method]} or
    [elements, step]), t_end (s), repeat (runs per case), targets (accuracies of the summary).
    scheduler / workers / serial: see ``runtime.studies.sweep.run_cases``.  out_dir (default
    ``results/error_vs_time/<scene stem>``) receives error_vs_time.csv, .png and .md.
    Raises StudyError / SceneError for invalid input and SchedulerError for an unreachable
    scheduler, all before any run starts.
    """
    start = time.perf_counter()
    if workers is not None and (isinstance(workers, bool) or not isinstance(workers, int)
                                or workers <= 0):
        raise StudyError(f"--workers: expected a positive integer, got {workers!r}")
    plan = plan_study(scene_path, elements=elements, step=step, integrator=integrator,
                      method=method, backend=backend, error=error, sensor=sensor,
                      reference=reference, t_end=t_end, repeat=repeat, targets=targets)
    out = Path(out_dir) if out_dir is not None else default_out(plan.path)
    runs = list(itertools.product(plan.elements, plan.steps, plan.integrators, plan.methods))
    if plan.reference is not None:
        runs.append(plan.reference)
    cases = []
    for i, (n, h, integ, meth) in enumerate(runs):
        try:
            text = case_scene(plan, n, h, integ, meth).to_toml()
        except SceneError as scene_error:
            what = "the reference run" if plan.reference is not None and i == len(runs) - 1 \
                else "a run"
            raise StudyError(f"study: {what} with {n} elements is not a valid scene: "
                             f"{scene_error}") from None
        cases.append({"scene_text": text, "repeat": plan.repeat,
                      "series": None if plan.measure == "static_tip" else plan.sensor})
    if scheduler is not None:
        check_scheduler(scheduler)
    results = run_cases(run_case, cases, scheduler=scheduler, workers=workers, serial=serial,
                        label="error-vs-time study")
    rows = _rows(plan, runs, results)
    out.mkdir(parents=True, exist_ok=True)
    write_csv(rows, out / "error_vs_time.csv")
    plot(plan, rows, out / "error_vs_time.png")
    wall = time.perf_counter() - start
    where = f"dask at {scheduler}" if scheduler else "this process" if serial or \
        len(cases) == 1 else f"a local dask cluster ({workers or 'one per core'} workers)"
    (out / "error_vs_time.md").write_text(markdown(plan, rows, wall, where), encoding="utf-8")
    reference_row = rows[-1] if plan.reference is not None else None
    if reference_row is not None and reference_row["status"] != "ok":
        raise StudyError(f"study.reference: the reference run ({reference_row['elements']} "
                         f"elements, step {reference_row['step']!r} s) {reference_row['status']}"
                         f": {reference_row['message']} (outputs in {out})")
    return rows


def default_out(scene_path: str | Path) -> Path:
    """The default study folder: ``results/error_vs_time/<scene stem>``."""
    return Path("results") / "error_vs_time" / Path(scene_path).stem


def _rows(plan: Plan, runs: list[tuple], results: list[dict]) -> list[dict]:
    """One CSV row per run, errors measured."""
    ref_t = ref_y = None
    if plan.reference is not None and results[-1]["status"] == "ok":
        ref_t = np.asarray(results[-1].get("t", []))
        ref_y = np.asarray(results[-1].get("y", []))
        if ref_y.size == 0:
            ref_t = ref_y = None
    rows = []
    for i, ((n, h, integ, meth), result) in enumerate(zip(runs, results, strict=True)):
        is_reference = plan.reference is not None and i == len(runs) - 1
        row = {"elements": n, "step": h, "integrator": integ, "method": meth,
               "backend": plan.backend, "error": math.nan, "simulate_s": result["simulate_s"],
               "total_s": result["total_s"], "status": result["status"],
               "measure": plan.measure, "value": math.nan, "exact": plan.exact,
               "newton_iterations": _iterations(result["summary"]),
               "role": "reference" if is_reference else "sweep", "message": result["message"]}
        summary = result["summary"]
        if result["status"] == "ok" and not is_reference:
            try:
                value, error = _measure(plan, summary, result, ref_t, ref_y)
                row.update(value=value, error=error)
            except (KeyError, ValueError, TypeError) as failure:
                row.update(status="failed", message=f"error measure: {failure}")
        elif is_reference and ref_y is not None:
            row.update(value=float(np.abs(ref_y).max()))
        rows.append(row)
    return rows


def _iterations(summary: dict) -> int | None:
    """Newton iterations of a run (static or dynamic): a machine-independent measure of work."""
    for key in ("dynamic", "static"):
        if key in summary:
            return summary[key].get("newton_iterations", summary[key].get("iterations"))
    return None


def _measure(plan: Plan, summary: dict, result: dict, ref_t, ref_y) -> tuple[float, float]:
    """(measured value, error) of one run."""
    if plan.measure == "static_tip":
        value = float(summary["static"]["sensors"][plan.sensor])
        return value, abs(value - plan.exact) / abs(plan.exact)
    t, y = np.asarray(result.get("t", [])), np.asarray(result.get("y", []))
    if t.size == 0:
        raise ValueError(f"the run wrote no time series of sensor {plan.sensor!r}")
    if plan.measure == "frequency":
        from runtime.app.signal import dominant_frequency

        keep = t >= plan.frequency_after
        value = dominant_frequency(t[keep], y[keep])
        return value, abs(value - plan.exact) / plan.exact
    if ref_y is None:
        raise ValueError("no reference run to compare with")
    scale = float(np.abs(ref_y).max())
    if scale == 0.0:
        raise ValueError(f"the reference run's sensor {plan.sensor!r} is zero throughout")
    difference = float(np.abs(np.interp(ref_t, t, y) - ref_y).max())
    return difference, difference / scale


def write_csv(rows: list[dict], path: Path) -> None:
    """error_vs_time.csv: CSV_COLUMNS, numbers with repr precision, absent values empty."""
    with path.open("w", newline="", encoding="utf-8") as f:
        writer = csv.writer(f, lineterminator="\n")
        writer.writerow(CSV_COLUMNS)
        for row in rows:
            writer.writerow(["" if row[c] is None or (isinstance(row[c], float)
                                                      and math.isnan(row[c])) else row[c]
                             for c in CSV_COLUMNS])


# --------------------------------------------------------------------------- reports

def _label(row: dict, plan: Plan) -> str:
    """The line a run belongs to: its method, and its integrator when several are swept."""
    if len(plan.integrators) > 1:
        return f"{row['method']} / {row['integrator']}"
    return row["method"]


def _point(row: dict) -> str:
    return f"{row['elements']}" if row["step"] is None else f"{row['elements']}, {row['step']:g}"


def _usable(rows: list[dict]) -> list[dict]:
    return [r for r in rows if r["role"] == "sweep" and r["status"] == "ok"
            and math.isfinite(r["error"]) and r["error"] > 0 and r["simulate_s"] > 0]


def _front(points: list[dict]) -> list[dict]:
    """Runs not beaten by a faster run with a smaller error (sorted by time)."""
    best, front = math.inf, []
    for row in sorted(points, key=lambda r: (r["simulate_s"], r["error"])):
        if row["error"] < best:
            front.append(row)
            best = row["error"]
    return front


def _describe_measure(plan: Plan) -> str:
    if plan.measure == "static_tip":
        c = plan.cantilever
        return (f"relative error of the static tip displacement (sensor `{plan.sensor}`) "
                f"against P L^3 / 3EI = {abs(plan.exact):.6g} m (P = {c.load:g} N, "
                f"L = {c.length:g} m, I = {c.inertia:.6g} m^4)")
    if plan.measure == "frequency":
        return (f"relative error of the response frequency of sensor `{plan.sensor}` after "
                f"t = {plan.frequency_after:g} s (sinusoid fit, not timed) against "
                f"1.8751^2 sqrt(EI / (rho A L^4)) = {plan.exact:.6g} rad/s")
    n, h, integ, meth = plan.reference
    return (f"max |difference| of sensor `{plan.sensor}` over 0..{plan.t_end:g} s against a "
            f"reference run ({n} elements, step {h:g} s, {integ}, {meth}), divided by the "
            "reference's max |value|")


def plot(plan: Plan, rows: list[dict], path: Path) -> None:
    """error_vs_time.png: log-log error against simulate time, one line (the runs no faster
    run beats) per method (and integrator); points annotated with elements[, step] (every
    point up to ANNOTATE_ALL points, else the points on the lines; the points on the lines
    first), each label beside its point where it overlaps no other label, else left out."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(9.5, 5.6))
    canvas = FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    usable = _usable(rows)
    annotate_all = len(usable) <= ANNOTATE_ALL
    labels = _unique([_label(r, plan) for r in rows if r["role"] == "sweep"])
    markers = "osD^vP*X"
    fronts, others = [], []    # (row, colour) to label: points on the lines first
    for k, label in enumerate(labels):
        points = [r for r in usable if _label(r, plan) == label]
        if not points:
            continue
        color = f"C{k % 10}"
        ax.loglog([r["simulate_s"] for r in points], [r["error"] for r in points],
                  markers[k % len(markers)], color=color, alpha=0.5, ms=5)
        front = _front(points)
        ax.loglog([r["simulate_s"] for r in front], [r["error"] for r in front], "-",
                  marker=markers[k % len(markers)], color=color, lw=1.4, ms=5, label=label)
        fronts += [(r, color) for r in front]
        if annotate_all:
            others += [(r, color) for r in points if r not in front]
    ax.set_xlabel("simulate time (s)")
    ax.set_ylabel(f"error ({plan.measure})")
    title = plan.scene.title if len(plan.scene.title) < 60 else plan.scene.title[:57] + "..."
    ax.set_title(f"{title}\n{plan.measure} error against run time; labels: elements"
                 f"{'' if plan.measure == 'static_tip' else ', step (s)'}"
                 f"{'' if annotate_all else ' (points on the lines)'}", fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    if usable:
        ax.legend(fontsize=8, title="line: best error\nfor the time", title_fontsize=7,
                  loc="upper left", bbox_to_anchor=(1.01, 1.0))
    else:
        ax.text(0.5, 0.5, "no run with a finite error", transform=ax.transAxes, ha="center")
    fig.subplots_adjust(left=0.09, right=0.75, bottom=0.1, top=0.89)
    canvas.draw()  # final limits and layout: label boxes in pixels from here on
    renderer = canvas.get_renderer()
    placed = []    # pixel boxes of the labels kept
    # right-above, right-below, left-above, left-below of the point (points, alignment)
    spots = [((4, 3), "left", "bottom"), ((4, -3), "left", "top"),
             ((-4, 3), "right", "bottom"), ((-4, -3), "right", "top")]
    for row, color in fronts + others:
        for offset, ha, va in spots:
            note = ax.annotate(_point(row), (row["simulate_s"], row["error"]),
                               textcoords="offset points", xytext=offset, ha=ha, va=va,
                               fontsize=6, color=color)
            box = note.get_window_extent(renderer)
            if not any(box.overlaps(other) for other in placed):
                placed.append(box)
                break
            note.remove()
    fig.savefig(path, dpi=110)


def default_targets(rows: list[dict]) -> list[float]:
    """Accuracy levels of the summary: the finest four of 1e-k and 3e-k between the smallest
    and the largest error, or the level just above every error."""
    errors = [r["error"] for r in _usable(rows)]
    if not errors:
        return []
    low, high = min(errors), max(errors)
    levels = [m * 10.0**k for k in range(math.ceil(math.log10(high)), -17, -1) for m in (3, 1)]
    inside = [t for t in levels if low <= t < high]
    return inside[-4:] if inside else [min(t for t in levels if t >= high)]


def _run_words(row: dict, plan: Plan) -> str:
    words = f"{row['method']} with {row['elements']} elements"
    if row["step"] is not None:
        words += f", step {row['step']:g} s, {row['integrator']}"
    return words


def _join(words: list[str]) -> str:
    """'a', 'a and b', 'a, b and c'."""
    return words[0] if len(words) == 1 else ", ".join(words[:-1]) + " and " + words[-1]


def _level(target: float) -> str:
    """An accuracy level as 3e-2, 1e-3, 2.5e-4."""
    mantissa, exponent = f"{target:.1e}".split("e")
    return f"{mantissa.rstrip('0').rstrip('.')}e{int(exponent)}"


def summary_paragraph(plan: Plan, rows: list[dict]) -> str:
    """One paragraph: for each accuracy target, the run that reaches it at the least
    simulate time and its speed-up over the best run of the slowest line reaching it."""
    usable = _usable(rows)
    if not usable:
        return "No run produced a finite error, so no choice can be recommended."
    targets = plan.targets or default_targets(rows)
    labels = _unique([_label(r, plan) for r in rows if r["role"] == "sweep"])
    findings: list[tuple[float, str]] = []     # (target, what holds at that accuracy)
    wins: dict[str, int] = {}
    for target in targets:
        reaching = [r for r in usable if r["error"] <= target]
        if not reaching:
            findings.append((target, "no run reaches it"))
            continue
        best = min(reaching, key=lambda r: r["simulate_s"])
        fastest: dict[str, float] = {}
        for r in reaching:
            label = _label(r, plan)
            fastest[label] = min(fastest.get(label, math.inf), r["simulate_s"])
        slowest = max(fastest, key=fastest.get)
        wins[_label(best, plan)] = wins.get(_label(best, plan), 0) + 1
        text = (f"the cheapest run is {_run_words(best, plan)} ({best['simulate_s']:.3g} s, "
                f"error {best['error']:.2g})")
        if slowest != _label(best, plan):
            text += (f", {fastest[slowest] / best['simulate_s']:.1f}x faster than the "
                     f"cheapest {slowest} run ({fastest[slowest]:.3g} s)")
        elif len(fastest) == 1 and len(labels) > 1:
            text += f", the only {'line' if len(plan.integrators) > 1 else 'method'} to reach it"
        missing = [label for label in labels if label not in fastest]
        if missing and len(fastest) > 1:
            text += f" ({', '.join(missing)} never reach it)"
        close = [f"{label} ({t:.3g} s)" for label, t in sorted(fastest.items(), key=lambda x: x[1])
                 if label != _label(best, plan) and t <= CLOSE * best["simulate_s"]]
        if close:
            text += (f"; {_join(close)} {'is' if len(close) == 1 else 'are'} within "
                     f"{round(100 * (CLOSE - 1))} %, a tie within timing noise")
        findings.append((target, text))
    sentences = []
    for text, group in itertools.groupby(findings, key=lambda finding: finding[1]):
        levels = [_level(target) for target, _ in group]
        if len(levels) == 1:
            sentences.append(f"for an error of {levels[0]} {text}")
        else:
            sentences.append(f"for errors of {_join(levels)} {text}")
    paragraph = "; ".join(sentences)
    paragraph = paragraph[0].upper() + paragraph[1:] + "."
    if wins:
        leader = max(wins, key=wins.get)
        reached = sum(1 for t in targets if any(r["error"] <= t for r in usable))
        paragraph += (f" Overall, {leader} is the cheapest choice at {wins[leader]} of "
                      f"{reached} accuracy level{'s' if reached != 1 else ''} reached.")
    return paragraph


def _cell(value: Any, spec: str = ".3g") -> str:
    if value is None or (isinstance(value, float) and math.isnan(value)):
        return "-"
    return format(value, spec) if isinstance(value, float) else str(value)


def markdown(plan: Plan, rows: list[dict], wall: float, where: str) -> str:
    """error_vs_time.md: what was measured, the table of runs and the summary paragraph."""
    ok = sum(1 for r in rows if r["role"] == "sweep" and r["status"] == "ok")
    sweep = sum(1 for r in rows if r["role"] == "sweep")
    lines = [f"# Error against run time: {plan.scene.title}", "",
             f"Scene `{plan.path}`; error: {_describe_measure(plan)}. {sweep} runs ({ok} ok)"
             f"{' plus the reference run' if plan.reference else ''}, backend {plan.backend}"
             f"{f', best of {plan.repeat} repeats' if plan.repeat > 1 else ''}; run in {where}, "
             f"study wall time {wall:.1f} s. Times: `simulate_s` is the analyses alone, "
             "`total_s` the whole run (kernel loading and plots included).", ""]
    lines += [f"Note: {note}." for note in plan.notes]
    if plan.notes:
        lines.append("")
    value_head = {"static_tip": "tip (m)", "frequency": "frequency (rad/s)",
                  "reference": "max diff"}[plan.measure]
    lines += [f"| elements | step (s) | integrator | method | {value_head} | error | "
              "Newton iterations | simulate (s) | total (s) | status |",
              "| ---: | ---: | --- | --- | ---: | ---: | ---: | ---: | ---: | --- |"]
    order = sorted(rows, key=lambda r: (r["role"] != "sweep", r["method"], r["integrator"] or "",
                                        r["elements"], -(r["step"] or 0.0)))
    for r in order:
        status = r["status"] if r["role"] == "sweep" else f"reference ({r['status']})"
        if r["status"] != "ok" and r["message"]:
            status += f": {r['message'].splitlines()[0][:80]}"
        lines.append(f"| {r['elements']} | {_cell(r['step'], 'g')} | {_cell(r['integrator'])} "
                     f"| {r['method']} | {_cell(r['value'], '.6g')} | {_cell(r['error'], '.3e')}"
                     f" | {_cell(r['newton_iterations'])} | {_cell(r['simulate_s'])} "
                     f"| {_cell(r['total_s'])} | {status} |")
    lines += ["", "## Summary", "", summary_paragraph(plan, rows), ""]
    return "\n".join(lines)


# --------------------------------------------------------------------------- command line

def _split(text: str | None, convert) -> list | None:
    """Comma-separated option values, converted where possible (left as text otherwise, so
    that validation names the option and the culprit)."""
    if text is None:
        return None
    items = [part.strip() for part in text.split(",")]
    if items == [""]:
        return []
    out: list = []
    for item in items:
        try:
            out.append(convert(item))
        except ValueError:
            out.append(item)
    return out


def cmd_error_vs_time(args: argparse.Namespace) -> int:
    """``ancf study error-vs-time``: run the study, print the Markdown; exit code 0, or 2
    with a one-line message for invalid input or an unreachable scheduler."""
    try:
        study(args.scene, args.out, elements=_split(args.elements, int),
                     step=_split(args.step, float), integrator=_split(args.integrator, str),
                     method=_split(args.method, str), backend=args.backend, error=args.error,
                     sensor=args.sensor, reference=_split(args.reference, _number_text),
                     t_end=_split(args.t_end, float)[0] if args.t_end else None,
                     repeat=args.repeat, targets=_split(args.targets, float),
                     scheduler=args.scheduler, workers=args.workers, serial=args.serial)
    except (StudyError, SchedulerError, SceneError) as error:
        print(f"ancf study error-vs-time: {str(error).splitlines()[0]}", file=sys.stderr)
        return 2
    out = Path(args.out) if args.out else default_out(args.scene)
    print((out / "error_vs_time.md").read_text(encoding="utf-8"))
    print(f"results in {out}/ (error_vs_time.csv, .png, .md)")
    return 0


def _number_text(text: str) -> int | float:
    return int(text) if re.fullmatch(r"[+-]?\d+", text) else float(text)


def add_cli(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Register ``error-vs-time`` in the ``ancf study`` sub-command group (``subparsers``:
    what ``study_parser.add_subparsers()`` returned); the command runs ``args.run(args)``."""
    parser = subparsers.add_parser(
        "error-vs-time", help="work-precision study: error against run time",
        description="Work-precision study: run every combination of mesh size, time step, "
                    "integrator and elastic force method, measure each run's error (closed form "
                    "or a reference run) and wall time; write error_vs_time.csv, .png and .md "
                    "and print the Markdown.")
    parser.add_argument("scene", help="scene TOML file (may hold a [study] table)")
    parser.add_argument("--elements", metavar="N,N,...", help="mesh sizes, e.g. 2,5,10")
    parser.add_argument("--step", metavar="H,H,...", help="time steps in s, e.g. 1e-3,5e-4")
    parser.add_argument("--integrator", metavar="NAME,...",
                        help=f"integrators: {', '.join(INTEGRATORS)}")
    parser.add_argument("--method", metavar="NAME,...",
                        help=f"elastic force methods: {', '.join(METHODS)}")
    parser.add_argument("--backend", help=f"kernel backend: {', '.join(BACKENDS)}")
    parser.add_argument("--error", help=f"error measure: {', '.join(MEASURES)}")
    parser.add_argument("--sensor", help="the sensor the error is computed from")
    parser.add_argument("--reference", metavar="ELEMENTS,STEP",
                        help="reference run of error 'reference' (default: twice the finest "
                             "mesh, half the finest step)")
    parser.add_argument("--t-end", dest="t_end", metavar="T",
                        help="end time in s (overrides [analysis.dynamic].t_end)")
    parser.add_argument("--repeat", type=int, help="runs per case; the fastest is kept")
    parser.add_argument("--targets", metavar="E,E,...",
                        help="accuracies of the summary (default: up to four levels 1e-k, "
                             "3e-k between the errors)")
    parser.add_argument("--scheduler", metavar="ADDRESS",
                        help="dask scheduler, e.g. tcp://host:8786 (default: a local cluster)")
    parser.add_argument("--workers", type=int, metavar="N",
                        help="workers of the local cluster (default: one per core)")
    parser.add_argument("--serial", action="store_true", help="run every case in this process")
    parser.add_argument("--out", metavar="DIR",
                        help="output folder (default: results/error_vs_time/<scene stem>)")
    parser.set_defaults(run=cmd_error_vs_time)
    return parser
