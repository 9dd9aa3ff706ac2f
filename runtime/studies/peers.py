"""Exudyn models of the paper's cantilever and rotating beam, for timing our solvers against a
peer (``ancf bench solvers``, issue 7).

Exudyn (optional: ``pip install exudyn==1.13.6``) has no element equal to ours, so these are
the closest it offers, with the data of docs/design.md section 10:

* cantilever: ``ObjectANCFBeam`` (Nachbagauer-Gruber-Gerstmayr shear-deformable 3D ANCF beam:
  nodes r, r_y, r_z (18 coordinates per element), centre line linear between the nodes,
  section-resultant material law: a 6x6 section stiffness on axial, shear, torsion and
  bending strains plus a penalty on cross-section deformation; only the rotary inertia of the
  section has mass) against our beam3d (3243: r, r_x, r_y, r_z, cubic along the axis, St.
  Venant-Kirchhoff continuum integrated over the volume).  The section stiffness mirrors a
  continuum with nu = 0: EA, GA (no shear correction), G (Iy + Iz), EIy, EIz, and the default
  cross-section penalty EA, EA, 2 GA;
* rotating beam: ``ObjectANCFCable2D`` (Euler-Bernoulli ANCF cable, r and r_x per node, EA and
  EI) against our beam2d (Omar-Shabana shear-deformable continuum, r, r_x, r_y per node).

Time integration mirrors the project's: ``trapezoidal`` is Exudyn's TrapezoidalIndex2
(Newmark beta = 1/4, gamma = 1/2, velocity-level constraints), ``generalized_alpha`` its
generalized-alpha (index 3) with spectral radius ``rho_inf``.  Fixed step, Newton converged on
the increment (``residualMode = 1``) with 1e-10 times the model size as its absolute and
relative tolerance, after our default (which bounds the largest entry of the increment; Exudyn
uses its own norm of the increment, so iteration counts may differ for the same accuracy).  The
clamp and the hub are coordinate constraints (Lagrange multipliers); Exudyn has no coordinate
elimination.  Time laws are Exudyn symbolic user functions (expression trees evaluated in C++,
no Python call during the solve).  Nothing is written to files or the console.
"""

from __future__ import annotations

import contextlib
import functools
import math
import time
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.linalg

from runtime.catalog import INTEGRATORS, NEWTON_MODES

# paper cantilever (docs/design.md section 10, scenes/cantilever.toml)
CANTILEVER = {"length": 5.0, "height": 0.1, "width": 0.1, "E": 132e9, "rho": 8245.2,
              "force": 300.0, "ramp": 3.5}
# paper rotating beam (docs/design.md section 10, scenes/rotating_beam.toml)
ROTATING_BEAM = {"length": 8.0, "area": 7.299e-5, "inertia": 8.215e-9, "E": 68.95e9,
                 "rho": 2766.67, "omega": 4.0, "t_ramp": 15.0}
TOLERANCE = 1e-10           # Newton, relative to the model size, as the project's default
#: The element of the planar peer models (rotating beam, cable cantilever, elastica)
PEER_ELEMENT = "ANCFCable2D"
#: Newton modes run with Exudyn, its default (modified Newton) first
NEWTON = tuple(sorted((mode for mode in NEWTON_MODES if mode != "auto"),
                     key=lambda mode: mode != "modified"))


@dataclass
class PeerRun:
    """One Exudyn dynamic run: wall times (s) of the solve and of building the model, work
    counters from Exudyn's solver, the final tip displacement (m) and the settings used."""

    simulate_s: float
    build_s: float
    steps: int
    newton_iterations: int
    jacobian_evaluations: int
    tip_displacement: float
    note: str
    history: tuple[np.ndarray, np.ndarray] | None = None   # (times s, tip value m), if asked


@functools.cache
def exudyn_available() -> bool:
    """True if Exudyn can be imported."""
    try:
        import exudyn  # noqa: F401
    except ImportError:
        return False
    return True


@contextlib.contextmanager
def _quiet() -> Iterator[None]:
    """Silence Exudyn's console output for the duration."""
    import exudyn as exu

    saved = exu.config.printToConsole
    exu.config.printToConsole = False
    try:
        yield
    finally:
        exu.config.printToConsole = saved


def _check(newton: str, integrator: str | None = None) -> None:
    if newton not in NEWTON:
        raise ValueError(f"newton: expected one of {', '.join(NEWTON)}, got {newton!r}")
    if integrator is not None and integrator not in INTEGRATORS:
        raise ValueError(f"integrator: expected one of {', '.join(INTEGRATORS)}, "
                         f"got {integrator!r}")


def _settings(size: float, every: float | None = None) -> Any:
    """Exudyn settings without file output, console output or timers; sensors (stored in
    memory, never written) record every ``every`` seconds when given."""
    import exudyn as exu

    s = exu.SimulationSettings()
    s.solution.file.write = False
    s.solution.sensors.active = every is not None
    if every is not None:
        s.solution.sensors.writePeriod = every
    s.show.globalTimers = False
    s.staticSolver.verboseMode = 0
    s.timeIntegration.verboseMode = 0
    newton = s.timeIntegration.newton
    newton.residualMode = 1
    newton.relativeTolerance = newton.absoluteTolerance = TOLERANCE * max(size, 1.0)
    s.linearSolver.solverType = exu.LinearSolverType.EigenSparse
    return s


