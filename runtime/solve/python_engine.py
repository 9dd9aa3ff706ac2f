"""Fixed-step implicit integrators for M q'' + A^T lambda = F(q, t), A q = 0 (the Python
engine: the readable reference of the compiled one in ``runtime.solve.compiled_engine``).

* ``trapezoidal``: the paper's scheme - the index-1 form (eq. 8) integrated with the
  second-order Adams-Moulton (trapezoidal) rule, Newton on the new accelerations, then
  projection of positions and velocities onto the constraints;
* ``generalized_alpha``: Chung-Hulbert generalized-alpha in the index-3 form of Arnold and
  Bruls, Newton on the positions, numerical damping set by the spectral radius ``rho_inf``.

Both work on the free coordinates of a ``DAESystem``; prescribed ones (hub rotations) enter
through their known values, rates and accelerations. Newton is ``full`` (the exact Jacobian
and a new factorisation at every iteration, the paper's) or ``modified`` (the Jacobian and
its factorisation are kept, across steps too, until the corrections stop shrinking by at
least ``CONTRACTION`` per iteration, or too slowly for the stop below; then they are
rebuilt at the current iterate) or ``auto``: modified Newton, except that after a step in
which the kept Jacobian went stale (a factorisation was needed) come steps of full Newton,
1 of them and doubling (up to ``MAX_FULL_STEPS``) while the modified step tried after them
goes stale again, back to 1 once one does not - when full Newton pays: each mode's recent
steps are tallied (steps, iterations, factorisations, halved every ``TALLY_WINDOW`` steps)
and weighed by what a new Jacobian costs against an iteration without one
(``runtime.solve.newton_cost``), and full Newton follows a stale step only while its cost
per step is the lower (before it is measured: while modified Newton's is above one
iteration with a new Jacobian, the least a step of full Newton costs). A modified step that
fails (Newton not converged, non-finite or singular) is done again from its start with full
Newton, as stale. ``auto`` is the default. Measured on the shipped scenes (docs/design.md,
"Newton modes by measurement"), modified Newton is 1.5-3.4x cheaper than full except where
the Jacobian changes fast (the rotating and spinning beams, the beam spun up on a hub);
``auto`` follows the cheaper of the two. The decisions depend on counts and the model's
structure only, so both engines take the same.

The stop (``Integrator.iterations_left``, the same in the compiled step): an iteration
whose matrix was built at its iterate (every one of full Newton) stops when its correction
of the positions is within ``tolerance`` times the model's length scale L; quadratic
convergence overshoots that by far.  With a kept Jacobian convergence is linear, and the
error left after a correction dx is estimated as ``r / (1 - r) |dx|`` with r the ratio of
the last two corrections (``CONTRACTION`` at a step's first): the step stops when that
estimate, carried into the positions, the velocities and the accelerations (the
integrator's factors: h^2/4, h/2, 1 of the accelerations for the trapezoidal rule; 1,
gamma', beta' of the positions for generalized-alpha), is within ``tolerance`` of each's
scale: L, and the largest velocity and acceleration of any free coordinate at the steps so
far or at the iterate.  A kept Jacobian is also marked stale when the iterations that
estimate still needs at rate r cost more than a new Jacobian (``jacobian_weight`` plus one
iteration) or than the iterations left; a kept Jacobian's correction larger than the one
before it is taken back, and the Jacobian rebuilt at the iterate before it (found on a stiff
PD-driven arm, where carrying on from the diverged iterate led Newton to another root).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from runtime import catalog
from runtime.catalog import NEWTON_MODES
from runtime.model.dae import DAESystem
from runtime.model.model import Model
from runtime.model.sliding_rows import SlideError
from runtime.model.time_laws import LoadFunctionError
from runtime.solve import cholmod, linear, newton_cost
from runtime.solve.linear import SchurSolver, single_threaded_blas

#: Modified Newton rebuilds the Jacobian when a correction is larger than this fraction of
#: the previous one (the same rule in both engines).
CONTRACTION = 0.5
#: ``auto`` Newton: at most this many steps of full Newton before modified Newton is tried
#: again
MAX_FULL_STEPS = 64
#: ``auto`` Newton: each mode's tally of steps, iterations and factorisations is halved when
#: its steps reach this (the comparison of the two modes follows the recent steps)
TALLY_WINDOW = 32


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
    factorisations: int = 0


@dataclass
class State:
    """Free coordinates, velocities, accelerations and joint multipliers at time ``t``."""

    t: float
    q: np.ndarray
    v: np.ndarray
    a: np.ndarray
    multipliers: np.ndarray
    extra: dict = field(default_factory=dict)


def newton_not_converged(iterations: int, correction: float) -> str:
    """The cause of a Newton failure, worded identically by both engines."""
    return (f"Newton did not converge in {iterations} iterations (last correction "
            f"{correction:.3g} m)")


NON_FINITE = "non-finite forces (the state blew up)"
SINGULAR = "singular iteration matrix"

#: a state this many times beyond what the scene can reach (``StateLimits``) is a blow-up
ABSURD = 1e6
#: time samples of the laws when their peaks are estimated
LAW_SAMPLES = 10_001


@dataclass(frozen=True)
class StateLimits:
    """The largest sane displacement (m) and velocity (m/s, 1/s for gradients) of any
    coordinate in a dynamic run: ``ABSURD`` times what the scene can reach by ``t_end``.

    The reach is the model's length scale L plus what its fastest initial or prescribed
    motion v0 (rigid rates times L) and the largest acceleration its loads can give a node,
    a = sum of the loads' peak forces / the smallest nodal mass, cover:
    L + v0 t + a t^2 / 2 (velocities: L / t + v0 + a t).  A state beyond it (or non-finite)
    is a divergence, whatever the engine."""

    displacement: float
    velocity: float

    @classmethod
    def of(cls, dae: DAESystem, t_end: float) -> StateLimits:
        """The limits of a run of ``dae`` to ``t_end`` (s)."""
        model = dae.model
        length = model.length_scale()
        times = np.linspace(0.0, t_end, LAW_SAMPLES)
        rates = np.abs(dae.prescribed_motion(times)[1]).max(initial=0.0)
        speed = float(np.abs(model.initial_velocities()).max(initial=0.0)) + rates * length
        peaks = np.abs(dae.load_factors(times)).max(axis=0, initial=0.0)
        force = float(sum(peak * np.abs(vector).max(initial=0.0) for peak, vector in
                          zip(peaks, dae.load_vectors, strict=True)))
        masses = model.mass.diagonal()[model.position_dofs().ravel()]
        acceleration = force / float(masses[masses > 0].min(initial=np.inf))
        return cls(ABSURD * (length + speed * t_end + acceleration * t_end**2 / 2),
                   ABSURD * (length / t_end + speed + acceleration * t_end))

    def first_insane(self, q: np.ndarray, v: np.ndarray, reference: np.ndarray
                     ) -> tuple[int, str] | None:
        """(row, cause) of the first state of a block (k, size) that is non-finite or
        beyond the limits, or None (vectorised over the block)."""
        finite = np.isfinite(q).all(axis=1) & np.isfinite(v).all(axis=1)
        with np.errstate(invalid="ignore"):
            displacement = np.abs(q - reference).max(axis=1, initial=0.0)
            velocity = np.abs(v).max(axis=1, initial=0.0)
        bad = ~finite | (displacement > self.displacement) | (velocity > self.velocity)
        if not bad.any():
            return None
        row = int(np.argmax(bad))
        if not finite[row]:
            return row, "non-finite state (the state blew up)"
        if displacement[row] > self.displacement:
            return row, (f"absurd displacement {displacement[row]:.3g} m (over "
                         f"{self.displacement:.3g} m, {ABSURD:g} times what the scene can "
                         f"reach; the state blew up)")
        return row, (f"absurd velocity {velocity[row]:.3g} m/s (over {self.velocity:.3g} "
                     f"m/s, {ABSURD:g} times what the scene can reach; the state blew up)")


def one_by_one(observe, model: Model):
    """An ``observe_block`` that hands each output time of a block to ``observe(t, q, v)``
    in turn, with the energy dissipated so far in ``model.dissipated_energy`` and the
    torsional springs' joint angles in ``model.spring_angles``."""
    def observe_block(times: np.ndarray, q: np.ndarray, v: np.ndarray,
                      dissipated: np.ndarray, angles: np.ndarray) -> None:
        for t, q_row, v_row, energy, angle in zip(times, q, v, dissipated, angles,
                                                  strict=True):
            model.dissipated_energy = float(energy)
            model.spring_angles = angle
            observe(float(t), q_row, v_row)
    return observe_block


