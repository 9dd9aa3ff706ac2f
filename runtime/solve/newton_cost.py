"""What a new Jacobian costs against a Newton iteration without one: the weight that the
``auto`` Newton mode of both engines weighs its counts with.

A step of Newton costs ``iterations * c_iteration + factorisations * c_jacobian``:

* ``c_iteration``, every iteration: the element forces, the residual (a mass product) and
  the solve with the kept factorisation (its Schur complement of the constraint rows
  included);
* ``c_jacobian``, an iteration that also rebuilds the matrix: the element Jacobians beyond
  the forces, their assembly, the factorisation and the Schur complement of the constraint
  rows (one solve per row and the dense LU of ``rows x rows``).

``jacobian_weight`` is ``c_jacobian / c_iteration``, estimated from the model's structure
only (never from timings), so the two engines, and every run of a scene, take the same
decisions.  Its terms are operation counts (the kernels' counted operations in
``element.json``, the band or the factor's column counts from CHOLMOD's symbolic analysis)
times costs per operation fitted to the compiled step's measured factorisation, solve and
kernel times on the shipped scenes and the bench plates and chains (full Newton, 2-core
machine, November 2026; the fit is within a factor 2 of every case, and the decisions it
serves only need the side of a ratio that ranges over 0.3 to 10).
"""

from __future__ import annotations

from runtime.model.dae import DAESystem
from runtime.solve.lapack import LAPACK_BANDWIDTH

#: nanoseconds per counted kernel operation (generated C, measured 0.11-0.22)
KERNEL_NS = 0.15
#: nanoseconds per Jacobian entry scattered into the band or the sparse values
ASSEMBLY_NS = 1.0
#: nanoseconds per mass-matrix entry of the residual and per factor entry of a solve
#: (a forward and a backward substitution)
RESIDUAL_NS, SOLVE_NS = 1.0, 2.0
#: a factor entry of a column of the Schur complement's multi-column solve
SCHUR_COLUMN_NS = 0.7
#: banded Cholesky: per flop ``n (b + 1)^2`` (the compiled step's own loops; LAPACK's
#: ``dpbtrf`` from ``lapack.LAPACK_BANDWIDTH`` on), and per call
BAND_NS, LAPACK_BAND_NS, BAND_CALL_NS = 0.2, 0.08, 500.0

#: CHOLMOD's supernodal Cholesky: per flop ``sum(column counts^2)``, per factor entry (its
#: small supernodes), per call (a solve's call costs SPARSE_SOLVE_CALL_NS)
SPARSE_NS, SPARSE_ENTRY_NS, SPARSE_CALL_NS, SPARSE_SOLVE_CALL_NS = 0.1, 10.0, 5000.0, 2000.0
#: dense LU of the Schur complement, per flop (2/3 rows^3)
DENSE_NS = 1.0


def _factor_size(linear) -> tuple[float, float, float]:
    """(factor entries, factorisation ns, solve-call ns) of the linear solver ``linear``
    (``runtime.solve.linear``: banded with its bandwidth, or sparse with CHOLMOD's analysis;
    a non-symmetric sparse matrix goes to SuperLU, costed as the band of its pattern)."""
    cholesky = getattr(linear, "cholesky", None)
    if cholesky is not None:
        counts = cholesky.column_counts()
        entries, flops = float(counts.sum()), float((counts.astype(float) ** 2).sum())
        return (entries, SPARSE_CALL_NS + SPARSE_NS * flops + SPARSE_ENTRY_NS * entries,
                SPARSE_SOLVE_CALL_NS)
    n = linear.pattern.shape[0]
    width = getattr(linear, "bandwidth", n - 1) + 1
    per_flop = LAPACK_BAND_NS if width > LAPACK_BANDWIDTH else BAND_NS   # width = bw + 1
    return float(n * width), BAND_CALL_NS + per_flop * n * width ** 2, 0.0


def kernel_work(dae: DAESystem) -> tuple[float, float, float]:
    """(counted operations of the element forces, of the forces with their Jacobians, the
    Jacobians' entries) of one evaluation of every element of ``dae``."""
    force_ops = jacobian_ops = entries = 0.0
    for group in dae.groups:
        kind, (elements, ndof) = group.element.kind, group.dofs.shape
        force_ops += elements * kind.operations(group.family, "force")
        jacobian_ops += elements * kind.operations(group.family, "force_jacobian")
        entries += elements * ndof * ndof
    return force_ops, jacobian_ops, entries


def jacobian_weight(dae: DAESystem, linear) -> float:
    """``c_jacobian / c_iteration`` (module docstring) of Newton on ``dae`` with the linear
    solver ``linear``: how many iterations with a kept Jacobian one new Jacobian costs."""
    force_ops, jacobian_ops, entries = kernel_work(dae)
    pattern = dae.model.pattern
    n, rows = pattern.shape[0], dae.constraint_rows
    factor_entries, factorisation, solve_call = _factor_size(linear)
    solve = solve_call + SOLVE_NS * factor_entries + SOLVE_NS * n * rows
    iteration = KERNEL_NS * force_ops + RESIDUAL_NS * pattern.nnz + solve
    schur = rows * SCHUR_COLUMN_NS * factor_entries + DENSE_NS * 2 / 3 * rows ** 3
    jacobian = (KERNEL_NS * max(jacobian_ops - force_ops, 0.0) + ASSEMBLY_NS * entries
                + factorisation + (solve_call + schur if rows else 0.0))
    return jacobian / iteration
