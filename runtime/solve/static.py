"""Static equilibrium of a model: Newton with load stepping, joints through multipliers."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from runtime.model.dae import StateLoads
from runtime.model.model import Model
from runtime.solve.linear import SaddleSolver, single_threaded_blas, solve_symmetric_banded


class ConvergenceError(RuntimeError):
    """Newton did not converge (the message says where and why)."""


class FreeMechanismError(ValueError):
    """A static analysis of a model that some body can move in freely (no equilibrium to
    find): the message names the bodies and their free motions."""


def check_held(model: Model) -> None:
    """FreeMechanismError naming every body free to move (``Model.free_motions``)."""
    motions = model.free_motions()
    if motions:
        raise FreeMechanismError(
            f"analysis.static: {'; '.join(motions)}: a static analysis needs every body held "
            f"(add a clamp, a pin or a joint to a held body), or remove [analysis.static]")


@dataclass
class StaticResult:
    """Equilibrium coordinates (size,), joint multipliers, iterations and load steps used."""

    q: np.ndarray
    multipliers: np.ndarray
    iterations: int
    load_steps: int


def newton_static(model: Model, q: np.ndarray, load: np.ndarray, settings,
                  multipliers: np.ndarray, state_load=None) -> tuple[np.ndarray, np.ndarray, int]:
    """Solve F_int(q) + load + f(q) - A^T mu = 0, A q = 0 for the free coordinates from
    ``q``; ``state_load(q)`` gives the follower loads f (size,) and their Jacobian data
    (``StateLoads.evaluate``; None: none), which make the matrix non-symmetric."""
    free, joints = model.free, model.joints_free
    scale = model.length_scale()
    q = q.copy()
    for iteration in range(1, settings.max_iterations + 1):
        force, data = model.internal_forces(q)
        if state_load is not None:
            follower, follower_data = state_load(q)
            force, data = force + follower, data + follower_data
        residual = (force + load)[free] - joints.T @ multipliers
        if not np.all(np.isfinite(residual)):
            raise ConvergenceError("static: non-finite residual")
        # J dq - A^T dmu = -R and A dq = -A q, written with the positive definite -J
        step, dual = _solve(model, -1.0, data, residual, -(model.joints @ q),
                            state_load is None)
        q[free] += step
        multipliers = multipliers + dual
        if np.abs(step).max() <= settings.tolerance * scale:
            return q, multipliers, iteration
    raise ConvergenceError(f"static: Newton did not converge in {settings.max_iterations} "
                           f"iterations (last step {np.abs(step).max():.3g} m)")


def solve_static(model: Model, settings, newton=None) -> StaticResult:
    """Equilibrium under every load at its nominal value (see ``_solve_static``); ``newton``
    solves one load increment (default ``newton_static``, in Python; the compiled engine's
    ``CompiledStatic`` is the other)."""
    if newton is not None:     # generated code: no BLAS threads to hold back
        return _solve_static(model, settings, newton)

    state_loads = StateLoads(model)
    factors = np.ones(len(model.scene.loads))

    def python_newton(q, fraction, multipliers):
        follower = (lambda q: state_loads.evaluate(q, fraction * factors, True)) \
            if state_loads else None
        return newton_static(model, q, fraction * model.nominal_load(), settings, multipliers,
                             follower)

    with single_threaded_blas():
        return _solve_static(model, settings, python_newton)


def _solve_static(model: Model, settings, newton) -> StaticResult:
    """Equilibrium under every load at its nominal value (time laws are not applied).

    The load is applied in ``settings.load_steps`` increments; an increment that fails is
    halved (down to 1/1024 of the load) before the analysis gives up, and one that succeeds
    lets the next grow again (doubling, up to the initial increment).
    """
    check_held(model)
    q = model.reference.copy()
    multipliers = np.zeros(model.joints.shape[0])
    done, increment, iterations, steps = 0.0, 1.0 / settings.load_steps, 0, 0
    while done < 1.0 - 1e-12:
        target = min(1.0, done + increment)
        try:
            q_new, mu_new, used = newton(q, target, multipliers)
        except ConvergenceError as error:
            increment /= 2
            if increment < 1.0 / 1024:
                raise ConvergenceError(f"{error}; load stepping reached 1/1024 of the load at "
                                       f"{done:.4g} of it") from None
            continue
        q, multipliers, done = q_new, mu_new, target
        iterations += used
        steps += 1
        increment = min(2 * increment, 1.0 / settings.load_steps)
    return StaticResult(q, multipliers, iterations, steps)


def _solve(model: Model, jacobian_coef: float, data: np.ndarray, rhs: np.ndarray,
           rhs_constraints: np.ndarray, symmetric: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Solve [[c J, A^T], [A, 0]] [x; y] = [rhs; rhs_constraints] over the free coordinates
    (J from ``Model.internal_forces`` data).  Without joints the matrix is banded and
    symmetric: banded Cholesky, O(n b^2), linear in the number of elements; a non-symmetric
    J (follower loads) goes through the general LU of ``SaddleSolver``."""
    if model.joints.shape[0] or not symmetric:
        matrix = jacobian_coef * model.jacobian_matrix(data)
        return SaddleSolver(matrix, model.joints_free).solve(rhs, rhs_constraints)
    return solve_symmetric_banded(jacobian_coef * model.banded(data), rhs), np.zeros(0)
