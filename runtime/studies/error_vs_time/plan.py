"""What an error-vs-time study runs: the ``[study]`` table and the command-line overrides
read and validated into a ``Plan`` (mesh sizes, steps, integrators, methods, the error
measure and its sensor), with the closed-form data of a cantilever scene that the
``static_tip`` and ``frequency`` errors are measured against.  Every invalid input is a
``StudyError`` raised here, before any run starts.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from runtime.catalog import BACKENDS, INTEGRATORS, METHODS
from runtime.model.scene import Scene, parse_scene
from runtime.model.toml_io import read_scene_file

MEASURES = ("static_tip", "frequency", "reference")
STUDY_KEYS = ("elements", "step", "integrator", "method", "backend", "error", "sensor",
              "reference", "t_end", "repeat", "targets")
REFERENCE_KEYS = ("elements", "step", "integrator", "method")
# first root of 1 + cos(x) cosh(x) = 0: omega_1 = BETA_L^2 sqrt(E I / (rho A L^4))
BETA_L = 1.8751040687119611
POSITION_SENSORS = ("displacement", "position")


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