def _solve(mbs: Any, size: float, t_end: float, step: float, newton: str, integrator: str,
           rho_inf: float, every: float | None = None,
           initial_accelerations: bool = False) -> tuple[float, Any]:
    """Run a fixed-step dynamic solve (sensors recording every ``every`` s, if given) from
    rest, or with ``initial_accelerations`` from its initial velocities (generalized-alpha
    then solves for the consistent accelerations at t = 0); returns (wall time, Exudyn
    solver)."""
    import exudyn as exu

    s = _settings(size, every)
    ti = s.timeIntegration
    ti.endTime = t_end
    ti.numberOfSteps = int(round(t_end / step))
    ti.adaptiveStep = False
    ti.newton.useModifiedNewton = newton == "modified"
    # both models start at rest with zero loads and hub acceleration: a(0) = 0 is exact (and
    # Exudyn cannot solve M a = F for ANCFBeam, whose section deformation modes have no mass)
    ti.generalizedAlpha.computeInitialAccelerations = initial_accelerations
    ti.generalizedAlpha.spectralRadius = rho_inf
    solver = (exu.DynamicSolverType.TrapezoidalIndex2 if integrator == "trapezoidal"
              else exu.DynamicSolverType.GeneralizedAlpha)
    start = time.perf_counter()
    try:
        mbs.SolveDynamic(s, solverType=solver)
    except exu.SolverError as error:
        reached = mbs.sys["dynamicSolver"].it.currentTime
        raise RuntimeError(f"Exudyn dynamic solve failed at t = {reached:g} s: {error}") \
            from error
    return time.perf_counter() - start, mbs.sys["dynamicSolver"]


def _note(model: str, newton: str, integrator: str, rho_inf: float, step: float) -> str:
    scheme = ("TrapezoidalIndex2 (Newmark 1/4, 1/2)" if integrator == "trapezoidal"
              else f"GeneralizedAlpha index 3, rho_inf = {rho_inf:g}")
    mode = ("modified Newton (Jacobian reused while it converges)" if newton == "modified"
            else "full Newton (Jacobian every iteration)")
    return (f"Exudyn {exudyn_version()} {model}; {scheme}; {mode}; step {step:g} s; "
            f"increment tolerance {TOLERANCE:g} x size; EigenSparse; symbolic time law")


def exudyn_version() -> str:
    """The installed Exudyn's version."""
    import exudyn as exu

    return exu.__version__


# --------------------------------------------------------------------------- cantilever

def _cantilever(elements: int, ramp: bool) -> tuple[Any, Any, list]:
    """The paper cantilever as Exudyn ANCFBeam elements, clamped at x = 0, tip load in -y
    (constant, or the cosine ramp of eq. 42).  Returns (container, system, nodes): keep the
    container alive while the system is used."""
    import exudyn as exu
    import exudyn.itemInterface as ei

    p = CANTILEVER
    area = p["height"] * p["width"]
    iz = p["width"] * p["height"] ** 3 / 12.0    # bending in x-y (load along y)
    iy = p["height"] * p["width"] ** 3 / 12.0
    shear = p["E"] / 2.0                          # nu = 0
    section = exu.BeamSection()
    section.stiffnessMatrix = np.diag([p["E"] * area, shear * area, shear * area,
                                       shear * (iy + iz), p["E"] * iy, p["E"] * iz])
    section.inertia = np.diag([p["rho"] * (iy + iz), p["rho"] * iy, p["rho"] * iz])
    section.massPerLength = p["rho"] * area

    container = exu.SystemContainer()
    mbs = container.AddSystem()
    ground = mbs.AddMarker(ei.MarkerNodeCoordinate(
        nodeNumber=mbs.AddNode(ei.NodePointGround()), coordinate=0))
    h = p["length"] / elements
    nodes = [mbs.AddNode(ei.NodePointSlope23(referenceCoordinates=[i * h, 0, 0, 0, 1, 0, 0, 0, 1],
                                             visualization=ei.VNodePointSlope23(show=False)))
             for i in range(elements + 1)]
    for a, b in zip(nodes, nodes[1:], strict=False):
        mbs.AddObject(ei.ObjectANCFBeam(nodeNumbers=[a, b], length=h, sectionData=section,
                                        visualization=ei.VObjectANCFBeam(show=False)))
    for c in range(9):  # clamp: position and both section slopes of the first node
        marker = mbs.AddMarker(ei.MarkerNodeCoordinate(nodeNumber=nodes[0], coordinate=c))
        mbs.AddObject(ei.CoordinateConstraint(markerNumbers=[ground, marker],
                                              visualization=ei.VCoordinateConstraint(show=False)))
    _tip_load(mbs, nodes[-1], [0.0, -p["force"], 0.0], p["ramp"] if ramp else None)
    mbs.Assemble()
    return container, mbs, nodes