def newton_mode(settings) -> str:
    """The Newton mode of dynamic ``settings`` (ValueError naming the option otherwise)."""
    if settings.newton not in NEWTON_MODES:
        raise ValueError(f"newton: expected one of {NEWTON_MODES}, got {settings.newton!r}")
    return settings.newton


def linear_solver(dae: DAESystem):
    """The linear solver of the Newton iterations on ``dae`` (``runtime.solve.linear``: the
    scene's, or chosen by the model's pattern); both engines use the same.  A non-symmetric
    iteration matrix (follower loads) takes the banded LU: the compiled step's sparse path
    is CHOLMOD's Cholesky (ValueError naming the key if a scene forces ``sparse``)."""
    model = dae.model
    requested = linear.requested(model)
    if not dae.symmetric:
        if requested == "sparse":
            raise ValueError("solver.linear_solver: \"sparse\" takes symmetric iteration "
                             "matrices; the follower loads of this scene make it "
                             "non-symmetric: use \"banded\" (its LU) or leave the key out")
        return linear.make("banded", model.pattern, symmetric=False)
    if requested is None and dae.constraint_rows >= linear.KKT_ROWS and cholmod.available():
        return linear.make("sparse", model.pattern)     # for the KKT system of its joints
    return linear.make(linear.choose(model.pattern, requested), model.pattern)


