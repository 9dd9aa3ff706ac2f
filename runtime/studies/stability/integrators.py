"""Integrator rows: free vibration of the slender beam2d (``plan.SLENDER``) from its static
deflection with each integrator and step, energy drift and Newton iterations measured, and
the rows that sum up each integrator's stable step range and the diagnostic runs.
"""

from __future__ import annotations

import functools
import math
import time

import numpy as np

from runtime.model.settings import Static
from runtime.studies.stability.plan import COMMON_STEP, SLENDER, T_END, row_record, slender_scene

DRIFT_TOLERANCE = 1e-2


def _label(integrator: str, rho_inf: float) -> str:
    return integrator if integrator == "trapezoidal" else f"{integrator}(rho_inf={rho_inf:g})"


def _tip_load() -> float:
    p = SLENDER
    inertia = p["width"] * p["height"] ** 3 / 12
    return 0.3 * p["E"] * inertia / p["length"] ** 3



@functools.cache
def _slender_start() -> tuple:
    """(unloaded model, static deflected coordinates) of the slender beam."""
    from runtime.model.model import Model
    from runtime.solve import static as analysis

    loaded = Model(slender_scene(_tip_load()))
    static = analysis.solve_static(loaded, Static())
    return Model(slender_scene()), static.q


def slender_frequencies() -> dict:
    """Lowest and highest angular frequencies (rad/s) of the slender beam about the
    reference, the analytic first axial frequency pi/2 sqrt(E/rho)/L, and the initial (static)
    tip deflection (m)."""
    from runtime.solve.modal import modal

    model, q_static = _slender_start()
    omega = modal(model, model.reference, model.free.size)
    p = SLENDER
    axial = math.pi / 2 * math.sqrt(p["E"] / p["rho"]) / p["length"]
    tip = float(q_static[model.node_dofs(p["elements"], "r")][1])
    return {"bending_1": float(omega[0]), "highest": float(omega[-1]), "axial_1": axial,
            "tip_deflection": -tip}


def integrator_case(integrator: str, step: float, rho_inf: float = 0.8, t_end: float = T_END,
                    max_iterations: int = 20) -> dict:
    """Free vibration of the slender beam from its static deflection for ``t_end`` s with a
    fixed ``step`` (s).  Returns energy drift (max |E(t) - E0| / E0 and the final one),
    Newton iterations (mean and max per step), the largest first Newton correction of a step
    (m), the status (ok | diverged), its message, the time reached and the wall time (s)."""
    from runtime.model.settings import Dynamic
    from runtime.solve.python_engine import INTEGRATORS, Divergence

    model, q_static = _slender_start()
    # full Newton (the paper's): the rows measure the integrators' convergence, not that of
    # a kept Jacobian
    settings = Dynamic(t_end=t_end, step=step, integrator=integrator, rho_inf=rho_inf,
                       max_iterations=max_iterations, newton="full")
    runner = INTEGRATORS[integrator](model, settings, q_static)
    energy0 = model.strain_energy(q_static)
    record = {"first": 0.0, "where": "", "new_step": True, "max_iterations": 0, "last": 0,
              "t": 0.0, "drift": 0.0, "final": 0.0, "t_drift": 0.0}
    check = runner.iterations_left
    coordinate = model.coordinate_names()

    def iterations_left(increment: np.ndarray, *state) -> float:
        if record["new_step"] and increment.size:
            index = int(np.argmax(np.abs(increment)))
            correction = runner.correction_factors[0] * abs(increment[index])   # m
            if correction > record["first"]:
                record["first"] = float(correction)
                record["where"] = coordinate[model.free[index]]
            record["new_step"] = False
        return check(increment, *state)

    runner.iterations_left = iterations_left

    def observe(t: float, q: np.ndarray, v: np.ndarray) -> None:
        total = model.strain_energy(q) + model.kinetic_energy(v)
        record["final"] = (total - energy0) / energy0
        if abs(record["final"]) > record["drift"]:
            record["drift"], record["t_drift"] = abs(record["final"]), t
        used = runner.counters.newton_iterations
        record["max_iterations"] = max(record["max_iterations"], used - record["last"])
        record["last"], record["t"], record["new_step"] = used, t, True

    status, message, t_failed = "ok", "", None
    start = time.perf_counter()
    try:
        runner.run(t_end, step, observe)
    except Divergence as error:
        status, message, t_failed = "diverged", str(error), error.time
        # the failed step's iterations are counted but not observed
        record["max_iterations"] = max(record["max_iterations"],
                                       runner.counters.newton_iterations - record["last"])
    wall = time.perf_counter() - start
    counters = runner.counters
    return {"integrator": integrator, "rho_inf": rho_inf, "label": _label(integrator, rho_inf),
            "step": step, "t_end": t_end, "max_iterations": max_iterations, "status": status,
            "message": message, "t_reached": record["t"], "t_failed": t_failed,
            "steps": counters.steps,
            "newton_iterations": counters.newton_iterations,
            "iterations_per_step": counters.newton_iterations / max(counters.steps, 1),
            "max_iterations_step": record["max_iterations"],
            "first_correction": record["first"], "first_correction_at": record["where"],
            "drift_max": record["drift"],
            "t_drift_max": record["t_drift"], "drift_final": record["final"],
            "energy0": energy0, "wall_s": wall}