def _tip_load(mbs: Any, node: int, load: list[float], ramp: float | None) -> None:
    """A force ``load`` on ``node``'s position: constant, or raised by the cosine ramp of
    eq. 42 over ``ramp`` seconds (a symbolic user function)."""
    import exudyn as exu
    import exudyn.itemInterface as ei
    from exudyn.advancedUtilities import CreateSymbolicUserFunction

    tip = mbs.AddMarker(ei.MarkerNodePosition(nodeNumber=node))
    if ramp is None:
        mbs.AddLoad(ei.LoadForceVector(markerNumber=tip, loadVector=load))
        return
    esym = exu.symbolic

    def cosine_ramp(mbs, t, load):
        f = esym.IfThenElse(t <= ramp, 0.5 * (1.0 - esym.cos(t * (math.pi / ramp))),
                            esym.Real(1.0))
        return [load[0] * f, load[1] * f, load[2] * f]

    law = CreateSymbolicUserFunction(mbs, cosine_ramp, "loadVectorUserFunction",
                                     itemTypeName="LoadForceVector")
    mbs.sys["peer_laws"] = [law]  # the expression tree must live as long as the system
    mbs.AddLoad(ei.LoadForceVector(markerNumber=tip, loadVector=load,
                                   loadVectorUserFunction=law))


def exudyn_cantilever(elements: int, t_end: float = 4.0, step: float = 1e-3,
                      newton: str = "modified", integrator: str = "trapezoidal",
                      rho_inf: float = 0.8) -> PeerRun:
    """The paper cantilever (scenes/cantilever.toml) run in Exudyn; ``tip_displacement`` is
    the final tip y displacement (m).  ``integrator`` and ``rho_inf`` as in a scene's
    [analysis.dynamic]; ``newton`` is ``modified`` (Exudyn's default) or ``full``."""
    import exudyn as exu

    _check(newton, integrator)
    with _quiet():
        start = time.perf_counter()
        container, mbs, nodes = _cantilever(elements, ramp=True)
        build_s = time.perf_counter() - start
        simulate_s, solver = _solve(mbs, CANTILEVER["length"], t_end, step, newton,
                                    integrator, rho_inf)
        tip = mbs.GetNodeOutput(nodes[-1], exu.OutputVariableType.Displacement)[1]
    return PeerRun(simulate_s, build_s, solver.it.currentStepIndex - 1,
                   solver.it.newtonStepsCount, solver.it.newtonJacobiCount, float(tip),
                   _note(f"ANCFBeam x {elements}", newton, integrator, rho_inf, step))


def exudyn_cantilever_static(elements: int = 10) -> float:
    """Static tip y displacement (m) of the Exudyn cantilever under the full 300 N."""
    import exudyn as exu

    with _quiet():
        container, mbs, nodes = _cantilever(elements, ramp=False)
        try:
            mbs.SolveStatic(_settings(CANTILEVER["length"]))
        except exu.SolverError as error:
            raise RuntimeError(f"Exudyn static solve failed: {error}") from error
        return float(mbs.GetNodeOutput(nodes[-1], exu.OutputVariableType.Displacement)[1])


def exudyn_cantilever_frequencies(elements: int = 10, modes: int = 4) -> np.ndarray:
    """Lowest ``modes`` natural frequencies (rad/s) of the Exudyn cantilever about the
    reference.  Solved as K^-1 M (M is singular: section deformation modes have no mass, so
    Exudyn's own ComputeODE2Eigenvalues cannot be used)."""
    with _quiet():
        container, mbs, _ = _cantilever(elements, ramp=False)
        mass, stiffness, _ = mbs.ComputeLinearizedSystem(_settings(CANTILEVER["length"]))
    free = slice(9, None)  # the clamped first node holds coordinates 0..8
    mu = scipy.linalg.eigh(mass[free, free], stiffness[free, free], eigvals_only=True)
    mu = mu[mu > 1e-12 * mu.max()]
    return np.sort(1.0 / np.sqrt(mu))[:modes]


# --------------------------------------------------------------------------- cables

def _cable(elements: int, length: float, mass_per_length: float, bending: float,
           axial: float) -> tuple[Any, Any, int, list]:
    """A straight chain of ``elements`` ObjectANCFCable2D along x from the origin (bending
    stiffness EI, axial stiffness EA).  Returns (container, system, ground marker, nodes),
    not assembled."""
    import exudyn as exu
    import exudyn.itemInterface as ei

    container = exu.SystemContainer()
    mbs = container.AddSystem()
    ground = mbs.AddMarker(ei.MarkerNodeCoordinate(
        nodeNumber=mbs.AddNode(ei.NodePointGround()), coordinate=0))
    h = length / elements
    nodes = [mbs.AddNode(ei.NodePoint2DSlope1(referenceCoordinates=[i * h, 0, 1, 0],
                                              visualization=ei.VNodePoint2DSlope1(show=False)))
             for i in range(elements + 1)]
    for a, b in zip(nodes, nodes[1:], strict=False):
        mbs.AddObject(ei.ObjectANCFCable2D(
            nodeNumbers=[a, b], length=h, massPerLength=mass_per_length,
            bendingStiffness=bending, axialStiffness=axial,
            visualization=ei.VObjectANCFCable2D(show=False)))
    return container, mbs, ground, nodes


def _hold(mbs: Any, ground: int, node: int, coordinate: int, **laws: Any) -> None:
    """A coordinate constraint of ``node``'s ``coordinate`` (its displacement zero, or the
    offset user functions ``laws``)."""
    import exudyn.itemInterface as ei

    marker = mbs.AddMarker(ei.MarkerNodeCoordinate(nodeNumber=node, coordinate=coordinate))
    mbs.AddObject(ei.CoordinateConstraint(markerNumbers=[ground, marker],
                                          visualization=ei.VCoordinateConstraint(show=False),
                                          **laws))


