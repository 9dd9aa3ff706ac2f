"""Static equilibrium paths through limit points: Crisfield's cylindrical arc length.

The load factor lambda is an unknown beside the free coordinates: equilibrium
F_int(q) + lambda P(q) - A^T mu = 0, A q = 0 (P the loads at their nominal values, follower
loads at their current direction: ``runtime.model.dae.StateLoads``), and each
step of the path moves a fixed length ``dl`` (m) over the free coordinates from the last
converged point, |Delta q| = dl.  Every Newton iteration makes the two solves of the load
stepping's Newton through ``runtime.solve.static._solve`` (the residual's correction dq_R
and the tangent displacement per unit load dq_P) and takes the correction
dq = dq_R + d_lambda dq_P whose d_lambda is the root of the quadratic constraint that keeps
the step closest to its previous direction (Crisfield 1981).  The predictor's sign follows
the previous step (its dot product with dq_P), so the path turns at limit points and snaps
back.  The step length adapts to the iterations used (towards ``DESIRED_ITERATIONS``, by
at most a factor of 2 per step); a step that fails (no real root, Newton not converged) is
halved, down to 1/1024 of the first one.  Convergence as in ``runtime.solve.static``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from runtime.model.dae import StateLoads
from runtime.model.model import Model
from runtime.solve.linear import single_threaded_blas
from runtime.solve.static import (
    Convergence,
    ConvergenceError,
    IllConditionedError,
    _solve,
    check_held,
    force_scale,
    load_factors,
)

#: iterations a step aims at: the step length grows when fewer were needed, shrinks when more
DESIRED_ITERATIONS = 4
#: the step length stays within these multiples of the first one
SMALLEST_STEP, LARGEST_STEP = 1.0 / 1024, 8.0


@dataclass
class PathResult:
    """The equilibrium path: ``load_factors`` (k,) and coordinates ``states`` (k, size) of
    its converged points, the start (lambda = 0, the reference) first; the last point's
    multipliers, Newton iterations and steps over the whole path, why it stopped, and the
    torsional springs' joint angles at the points (k, loads; rad, turns counted from point
    to point: ``StateLoads.spring_angles``)."""

    load_factors: np.ndarray
    states: np.ndarray
    multipliers: np.ndarray
    iterations: int
    steps: int
    stopped: str
    spring_angles: np.ndarray

    @property
    def q(self) -> np.ndarray:
        """Coordinates (size,) of the last point."""
        return self.states[-1]

    @property
    def load_factor(self) -> float:
        """Load factor of the last point."""
        return float(self.load_factors[-1])


class _Failed(Exception):
    """A step that did not converge (the message says why); the step is retried shorter."""


def trace_path(model: Model, settings, stop: Callable[[np.ndarray, float], str | None]
               ) -> PathResult:
    """The path of equilibria of ``model`` from its reference under lambda times every load
    (``settings``: ``runtime.model.settings.Static`` with ``method = "arc_length"``).
    ``stop(q_full, lambda)`` returns why the path ends at a converged point, or None to go
    on; the path also ends at ``settings.max_steps`` points.  Raises ConvergenceError when a
    step fails at 1/1024 of the first step length (IllConditionedError at once)."""
    check_held(model)
    with single_threaded_blas():
        return _PathTracer(model, settings).trace(stop)


class _PathTracer:
    """The state of a path being traced: the last converged point and the step length."""

    def __init__(self, model: Model, settings) -> None:
        self.model, self.settings = model, settings
        self.convergence = Convergence.of(model, settings.tolerance)
        self.nominal = model.nominal_load()[model.free]
        self.state_loads = StateLoads(model)
        #: the state loads' factors: the loads that lambda scales (follower loads), and the
        #: force elements, which it does not (``Load.load_factor``)
        self.scaled = load_factors(model, 1.0) - load_factors(model, 0.0)
        self.structural = load_factors(model, 0.0)
        self.follows = any(self.scaled[index] for index, _, _ in self.state_loads.loads)
        if not np.any(self.nominal) and not self.follows:
            raise ConvergenceError("static: arc length needs a load (every load is zero): "
                                   "the path of lambda times no load is the reference")
        self.rows = model.joints.shape[0] + model.holonomic.rows
        self.no_constraint = np.zeros(self.rows)

    def _linearise(self, q: np.ndarray, lam: float, mu: np.ndarray):
        """(internal + state forces (size,), their Jacobian data (with the quadratic rows'
        geometric stiffness at the multipliers ``mu``), the load pattern P(q) (free,): the
        loads at unit factor, followers included) at (q, lambda)."""
        model = self.model
        force, data = model.internal_forces(q)
        pattern = self.nominal
        if self.state_loads:
            structural, structural_data = self.state_loads.evaluate(q, self.structural,
                                                                    True)[:2]
            follower, follower_data = self.state_loads.evaluate(q, self.scaled, True)[:2]
            force = force + structural + lam * follower
            data = data + structural_data + lam * follower_data
            pattern = self.nominal + follower[model.free]
        if model.holonomic:
            data = data - model.holonomic_stiffness(mu[model.joints.shape[0]:], q)
        return force, data, pattern

    def _tangent(self, data: np.ndarray, pattern: np.ndarray, rows) -> tuple[np.ndarray,
                                                                            np.ndarray]:
        """(dq_P, dmu_P): the free coordinates' and multipliers' rates per unit load factor
        at an iterate of Jacobian ``data``, load pattern ``pattern`` and constraint
        ``rows``."""
        return self._solve(data, pattern, self.no_constraint, rows)

    def _solve(self, data: np.ndarray, rhs: np.ndarray, rhs_constraints: np.ndarray, rows):
        """The load stepping's linear solve (non-symmetric with state loads)."""
        return _solve(self.model, -1.0, data, rhs, rhs_constraints, not self.state_loads,
                      rows)

    def trace(self, stop) -> PathResult:
        model, settings = self.model, self.settings
        q = model.reference.copy()
        mu = np.zeros(self.rows)
        lam = 0.0
        _, data, pattern = self._linearise(q, lam, mu)
        rows = self.model.constraint_rows(q)
        first = settings.arc_length or (float(np.linalg.norm(
            self._tangent(data, pattern, rows)[0])) / settings.load_steps)
        length, previous = first, None
        factors, states = [0.0], [q.copy()]
        angles = [self.state_loads.spring_angles(q[None, :])[0]]
        iterations, stopped = 0, f"max_steps = {settings.max_steps} points"
        while len(states) <= settings.max_steps:
            try:
                q_new, mu_new, lam_new, step, used = self._step(q, mu, lam, length, previous)
            except IllConditionedError:
                raise
            except (_Failed, ConvergenceError) as error:
                length /= 2
                if length < SMALLEST_STEP * first:
                    raise ConvergenceError(
                        f"{error}; arc length reached 1/1024 of its first step "
                        f"({first:.3g} m) at load factor {lam:.6g} after "
                        f"{len(states) - 1} steps") from None
                continue
            q, mu, lam, previous = q_new, mu_new, lam_new, step
            self.state_loads.accept(q)
            iterations += used
            factors.append(lam)
            states.append(q.copy())
            angles.append(self.state_loads.spring_angles(q[None, :])[0])
            reason = stop(q, lam)
            if reason is not None:
                stopped = reason
                break
            growth = np.clip(np.sqrt(DESIRED_ITERATIONS / max(used, 1)), 0.5, 2.0)
            length = min(length * growth, LARGEST_STEP * first)
        return PathResult(np.array(factors), np.array(states), mu, iterations,
                          len(states) - 1, stopped, np.array(angles))

    def _step(self, q: np.ndarray, mu: np.ndarray, lam: float, length: float,
              previous: np.ndarray | None):
        """One step of length ``length`` from the converged point (q, mu, lam): (q, mu,
        lam, Delta q over the free coordinates, iterations).  Raises _Failed,
        ConvergenceError."""
        model, test = self.model, self.convergence
        free = model.free
        _, data, pattern = self._linearise(q, lam, mu)
        rows = self.model.constraint_rows(q)
        rate, rate_mu = self._tangent(data, pattern, rows)
        direction = 1.0 if previous is None or previous @ rate >= 0.0 else -1.0
        d_lam = direction * length / np.linalg.norm(rate)
        increment = d_lam * rate
        q, mu, lam = q.copy(), mu + d_lam * rate_mu, lam + d_lam
        q[free] += increment
        for iteration in range(1, self.settings.max_iterations + 1):
            force, data, pattern = self._linearise(q, lam, mu)
            rows, violation = model.constraint_rows(q), model.constraint_values(q)
            applied = lam * self.nominal
            residual = force[free] + applied - rows.T @ mu
            if not np.all(np.isfinite(residual)):
                raise ConvergenceError("static: non-finite residual")
            correction, correction_mu = self._solve(data, residual, -violation, rows)
            rate, rate_mu = self._tangent(data, pattern, rows)
            d_lam = self._root(increment, correction, rate, length)
            step = correction + d_lam * rate
            increment = increment + step
            q[free] += step
            mu = mu + correction_mu + d_lam * rate_mu
            lam += d_lam
            size = float(np.abs(step).max(initial=0.0))
            remaining = float(np.abs(residual).max(initial=0.0))
            scale = force_scale(force, applied)
            if test.converged(size, remaining, scale):
                test.check_resolved(scale)
                return q, mu, lam, increment, iteration
        raise test.not_converged(self.settings.max_iterations, size, remaining, scale)

    @staticmethod
    def _root(increment: np.ndarray, correction: np.ndarray, rate: np.ndarray,
              length: float) -> float:
        """d_lambda with |increment + correction + d_lambda rate| = length, the root whose
        new increment is closest in direction to ``increment`` (Crisfield)."""
        base = increment + correction
        a, b, c = rate @ rate, 2.0 * (rate @ base), base @ base - length**2
        discriminant = b * b - 4.0 * a * c
        if discriminant < 0.0:
            raise _Failed(f"static: arc length step of {length:.3g} m has no real root "
                          f"(the constraint misses the path)")
        root = np.sqrt(discriminant)
        roots = ((-b + root) / (2 * a), (-b - root) / (2 * a))
        return max(roots, key=lambda r: (base + r * rate) @ increment)