def uses_kkt(dae: DAESystem, solver) -> bool:
    """Whether the joints of ``dae`` go through the KKT system of the iteration matrices and
    the constraint rows (``linear.KKTSystem``): when the rows are many (``linear.KKT_ROWS``)
    and ``solver`` is the sparse one (CHOLMOD); else through the Schur complement of the
    factorised matrix.  Both engines make the same choice."""
    return dae.constraint_rows >= linear.KKT_ROWS and solver.name == "sparse" \
        and dae.symmetric


def constraint_system(dae: DAESystem, solver) -> linear.KKTSystem | None:
    """The KKT system of ``dae``'s iteration matrices and rows when ``uses_kkt``, else
    None."""
    if not uses_kkt(dae, solver):
        return None
    rows = dae.constraint_matrix(dae.model.reference) if dae.nonlinear else dae.joints_free
    return linear.KKTSystem(dae.model.pattern, rows,
                            refinements=linear.ITERATION_KKT_REFINEMENTS)


def dae_system(model: Model, q_full: np.ndarray) -> DAESystem:
    """The engines' ``DAESystem`` of ``model`` at ``q_full``, built with BLAS on one thread
    (the joints' projector: small banded solves, which OpenBLAS's threads only slow
    down)."""
    with single_threaded_blas():
        return DAESystem(model, q_full)


def mass_solver(dae: DAESystem) -> SchurSolver:
    """The mass matrix with the joints, factorised once (banded Cholesky of the constant
    ``M_ff``, the joints by their Schur complement; BLAS on one thread, as
    ``dae_system``): the solves of consistent accelerations (``initial_state``,
    ``OutputDynamics``)."""
    with single_threaded_blas():
        return SchurSolver(dae.mass_band, dae.joints_free)


def initial_state(dae: DAESystem, t: float = 0.0, mass: SchurSolver | None = None) -> State:
    """Consistent initial state: the model's initial velocities (at rest by default, except
    prescribed motions; with quadratic constraint rows projected onto [A; Phi_q] v = 0),
    M a = F - M_fp a_p with the joints' accelerations A_f a + A_p a_p = 0 (and
    Phi_q a = -(Phi_q,p a_p + v^T H v) for quadratic rows); ``mass``: ``mass_solver(dae)``,
    factorised once per engine."""
    qp, vp, ap = (x[0] for x in dae.prescribed_motion([t]))
    q = dae.fixed_values[dae.free].copy()
    v = dae.initial_velocity.copy()
    q_full = dae.full_coordinates(q, qp)
    mass = mass or mass_solver(dae)
    if dae.nonlinear:     # velocities onto Phi_q v = 0 (mass-orthogonal; a no-op when the
        # scene's initial velocities are consistent, as the mechanisms' rigid motions are)
        rows = SchurSolver(mass.factor, dae.constraint_matrix(q_full))
        v = v - rows.solve(np.zeros_like(v), dae.velocity_violation(
            q_full, dae.full_velocities(v, vp)))[0]
    force, _, _ = dae.internal_forces(q_full, dae.full_velocities(v, vp), jacobian=False)
    factors = dae.load_factors([t])[0]
    force = force[dae.free] + factors @ dae.load_vectors
    if dae.state_loads:
        try:
            force += dae.state_loads.evaluate(q_full, factors, False,
                                              dae.full_velocities(v, vp), t)[0][dae.free]
        except LoadFunctionError as error:   # a Python load failed at the start
            raise Divergence(t, str(error)) from None
    if dae.nonlinear:       # Phi_q a = -(Phi_q,p a_p + v^T H v)
        a, lam = rows.solve(force - dae.mass_fp @ ap, -dae.acceleration_violation(
            q_full, dae.full_velocities(v, vp), dae.full_accelerations(np.zeros_like(v), ap)))
    else:
        a, lam = mass.solve(force - dae.mass_fp @ ap, -(dae.joints_prescribed @ ap))
    return State(t, q, v, a, lam, {"dissipated": 0.0,
                                   "power": dae.dissipation_power(q, v, qp, vp)})


