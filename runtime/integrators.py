"""Fixed-step implicit integrators for M q'' + A^T lambda = F(q, t), A q = 0.

* ``trapezoidal``: the paper's scheme - the index-1 form (eq. 8) integrated with the
  second-order Adams-Moulton (trapezoidal) rule, Newton on the new accelerations with the
  exact Jacobian, then projection of positions and velocities onto the constraints;
* ``generalized_alpha``: Chung-Hulbert generalized-alpha in the index-3 form of Arnold and
  Bruls, Newton on the positions, numerical damping set by the spectral radius ``rho_inf``.

Both work on the free coordinates; prescribed ones (hub rotations) enter through their known
values, rates and accelerations.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg
import scipy.sparse.linalg

from runtime.analysis import length_scale
from runtime.linear import DENSE_LIMIT, SaddleSolver, single_threaded_blas
from runtime.model import Model


class Divergence(RuntimeError):
    """A dynamic run that cannot go on: ``time`` (s) and ``cause``."""

    def __init__(self, time: float, cause: str) -> None:
        super().__init__(f"diverged at t = {time:.6g} s: {cause}")
        self.time, self.cause = time, cause


@dataclass
class Counters:
    """Work done by a run."""

    steps: int = 0
    newton_iterations: int = 0
    force_evaluations: int = 0
    jacobian_evaluations: int = 0


@dataclass
class State:
    """Free coordinates, velocities, accelerations and joint multipliers at time ``t``."""

    t: float
    q: np.ndarray
    v: np.ndarray
    a: np.ndarray
    multipliers: np.ndarray
    extra: dict = field(default_factory=dict)


class Integrator:
    """Shared machinery: residual pieces, initial accelerations, the step loop."""

    def __init__(self, model: Model, settings, q_full: np.ndarray) -> None:
        self.model, self.settings = model, settings
        self.counters = Counters()
        self.scale = length_scale(model)
        self.fixed_values = q_full.copy()
        self._mass_solver = _factor(model.mass_ff)

    def full(self, q: np.ndarray, t: float) -> tuple[np.ndarray, np.ndarray]:
        """Global coordinates and prescribed accelerations at time t."""
        qp, _, ap = self.model.prescribed_state(t)
        return self.model.full(q, qp, self.fixed_values), ap

    def full_velocity(self, v: np.ndarray, t: float) -> np.ndarray:
        """Global velocity vector (fixed coordinates at rest)."""
        _, vp, _ = self.model.prescribed_state(t)
        out = np.zeros(self.model.size)
        out[self.model.free] = v
        out[self.model.prescribed] = vp
        return out

    def forces(self, q: np.ndarray, t: float, jacobian: bool = True):
        """Free part of elastic + external force, and the free-free Jacobian (or None)."""
        q_full, _ = self.full(q, t)
        force, data = self.model.internal_forces(q_full, jacobian)
        self.counters.force_evaluations += 1
        total = (force + self.model.external_forces(t))[self.model.free]
        if not np.all(np.isfinite(total)):
            raise Divergence(t, "non-finite forces (the state blew up)")
        if jacobian:
            self.counters.jacobian_evaluations += 1
        return total, data

    def initial_state(self, t: float = 0.0) -> State:
        """Consistent initial state at rest (except prescribed motions)."""
        m = self.model
        q = self.fixed_values[m.free].copy()
        force, _ = self.forces(q, t, jacobian=False)
        _, _, ap = m.prescribed_state(t)
        solver = SaddleSolver(m.mass_ff, m.joints_free)
        a, lam = solver.solve(force - m.mass_fp @ ap, -(m.joints_prescribed @ ap))
        return State(t, q, np.zeros_like(q), a, lam)

    def run(self, t_end: float, step: float, observe, progress=None) -> State:
        """Integrate from rest at t = 0 to ``t_end``; ``observe(t, q_full, v_full)`` is called
        at t = 0 and every ``output_every`` seconds.  Raises Divergence."""
        with single_threaded_blas():
            return self._run(t_end, step, observe, progress)

    def _run(self, t_end: float, step: float, observe, progress) -> State:
        state = self.initial_state()
        every = self.settings.output_every or step
        steps = int(round(t_end / step))
        stride = max(1, int(round(every / step)))
        observe(0.0, self.full(state.q, 0.0)[0], self.full_velocity(state.v, 0.0))
        for n in range(1, steps + 1):
            t = n * step
            state = self.step(state, t, step)
            self.counters.steps += 1
            if n % stride == 0 or n == steps:
                observe(t, self.full(state.q, t)[0], self.full_velocity(state.v, t))
            if progress is not None:
                progress.update(t)
        return state

    def residual(self, a: np.ndarray, force: np.ndarray, prescribed_acceleration: np.ndarray,
                 multipliers: np.ndarray) -> np.ndarray:
        """M_ff a + M_fp a_p + A^T lambda - F: the equations of motion of the free part."""
        m = self.model
        residual = m.mass_ff_op @ a - force
        if prescribed_acceleration.size:
            residual += m.mass_fp_op @ prescribed_acceleration
        if m.joints_free.shape[0]:
            residual += m.joints_free.T @ multipliers
        return residual

    def converged(self, increment: np.ndarray) -> bool:
        return float(np.abs(increment).max(initial=0.0)) <= self.settings.tolerance * self.scale

    def step(self, state: State, t: float, h: float) -> State:  # pragma: no cover - abstract
        raise NotImplementedError


def _factor(matrix):
    """Factorisation of the constant free-free mass matrix (done once)."""
    if matrix.shape[0] <= DENSE_LIMIT:
        factor = scipy.linalg.cho_factor(matrix.toarray())
        return lambda rhs: scipy.linalg.cho_solve(factor, rhs)
    return scipy.sparse.linalg.splu(matrix.tocsc()).solve


class Trapezoidal(Integrator):
    """The paper's integrator (see the module docstring)."""

    def step(self, state: State, t: float, h: float) -> State:
        m = self.model
        joints = m.joints_free
        _, _, ap = m.prescribed_state(t)
        a, lam = state.a.copy(), state.multipliers.copy()
        base_q = state.q + h * state.v + h * h / 4 * state.a
        for _ in range(self.settings.max_iterations):
            q = base_q + h * h / 4 * a
            force, jacobian = self.forces(q, t)
            self.counters.newton_iterations += 1
            residual = self.residual(a, force, ap, lam)
            constraint = joints @ a + m.joints_prescribed @ ap if joints.shape[0] else None
            da, dlam = m.solve(1.0, -h * h / 4, jacobian, -residual,
                               None if constraint is None else -constraint)
            a += da
            lam += dlam
            if self.converged(h * h / 4 * da):
                break
        else:
            raise Divergence(t, f"Newton did not converge in {self.settings.max_iterations} "
                             f"iterations (last correction {np.abs(h * h / 4 * da).max():.3g} m)")
        q = base_q + h * h / 4 * a
        v = state.v + h / 2 * (state.a + a)
        if joints.shape[0]:
            q, v = self.project(q, v, t)
        return State(t, q, v, a, lam)

    def project(self, q: np.ndarray, v: np.ndarray, t: float):
        """Mass-orthogonal projection of positions and velocities onto A q = 0, A v = 0."""
        m = self.model
        qp, vp, _ = m.prescribed_state(t)
        joints = m.joints_free.toarray()
        minv_at = self._mass_solver(joints.T)
        schur = joints @ minv_at
        for _ in range(3):
            violation = joints @ q + m.joints_prescribed @ qp + m.joints[:, m.fixed] @ \
                self.fixed_values[m.fixed]
            q = q - minv_at @ np.linalg.solve(schur, violation)
        v = v - minv_at @ np.linalg.solve(schur, joints @ v + m.joints_prescribed @ vp)
        return q, v


