"""The ``gram_<variant>`` families: the compact gram tensor Dm with U = g^T Dm g, g = DeltaG,
unrolled or as loops over pair tables (large elements)."""

from __future__ import annotations

from symgen import derive
from symgen.element import ElementSpec
from symgen.ir import Array, Kernel, Loop, Temporaries, ref
from symgen.methods.common import (
    KERNELS,
    coordinate_arrays,
    gram_gradient,
    gram_linear,
    gram_linear_arrays,
    kernel_name,
    loop_tables,
    looped,
    looped_start,
    materialize,
    quantity_output,
    store,
    store_symmetric,
    translate,
)


def gram_kernel(spec: ElementSpec, quantities, variant: str,
                bending: str = "simple") -> Kernel:
    """Gram form: g = DeltaG = Q0 dQ^T + dQ Q^T (upper), h = Dm g + c, U = g.(h + c),
    F = -T' Q, with c the linear term of energies that have one (the cable's bending,
    ``symgen.energies``; zero otherwise).

    T'_kk = 4 h_kk, T'_kl = 2 h_kl.  Jacobian: -(2 Gamma^T Dm Gamma + T' kron I) with
    Gamma = dg/de, built as W = Dm Gamma first.
    """
    d, n, ndof = spec.dim, spec.n_shape, spec.ndof
    pattern = derive.patterns(spec, variant)
    arrays = [*coordinate_arrays(spec, True),
              Array("gram", len(pattern.gram), "shared", "gram matrix Dm, gram-pattern order"),
              *gram_linear_arrays(spec, "shared", bending),
              *[quantity_output(spec, quantity) for quantity in quantities]]
    doc = {"energy": "strain energy U = g^T Dm g", "force": "elastic force F = -T' Q",
           "jacobian": "elastic Jacobian -(2 Gamma^T Dm Gamma + T' kron I)"}
    temps = Temporaries()
    body: list = []
    q, q0, dq = translate(spec, body, temps, with_reference=True)
    pairs = derive.pairs(n)
    pidx = derive.pair_index(n)
    node = lambda vec, k: [vec[k * d + c] for c in range(d)]  # noqa: E731
    g = materialize(body, temps, [
        sum(a0 * b1 + a1 * b2 for a0, b1, a1, b2 in
            zip(node(q0, k), node(dq, m), node(dq, k), node(q, m), strict=True))
        for k, m in pairs])
    dm = {}
    for v, (a, b) in enumerate(pattern.gram):
        dm[(a, b)] = dm[(b, a)] = ref("gram", v)
    linear = gram_linear(spec, bending)
    hvec = materialize(body, temps, [
        sum(dm[(a, b)] * g[b] for b in range(len(pairs)) if (a, b) in dm) + linear[a]
        for a in range(len(pairs))])
    kernel = Kernel(kernel_name(quantities),
                    "; ".join(doc[q] for q in quantities).capitalize() + ".", arrays, body)
    if "energy" in quantities:
        store(body, "energy", [sum(x * (y + c) for x, y, c in zip(g, hvec, linear,
                                                                  strict=True))])

    def tprime(k: int, m: int):
        return (4 if k == m else 2) * hvec[pidx[(k, m)]]

    if "force" in quantities:
        force = [-sum(tprime(k, m) * q[m * d + c] for m in range(n))
                 for k in range(n) for c in range(d)]
        store(body, "force", force)
    if "jacobian" not in quantities:
        return kernel

    def gamma(a: int, p: int, c: int):
        """d g_a / d Q_pc."""
        return gram_gradient(q, pairs, d, a, p, c)

    w_exprs = {}
    for a in range(len(pairs)):
        for p in range(n):
            for c in range(d):
                w_exprs[(a, p, c)] = sum(
                    dm[(a, b)] * gamma(b, p, c) for b in range(len(pairs))
                    if (a, b) in dm and p in pairs[b])
    w_names = dict(zip(w_exprs, materialize(body, temps, list(w_exprs.values())), strict=True))
    upper = {}
    for i, j in derive.pairs(ndof):
        (p, b), (qn, c) = divmod(i, d), divmod(j, d)
        value = 2 * sum(gamma(a, p, b) * w_names[(a, qn, c)] for a in range(len(pairs))
                        if p in pairs[a])
        if b == c:
            value += tprime(p, qn)
        upper[(i, j)] = -value
    names = materialize(body, temps, list(upper.values()))
    store_symmetric(body, "jacobian", ndof, dict(zip(upper, names, strict=True)), False)
    return kernel


def looped_gram_kernel(spec: ElementSpec, quantities, variant: str) -> Kernel:
    """``gram_kernel`` as tight loops over the pair and pattern tables (large elements):
    g = Q0 dQ^T + dQ Q^T, h = Dm g, U = g.h, F = -T'(h) Q,
    J = -(2 Gamma^T (Dm Gamma) + T'(h) kron I)."""
    npairs = len(derive.pairs(spec.n_shape))
    pattern = derive.patterns(spec, variant)
    body: list = []
    local = looped_start(spec, body, velocities=False)
    local += [Array("g", npairs, "local", "DeltaG, upper triangle"),
              Array("h", npairs, "local", "Dm g")]
    body += [Loop("zero", "g", (npairs,)), Loop("pair_products", "g", ("Q0", "DQ")),
             Loop("pair_products", "g", ("DQ", "Q")), Loop("zero", "h", (npairs,)),
             Loop("sym_pattern", "h", ("gram", "g"))]
    if "energy" in quantities:
        body.append(Loop("dot", "energy", ("g", "h", npairs)))
    if "force" in quantities:
        body.append(Loop("pair_force", "force", ("h", "Q"), -1))
    if "jacobian" in quantities:
        local.append(Array("W", npairs * spec.ndof, "local", "Dm Gamma"))
        body += [Loop("zero", "W", (npairs * spec.ndof,)), Loop("gamma", "W", ("gram", "Q")),
                 Loop("gamma_t", "jacobian", ("Q", "W"), -2),
                 Loop("kron_pair", "jacobian", ("h",), -1)]
    doc = {"energy": "strain energy U = g^T Dm g", "force": "elastic force F = -T' Q",
           "jacobian": "elastic Jacobian -(2 Gamma^T Dm Gamma + T' kron I)"}
    arrays = [*coordinate_arrays(spec, True),
              Array("gram", len(pattern.gram), "shared", "gram matrix Dm, gram-pattern order"),
              *[quantity_output(spec, quantity) for quantity in quantities], *local]
    return Kernel(kernel_name(quantities),
                  "; ".join(doc[q] for q in quantities).capitalize() + " (looped).", arrays,
                  body, loop_tables(spec, variant))


def build(spec: ElementSpec, variant: str) -> list[Kernel]:
    """The kernels of the ``gram_<variant>`` family, looped where ``looped`` says so."""
    builder = looped_gram_kernel if looped(spec, "gram", variant) else gram_kernel
    return [builder(spec, quantities, variant) for quantities in KERNELS]