class OutputDynamics:
    """The equations of motion at output states, for the sensors that need them
    (accelerations, reactions): ``M_ff a + A_f^T lambda = F_free - M_fp a_p`` with
    ``A_f a = -A_p a_p``, solved at each state of a block (the consistent accelerations of
    its positions and velocities, as ``initial_state`` solves them at t = 0; F with the
    follower loads at the state).  Both engines' output states go through it, so their
    sensors differ only as their states do."""

    def __init__(self, dae: DAESystem, mass: SchurSolver | None = None) -> None:
        self.dae = dae
        self.solver = mass or mass_solver(dae)
        loads = dae.model.nominal_loads()
        self.load_vectors = (np.array([vector for _, vector in loads]) if loads
                             else np.zeros((0, dae.size)))

    def __call__(self, times: np.ndarray, q_full: np.ndarray, v_full: np.ndarray,
                 angles: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(accelerations (k, size), multipliers (k, joints), applied force F (k, size)) at
        the states (k, size) of the output times (k,) (s), the torsional springs at their
        joint angles ``angles`` (k, loads; ``Samples.spring_angles``; None: as they are
        counted); BLAS on one thread (small banded solves, which threads only slow down)."""
        with single_threaded_blas():
            return self._evaluate(times, q_full, v_full, angles)

    def _evaluate(self, times: np.ndarray, q_full: np.ndarray, v_full: np.ndarray,
                  angles: np.ndarray | None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        dae = self.dae
        _, _, ap = dae.prescribed_motion(times)
        factors = dae.load_factors(times)
        force = factors @ self.load_vectors
        for row in range(len(times)):
            force[row] += dae.internal_forces(q_full[row], v_full[row], jacobian=False)[0]
            if dae.state_loads:     # follower and Python loads, force elements
                if angles is not None:
                    dae.state_loads.count_turns(angles[row])
                force[row] += dae.state_loads.evaluate(q_full[row], factors[row], False,
                                                       v_full[row], float(times[row]))[0]
        rhs = force[:, dae.free] - (dae.mass_fp @ ap.T).T if ap.size else force[:, dae.free]
        accelerations = np.zeros_like(force)
        accelerations[:, dae.prescribed] = ap
        if dae.nonlinear:     # the constraint rows at each state
            lam = np.zeros((len(times), dae.constraint_rows))
            for row in range(len(times)):
                accelerations[row, dae.free], lam[row] = SchurSolver(
                    self.solver.factor, dae.constraint_matrix(q_full[row])).solve(
                    rhs[row], -dae.acceleration_violation(q_full[row], v_full[row],
                                                          accelerations[row]))
            return accelerations, lam, force
        a, lam = self.solver.solve(rhs.T, -(dae.joints_prescribed @ ap.T) if dae.joints
                                   else None)
        accelerations[:, dae.free] = a.T
        return accelerations, np.asarray(lam).T.reshape(len(times), dae.joints), force


class Integrator:
    """Shared machinery: forces, Newton linear solves, initial accelerations, the loop."""

    engine = "python"
    compile_s = 0.0          # nothing to compile (the compiled engine's first-use cost)
    modules: tuple[str, ...] = ()   # nothing built beyond the kernels

    def __init__(self, model: Model, settings, q_full: np.ndarray) -> None:
        self.dae = dae_system(model, q_full)
        self.settings = settings
        self.newton = newton_mode(settings)
        self.counters = Counters()
        #: seconds in steps, in element kernels, in factorisations and in the solves with
        #: them (as the compiled engine)
        self.timing = {"steps_s": 0.0, "kernel_s": 0.0, "factorisation_s": 0.0,
                       "solve_s": 0.0}
        self.scale = self.dae.scale
        self.linear = linear_solver(self.dae)
        #: the name of the linear solver (``runtime.catalog.LINEAR_SOLVERS``)
        self.linear_solver = self.linear.name
        self._mass = linear.pattern_values(self.dae.mass_ff, model.pattern)
        #: the constant mass matrix with the joints, factorised once (``mass_solver``)
        self.mass = mass_solver(self.dae)
        self._solver: SchurSolver | None = None   # kept across iterations (modified Newton)
        self._refresh = True
        self._full_step = self.newton == "full"   # this step rebuilds at every iteration
        self._full_steps = 0       # auto: steps of full Newton still to do ...
        self._probe = 1            # ... and how many after the next stale modified step
        #: the joints' KKT system when they are many (else their Schur complement)
        self.kkt = constraint_system(self.dae, self.linear)
        #: auto: what a new Jacobian costs in iterations without one, and the tallies
        #: [steps, iterations, factorisations] of the full (True) and modified (False) steps
        self.jacobian_weight = newton_cost.jacobian_weight(self.dae, self.linear)
        self._tally = {True: [0.0, 0.0, 0.0], False: [0.0, 0.0, 0.0]}
        self._rebuilt = False      # the last iteration's matrix was built at its iterate
        #: the largest velocity and acceleration of any free coordinate at the steps so far
        #: (the kept Jacobian's stop measures their corrections against them)
        self.velocity_scale = self.acceleration_scale = 0.0

    # --- pieces of a Newton iteration --------------------------------------------------

    def forces(self, q: np.ndarray, v: np.ndarray, t: float, prescribed, loads: np.ndarray,
               jacobian: bool):
        """Free part of elastic (+ damping) + external force (nf,) at free coordinates q and
        velocities v, and the Jacobian data (d/dq, d/dv or None) or None."""
        dae = self.dae
        qp, vp, _ = prescribed
        q_full, v_full = dae.full_coordinates(q, qp), dae.full_velocities(v, vp)
        force, data, data_dot = dae.internal_forces(q_full, v_full, jacobian)
        self.counters.force_evaluations += 1
        total = force[dae.free] + loads @ dae.load_vectors
        if dae.state_loads:     # follower and Python loads: force, stiffness, damping
            state_force, state_data, state_dot = dae.state_loads.evaluate(
                q_full, loads, jacobian, v_full, t)
            total += state_force[dae.free]
            if jacobian:
                data = data + state_data
            if state_dot is not None:
                data_dot = state_dot if data_dot is None else data_dot + state_dot
        if not np.all(np.isfinite(total)):
            raise Divergence(t, NON_FINITE)
        if jacobian:
            self.counters.jacobian_evaluations += 1
        return total, (data, data_dot)

    def residual(self, a: np.ndarray, force: np.ndarray, ap: np.ndarray,
                 multipliers: np.ndarray, q_full: np.ndarray | None) -> np.ndarray:
        """M_ff a + M_fp a_p + A^T lambda (+ Phi_q(q)^T lambda) - F: the equations of motion
        of the free part at the coordinates q_full (read only with quadratic rows)."""
        dae = self.dae
        residual = dae.mass_ff @ a - force
        if ap.size:
            residual += dae.mass_fp @ ap
        if dae.nonlinear:
            residual += dae.constraint_forces(q_full, multipliers)
        elif dae.joints:
            residual += dae.joints_free.T @ multipliers
        return residual

    def linear_step(self, q: np.ndarray, v: np.ndarray, t: float, prescribed,
                    loads: np.ndarray, coefficients: tuple[float, float, float], residual_of,
                    constraint, multipliers: np.ndarray):
        """One Newton iteration at (q, v): forces (and the Jacobians, when they are rebuilt),
        the residual ``residual_of(force, q_full)``, and the solution of [[S, A^T], [A, 0]]
        [dx; dy] = -[r; c] with S = c_m M + c_q dF/dq + c_v dF/dv, (c_m, c_q, c_v) =
        ``coefficients`` (with quadratic constraint rows, A holds their Phi_q at q and S
        their geometric stiffness -c_q (Phi_q^T lambda)_q at the ``multipliers``).
        Returns (dx, dy)."""
        rebuild = self._full_step or self._refresh or self._solver is None
        force, (data, data_dot) = self.forces(q, v, t, prescribed, loads, rebuild)
        # the coordinates the quadratic rows are evaluated at (unused by linear joints)
        q_full = self.dae.full_coordinates(q, prescribed[0]) if self.dae.nonlinear else None
        self.counters.newton_iterations += 1
        if rebuild:
            mass_coef, jacobian_coef, damping_coef = coefficients
            values = jacobian_coef * data + mass_coef * self._mass
            if data_dot is not None:
                values += damping_coef * data_dot
            rows = self.dae.joints_free
            if self.dae.nonlinear:
                values = values - jacobian_coef * self.dae.geometric_stiffness(multipliers,
                                                                             q_full)
                rows = self.dae.constraint_matrix(q_full)
            start = time.perf_counter()
            try:
                self._solver = (SchurSolver(self.linear.factor(values), rows)
                                if self.kkt is None else self.kkt.factor(values, rows))
            except np.linalg.LinAlgError:
                raise Divergence(t, SINGULAR) from None
            finally:
                self.timing["factorisation_s"] += time.perf_counter() - start
            self.counters.factorisations += 1
            self._refresh = False
        self._rebuilt = rebuild
        violation = constraint(q_full)
        start = time.perf_counter()
        solution = self._solver.solve(-residual_of(force, q_full), None if violation is None
                                      else -violation)
        self.timing["solve_s"] += time.perf_counter() - start
        return solution

    def dissipation(self, previous: State, q: np.ndarray, v: np.ndarray, prescribed,
                    h: float) -> dict:
        """Energy dissipated by damping (J) since t = 0 after a step to (q, v): the
        trapezoidal rule on the dissipated power (W) at the two ends of the step."""
        if not self.dae.damped:
            return {"dissipated": 0.0, "power": 0.0}
        qp, vp, _ = prescribed
        power = self.dae.dissipation_power(q, v, qp, vp)
        return {"dissipated": previous.extra["dissipated"]
                + h / 2 * (previous.extra["power"] + power), "power": power}

    def iterations_left(self, increment: np.ndarray, previous: float | None, v: np.ndarray,
                        a: np.ndarray) -> float:
        """Newton's stop (module docstring) after an iteration that corrected the unknowns
        by ``increment`` (``previous``: the largest entry of the step's correction before,
        or None), at the velocities ``v`` and accelerations ``a`` it reached: 0 when
        converged, else the iterations still needed at the corrections' rate of decrease
        (inf when not measured or not decreasing)."""
        size = float(np.abs(increment).max(initial=0.0))
        position, velocity, acceleration = self.correction_factors
        tolerance = self.settings.tolerance
        within = position * size <= tolerance * self.scale
        if self._rebuilt or size == 0.0:   # quadratic convergence overshoots the test
            return 0.0 if within else math.inf
        rate = CONTRACTION if previous is None else size / previous
        if rate >= 1.0:
            return math.inf
        left = rate / (1.0 - rate) * size
        bound = tolerance * min(
            self.scale / position,
            max(self.velocity_scale, float(np.abs(v).max(initial=0.0))) / velocity,
            max(self.acceleration_scale, float(np.abs(a).max(initial=0.0))) / acceleration)
        if within and left <= bound:
            return 0.0
        if previous is None or bound == 0.0:
            return math.inf
        return max(math.log(bound / left) / math.log(rate), 1.0)

    def newton_loop(self, t: float, iterate, undo) -> None:
        """Run ``iterate()`` (one Newton iteration, returning the correction of the
        unknowns and the velocities and accelerations it reached) until it converges.  With
        a kept Jacobian, a correction larger than the one before is taken back (``undo()``)
        and the Jacobian rebuilt at the iterate before it; modified Newton marks the
        Jacobian stale when a correction is more than ``CONTRACTION`` of the one before or
        the iterations still needed (``iterations_left``) cost more than a new Jacobian."""
        previous = None
        for iteration in range(1, self.settings.max_iterations + 1):
            increment, v, a = iterate()
            size = float(np.abs(increment).max(initial=0.0))
            left = self.iterations_left(increment, previous, v, a)
            if left == 0.0:
                return
            if not self._rebuilt and previous is not None and size > previous:
                # a kept Jacobian that drives the iterates away: not carried on from there
                undo()
                self._refresh, previous = True, None
                continue
            if previous is not None and (size > CONTRACTION * previous
                                         or left > min(self.jacobian_weight + 1.0,
                                                       self.settings.max_iterations
                                                       - iteration)):
                self._refresh = True
            previous = size
        raise Divergence(t, newton_not_converged(self.settings.max_iterations,
                                                 self.correction_factors[0] * size))

    # --- the loop ----------------------------------------------------------------------

    def initial_state(self, t: float = 0.0) -> State:
        return initial_state(self.dae, t, self.mass)

    def run(self, t_end: float, step: float, observe=None, progress=None, *,
            observe_block=None) -> State:
        """Integrate from rest at t = 0 to ``t_end``; the state at t = 0 and every
        ``output_every`` seconds goes to ``observe(t, q_full, v_full)``, or to
        ``observe_block(times, q_full, v_full, dissipated, angles)`` as a block of one
        output time ((1,), (1, size), (1, size), (1,), (1, loads): the torsional springs'
        joint angles in rad, turns counted, ``StateLoads.spring_angles``).  Raises
        Divergence."""
        observe_block = observe_block or one_by_one(observe, self.dae.model)
        with single_threaded_blas():
            return self._run(t_end, step, observe_block, progress)

    def _observe(self, observe_block, state: State, output: bool) -> None:
        """Count the turns of the torsional springs up to the accepted ``state``; with
        ``output``, observe it."""
        loads = self.dae.state_loads
        if not (output or loads.turning):
            return
        qp, vp, _ = self.dae.prescribed_motion([state.t])
        q_full = self.dae.full_coordinates(state.q[None, :], qp)
        loads.accept(q_full[0])
        if output:
            observe_block(np.array([state.t]), q_full,
                          self.dae.full_velocities(state.v[None, :], vp),
                          np.array([state.extra["dissipated"]]), loads.spring_angles(q_full))

    def _run(self, t_end: float, step: float, observe_block, progress) -> State:
        self.dae.state_loads.reset_turns()      # a run counts turns afresh
        state = self.initial_state()
        every = self.settings.output_every or step
        steps = int(round(t_end / step))
        stride = max(1, int(round(every / step)))
        self._observe(observe_block, state, True)
        for n in range(1, steps + 1):
            state = self.advance(state, n, step)
            self._observe(observe_block, state, n % stride == 0 or n == steps)
            if progress is not None:
                progress.update(state.t)
        return state

    def advance(self, state: State, n: int, h: float) -> State:
        """Step ``n`` (to t = n h) from ``state``."""
        t = n * h
        start, kernels = time.perf_counter(), self.dae.model.kernel_seconds
        # a factorisation this step is a stale Jacobian only if there was one to keep
        kept = self._solver is not None
        iterations, factorisations = (self.counters.newton_iterations,
                                      self.counters.factorisations)
        if self.newton == "auto":
            self._full_step = self._full_steps > 0
            self._full_steps -= self._full_step
        started_full = self._full_step
        try:
            prescribed = tuple(x[0] for x in self.dae.prescribed_motion([t]))
            loads = self.dae.load_factors([t])[0]
            try:
                state = self.step(state, t, h, prescribed, loads)
            except (Divergence, SlideError):     # (as the compiled step: a non-finite step)
                if self.newton != "auto" or self._full_step:
                    raise
                # the kept Jacobian could not carry the step: again from its start with
                # full Newton, and full Newton for the next steps
                self._full_step = True
                self._schedule_full_steps()
                state = self.step(state, t, h, prescribed, loads)
        except (LoadFunctionError, SlideError) as error:   # a Python load or time law
            raise Divergence(t, str(error)) from None       # failed, a point left its body
        finally:
            self.timing["steps_s"] += time.perf_counter() - start
            self.timing["kernel_s"] += self.dae.model.kernel_seconds - kernels
        self.counters.steps += 1
        self.velocity_scale = max(self.velocity_scale, float(np.abs(state.v).max(initial=0.0)))
        self.acceleration_scale = max(self.acceleration_scale,
                                      float(np.abs(state.a).max(initial=0.0)))
        if self.newton == "auto" and kept:
            self._count(started_full, self.counters.newton_iterations - iterations,
                        self.counters.factorisations - factorisations)
            if not self._full_step:
                if self.counters.factorisations == factorisations:
                    self._probe = 1
                elif self._full_newton_pays():     # the kept Jacobian went stale
                    self._schedule_full_steps()
        return state

    def _count(self, full: bool, iterations: int, factorisations: int) -> None:
        """``auto``: add a step of ``iterations`` and ``factorisations`` to the tally of its
        mode (``full`` or modified), halved when its steps reach ``TALLY_WINDOW``."""
        tally = self._tally[full]
        tally[0] += 1.0
        tally[1] += iterations
        tally[2] += factorisations
        if tally[0] >= TALLY_WINDOW:
            for i in range(3):
                tally[i] *= 0.5

    def _full_newton_pays(self) -> bool:
        """``auto``: whether full Newton's cost per step (iterations plus factorisations
        times ``jacobian_weight``) is below modified Newton's; before it is measured,
        whether modified Newton's is above the least full Newton can cost (one iteration
        with a new Jacobian a step)."""
        (full_steps, full_iterations, full_factorisations) = self._tally[True]
        (steps, iterations, factorisations) = self._tally[False]
        weight = self.jacobian_weight
        if full_steps == 0.0:
            return iterations + weight * factorisations > (1.0 + weight) * steps
        return ((full_iterations + weight * full_factorisations) * steps
                < (iterations + weight * factorisations) * full_steps)

    def _schedule_full_steps(self) -> None:
        """``auto``: full Newton for the next steps, doubling their number while the
        modified step after them needs a new Jacobian again."""
        self._full_steps = self._probe
        self._probe = min(2 * self._probe, MAX_FULL_STEPS)

    def step(self, state: State, t: float, h: float, prescribed, loads) -> State:
        raise NotImplementedError  # pragma: no cover - abstract


class Trapezoidal(Integrator):
    """The paper's integrator (see the module docstring)."""

    _projection: ManifoldProjection | None = None

    def step(self, state: State, t: float, h: float, prescribed, loads) -> State:
        dae = self.dae
        qp, vp, ap = prescribed
        a, lam = state.a.copy(), state.multipliers.copy()
        base_q = state.q + h * state.v + h * h / 4 * state.a
        base_v = state.v + h / 2 * state.a
        k = h * h / 4
        self.correction_factors = (k, h / 2, 1.0)

        def constraint(q_full: np.ndarray) -> np.ndarray | None:
            if dae.nonlinear:     # Phi_q a + v^T H v at the iterate
                return dae.acceleration_violation(
                    q_full, dae.full_velocities(base_v + h / 2 * a, vp),
                    dae.full_accelerations(a, ap))
            return dae.joints_free @ a + dae.joints_prescribed @ ap if dae.joints else None

        last = []

        def iterate() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
            nonlocal a, lam
            da, dlam = self.linear_step(base_q + k * a, base_v + h / 2 * a, t, prescribed,
                                        loads, (1.0, -k, -h / 2),
                                        lambda force, q_full: self.residual(a, force, ap, lam,
                                                                            q_full),
                                        constraint, lam)
            a = a + da
            lam = lam + dlam
            last[:] = da, dlam
            return da, base_v + h / 2 * a, a

        def undo() -> None:
            nonlocal a, lam
            a = a - last[0]
            lam = lam - last[1]

        self.newton_loop(t, iterate, undo)
        q = base_q + k * a
        v = state.v + h / 2 * (state.a + a)
        if dae.nonlinear:
            if self._projection is None:
                self._projection = ManifoldProjection(
                    dae, self.mass, self.settings.tolerance * self.scale,
                    self.settings.max_iterations)
            projected = self._projection(q, v, qp, vp)
            if projected is None:
                raise Divergence(t, PROJECTION_FAILED)
            q, v = projected
        elif dae.joints:
            q, v = self.project(q, v, qp, vp)
        return State(t, q, v, a, lam, self.dissipation(state, q, v, prescribed, h))

    def project(self, q: np.ndarray, v: np.ndarray, qp: np.ndarray, vp: np.ndarray):
        """Mass-orthogonal projection of positions and velocities onto A q = 0, A v = 0."""
        dae = self.dae
        for _ in range(3):
            violation = (dae.joints_free @ q + dae.joints_prescribed @ qp
                         + dae.joint_fixed_part)
            q = q - dae.projector @ violation
        v = v - dae.projector @ (dae.joints_free @ v + dae.joints_prescribed @ vp)
        return q, v