def _record(mbs: Any, nodes: list) -> list[int]:
    """Sensors storing the coordinates of ``nodes`` in memory (call before Assemble)."""
    import exudyn as exu
    import exudyn.itemInterface as ei

    return [mbs.AddSensor(ei.SensorNode(nodeNumber=node, storeInternal=True, writeToFile=False,
                                        outputVariableType=exu.OutputVariableType.Coordinates,
                                        visualization=ei.VSensorNode(show=False)))
            for node in nodes]


def _positions(mbs: Any, node: int, sensor: int) -> tuple[np.ndarray, np.ndarray]:
    """(times, coordinates + reference) recorded by a ``_record`` sensor of ``node``."""
    data = np.asarray(mbs.GetSensorStoredData(sensor))
    reference = np.asarray(mbs.GetNodeParameter(node, "referenceCoordinates"))
    return data[:, 0], data[:, 1:] + reference


# --------------------------------------------------------------------------- rotating beam

def _spin_up(w: float, T: float) -> tuple[Any, Any]:
    """The spin-up law of eq. 45 (to ``w`` rad/s in ``T`` s) and its rate as functions of
    Exudyn's symbolic time."""
    import exudyn as exu

    esym, c = exu.symbolic, T / (2.0 * math.pi)

    def angle(t):
        ramp = (w / T) * (0.5 * t * t - 2.0 * c * c * esym.sin(t * (math.pi / T)) ** 2)
        return esym.IfThenElse(t <= T, ramp, w * (t - 0.5 * T))

    def rate(t):
        ramp = (w / T) * (t - c * esym.sin(t * (2.0 * math.pi / T)))
        return esym.IfThenElse(t <= T, ramp, esym.Real(w))

    return angle, rate


def _rotating_beam(elements: int) -> tuple[Any, Any, list]:
    """The paper rotating beam as Exudyn ANCFCable2D elements; the first node stays at the
    origin and its slope is driven to (cos a, sin a) by the spin-up law a(t) of eq. 45.
    Returns (container, system, nodes), not assembled."""
    import exudyn as exu
    from exudyn.advancedUtilities import CreateSymbolicUserFunction

    p = ROTATING_BEAM
    esym = exu.symbolic
    angle, rate = _spin_up(p["omega"], p["t_ramp"])

    # offsets of the slope displacements (reference slope (1, 0)) and their time derivatives;
    # Exudyn records each law once with symbolic arguments (mbs, t, item, offset)
    def slope_x(mbs, t, item, offset):
        return esym.cos(angle(t)) - 1.0

    def slope_y(mbs, t, item, offset):
        return esym.sin(angle(t))

    def slope_x_t(mbs, t, item, offset):
        return -esym.sin(angle(t)) * rate(t)

    def slope_y_t(mbs, t, item, offset):
        return esym.cos(angle(t)) * rate(t)

    container, mbs, ground, nodes = _cable(elements, p["length"], p["rho"] * p["area"],
                                           p["E"] * p["inertia"], p["E"] * p["area"])
    mbs.sys["peer_laws"] = []  # the expression trees must live as long as the system
    laws = [None, None, (slope_x, slope_x_t), (slope_y, slope_y_t)]
    for coordinate, law in enumerate(laws):
        kwargs = {}
        if law is not None:
            kwargs = {name: CreateSymbolicUserFunction(mbs, f, name,
                                                       itemTypeName="ObjectConnectorCoordinate")
                      for name, f in zip(("offsetUserFunction", "offsetUserFunction_t"), law,
                                         strict=True)}
            mbs.sys["peer_laws"].extend(kwargs.values())
        _hold(mbs, ground, nodes[0], coordinate, **kwargs)
    return container, mbs, nodes


def _transverse(hub: np.ndarray, tip: np.ndarray) -> np.ndarray:
    """Tip displacement across the hub frame (our sensor ``tip_transverse``) from node
    coordinates (..., 4) of the hub and the tip: the frame is the hub's slope, normalised,
    about the hub."""
    axis = hub[..., 2:] / np.linalg.norm(hub[..., 2:], axis=-1, keepdims=True)
    return (-axis[..., 1] * (tip[..., 0] - hub[..., 0])
            + axis[..., 0] * (tip[..., 1] - hub[..., 1]))


