"""The ``cij`` family: the paper's invariants C^ij, K1, U0 (eqs. 27-41); the storage pattern
only changes the sparse operators built at run time."""

from __future__ import annotations

import sympy as sp

from symgen import derive
from symgen.element import ElementSpec
from symgen.ir import Array, Assign, Kernel, Loop, SparseProduct, Temporaries, ref, refs
from symgen.methods.common import (
    KERNELS,
    coordinate_arrays,
    kernel_name,
    loop_tables,
    looped,
    materialize,
    quantity_output,
    store,
    translate,
)


def cij_sizes(spec: ElementSpec, variant: str) -> dict[str, int]:
    """Rows and structural nonzeros of the two sparse operators of the cij method."""
    d = spec.dim
    pattern = derive.patterns(spec, variant)
    k2 = sum(d * d if k < p else d * (d + 1) // 2 for k, p, _, _ in pattern.cij)
    jac = sum(4 * d * d if k < p else 2 * d * d for k, p, _, _ in pattern.cij)
    return {"k2_rows": len(derive.pairs(spec.ndof)), "k2_nnz": k2,
            "jacobian_rows": spec.ndof**2, "jacobian_nnz": jac,
            "products": len(derive.pairs(spec.ndof))}


def cij_kernel(spec: ElementSpec, quantities, variant: str = "straight") -> Kernel:
    """The paper's method: (K2)_ij = e^T C^ij e, F = -(K2 + K1) e, eq. 38, eq. 39.

    K2 (upper triangle) and the double sum of eq. 38 are sparse products of shared CSR
    operators, assembled from the stored C^ij once per element set, with the vector of
    coordinate products p_st = e_s e_t (s <= t).
    """
    d, n, ndof = spec.dim, spec.n_shape, spec.ndof
    sizes = cij_sizes(spec, variant)
    npairs_dof = sizes["k2_rows"]
    arrays = [*coordinate_arrays(spec, False),
              Array("k1", len(derive.pairs(n)), "shared", "shape-level K1, upper triangle"),
              Array("u0", 1, "shared", "U0 (J)"),
              Array("k2_matrix", npairs_dof, "csr",
                    "maps coordinate products p to the upper triangle of K2"),
              Array("products", npairs_dof, "local", "p_st = e_s e_t, s <= t"),
              Array("k2", npairs_dof, "local", "upper triangle of K2(e)")]
    if "jacobian" in quantities:
        arrays.append(Array("jacobian_matrix", ndof * ndof, "csr",
                            "maps p to sum_j sum_s e_s (C^ij + C^ij^T)_sk e_j of eq. 38"))
        arrays.append(Array("second", ndof * ndof, "local", "the double sum of eq. 38"))
    arrays += [quantity_output(spec, quantity) for quantity in quantities]
    if looped(spec):
        return _looped_cij_kernel(spec, quantities, variant, arrays)
    temps = Temporaries()
    body: list = []
    q, _, _ = translate(spec, body, temps, with_reference=False)
    for a, (s, t) in enumerate(derive.pairs(ndof)):
        body.append(Assign(f"products[{a}]", sp.sympify(q[s] * q[t])))
    body.append(SparseProduct("k2", "k2_matrix", "products", npairs_dof, sizes["k2_nnz"]))
    pidx_dof, pidx = derive.pair_index(ndof), derive.pair_index(n)
    k1 = refs("k1", len(derive.pairs(n)))

    def k1_entry(i: int, j: int):
        (k, ca), (p, cb) = divmod(i, d), divmod(j, d)
        return k1[pidx[(k, p)]] if ca == cb else 0

    k2 = refs("k2", npairs_dof)
    doc = {"energy": "strain energy by eq. 39", "force": "elastic force F = -(K2(e) + K1) e, "
           "eqs. 25-35", "jacobian": "elastic Jacobian by eq. 38"}
    kernel = Kernel(kernel_name(quantities),
                    "; ".join(doc[q] for q in quantities).capitalize() + ".", arrays, body)
    if "energy" in quantities:
        quartic = sum((1 if i == j else 2) * q[i] * k2[pidx_dof[(i, j)]] * q[j]
                      for i, j in derive.pairs(ndof))
        quadratic = sum((1 if i == j else 2) * q[i] * k1_entry(i, j) * q[j]
                        for i, j in derive.pairs(ndof))
        store(body, "energy", [quartic / 4 + quadratic / 2 + ref("u0", 0)])
        if quantities == ("energy",):
            return kernel
    stiffness = materialize(body, temps, [k2[pidx_dof[(i, j)]] + k1_entry(i, j)
                                           for i, j in derive.pairs(ndof)])
    if "force" in quantities:
        force = [-sum(stiffness[pidx_dof[(i, j)]] * q[j] for j in range(ndof))
                 for i in range(ndof)]
        store(body, "force", force)
    if "jacobian" not in quantities:
        return kernel
    body.append(SparseProduct("second", "jacobian_matrix", "products", ndof * ndof,
                              sizes["jacobian_nnz"]))
    second = refs("second", ndof * ndof)
    store(body, "jacobian", [-stiffness[pidx_dof[(i, k)]] - second[i * ndof + k]
                              for i in range(ndof) for k in range(ndof)])
    return kernel


def _looped_cij_kernel(spec: ElementSpec, quantities, variant: str, arrays: list) -> Kernel:
    """``cij_kernel`` with its coordinate-level parts as loops (large elements): the products
    p_st, K2 = k2_matrix p and the double sum of eq. 38 as sparse products, force, Jacobian
    and energy as loops over the coordinates."""
    ndof = spec.ndof
    sizes = cij_sizes(spec, variant)
    temps = Temporaries()
    body: list = []
    q, _, _ = translate(spec, body, temps, with_reference=False)
    for i, value in enumerate(q):
        body.append(Assign(f"Q[{i}]", sp.sympify(value)))
    body.append(Loop("dof_products", "products", ("Q",)))
    body.append(SparseProduct("k2", "k2_matrix", "products", sizes["k2_rows"],
                              sizes["k2_nnz"]))
    if "energy" in quantities:
        body.append(Loop("cij_energy", "energy", ("Q", "k2", "k1", "u0")))
    if "force" in quantities:
        body.append(Loop("cij_force", "force", ("Q", "k2", "k1"), -1))
    if "jacobian" in quantities:
        body.append(SparseProduct("second", "jacobian_matrix", "products", ndof * ndof,
                                  sizes["jacobian_nnz"]))
        body.append(Loop("cij_jacobian", "jacobian", ("k2", "k1", "second"), -1))
    doc = {"energy": "strain energy by eq. 39", "force": "elastic force F = -(K2(e) + K1) e, "
           "eqs. 25-35", "jacobian": "elastic Jacobian by eq. 38"}
    arrays = [*arrays, Array("Q", ndof, "local", "coordinates relative to the first node")]
    return Kernel(kernel_name(quantities),
                  "; ".join(doc[q] for q in quantities).capitalize() + " (looped).", arrays,
                  body, loop_tables(spec, "straight"))


def build(spec: ElementSpec) -> list[Kernel]:
    """The kernels of the ``cij`` family."""
    return [cij_kernel(spec, quantities, "straight") for quantities in KERNELS]