class GeneralizedAlpha(Integrator):
    """Generalized-alpha, index-3 form (see the module docstring)."""

    def __init__(self, model: Model, settings, q_full: np.ndarray) -> None:
        super().__init__(model, settings, q_full)
        rho = settings.rho_inf
        self.alpha_m = (2 * rho - 1) / (rho + 1)
        self.alpha_f = rho / (rho + 1)
        self.gamma = 0.5 + self.alpha_f - self.alpha_m
        self.beta = 0.25 * (self.gamma + 0.5) ** 2

    def initial_state(self, t: float = 0.0) -> State:
        state = super().initial_state(t)
        state.extra["abar"] = state.a.copy()
        return state

    def step(self, state: State, t: float, h: float) -> State:
        m = self.model
        joints = m.joints_free
        am, af, gamma, beta = self.alpha_m, self.alpha_f, self.gamma, self.beta
        _, _, ap = m.prescribed_state(t)
        abar = state.extra["abar"]
        q = state.q + h * state.v + h * h * (0.5 - beta) * abar
        v = state.v + h * (1 - gamma) * abar
        abar_new = (af * state.a - am * abar) / (1 - am)
        q = q + h * h * beta * abar_new
        v = v + h * gamma * abar_new
        a = np.zeros_like(state.a)
        lam = state.multipliers.copy()
        beta_prime = (1 - am) / (h * h * beta * (1 - af))
        gamma_prime = gamma / (h * beta)
        fixed_part = m.joints_prescribed @ m.prescribed_state(t)[0] + \
            m.joints[:, m.fixed] @ self.fixed_values[m.fixed]
        for _ in range(self.settings.max_iterations):
            force, jacobian = self.forces(q, t)
            self.counters.newton_iterations += 1
            residual = self.residual(a, force, ap, lam)
            constraint = joints @ q + fixed_part if joints.shape[0] else None
            dq, dlam = m.solve(beta_prime, -1.0, jacobian, -residual,
                               None if constraint is None else -constraint)
            q += dq
            v += gamma_prime * dq
            a += beta_prime * dq
            lam += dlam
            if self.converged(dq):
                break
        else:
            raise Divergence(t, f"Newton did not converge in {self.settings.max_iterations} "
                             f"iterations (last correction {np.abs(dq).max():.3g} m)")
        abar_new = abar_new + (1 - af) / (1 - am) * a
        return State(t, q, v, a, lam, {"abar": abar_new})


INTEGRATORS = {"trapezoidal": Trapezoidal, "generalized_alpha": GeneralizedAlpha}