def _unit(coordinate: str) -> str:
    """How to read a correction of ``coordinate`` (r.x: a position; r_x.y: a gradient)."""
    if coordinate.startswith("r_"):
        return " (a gradient component, dimensionless; unit vectors in the reference)"
    return " m"


def _damping(result: dict) -> str:
    if result["integrator"] == "trapezoidal":
        return "the trapezoidal rule does not damp them (spectral radius 1)"
    return f"generalized-alpha damps them only to rho_inf = {result['rho_inf']:g} per step"


def integrator_rows(results: list[dict], frequencies: dict | None = None) -> list[dict]:
    """Rows of the integrator group from ``integrator_case`` results: one per run (energy
    drift within 1 %, the run must not diverge), one summary per integrator (largest step
    that ran, smallest that failed) and the diagnostic runs with more Newton iterations."""
    rows = []
    if frequencies:
        ratio = frequencies["axial_1"] / frequencies["bending_1"]
        rows.append(row_record(
            group="integrator", case="slender beam: axial / bending frequency", method="-",
            measured=ratio, tolerance=None, passed=None,
            detail=(f"first bending {frequencies['bending_1']:.4g} rad/s, first axial (pi/2 "
                    f"c/L) {frequencies['axial_1']:.4g} rad/s, highest mode of the 4-element "
                    f"mesh {frequencies['highest']:.3g} rad/s"),
            cause=(f"informational: the stiff problem: L/h = "
                   f"{SLENDER['length'] / SLENDER['height']:g}, {SLENDER['elements']} beam2d "
                   f"elements, released at rest from the static tip deflection "
                   f"{frequencies['tip_deflection']:.4g} m of a tip load, run for {T_END:g} s "
                   f"(about two bending periods); drift = max |E(t) - E0| / E0 of strain + "
                   f"kinetic energy")))
    scan = [r for r in results if r["max_iterations"] == 20]
    for r in scan:
        ran = r["status"] == "ok"
        passed = ran and r["drift_max"] <= DRIFT_TOLERANCE
        reached = (f"ran to t = {r['t_reached']:.4g} s" if ran else "no step completed"
                   if r["steps"] == 0 else f"last step completed at t = {r['t_reached']:.4g} s")
        detail = (f"{reached}; final drift {r['drift_final']:+.2e}; Newton "
                  f"{r['iterations_per_step']:.2f}/step (max {r['max_iterations_step']}); "
                  f"largest first Newton correction {r['first_correction']:.2g} (on "
                  f"{r['first_correction_at']}); {r['wall_s']:.2f} s")
        cause = ""
        if not ran:
            cause = (f"{r['message']}: the predictor (from the previous accelerations) carries the "
                     f"high-frequency components (shear and cross-section modes of the fully "
                     f"parameterised element) and {_damping(r)}; the first Newton correction "
                     f"of a step reached {r['first_correction']:.2g} on "
                     f"{r['first_correction_at']}{_unit(r['first_correction_at'])}")
        elif not passed:
            cause = (f"numerical dissipation of generalized-alpha (rho_inf = {r['rho_inf']:g}), "
                     f"by design: at this step it also takes energy from the modes that carry "
                     f"the motion (final drift {r['drift_final']:+.1e})"
                     if r["integrator"] == "generalized_alpha" and r["drift_final"] < 0
                     else "energy error of the scheme on the nonlinear problem")
        rows.append(row_record(group="integrator", case=f"step {r['step']:g} s", method=r["label"],
                         measured=r["drift_max"], tolerance=DRIFT_TOLERANCE, passed=passed,
                         detail=detail, cause=cause))
    labels = list(dict.fromkeys(r["label"] for r in scan))
    for label in labels:
        runs = sorted((r for r in scan if r["label"] == label), key=lambda r: r["step"])
        ok = [r["step"] for r in runs if r["status"] == "ok"]
        failed = [r for r in runs if r["status"] != "ok"]
        common = next((r for r in runs if r["step"] == COMMON_STEP), None)
        largest = max(ok) if ok else float("nan")
        parts = [f"largest step that ran {largest:g} s"]
        if failed:
            first = failed[0]
            parts.append(f"smallest that failed {first['step']:g} s (at t = "
                         f"{first['t_failed']:.3g} s)")
            if ok and max(ok) > first["step"]:
                parts.append("not monotone: a larger step ran again")
        else:
            parts.append(f"none failed up to {runs[-1]['step']:g} s")
        if common is not None:
            parts.append(f"at h = {COMMON_STEP:g} s: drift {common['drift_max']:.2e}, Newton "
                         f"{common['iterations_per_step']:.2f}/step")
        newton = [r for r in failed if "Newton did not converge" in r["message"]]
        cause = ("informational: every failure of the scan is Newton's iteration limit (20 per "
                 "step); the diagnostic rows below show what more iterations give"
                 if len(newton) == len(failed) else
                 "informational: failures: " + "; ".join(r["message"] for r in failed))
        rows.append(row_record(group="integrator", case="stable step range", method=label,
                         measured=largest, tolerance=None, passed=None, detail="; ".join(parts),
                         cause=cause))
    for r in results:
        if r["max_iterations"] == 20:
            continue
        ran = r["status"] == "ok"
        if not ran:
            cause = f"still fails: {r['message']}"
        elif r["drift_max"] <= 10 * DRIFT_TOLERANCE:
            cause = (f"with more Newton iterations the step runs (energy within "
                     f"{r['drift_max']:.1%}), so the failure at 20 iterations is Newton's slow "
                     f"start from a poor predictor, not an instability of the scheme")
        else:
            cause = (f"Newton now converges, but to a non-physical root of the step equations: "
                     f"the total energy jumps to {1 + r['drift_max']:.2g} times its initial "
                     f"value at t = {r['t_drift_max']:.3g} s and ends at "
                     f"{1 + r['drift_final']:.3g} times it; the iteration limit was hiding a "
                     f"useless solution")
        rows.append(row_record(
            group="integrator", case=f"step {r['step']:g} s, {r['max_iterations']} Newton "
                                     f"iterations allowed", method=r["label"],
            measured=r["drift_max"], tolerance=None, passed=None,
            detail=(f"{'ran' if ran else 'diverged'} to t = {r['t_reached']:.4g} s; Newton "
                    f"{r['iterations_per_step']:.2f}/step (max {r['max_iterations_step']}); "
                    f"max drift {r['drift_max']:.2e} at t = {r['t_drift_max']:.3g} s, final "
                    f"{r['drift_final']:+.2e}"),
            cause="informational (diagnostic): " + cause))
    return rows