class ManifoldProjection:
    """The trapezoidal scheme's mass-orthogonal projection onto the joints and the quadratic
    constraint rows, Phi(q) = 0 then Phi_q v = 0: q -= M^-1 C^T (C M^-1 C^T)^-1 Phi(q) with
    C = [A; Phi_q] at the current q, iterated until the correction is within ``tolerance``
    (m), at most ``max_iterations`` times; then the velocities with C at the projected q.
    M is the engine's ``mass_solver`` (factorised once, apart from the iteration matrices'
    solver, whose factorisations last only until its next one).  The compiled step does
    the same in C (``project`` in templates/stepper.c.j2)."""

    def __init__(self, dae: DAESystem, mass: SchurSolver, tolerance: float,
                 max_iterations: int) -> None:
        self.dae, self.tolerance, self.max_iterations = dae, tolerance, max_iterations
        self.mass = mass.factor

    def __call__(self, q: np.ndarray, v: np.ndarray, qp: np.ndarray, vp: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray] | None:
        """Projected (q, v) (free coordinates) with the prescribed values and rates (qp, vp);
        None if the positions did not converge."""
        dae = self.dae
        for _ in range(self.max_iterations):
            q_full = dae.full_coordinates(q, qp)
            projector = SchurSolver(self.mass, dae.constraint_matrix(q_full))
            correction = projector.solve(np.zeros_like(q), dae.violation(q_full))[0]
            q = q - correction
            if float(np.abs(correction).max(initial=0.0)) <= self.tolerance:
                break
        else:
            return None
        q_full = dae.full_coordinates(q, qp)
        projector = SchurSolver(self.mass, dae.constraint_matrix(q_full))
        v = v - projector.solve(np.zeros_like(v), dae.velocity_violation(
            q_full, dae.full_velocities(v, vp)))[0]
        return q, v


