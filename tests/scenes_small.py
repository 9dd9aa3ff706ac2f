"""Small scenes for the solver tests: dict builders (the TOML layout of DESIGN.md section 7),
a TOML writer for them, and an in-memory runner that records sensor time series (and, if
asked, the full states) without writing files or plots.

Closed-form beam values used by the tests are written out here from textbook formulas, never
taken from the code under test.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from runtime import analysis
from runtime.integrators import INTEGRATORS
from runtime.model import Model
from runtime.scene import parse_scene
from runtime.sensors import Sensors

# first root of 1 + cos(x) cosh(x) = 0 (clamped-free beam), more digits than the paper's 1.8751
BETA1_L = 1.8751040687119611

STEEL = {"E": 2.1e11, "nu": 0.0, "rho": 7800.0}


# --------------------------------------------------------------------------- closed forms

def second_moment(height: float, width: float) -> float:
    """I (m^4) of a rectangle for bending in the local x-y plane (about local z)."""
    return width * height**3 / 12.0


def cantilever_frequency(E: float, rho: float, height: float, width: float,
                         length: float) -> float:
    """Lowest bending frequency (rad/s) of an Euler-Bernoulli cantilever."""
    area = height * width
    return BETA1_L**2 * math.sqrt(E * second_moment(height, width) / (rho * area * length**4))


def tip_deflection(force: float, E: float, height: float, width: float, length: float) -> float:
    """P L^3 / (3 E I): Euler-Bernoulli tip deflection (m) of a cantilever under a tip load."""
    return force * length**3 / (3.0 * E * second_moment(height, width))


# --------------------------------------------------------------------------- scene dicts

def body(name: str = "beam", element: str = "beam2d", elements: int = 4,
         start=(0.0, 0.0), end=(1.0, 0.0), height: float = 0.1, width: float = 0.1,
         material: str = "m") -> dict:
    """A straight [[body]] table."""
    return {"name": name, "element": element, "material": material,
            "section": {"height": height, "width": width}, "elements": elements,
            "start": list(start), "end": list(end)}


def scene(bodies: list[dict], constraints: list[dict] = (), loads: list[dict] = (),
          sensors: list[dict] = (), analysis_tables: dict | None = None,
          material: dict | None = None, solver: dict | None = None,
          title: str = "test scene") -> dict:
    """A whole scene dict (as tomllib would return it)."""
    data = {"title": title, "material": {"m": dict(material or STEEL)}, "body": list(bodies),
            "constraint": list(constraints), "load": list(loads), "sensor": list(sensors),
            "analysis": dict(analysis_tables or {})}
    if solver:
        data["solver"] = dict(solver)
    return data


def cantilever(elements: int = 4, element: str = "beam2d", length: float = 1.0,
               height: float = 0.1, width: float = 0.1, material: dict | None = None,
               force=None, law: dict | None = None, gravity=None, sensors=None,
               analysis_tables: dict | None = None, solver: dict | None = None) -> dict:
    """A cantilever along +x clamped at node 0, with an optional tip force and gravity.
    Default sensors: the tip displacement components, strain and kinetic energy."""
    dim = 2 if element == "beam2d" else 3
    zero = [0.0] * dim
    end = [length] + [0.0] * (dim - 1)
    loads = []
    if force is not None:
        load = {"type": "point_force", "node": "beam:-1", "force": list(force)}
        if law is not None:
            load["time_law"] = law
        loads.append(load)
    if gravity is not None:
        loads.append({"type": "gravity", "acceleration": list(gravity)})
    if sensors is None:
        sensors = [{"name": f"tip_{c}", "type": "displacement", "node": "beam:-1",
                    "component": c} for c in "xyz"[:dim]]
        sensors += [{"name": "strain", "type": "strain_energy"},
                    {"name": "kinetic", "type": "kinetic_energy"}]
    return scene([body(element=element, elements=elements, start=zero, end=end,
                       height=height, width=width)],
                 [{"type": "clamp", "node": "beam:0"}], loads, sensors, analysis_tables,
                 material, solver)


# --------------------------------------------------------------------------- TOML writer

def _value(value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int | float):
        if isinstance(value, float) and not math.isfinite(value):
            raise ValueError(f"no TOML spelling for {value!r}")
        return repr(value)
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_value(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{k} = {_value(v)}" for k, v in value.items()) + "}"
    raise TypeError(f"cannot write {value!r} as TOML")


def _is_table_array(value) -> bool:
    return isinstance(value, list) and bool(value) and all(isinstance(v, dict) for v in value)


def _emit(data: dict, path: str, lines: list[str]) -> None:
    for key, value in data.items():
        if not isinstance(value, dict) and not _is_table_array(value) and value != []:
            lines.append(f"{key} = {_value(value)}")
    for key, value in data.items():
        sub = f"{path}.{key}" if path else key
        if isinstance(value, dict):
            lines.append(f"\n[{sub}]")
            _emit(value, sub, lines)
        elif _is_table_array(value):
            for item in value:  # items of arrays of tables: nested tables are inline
                lines.append(f"\n[[{sub}]]")
                lines.extend(f"{k} = {_value(v)}" for k, v in item.items())


def to_toml(data: dict) -> str:
    """TOML text of a scene dict (tables as [a.b], arrays of tables as [[a]])."""
    lines: list[str] = []
    _emit(data, "", lines)
    return "\n".join(lines) + "\n"


def write_scene(data: dict, folder: Path, name: str = "scene.toml") -> Path:
    """Write a scene dict as a TOML file in ``folder``; returns its path."""
    path = Path(folder) / name
    path.write_text(to_toml(data))
    return path


# --------------------------------------------------------------------------- in-memory runs

@dataclass
class Run:
    """What ``simulate`` computed: the model, static and modal results, time series."""

    model: Model
    sensors: Sensors
    static: analysis.StaticResult | None = None
    static_values: dict = field(default_factory=dict)
    frequencies: np.ndarray | None = None
    t: np.ndarray | None = None
    series: dict = field(default_factory=dict)
    states: list = field(default_factory=list)      # (t, q_full, v_full) when kept
    counters: object = None

    def __getitem__(self, name: str) -> np.ndarray:
        return self.series[name]


def build(data: dict, method: str | None = None, backend: str | None = None) -> Model:
    """Model of a scene dict."""
    return Model(parse_scene(data), method, backend)


def simulate(data: dict, method: str | None = None, backend: str | None = None,
             keep_states: bool = False) -> Run:
    """Run the analyses of a scene dict in memory (static, modal about its ``about``,
    dynamic with its integrator), recording every sensor at each output time."""
    model = build(data, method, backend)
    scene_ = model.scene
    sensors = Sensors(model)
    out = Run(model, sensors)
    if scene_.static is not None:
        out.static = analysis.solve_static(model, scene_.static)
        out.static_values = sensors.values(out.static.q)
    if scene_.modal is not None:
        about = model.reference
        if scene_.modal.about == "static":
            about = out.static.q
        out.frequencies = analysis.modal(model, about, scene_.modal.modes)
    if scene_.dynamic is not None:
        settings = scene_.dynamic
        integrator = INTEGRATORS[settings.integrator](model, settings, model.reference)
        times, rows = [], []

        def observe(t, q, v):
            times.append(t)
            rows.append(sensors.values(q, v, t))
            if keep_states:
                out.states.append((t, q.copy(), v.copy()))

        integrator.run(settings.t_end, settings.step, observe)
        out.counters = integrator.counters
        out.t = np.array(times)
        out.series = {name: np.array([r[name] for r in rows]) for name in sensors.names}
    return out
