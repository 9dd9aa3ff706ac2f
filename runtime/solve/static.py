"""Static equilibrium of a model: Newton with load stepping, joints through multipliers.

Convergence is tested on the correction and on the residual (``Convergence``): the largest
correction within ``tolerance`` times the model's length scale, and the largest residual
within ``tolerance`` times the force scale of the iterate (the largest of the applied load,
the internal forces and the reactions) plus the rounding floor of the residual,
eps |K| L: near equilibrium the residual of a model of stiffness |K| (N/m) and size L (m)
cannot fall below rounding, so a stiff model still converges in the usual number of
iterations.  A model whose rounding noise eps |K| L is over ``NOISE_LIMIT`` times its forces
(a shear correction of 1e30, say: the residual is noise, not a digit of it resolved; a tiny
load on a stiff model, whose noise is in its stiff axial modes, is not) has no equilibrium
to find
in double precision: that is an ``IllConditionedError``, a divergence that load stepping
does not retry.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np
import scipy.sparse

from runtime.model.dae import StateLoads
from runtime.model.model import Model
from runtime.solve.linear import SaddleSolver, for_model, single_threaded_blas

#: rounding noise over this many times the forces: nothing of the equilibrium is resolved
NOISE_LIMIT = 1e3
#: safety factor on the rounding floor eps |K| L of the residual (measured floors are
#: 0.3 - 1 of eps |K| L on the shipped scenes)
FLOOR_FACTOR = 10.0


class ConvergenceError(RuntimeError):
    """Newton did not converge (the message says where and why)."""


class IllConditionedError(ConvergenceError):
    """The residual's rounding noise is far above the forces: no equilibrium can be resolved in
    double precision (a smaller load increment does not help)."""


class SnapThroughError(ConvergenceError):
    """A load increment jumped past a limit point to another branch of equilibria."""


class FreeMechanismError(ValueError):
    """A static analysis of a model that some body can move in freely (no equilibrium to
    find): the message names the bodies and their free motions."""


def check_held(model: Model) -> None:
    """FreeMechanismError naming every body free to move (``Model.free_motions``)."""
    motions = model.free_motions() + [
        f"rigid body {name!r} is free to move (no joint or spring holds it)"
        for name in model.rigid if name not in _held_rigid(model)]
    if motions:
        raise FreeMechanismError(
            f"analysis.static: {'; '.join(motions)}: a static analysis needs every body held "
            f"(add a clamp, a pin or a joint to a held body), or remove [analysis.static]")


def _held_rigid(model: Model) -> set[str]:
    """Names of the rigid items that some joint or force element reaches (a point mass on
    a node moves with its node)."""
    held = {name for name, rigid in model.rigid.items() if not rigid.dofs.size}
    for constraint in model.scene.constraints:      # the body joints
        held.update((getattr(constraint, "body", None), getattr(constraint, "other", None)))
    for load in model.scene.loads:                  # the ends of spring-dampers
        for end in (getattr(load, "end_a", None), getattr(load, "end_b", None)):
            held.add(getattr(end, "body", None))
    return held


@dataclass(frozen=True)
class Convergence:
    """The convergence test of a static Newton solve of ``model`` with relative
    ``tolerance``: corrections within ``correction`` (m), residuals within
    ``tolerance * force_scale + floor`` (N), where ``floor = FLOOR_FACTOR eps |K| L`` is the
    rounding floor of the residual (``stiffness`` |K| (N/m) the largest diagonal entry of the
    tangent stiffness at the reference, ``length`` L (m) the model's length scale)."""

    tolerance: float
    correction: float
    stiffness: float
    length: float

    @classmethod
    def of(cls, model: Model, tolerance: float) -> Convergence:
        """The test for ``model``: its stiffness measured once, at the reference."""
        _, data = model.internal_forces(model.reference)
        band = model.banded(data)
        stiffness = float(np.abs(band[-1]).max(initial=0.0))
        length = model.length_scale()
        return cls(tolerance, tolerance * length, stiffness, length)

    @property
    def noise(self) -> float:
        """The rounding noise of the residual, eps |K| L (N)."""
        return np.finfo(float).eps * self.stiffness * self.length

    @property
    def floor(self) -> float:
        """The rounding floor of the residual (N): ``FLOOR_FACTOR`` times its noise."""
        return FLOOR_FACTOR * self.noise

    def residual_tolerance(self, force_scale: float) -> float:
        """The largest residual (N) accepted at an iterate of force scale ``force_scale``."""
        return self.tolerance * force_scale + self.floor

    def converged(self, correction: float, residual: float, force_scale: float) -> bool:
        """Whether a correction (m) and the residual (N) it corrected are small enough."""
        return (correction <= self.correction
                and residual <= self.residual_tolerance(force_scale))

    def check_resolved(self, force_scale: float) -> None:
        """IllConditionedError when the rounding noise is over ``NOISE_LIMIT`` times the
        forces (N) at a converged iterate."""
        if self.noise > NOISE_LIMIT * force_scale:
            raise IllConditionedError(
                f"static: no equilibrium can be resolved in double precision: the rounding "
                f"noise of the residual, eps x stiffness {self.stiffness:.3g} N/m x size "
                f"{self.length:.3g} m = {self.noise:.3g} N, is over {NOISE_LIMIT:g} times the "
                f"forces "
                f"({force_scale:.3g} N); check the materials' E and shear_correction and "
                f"the sections")

    def not_converged(self, iterations: int, correction: float, residual: float,
                      force_scale: float) -> ConvergenceError:
        """The error of a solve that did not converge in ``iterations``, worded identically
        by both engines."""
        return ConvergenceError(
            f"static: Newton did not converge in {iterations} iterations (last step "
            f"{correction:.3g} m, residual {residual:.3g} N against a tolerance of "
            f"{self.residual_tolerance(force_scale):.3g} N)")


def force_scale(force: np.ndarray, load: np.ndarray) -> float:
    """The force scale (N) of an iterate: the largest internal force (size,), reactions at
    held coordinates included, or applied load (free,)."""
    return max(float(np.abs(force).max(initial=0.0)), float(np.abs(load).max(initial=0.0)))


@dataclass
class StaticResult:
    """Equilibrium coordinates (size,), joint multipliers, iterations and load steps used,
    and the torsional springs' joint angles (loads,; rad, turns counted from one load level
    to the next: ``StateLoads.spring_angles``; None: each within half a turn of 0)."""

    q: np.ndarray
    multipliers: np.ndarray
    iterations: int
    load_steps: int
    spring_angles: np.ndarray | None = None


def newton_static(model: Model, q: np.ndarray, load: np.ndarray, settings,
                  multipliers: np.ndarray, convergence: Convergence | None = None,
                  state_load=None) -> tuple[np.ndarray, np.ndarray, int]:
    """Solve F_int(q) + load + f(q) - A^T mu = 0, A q = 0 for the free coordinates from
    ``q`` (load (size,) N); ``convergence`` the test (default: ``Convergence.of`` the
    model); ``state_load(q)`` gives the follower loads f (size,) and their Jacobian data
    (``StateLoads.evaluate``; None: none), which make the matrix non-symmetric.
    Raises ConvergenceError, IllConditionedError."""
    free, joints = model.free, model.joints_free
    test = convergence or Convergence.of(model, settings.tolerance)
    applied = load[free]
    q = q.copy()
    holonomic, nj = model.holonomic, joints.shape[0]
    for iteration in range(1, settings.max_iterations + 1):
        force, data = model.internal_forces(q)
        if state_load is not None:
            follower, follower_data = state_load(q)
            force, data = force + follower, data + follower_data
        rows, violation = model.constraint_rows(q), model.constraint_values(q)
        if holonomic:     # the quadratic rows' geometric stiffness in J
            data = data - model.holonomic_stiffness(multipliers[nj:], q)
        residual = force[free] + applied - rows.T @ multipliers
        if not np.all(np.isfinite(residual)):
            raise ConvergenceError("static: non-finite residual")
        # J dq - A^T dmu = -R and A dq = -A q, written with the positive definite -J
        step, dual = _solve(model, -1.0, data, residual, -violation, state_load is None, rows)
        q[free] += step
        multipliers = multipliers + dual
        size, scale = float(np.abs(step).max(initial=0.0)), force_scale(force, applied)
        remaining = float(np.abs(residual).max(initial=0.0))
        if test.converged(size, remaining, scale):
            test.check_resolved(scale)
            return q, multipliers, iteration
    raise test.not_converged(settings.max_iterations, size, remaining, scale)


def load_factors(model: Model, factor: float) -> np.ndarray:
    """The factor (loads,) of every scene load in a static analysis at load factor
    ``factor``: ``factor`` for the loads, 1 for the force elements (``Load.load_factor``)."""
    return np.array([factor if load.load_factor else 1.0 for load in model.scene.loads])


def solve_static(model: Model, settings, newton=None) -> StaticResult:
    """Equilibrium under every load at its nominal value (see ``_solve_static``); ``newton``
    solves one load increment (default ``newton_static``, in Python; the compiled engine's
    ``CompiledStatic`` is the other, which also counts the turns: ``TurnCount``)."""
    if newton is not None:     # generated code: no BLAS threads to hold back
        return _solve_static(model, settings, newton, newton)

    convergence = Convergence.of(model, settings.tolerance)
    state_loads = StateLoads(model)

    def python_newton(q, fraction, multipliers):
        factors = load_factors(model, fraction)
        follower = (lambda q: state_loads.evaluate(q, factors, True)[:2]) \
            if state_loads else None
        return newton_static(model, q, fraction * model.nominal_load(), settings, multipliers,
                             convergence, follower)

    with single_threaded_blas():
        return _solve_static(model, settings, python_newton, state_loads)


class TurnCount(Protocol):
    """What counts the torsional springs' turns of a static solve: ``StateLoads`` (the
    Python solves) or ``CompiledStatic``."""

    def accept(self, q_full: np.ndarray) -> None:
        """Count the turns up to the converged state q_full (size,)."""

    def spring_angles(self, q_full: np.ndarray) -> np.ndarray:
        """The joint angles (k, loads) at the states q_full (k, size), turns counted."""


def _solve_static(model: Model, settings, newton, turns: TurnCount) -> StaticResult:
    """Equilibrium under every load at its nominal value (time laws are not applied).

    The load is applied in ``settings.load_steps`` increments; an increment that fails is
    halved (down to 1/1024 of the load) before the analysis gives up, and one that succeeds
    lets the next grow again (doubling, up to the initial increment).  An
    IllConditionedError is not retried.  An increment that jumps past a limit point to
    another branch (``_snapped``) fails like one that does not converge.  The torsional
    springs count turns (``turns``: those ``newton`` evaluates) from one converged
    increment to the next.
    """
    check_held(model)
    q = model.reference.copy()
    multipliers = np.zeros(model.joints.shape[0] + model.holonomic.rows)
    done, increment, iterations, steps = 0.0, 1.0 / settings.load_steps, 0, 0
    energy, snapped = _PathEnergy(model), False
    while done < 1.0 - 1e-12:
        target = min(1.0, done + increment)
        try:
            q_new, mu_new, used = newton(q, target, _rigid_multipliers(
                model, q, target * model.nominal_load(), multipliers))
            energy.check(q, done, q_new, target)
        except IllConditionedError:
            raise
        except ConvergenceError as error:
            increment /= 2
            snapped = snapped or isinstance(error, SnapThroughError)
            if increment < 1.0 / 1024:
                limit = (" (a limit point: larger increments jumped past it; "
                         'method = "arc_length" traces the path beyond)' if snapped else "")
                raise ConvergenceError(f"{error}; load stepping reached 1/1024 of the load at "
                                       f"{done:.4g} of it{limit}") from None
            continue
        q, multipliers, done = q_new, mu_new, target
        turns.accept(q)
        iterations += used
        steps += 1
        increment = min(2 * increment, 1.0 / settings.load_steps)
    return StaticResult(q, multipliers, iterations, steps,
                        turns.spring_angles(q[None, :])[0])


def _rigid_multipliers(model: Model, q: np.ndarray, load: np.ndarray,
                       multipliers: np.ndarray) -> np.ndarray:
    """The multipliers corrected so that the constraint forces balance ``load`` (size,) on
    the coordinates of the rigid items at q (least squares, the smallest correction): a
    rigid body has no elastic stiffness, only the geometric stiffness of its constraints
    (Phi_q^T lambda)_q, so Newton needs multipliers of the right size from its first
    iteration (from zero, a body hanging from a revolute joint has a singular matrix)."""
    if not model.holonomic or not model.rigid:
        return multipliers
    rigid = model.free_position[np.concatenate([r.dofs for r in model.rigid.values()])]
    rigid = rigid[rigid >= 0]
    rows = model.constraint_rows(q).tocsc()[:, rigid].toarray()
    mismatch = load[model.free][rigid] - rows.T @ multipliers
    return multipliers + np.linalg.lstsq(rows.T, mismatch, rcond=None)[0]


class _PathEnergy:
    """The check that a load increment stayed on its branch of equilibria.

    With the total potential Pi(q, lambda) = U(q) - lambda P.(q - q0) (P the nominal loads,
    all conservative), equilibria along a path satisfy dPi/dlambda = -P.(q - q0), and on a
    stable branch P.(q - q0) grows with lambda (its rate P K^-1 P > 0).  So an increment from
    a to b along stable equilibria has Pi_b - Pi_a >= -(lambda_b - lambda_a) P.(q_b - q0),
    exactly; an equilibrium below that bound was reached by jumping past a limit point
    (the structure would snap through).  Follower loads are not conservative (no potential):
    with them the check is not made."""

    #: slack of the bound, relative to the energies compared (rounding, residuals)
    SLACK = 1e-6

    def __init__(self, model: Model) -> None:
        self.model, self.pattern = model, model.nominal_load()
        self.conservative = not StateLoads(model)

    def check(self, q_a: np.ndarray, lam_a: float, q_b: np.ndarray, lam_b: float) -> None:
        """ConvergenceError when the increment from (q_a, lam_a) to (q_b, lam_b) left its
        branch."""
        if not self.conservative:
            return
        model = self.model
        x_a, x_b = (float(self.pattern @ (q - model.reference)) for q in (q_a, q_b))
        u_a, u_b = (float(model.strain_energy(q)) for q in (q_a, q_b))
        drop = (u_b - lam_b * x_b) - (u_a - lam_a * x_a)
        bound = -(lam_b - lam_a) * x_b
        slack = self.SLACK * (abs(u_a) + abs(u_b) + abs(lam_a * x_a) + abs(lam_b * x_b))
        if drop < bound - slack:
            raise SnapThroughError(
                f"static: the load increment from {lam_a:.4g} to {lam_b:.4g} of the load "
                f"jumped past a limit point to another branch of equilibria (the total "
                f"potential fell {bound - drop:.3g} J below what a path of stable equilibria "
                f"allows: the structure snaps through); trace it with method = "
                f'"arc_length"')


def _solve(model: Model, jacobian_coef: float, data: np.ndarray, rhs: np.ndarray,
           rhs_constraints: np.ndarray, symmetric: bool = True,
           rows: scipy.sparse.spmatrix | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Solve [[c J, A^T], [A, 0]] [x; y] = [rhs; rhs_constraints] over the free coordinates
    (J from ``Model.internal_forces`` data).  Without joints and symmetric by the model's
    linear solver (``runtime.solve.linear.for_model``: banded for chains, sparse for meshes);
    with joints (where J alone may be singular) or a non-symmetric J (follower loads) by the
    sparse or small dense LU of the saddle point; ``rows``: the constraint rows (default the
    joints A_f; with quadratic rows, [A_f; Phi_q])."""
    rows = model.joints_free if rows is None else rows
    if rows.shape[0] or not symmetric:
        matrix = jacobian_coef * model.jacobian_matrix(data)
        return SaddleSolver(matrix, rows).solve(rhs, rhs_constraints)
    return for_model(model).factor(jacobian_coef * data).solve(rhs), np.zeros(0)