def exudyn_rotating_beam(elements: int = 10, t_end: float = 20.0, step: float = 1e-3,
                         newton: str = "modified", integrator: str = "generalized_alpha",
                         rho_inf: float = 0.8, every: float | None = None) -> PeerRun:
    """The paper rotating beam (scenes/rotating_beam.toml) run in Exudyn; ``tip_displacement`` is
    the final tip deflection across the hub frame (m), as our sensor ``tip_transverse``, and
    with ``every`` (s) ``history`` its time series at that interval.
    Generalized-alpha by default: Exudyn's undamped TrapezoidalIndex2 loses Newton convergence
    after the spin-up (t = 16.9 s with a 5e-3 s step; it holds with 1e-3 s)."""
    import exudyn as exu

    _check(newton, integrator)
    with _quiet():
        start = time.perf_counter()
        container, mbs, nodes = _rotating_beam(elements)
        sensors = _record(mbs, [nodes[0], nodes[-1]])
        mbs.Assemble()
        build_s = time.perf_counter() - start
        simulate_s, solver = _solve(mbs, ROTATING_BEAM["length"], t_end, step, newton,
                                    integrator, rho_inf, every)
        history = None
        if every is not None:
            t, hub = _positions(mbs, nodes[0], sensors[0])
            history = (t, _transverse(hub, _positions(mbs, nodes[-1], sensors[1])[1]))
        final = [np.asarray(mbs.GetNodeOutput(node, exu.OutputVariableType.Coordinates))
                 + np.asarray(mbs.GetNodeParameter(node, "referenceCoordinates"))
                 for node in (nodes[0], nodes[-1])]
    return PeerRun(simulate_s, build_s, solver.it.currentStepIndex - 1,
                   solver.it.newtonStepsCount, solver.it.newtonJacobiCount,
                   float(_transverse(*final)),
                   _note(f"{PEER_ELEMENT} x {elements}", newton, integrator, rho_inf, step),
                   history)


# --------------------------------------------------------------------------- cable cantilever

def _clamped_cable(elements: int, length: float, mass_per_length: float, bending: float,
                   axial: float, load: list[float], ramp: float | None) -> tuple[Any, Any, list]:
    """A cable clamped at the origin (position and slope held) with a tip force ``load``
    (constant, or cosine-ramped over ``ramp`` s); returns (container, system, nodes), not
    assembled."""
    container, mbs, ground, nodes = _cable(elements, length, mass_per_length, bending, axial)
    for coordinate in range(4):
        _hold(mbs, ground, nodes[0], coordinate)
    _tip_load(mbs, nodes[-1], [*load, 0.0], ramp)
    return container, mbs, nodes


def exudyn_cantilever_cable(elements: int, t_end: float = 4.0, step: float = 1e-3,
                            newton: str = "modified", integrator: str = "trapezoidal",
                            rho_inf: float = 0.8, every: float | None = None) -> PeerRun:
    """The paper cantilever (scenes/cantilever.toml) as a planar ANCFCable2D chain (EA, EI of
    the 0.1 x 0.1 section; the tip load in -y ramped over 3.5 s); ``tip_displacement`` is the
    final tip y displacement (m), and with ``every`` (s) ``history`` its time series."""
    import exudyn as exu

    _check(newton, integrator)
    p = CANTILEVER
    area = p["height"] * p["width"]
    with _quiet():
        start = time.perf_counter()
        container, mbs, nodes = _clamped_cable(
            elements, p["length"], p["rho"] * area, p["E"] * p["width"] * p["height"] ** 3 / 12,
            p["E"] * area, [0.0, -p["force"]], p["ramp"])
        sensor = _record(mbs, [nodes[-1]])[0]
        mbs.Assemble()
        build_s = time.perf_counter() - start
        simulate_s, solver = _solve(mbs, p["length"], t_end, step, newton, integrator,
                                    rho_inf, every)
        history = None
        if every is not None:
            data = np.asarray(mbs.GetSensorStoredData(sensor))
            history = (data[:, 0], data[:, 2])
        tip = mbs.GetNodeOutput(nodes[-1], exu.OutputVariableType.Coordinates)[1]
    return PeerRun(simulate_s, build_s, solver.it.currentStepIndex - 1,
                   solver.it.newtonStepsCount, solver.it.newtonJacobiCount, float(tip),
                   _note(f"{PEER_ELEMENT} x {elements}", newton, integrator, rho_inf, step),
                   history)


@dataclass
class PeerStatic:
    """One Exudyn static solve: wall time (s) of the solve, Newton iterations, the tip
    displacement (x, y) (m) and the settings used."""

    simulate_s: float
    newton_iterations: int
    tip: tuple[float, float]
    note: str


def exudyn_elastica(elements: int, load_steps: int = 20, newton: str = "full", *,
                    length: float, height: float, width: float, E: float,
                    force: tuple[float, float]) -> PeerStatic:
    """A clamped ANCFCable2D cantilever of ``length`` (m) along x, section ``height`` x
    ``width`` (m, EI = E w h^3 / 12, EA = E w h), under a fixed-direction tip ``force`` (N),
    solved statically in ``load_steps`` equal load increments with ``newton`` (``full`` or
    ``modified``)."""
    import exudyn as exu

    _check(newton)
    with _quiet():
        container, mbs, nodes = _clamped_cable(elements, length, 1.0,
                                               E * width * height ** 3 / 12.0,
                                               E * width * height, list(force), None)
        mbs.Assemble()
        s = _settings(length)
        s.staticSolver.numberOfLoadSteps = load_steps
        s.staticSolver.newton.useModifiedNewton = newton == "modified"
        start = time.perf_counter()
        try:
            mbs.SolveStatic(s)
        except exu.SolverError as error:
            raise RuntimeError(f"Exudyn static solve failed: {error}") from error
        simulate_s = time.perf_counter() - start
        iterations = mbs.sys["staticSolver"].it.newtonStepsCount
        tip = mbs.GetNodeOutput(nodes[-1], exu.OutputVariableType.Coordinates)[:2]
    mode = "modified" if newton == "modified" else "full"
    note = (f"Exudyn {exudyn_version()} {PEER_ELEMENT} x {elements}; static, {load_steps} load "
            f"steps; {mode} Newton; increment tolerance {TOLERANCE:g} x size; EigenSparse")
    return PeerStatic(simulate_s, iterations, (float(tip[0]), float(tip[1])), note)


