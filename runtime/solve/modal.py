"""Modal analysis of a model: the lowest frequencies and mode shapes linearised about a
configuration (fixed and prescribed coordinates held, joints through their null space)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg
import scipy.sparse
import scipy.sparse.linalg

from runtime.model.model import Model
from runtime.solve.linear import DENSE_LIMIT, single_threaded_blas


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
    if model.holonomic:
        raise ValueError("analysis.modal: modes of models with rigid bodies or their joints "
                         "(quadratic constraint rows) are not built yet; remove "
                         "[analysis.modal]")
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
