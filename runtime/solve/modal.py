"""Modal analysis of a model: the lowest frequencies and mode shapes linearised about a
configuration (fixed and prescribed coordinates held, joints through their null space).

With quadratic constraint rows (rigid bodies in natural coordinates and their joints) the
linearisation is on the constraint manifold at q: the mode shapes lie in the null space of
``C = [A_f; Phi_q,f(q)]``, and the stiffness is the tangent one of the constrained system,
``K = -dF/dq + sum_i lambda_i H_i`` with the multipliers lambda of the rows at q (the
static solution's, whose loads they balance: the restoring moment of a pendulum is all in
that term, since gravity itself has no stiffness).  At an unloaded reference the rows carry
no multipliers.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.sparse
import scipy.sparse.linalg

from runtime.model.model import Model
from runtime.solve import cholmod
from runtime.solve.linear import DENSE_LIMIT, single_threaded_blas


@dataclass
class ModalResult:
    """Lowest angular frequencies (rad/s), ascending, and their mode shapes (modes, size):
    full coordinate vectors (fixed and prescribed coordinates zero), each scaled so that its
    largest position component (of a node, a rigid body's origin or a point mass) is +1
    (unitless)."""

    frequencies: np.ndarray
    shapes: np.ndarray


def modal(model: Model, q: np.ndarray, modes: int,
          multipliers: np.ndarray | None = None) -> np.ndarray:
    """Lowest ``modes`` angular frequencies (rad/s) linearised about ``q`` (fixed and
    prescribed coordinates held, joints enforced through their null space); ``multipliers``
    (joint rows then quadratic rows) those of an equilibrium at q, e.g. the static
    solution's (None: the least-squares balance of the internal forces at q, zero at an
    unloaded reference)."""
    with single_threaded_blas():
        return _modal(model, q, modes, multipliers, vectors=False)[0]


def modal_shapes(model: Model, q: np.ndarray, modes: int,
                 multipliers: np.ndarray | None = None) -> ModalResult:
    """Frequencies and mode shapes of the ``modes`` lowest modes about ``q`` (see
    :func:`modal`): eigenvectors mapped from the free coordinates (and the joints' null
    space) back to full coordinate vectors."""
    with single_threaded_blas():
        omega, vectors = _modal(model, q, modes, multipliers, vectors=True)
    shapes = np.zeros((omega.size, model.size))
    shapes[:, model.free] = vectors.T
    # positions: the nodes', and the origins of rigid bodies and free point masses
    positions = np.concatenate([model.position_dofs().ravel()] + [
        rigid.dofs[:model.dim] for rigid in model.rigid.values() if rigid.dofs.size])
    for shape in shapes:
        largest = shape[positions][np.argmax(np.abs(shape[positions]))]
        if largest != 0:
            shape /= largest
    return ModalResult(omega, shapes)


def _constraint_rows(model: Model, q: np.ndarray,
                     multipliers: np.ndarray | None) -> tuple[scipy.sparse.csr_matrix,
                                                              np.ndarray | None]:
    """(C (rows, nf), the multipliers of the quadratic rows or None without them) at q."""
    rows = model.constraint_rows(q)
    if not model.holonomic:
        return rows, None
    if multipliers is None:         # C^T lambda = F(q): the balance of the internal forces
        force = model.internal_forces(q, jacobian=False)[0][model.free]
        multipliers = np.linalg.lstsq(rows.T.toarray(), force, rcond=None)[0]
    elif multipliers.shape != (rows.shape[0],):
        raise ValueError(f"modal: multipliers: expected {rows.shape[0]} values (joint rows, "
                         f"then quadratic rows), got shape {multipliers.shape}")
    return rows, multipliers[model.joints_free.shape[0]:]


def _dense_lowest(stiffness: np.ndarray, mass: np.ndarray, modes: int, vectors: bool):
    """The ``modes`` lowest eigenvalues (and eigenvectors) of K v = lambda M v, dense.  With
    K positive definite as the largest of M v = mu K v, mu = 1 / lambda: their relative
    accuracy is that of the round-off, where eigh(K, M) resolves the lowest lambda only to
    round-off times the largest (a slender beam's bending against its axial stiffness: a
    120-element chain, L/h = 600, 5.4e-5 off beam theory's first frequency where the
    inverse form and the shift-invert iterations are 1.2e-5, the discretisation's).  Else
    (a free mechanism, a buckled state) eigh(K, M)."""
    n = stiffness.shape[0]
    try:
        found = scipy.linalg.eigh(mass, stiffness, eigvals_only=not vectors,
                                  subset_by_index=[n - modes, n - 1])
    except np.linalg.LinAlgError:       # K not positive definite
        return scipy.linalg.eigh(stiffness, mass, eigvals_only=not vectors,
                                 subset_by_index=[0, modes - 1])
    inverse, eigenvectors = found if vectors else (found, None)
    values = 1.0 / inverse
    return (values, eigenvectors) if vectors else values


def _inverse(stiffness) -> scipy.sparse.linalg.LinearOperator | None:
    """K^-1 for the shift-invert iterations (sigma = 0) by CHOLMOD's Cholesky of a sparse,
    positive definite K (a held structure), instead of the SuperLU that eigsh takes
    otherwise: 4 modes of a clamped plate3d 16 x 16 (3264 coordinates) in 75 ms against 210,
    32 x 32 (12672) in 0.21 s against 2.2 s, frequencies equal to 4e-10; None (SuperLU) for
    a dense K (the joints' null space), without CHOLMOD, or when K is not positive definite
    (a mechanism, a buckled state)."""
    if not scipy.sparse.issparse(stiffness) or not cholmod.available():
        return None
    symmetric = ((stiffness + stiffness.T) / 2).tocsr()
    symmetric.sort_indices()
    cholesky = cholmod.Cholesky(symmetric)
    try:
        cholesky.factorize(symmetric.data)
    except cholmod.NotPositiveDefinite:
        return None
    return scipy.sparse.linalg.LinearOperator(symmetric.shape, matvec=cholesky.solve,
                                              dtype=float)


def _modal(model: Model, q: np.ndarray, modes: int, multipliers: np.ndarray | None,
           vectors: bool) -> tuple[np.ndarray, np.ndarray | None]:
    """(frequencies (modes,), eigenvectors over the free coordinates (nf, modes) or None)."""
    rows, quadratic = _constraint_rows(model, q, multipliers)
    _, data = model.internal_forces(q)
    if quadratic is not None:       # the rows' geometric stiffness sum lambda_i H_i
        data = data - model.holonomic_stiffness(quadratic, q)
    stiffness = -model.jacobian_matrix(data)
    mass = model.mass_ff
    basis = None
    if rows.shape[0]:
        basis = scipy.linalg.null_space(rows.toarray())
        stiffness = basis.T @ (stiffness @ basis)
        mass = basis.T @ (mass @ basis)
    n = stiffness.shape[0]
    modes = min(modes, n)
    if n <= DENSE_LIMIT:
        dense = stiffness.toarray() if scipy.sparse.issparse(stiffness) else stiffness
        dense_mass = mass.toarray() if scipy.sparse.issparse(mass) else mass
        found = _dense_lowest((dense + dense.T) / 2, dense_mass, modes, vectors)
    else:
        found = scipy.sparse.linalg.eigsh(stiffness, k=modes, M=mass, sigma=0.0,
                                          OPinv=_inverse(stiffness),
                                          return_eigenvectors=vectors)
    values, eigenvectors = found if vectors else (found, None)
    order = np.argsort(values)
    omega = np.sqrt(np.clip(values[order], 0.0, None))
    if eigenvectors is None:
        return omega, None
    eigenvectors = eigenvectors[:, order]
    return omega, eigenvectors if basis is None else basis @ eigenvectors