# --------------------------------------------------------------------------- slider-crank

#: scenes/slider_crank.toml: a steel flywheel disc (radius 0.15 m, 50 mm thick) driven
#: about z at 10 rad/s, crank pin on its rim at 60 degrees at t = 0; a 10 mm x 10 mm
#: aluminium rod of 0.5 m hinged at the pin; a 0.5 kg slider on the x axis hinged at the
#: rod's end; no gravity; the rigid mechanism's velocities at t = 0
SLIDER_CRANK = {"radius": 0.15, "thickness": 0.05, "density": 7800.0, "omega": 10.0,
                "angle": math.pi / 3, "rod": 0.5, "side": 0.01, "E": 7.0e10, "rho": 2700.0,
                "slider": 0.5}


def _slider_crank_kinematics() -> dict[str, Any]:
    """Positions and velocities of the rigid slider-crank at t = 0 (m, m/s, rad/s)."""
    p = SLIDER_CRANK
    r, length, phi, omega = p["radius"], p["rod"], p["angle"], p["omega"]
    pin = np.array([r * math.cos(phi), r * math.sin(phi)])
    pin_velocity = omega * np.array([-pin[1], pin[0]])
    slider = np.array([pin[0] + math.sqrt(length**2 - pin[1] ** 2), 0.0])
    direction = (slider - pin) / length
    # the rod turns at w about the pin so that its end stays on the x axis
    rod_rate = -pin_velocity[1] / (length * direction[0])
    slider_velocity = pin_velocity + rod_rate * length * np.array([-direction[1],
                                                                   direction[0]])
    return {"pin": pin, "pin_velocity": pin_velocity, "slider": slider,
            "direction": direction, "rod_rate": rod_rate,
            "slider_velocity": slider_velocity}


def _slider_crank(elements: int) -> tuple[Any, Any, dict[str, int]]:
    """The slider-crank in Exudyn: ObjectRigidBody2D crank on a RevoluteJoint2D to the
    ground, driven by a coordinate constraint on its angle (offset omega t, a symbolic user
    function), an ObjectANCFCable2D rod (EA, EI of the square section) hinged to the crank
    pin and to a MassPoint2D slider held on the x axis by a coordinate constraint.  Returns
    (container, system, {"slider": node, "crank": node}), not assembled."""
    import exudyn as exu
    import exudyn.itemInterface as ei
    from exudyn.advancedUtilities import CreateSymbolicUserFunction

    p, k = SLIDER_CRANK, _slider_crank_kinematics()
    container = exu.SystemContainer()
    mbs = container.AddSystem()
    ground_node = mbs.AddNode(ei.NodePointGround())
    ground = mbs.AddObject(ei.ObjectGround())
    disc_mass = p["density"] * math.pi * p["radius"] ** 2 * p["thickness"]
    crank_node = mbs.AddNode(ei.NodeRigidBody2D(referenceCoordinates=[0.0, 0.0, p["angle"]],
                                                initialVelocities=[0.0, 0.0, p["omega"]]))
    crank = mbs.AddObject(ei.ObjectRigidBody2D(
        nodeNumber=crank_node, mass=disc_mass, inertia=disc_mass * p["radius"] ** 2 / 2,
        visualization=ei.VObjectRigidBody2D(show=False)))
    hidden = {"visualization": ei.VRevoluteJoint2D(show=False)}
    mbs.AddObject(ei.RevoluteJoint2D(markerNumbers=[
        mbs.AddMarker(ei.MarkerBodyPosition(bodyNumber=ground, localPosition=[0, 0, 0])),
        mbs.AddMarker(ei.MarkerBodyPosition(bodyNumber=crank, localPosition=[0, 0, 0]))],
        **hidden))
    area, side = p["side"] ** 2, p["side"]
    h, (dx, dy), w = p["rod"] / elements, k["direction"], k["rod_rate"]
    nodes = []
    for i in range(elements + 1):
        offset = i * h * k["direction"]
        position = k["pin"] + offset
        velocity = k["pin_velocity"] + w * np.array([-offset[1], offset[0]])
        nodes.append(mbs.AddNode(ei.NodePoint2DSlope1(
            referenceCoordinates=[*position, dx, dy],
            initialVelocities=[*velocity, -w * dy, w * dx],
            visualization=ei.VNodePoint2DSlope1(show=False))))
    for a, b in zip(nodes, nodes[1:], strict=False):
        mbs.AddObject(ei.ObjectANCFCable2D(
            nodeNumbers=[a, b], length=h, massPerLength=p["rho"] * area,
            bendingStiffness=p["E"] * side**4 / 12, axialStiffness=p["E"] * area,
            visualization=ei.VObjectANCFCable2D(show=False)))
    local_pin = [p["radius"], 0.0, 0.0]
    mbs.AddObject(ei.RevoluteJoint2D(markerNumbers=[
        mbs.AddMarker(ei.MarkerBodyPosition(bodyNumber=crank, localPosition=local_pin)),
        mbs.AddMarker(ei.MarkerNodePosition(nodeNumber=nodes[0]))], **hidden))
    slider_node = mbs.AddNode(ei.NodePoint2D(referenceCoordinates=list(k["slider"]),
                                             initialVelocities=list(k["slider_velocity"])))
    mbs.AddObject(ei.MassPoint2D(mass=p["slider"], nodeNumber=slider_node,
                                 visualization=ei.VMassPoint2D(show=False)))
    mbs.AddObject(ei.RevoluteJoint2D(markerNumbers=[
        mbs.AddMarker(ei.MarkerNodePosition(nodeNumber=nodes[-1])),
        mbs.AddMarker(ei.MarkerNodePosition(nodeNumber=slider_node))], **hidden))
    ground_coordinate = mbs.AddMarker(ei.MarkerNodeCoordinate(nodeNumber=ground_node,
                                                              coordinate=0))
    _hold(mbs, ground_coordinate, slider_node, 1)
    omega = p["omega"]

    def drive(mbs, t, item, offset):       # the crank angle's displacement omega t
        return omega * t

    def drive_t(mbs, t, item, offset):
        return exu.symbolic.Real(omega)

    laws = {name: CreateSymbolicUserFunction(mbs, f, name,
                                             itemTypeName="ObjectConnectorCoordinate")
            for name, f in (("offsetUserFunction", drive), ("offsetUserFunction_t", drive_t))}
    mbs.sys["peer_laws"] = list(laws.values())  # the expression trees live with the system
    _hold(mbs, ground_coordinate, crank_node, 2, **laws)
    return container, mbs, {"slider": slider_node, "crank": crank_node}


