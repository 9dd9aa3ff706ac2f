"""Static equilibrium (Newton with load stepping) and modal analysis of a model."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.sparse.linalg

from runtime.model.model import Model
from runtime.solve.linear import DENSE_LIMIT, single_threaded_blas


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


def length_scale(model: Model) -> float:
    """A characteristic length (m) for convergence tests: the largest reference extent."""
    return float(max(np.ptp(model.reference), 1.0))


def newton_static(model: Model, q: np.ndarray, load: np.ndarray, settings,
                  multipliers: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
    """Solve F_int(q) + load - A^T mu = 0, A q = 0 for the free coordinates from ``q``."""
    free, joints = model.free, model.joints_free
    scale = length_scale(model)
    q = q.copy()
    for iteration in range(1, settings.max_iterations + 1):
        force, data = model.internal_forces(q)
        residual = (force + load)[free] - joints.T @ multipliers
        if not np.all(np.isfinite(residual)):
            raise ConvergenceError("static: non-finite residual")
        # J dq - A^T dmu = -R and A dq = -A q, written with the positive definite -J
        step, dual = model.solve(0.0, -1.0, data, residual, -(model.joints @ q))
        q[free] += step
        multipliers = multipliers + dual
        if np.abs(step).max() <= settings.tolerance * scale:
            return q, multipliers, iteration
    raise ConvergenceError(f"static: Newton did not converge in {settings.max_iterations} "
                           f"iterations (last step {np.abs(step).max():.3g} m)")


def solve_static(model: Model, settings) -> StaticResult:
    """Equilibrium under every load at its nominal value (see ``_solve_static``)."""
    with single_threaded_blas():
        return _solve_static(model, settings)


def _solve_static(model: Model, settings) -> StaticResult:
    """Equilibrium under every load at its nominal value (time laws are not applied).

    The load is applied in ``settings.load_steps`` increments; an increment that fails is
    halved (down to 1/1024 of the load) before the analysis gives up, and one that succeeds
    lets the next grow again (doubling, up to the initial increment).
    """
    check_held(model)
    nominal = model.nominal_load()
    q = model.reference.copy()
    multipliers = np.zeros(model.joints.shape[0])
    done, increment, iterations, steps = 0.0, 1.0 / settings.load_steps, 0, 0
    while done < 1.0 - 1e-12:
        target = min(1.0, done + increment)
        try:
            q_new, mu_new, used = newton_static(model, q, target * nominal, settings, multipliers)
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


@dataclass
class ModalResult:
    """Lowest angular frequencies (rad/s), ascending, and their mode shapes (modes, size):
    full coordinate vectors (fixed and prescribed coordinates zero), each scaled so that its
    largest nodal position component is +1 (unitless)."""

    frequencies: np.ndarray
    shapes: np.ndarray


def modal(model: Model, q: np.ndarray, modes: int) -> np.ndarray:
    """Lowest ``modes`` angular frequencies (rad/s) linearised about ``q`` (fixed and
    prescribed coordinates held, joints enforced through their null space)."""
    with single_threaded_blas():
        return _modal(model, q, modes, vectors=False)[0]


def modal_shapes(model: Model, q: np.ndarray, modes: int) -> ModalResult:
    """Frequencies and mode shapes of the ``modes`` lowest modes about ``q`` (see
    :func:`modal`): eigenvectors mapped from the free coordinates (and the joints' null
    space) back to full coordinate vectors."""
    with single_threaded_blas():
        omega, vectors = _modal(model, q, modes, vectors=True)
    shapes = np.zeros((omega.size, model.size))
    shapes[:, model.free] = vectors.T
    positions = model.position_dofs().ravel()
    for shape in shapes:
        largest = shape[positions][np.argmax(np.abs(shape[positions]))]
        if largest != 0:
            shape /= largest
    return ModalResult(omega, shapes)


def _modal(model: Model, q: np.ndarray, modes: int,
           vectors: bool) -> tuple[np.ndarray, np.ndarray | None]:
    """(frequencies (modes,), eigenvectors over the free coordinates (nf, modes) or None)."""
    _, data = model.internal_forces(q)
    stiffness = -model.jacobian_matrix(data)
    mass = model.mass_ff
    basis = None
    if model.joints_free.shape[0]:
        basis = scipy.linalg.null_space(model.joints_free.toarray())
        stiffness = basis.T @ (stiffness @ basis)
        mass = basis.T @ (mass @ basis)
    n = stiffness.shape[0]
    modes = min(modes, n)
    if n <= DENSE_LIMIT:
        dense = stiffness.toarray() if scipy.sparse.issparse(stiffness) else stiffness
        dense_mass = mass.toarray() if scipy.sparse.issparse(mass) else mass
        found = scipy.linalg.eigh((dense + dense.T) / 2, dense_mass, eigvals_only=not vectors,
                                  subset_by_index=[0, modes - 1])
    else:
        found = scipy.sparse.linalg.eigsh(stiffness, k=modes, M=mass, sigma=0.0,
                                          return_eigenvectors=vectors)
    values, eigenvectors = found if vectors else (found, None)
    order = np.argsort(values)
    omega = np.sqrt(np.clip(values[order], 0.0, None))
    if eigenvectors is None:
        return omega, None
    eigenvectors = eigenvectors[:, order]
    return omega, eigenvectors if basis is None else basis @ eigenvectors