#: the cause of a projection that does not converge, worded identically by both engines
PROJECTION_FAILED = "the projection onto the constraints did not converge"


class GeneralizedAlpha(Integrator):
    """Generalized-alpha, index-3 form (see the module docstring)."""

    def __init__(self, model: Model, settings, q_full: np.ndarray) -> None:
        super().__init__(model, settings, q_full)
        self.alpha_m, self.alpha_f, self.gamma, self.beta = alpha_parameters(settings.rho_inf)

    def initial_state(self, t: float = 0.0) -> State:
        state = super().initial_state(t)
        state.extra["abar"] = state.a.copy()
        return state

    def step(self, state: State, t: float, h: float, prescribed, loads) -> State:
        dae = self.dae
        qp, _, ap = prescribed
        am, af, gamma, beta = self.alpha_m, self.alpha_f, self.gamma, self.beta
        abar = state.extra["abar"]
        q = state.q + h * state.v + h * h * (0.5 - beta) * abar
        v = state.v + h * (1 - gamma) * abar
        abar_new = (af * state.a - am * abar) / (1 - am)
        # the predictor: the new accelerations start at the last ones (a_n), so the first
        # correction is O(h) of them, not all of them (Arnold and Bruls' a = 0)
        a = state.a.copy()
        start = abar_new + (1 - af) / (1 - am) * a
        q = q + h * h * beta * start
        v = v + h * gamma * start
        lam = state.multipliers.copy()
        beta_prime = (1 - am) / (h * h * beta * (1 - af))
        gamma_prime = gamma / (h * beta)
        fixed_part = dae.joints_prescribed @ qp + dae.joint_fixed_part
        self.correction_factors = (1.0, gamma_prime, beta_prime)

        def constraint(q_full: np.ndarray) -> np.ndarray | None:
            if dae.nonlinear:
                return dae.violation(q_full)
            return dae.joints_free @ q + fixed_part if dae.joints else None

        last = []

        def iterate() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
            nonlocal q, v, a, lam
            dq, dlam = self.linear_step(q, v, t, prescribed, loads,
                                        (beta_prime, -1.0, -gamma_prime),
                                        lambda force, q_full: self.residual(a, force, ap, lam,
                                                                            q_full),
                                        constraint, lam)
            q = q + dq
            v = v + gamma_prime * dq
            a = a + beta_prime * dq
            lam = lam + dlam
            last[:] = dq, dlam
            return dq, v, a

        def undo() -> None:
            nonlocal q, v, a, lam
            q = q - last[0]
            v = v - gamma_prime * last[0]
            a = a - beta_prime * last[0]
            lam = lam - last[1]

        self.newton_loop(t, iterate, undo)
        abar_new = abar_new + (1 - af) / (1 - am) * a
        return State(t, q, v, a, lam, {"abar": abar_new,
                                       **self.dissipation(state, q, v, prescribed, h)})


def alpha_parameters(rho_inf: float) -> tuple[float, float, float, float]:
    """(alpha_m, alpha_f, gamma, beta) of generalized-alpha for the spectral radius rho_inf."""
    alpha_m = (2 * rho_inf - 1) / (rho_inf + 1)
    alpha_f = rho_inf / (rho_inf + 1)
    gamma = 0.5 + alpha_f - alpha_m
    return alpha_m, alpha_f, gamma, 0.25 * (gamma + 0.5) ** 2


INTEGRATORS = {"trapezoidal": Trapezoidal, "generalized_alpha": GeneralizedAlpha}
assert tuple(INTEGRATORS) == catalog.INTEGRATORS