def exudyn_slider_crank(elements: int = 8, t_end: float = 0.7, step: float = 2.5e-4,
                        newton: str = "modified", integrator: str = "generalized_alpha",
                        rho_inf: float = 0.9, every: float | None = None) -> PeerRun:
    """The slider-crank of scenes/slider_crank.toml in Exudyn (``_slider_crank``), from the
    rigid mechanism's velocities with consistent initial accelerations;
    ``tip_displacement`` is the slider's final x position (m), and with ``every`` (s)
    ``history`` its time series."""
    import exudyn as exu

    _check(newton, integrator)
    with _quiet():
        start = time.perf_counter()
        container, mbs, nodes = _slider_crank(elements)
        sensor = _record(mbs, [nodes["slider"]])[0]
        mbs.Assemble()
        build_s = time.perf_counter() - start
        simulate_s, solver = _solve(mbs, SLIDER_CRANK["rod"], t_end, step, newton,
                                    integrator, rho_inf, every, initial_accelerations=True)
        history = None
        if every is not None:
            t, position = _positions(mbs, nodes["slider"], sensor)
            history = (t, position[:, 0])
        x = (mbs.GetNodeOutput(nodes["slider"], exu.OutputVariableType.Coordinates)[0]
             + mbs.GetNodeParameter(nodes["slider"], "referenceCoordinates")[0])
    return PeerRun(simulate_s, build_s, solver.it.currentStepIndex - 1,
                   solver.it.newtonStepsCount, solver.it.newtonJacobiCount, float(x),
                   _note(f"RigidBody2D crank, {PEER_ELEMENT} x {elements} rod, MassPoint2D "
                         "slider", newton, integrator, rho_inf, step), history)


# --------------------------------------------------------------------------- four-bar

#: scenes/four_bar.toml: ground pivots 0.45 m apart, a steel crank bar of 0.15 m (20 mm
#: square) spun up about z from rest to 2 pi rad/s in 0.5 s, pointing along +y at t = 0; a
#: 0.5 m aluminium coupler of 8 mm square section; a steel rocker bar of 0.35 m (20 mm
#: square); no gravity
FOUR_BAR = {"crank": 0.15, "coupler": 0.5, "rocker": 0.35, "ground": 0.45, "bar": 0.02,
            "density": 7800.0, "side": 0.008, "E": 7.0e10, "rho": 2700.0,
            "omega": 2.0 * math.pi, "t_ramp": 0.5}


def four_bar_tip() -> np.ndarray:
    """The coupler's end C (2,) at t = 0 (m): the linkage's closure with the crank along +y,
    on the branch above the line from the crank pin to the rocker's pivot."""
    p = FOUR_BAR
    pin, pivot = np.array([0.0, p["crank"]]), np.array([p["ground"], 0.0])
    span = pivot - pin
    distance = float(np.linalg.norm(span))
    along = (p["coupler"] ** 2 - p["rocker"] ** 2 + distance**2) / (2 * distance)
    unit = span / distance
    return pin + along * unit + math.sqrt(p["coupler"] ** 2 - along**2) * np.array(
        [-unit[1], unit[0]])


