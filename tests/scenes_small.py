"""Small scenes for the solver tests, built with the scene API (``runtime.Scene`` and its
parts), an in-memory runner that records sensor time series (and, if asked, the full
states) without writing files or plots, and the comparison of the two engines on a scene.

Closed-form beam values used by the tests are written out here from textbook formulas, never
taken from the code under test.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from runtime import (
    Body,
    Clamp,
    Constant,
    Displacement,
    Gravity,
    KineticEnergy,
    Material,
    PointForce,
    Scene,
    Sensor,
    StrainEnergy,
)
from runtime.model.items.sensors import Sensors
from runtime.model.model import Model
from runtime.model.time_laws import Law
from runtime.solve import engines, modal
from runtime.solve import static as analysis
from runtime.solve.python_engine import INTEGRATORS, Divergence

# first root of 1 + cos(x) cosh(x) = 0 (clamped-free beam), more digits than the paper's 1.8751
BETA1_L = 1.8751040687119611

STEEL = Material("m", E=2.1e11, nu=0.0, rho=7800.0)
CONSTANT = Constant()


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


# --------------------------------------------------------------------------- scenes

def body(name: str = "beam", element: str = "beam2d", elements: int = 4,
         start=(0.0, 0.0), end=(1.0, 0.0), height: float = 0.1, width: float = 0.1,
         material: str = "m") -> Body:
    """A straight body."""
    return Body(name, element, material, height, width, elements, start, end)


def scene(bodies, constraints=(), loads=(), sensors=(), material: Material = STEEL,
          title: str = "test scene", **settings) -> Scene:
    """A scene of one material; ``settings``: static, modal, dynamic, solver, output."""
    return Scene(title=title, materials=[material], bodies=bodies, constraints=constraints,
                 loads=loads, sensors=sensors, **settings)


def cantilever(elements: int = 4, element: str = "beam2d", length: float = 1.0,
               height: float = 0.1, width: float = 0.1, material: Material = STEEL,
               force=None, law: Law = CONSTANT, gravity=None,
               sensors: list[Sensor] | None = None, **settings) -> Scene:
    """A cantilever along +x clamped at node 0, with an optional tip force (following
    ``law``) and gravity.  Default sensors: the tip displacement components, strain and
    kinetic energy.  ``settings`` as for ``scene``."""
    dim = 2 if element == "beam2d" else 3
    loads = []
    if force is not None:
        loads.append(PointForce("beam:-1", force, time_law=law))
    if gravity is not None:
        loads.append(Gravity(gravity))
    if sensors is None:
        sensors = [Displacement(f"tip_{c}", "beam:-1", c) for c in "xyz"[:dim]]
        sensors += [StrainEnergy("strain"), KineticEnergy("kinetic")]
    return scene([body(element=element, elements=elements, start=(0.0,) * dim,
                       end=(length,) + (0.0,) * (dim - 1), height=height, width=width)],
                 [Clamp("beam:0")], loads, sensors, material, **settings)


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


def simulate(scene_: Scene, method: str | None = None, backend: str | None = None,
             keep_states: bool = False) -> Run:
    """Run the analyses of a scene in memory (static, modal about its ``about``, dynamic with
    its integrator), recording every sensor at each output time."""
    model = Model(scene_, method, backend)
    sensors = Sensors(model)
    out = Run(model, sensors)
    if scene_.static is not None:
        out.static = analysis.solve_static(model, scene_.static)
        out.static_values = sensors.values(out.static.q)
    if scene_.modal is not None:
        about = model.reference
        if scene_.modal.about == "static":
            about = out.static.q
        out.frequencies = modal.modal(model, about, scene_.modal.modes)
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


# --------------------------------------------------------------------------- engines

def engine_history(model: Model, settings, engine: str):
    """(states [(t, q_full, v_full)], counters, divergence or None) of one engine."""
    runner = engines.make(engine, model, settings, model.reference)
    states = []
    failure = None
    try:
        runner.run(settings.t_end, settings.step,
                   lambda t, q, v: states.append((t, q.copy(), v.copy())))
    except Divergence as error:
        failure = (error.time, error.cause)
    return states, dataclasses.asdict(runner.counters), failure


#: with a kept Jacobian (modified, auto Newton) the corrections shrink linearly and often
#: end within round-off of the tolerance, so one engine takes one more iteration than the
#: other now and then (the shipped cable cantilever: 1861 against 1865 in 1000 steps); the
#: counts agree to this fraction, the steps exactly
COUNT_RTOL = 0.02


def counts_agree(compiled: dict, python: dict, newton: str, rtol: float = COUNT_RTOL) -> None:
    """Assert the two engines' counters equal (full Newton: quadratic convergence ends far
    below the tolerance) or, with a kept Jacobian, within ``rtol`` (steps equal)."""
    if newton == "full":
        assert compiled == python                 # steps, Newton iterations, evaluations
        return
    assert compiled["steps"] == python["steps"]
    for key, count in python.items():
        assert abs(compiled[key] - count) <= rtol * count + 2, (key, compiled, python)


def state_bounds(q_rtol: float, v_rtol: float, q_scale: float, v_scale: float,
                 settings) -> tuple[float, float]:
    """The agreement of the engines' positions and velocities: q_rtol of ``q_scale`` and
    v_rtol of ``v_scale``, or with a kept Jacobian (the two may stop one iteration apart) at
    least ten times the Newton tolerance, and the velocity that makes in a step (2 / h)."""
    q_bound, v_bound = q_rtol * q_scale, v_rtol * v_scale
    if settings.newton == "full":
        return q_bound, v_bound
    newton = 10 * settings.tolerance * q_scale
    return max(q_bound, newton), max(v_bound, 2 * newton / settings.step)


def compare_engines(scene_: Scene, q_rtol: float = 1e-12, v_rtol: float = 1e-9,
                    sensor_rtol: float | None = None, count_rtol: float = COUNT_RTOL,
                    **dynamic) -> tuple[dict, list, tuple | None]:
    """Run both engines; assert equal counters (``counts_agree``) and failures, and states
    equal to q_rtol of the largest coordinate and velocities to v_rtol of the largest
    velocity (with a kept Jacobian, to the Newton tolerance at least: ``state_bounds``); with
    ``sensor_rtol``, every sensor of the scene equal to sensor_rtol of its largest value over
    the run, energies of the largest energy (a conserved total or a small strain energy is a
    difference of larger ones), a sensor that stays 0 (a constraint violation) to 1e-15 of
    the model's length scale.  Returns the Python engine's (counters, states, failure)."""
    settings = dataclasses.replace(scene_.dynamic, **dynamic)
    model = Model(scene_)
    python = engine_history(model, settings, "python")
    compiled = engine_history(model, settings, "compiled")
    counts_agree(compiled[1], python[1], settings.newton, count_rtol)
    assert compiled[2] == python[2]          # divergence time and cause (or none)
    assert len(compiled[0]) == len(python[0]) >= 1
    q_scale = max(np.abs(q).max() for _, q, _ in python[0])
    v_scale = max(max(np.abs(v).max() for _, _, v in python[0]), 1e-3)
    q_bound, v_bound = state_bounds(q_rtol, v_rtol, q_scale, v_scale, settings)
    for (tp, qp, vp), (tc, qc, vc) in zip(python[0], compiled[0], strict=True):
        assert tc == tp
        assert np.abs(qc - qp).max() <= q_bound
        assert np.abs(vc - vp).max() <= v_bound
    if sensor_rtol is not None:
        sensors = Sensors(model)
        series = [np.array([[row[name] for name in sensors.names] for row in
                            (sensors.values(q, v, t) for t, q, v in states[0])])
                  for states in (python, compiled)]
        scale = np.abs(series[0]).max(axis=0)
        energy = np.array([s.energy for s in sensors.sensors])
        if energy.any():
            scale[energy] = scale[energy].max()
        bound = np.maximum(sensor_rtol * scale, 1e-15 * model.length_scale())
        assert np.all(np.abs(series[1] - series[0]) <= bound)
    return python[1], python[0], python[2]