def _four_bar(elements: int) -> tuple[Any, Any, dict[str, int]]:
    """The four-bar in Exudyn: ObjectRigidBody2D crank and rocker (nodes at their centres
    of mass) on RevoluteJoint2D pivots, the crank driven by a coordinate constraint on its
    angle (the symbolic spin-up law), an ObjectANCFCable2D coupler hinged to both by
    RevoluteJoint2D.  Returns (container, system, {"crank": node, "rocker": node}), not
    assembled."""
    import exudyn as exu
    import exudyn.itemInterface as ei
    from exudyn.advancedUtilities import CreateSymbolicUserFunction

    p = FOUR_BAR
    container = exu.SystemContainer()
    mbs = container.AddSystem()
    ground_node = mbs.AddNode(ei.NodePointGround())
    ground = mbs.AddObject(ei.ObjectGround())
    hidden = {"visualization": ei.VRevoluteJoint2D(show=False)}
    tip = four_bar_tip()
    bodies = {}
    for name, pivot, angle in (("crank", np.zeros(2), math.pi / 2),
                               ("rocker", np.array([p["ground"], 0.0]),
                                math.atan2(tip[1], tip[0] - p["ground"]))):
        length, bar = p[name], p["bar"]
        mass = p["density"] * length * bar * bar
        centre = pivot + 0.5 * length * np.array([math.cos(angle), math.sin(angle)])
        node = mbs.AddNode(ei.NodeRigidBody2D(referenceCoordinates=[*centre, angle]))
        body = mbs.AddObject(ei.ObjectRigidBody2D(
            nodeNumber=node, mass=mass, inertia=mass * (length**2 + bar**2) / 12,
            visualization=ei.VObjectRigidBody2D(show=False)))
        mbs.AddObject(ei.RevoluteJoint2D(markerNumbers=[
            mbs.AddMarker(ei.MarkerBodyPosition(bodyNumber=ground,
                                                localPosition=[*pivot, 0.0])),
            mbs.AddMarker(ei.MarkerBodyPosition(bodyNumber=body,
                                                localPosition=[-0.5 * length, 0.0, 0.0]))],
            **hidden))
        bodies[name] = (node, body)
    area, side = p["side"] ** 2, p["side"]
    pin = np.array([0.0, p["crank"]])
    direction = (tip - pin) / p["coupler"]
    h = p["coupler"] / elements
    nodes = [mbs.AddNode(ei.NodePoint2DSlope1(
        referenceCoordinates=[*(pin + i * h * direction), *direction],
        visualization=ei.VNodePoint2DSlope1(show=False))) for i in range(elements + 1)]
    for a, b in zip(nodes, nodes[1:], strict=False):
        mbs.AddObject(ei.ObjectANCFCable2D(
            nodeNumbers=[a, b], length=h, massPerLength=p["rho"] * area,
            bendingStiffness=p["E"] * side**4 / 12, axialStiffness=p["E"] * area,
            visualization=ei.VObjectANCFCable2D(show=False)))
    for name, node in (("crank", nodes[0]), ("rocker", nodes[-1])):
        mbs.AddObject(ei.RevoluteJoint2D(markerNumbers=[
            mbs.AddMarker(ei.MarkerBodyPosition(bodyNumber=bodies[name][1],
                                                localPosition=[0.5 * p[name], 0.0, 0.0])),
            mbs.AddMarker(ei.MarkerNodePosition(nodeNumber=node))], **hidden))
    angle, rate = _spin_up(p["omega"], p["t_ramp"])
    laws = {name: CreateSymbolicUserFunction(mbs, f, name,
                                             itemTypeName="ObjectConnectorCoordinate")
            for name, f in (("offsetUserFunction", lambda mbs, t, item, offset: angle(t)),
                            ("offsetUserFunction_t", lambda mbs, t, item, offset: rate(t)))}
    mbs.sys["peer_laws"] = list(laws.values())  # the expression trees live with the system
    _hold(mbs, mbs.AddMarker(ei.MarkerNodeCoordinate(nodeNumber=ground_node, coordinate=0)),
          bodies["crank"][0], 2, **laws)
    return container, mbs, {name: node for name, (node, _) in bodies.items()}


def exudyn_four_bar(elements: int = 8, t_end: float = 1.5, step: float = 5e-4,
                    newton: str = "modified", integrator: str = "generalized_alpha",
                    rho_inf: float = 0.9, every: float | None = None) -> PeerRun:
    """The four-bar of scenes/four_bar.toml in Exudyn (``_four_bar``), from rest;
    ``tip_displacement`` is the final y of the rocker's tip (m), and with ``every`` (s)
    ``history`` the rocker's angle (rad) as a time series."""
    import exudyn as exu

    _check(newton, integrator)
    with _quiet():
        start = time.perf_counter()
        container, mbs, nodes = _four_bar(elements)
        sensor = _record(mbs, [nodes["rocker"]])[0]
        mbs.Assemble()
        build_s = time.perf_counter() - start
        simulate_s, solver = _solve(mbs, FOUR_BAR["coupler"], t_end, step, newton,
                                    integrator, rho_inf, every)
        history = None
        if every is not None:
            t, coordinates = _positions(mbs, nodes["rocker"], sensor)
            history = (t, coordinates[:, 2])
        angle = (mbs.GetNodeOutput(nodes["rocker"], exu.OutputVariableType.Coordinates)[2]
                 + mbs.GetNodeParameter(nodes["rocker"], "referenceCoordinates")[2])
    return PeerRun(simulate_s, build_s, solver.it.currentStepIndex - 1,
                   solver.it.newtonStepsCount, solver.it.newtonJacobiCount,
                   FOUR_BAR["rocker"] * math.sin(angle),
                   _note(f"RigidBody2D crank and rocker, {PEER_ELEMENT} x {elements} coupler",
                         newton, integrator, rho_inf, step), history)
