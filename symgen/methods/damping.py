"""The ``damping_<variant>`` families: Kelvin-Voigt damping through the gram tensor Dm (its
own family, so undamped models never compile it), unrolled or looped."""

from __future__ import annotations

from symgen import derive
from symgen.element import ElementSpec
from symgen.ir import Array, Kernel, Loop, Temporaries, ref
from symgen.methods.common import (
    DAMPING_KERNELS,
    coordinate_arrays,
    gram_gradient,
    gram_linear,
    gram_linear_arrays,
    loop_tables,
    looped,
    looped_start,
    materialize,
    relative_velocities,
    store,
    store_symmetric,
    translate,
)


def damping_arrays(spec: ElementSpec, name: str) -> tuple[Array, list[Array]]:
    """The e_dot input, alpha, and the outputs of a damping kernel ``name``."""
    e_dot = Array("e_dot", spec.ndof, "batch", "element velocities de/dt, node-major")
    alpha = Array("alpha", 1, "shared", "Kelvin-Voigt damping coefficient alpha (s)")
    force_doc = {"damping_force": "damping force -alpha int (deps/de)^T D eps_dot dV0 (N)",
                 "damped_force_jacobians": "elastic plus damping force (N)"}
    outputs = [Array("force", spec.ndof, "output", force_doc[name])]
    if name != "damping_force":
        outputs += [Array("jacobian", spec.ndof**2, "output",
                          "d(elastic plus damping force)/de (N/m), row-major ndof x ndof"),
                    Array("jacobian_dot", spec.ndof**2, "output",
                          "d(elastic plus damping force)/d(e_dot) (N s/m), row-major ndof x "
                          "ndof")]
    return e_dot, [alpha, *outputs]


def gram_damping_kernel(spec: ElementSpec, name: str, variant: str,
                        bending: str = "simple") -> Kernel:
    """Kelvin-Voigt damping through the gram invariant: the dissipation is alpha gd^T Dm gd
    with gd = dG/dt = Qdot Q^T + Q Qdot^T (upper), so with hd = Dm (alpha gd) the damping
    force is -T'(hd) Q, d/de_dot = -2 alpha Gamma^T Dm Gamma and d/de = -(2 alpha Gamma^T Dm
    Gammadot + T'(hd) kron I) (Gammadot = Gamma of Qdot).  The one-pass kernel uses
    h = Dm (g + alpha gd) for the elastic plus damping force and its Jacobian.  An energy
    with a linear term c (the cable's bending, ``symgen.energies``) adds c to h of the
    one-pass kernel, and its damping -alpha T'(c) Qdot to the force and -alpha T'(c) kron I
    to d/de_dot."""
    d, n, ndof = spec.dim, spec.n_shape, spec.ndof
    pattern = derive.patterns(spec, variant)
    e_dot, tail = damping_arrays(spec, name)
    arrays = [*coordinate_arrays(spec, True), e_dot,
              Array("gram", len(pattern.gram), "shared", "gram matrix Dm, gram-pattern order"),
              *gram_linear_arrays(spec, "shared", bending), *tail]
    temps = Temporaries()
    body: list = []
    q, q0, dq = translate(spec, body, temps, with_reference=True)
    qd = relative_velocities(spec)
    alpha = ref("alpha", 0)
    pairs = derive.pairs(n)
    pidx = derive.pair_index(n)
    node = lambda vec, k: [vec[k * d + c] for c in range(d)]  # noqa: E731
    combined = name == "damped_force_jacobians"
    gd = materialize(body, temps, [
        alpha * sum(a * b + c * e for a, b, c, e in
                    zip(node(qd, k), node(q, m), node(q, k), node(qd, m), strict=True))
        for k, m in pairs])
    if combined:
        g = materialize(body, temps, [
            sum(a0 * b1 + a1 * b2 for a0, b1, a1, b2 in
                zip(node(q0, k), node(dq, m), node(dq, k), node(q, m), strict=True))
            for k, m in pairs])
        strain = materialize(body, temps, [x + y for x, y in zip(g, gd, strict=True)])
    else:
        strain = gd
    dm = {}
    for v, (a, b) in enumerate(pattern.gram):
        dm[(a, b)] = dm[(b, a)] = ref("gram", v)
    linear = gram_linear(spec, bending)
    hvec = materialize(body, temps, [
        sum(dm[(a, b)] * strain[b] for b in range(len(pairs)) if (a, b) in dm)
        + (linear[a] if combined else 0) for a in range(len(pairs))])

    def tprime(k: int, m: int, vec=hvec):
        return (4 if k == m else 2) * vec[pidx[(k, m)]]

    doc = {"damping_force": "Kelvin-Voigt damping force -T'(Dm alpha gd) Q",
           "damped_force_jacobians": "elastic plus damping force and its Jacobians with "
           "respect to e and e_dot, in one pass"}[name]
    kernel = Kernel(name, doc + " (gram form).", arrays, body)
    store(body, "force", [-sum(tprime(k, m) * q[m * d + c]
                               + alpha * tprime(k, m, linear) * qd[m * d + c]
                               for m in range(n)) for k in range(n) for c in range(d)])
    if name == "damping_force":
        return kernel

    def gamma(vec, a: int, p: int, c: int):
        """d g_a / d Q_pc with the matrix ``vec`` for Q (Gamma, or Gammadot with Qdot)."""
        return gram_gradient(vec, pairs, d, a, p, c)

    def dm_times(vec, scale):
        exprs = {}
        for a in range(len(pairs)):
            for p in range(n):
                for c in range(d):
                    exprs[(a, p, c)] = scale * sum(
                        dm[(a, b)] * gamma(vec, b, p, c) for b in range(len(pairs))
                        if (a, b) in dm and p in pairs[b])
        return dict(zip(exprs, materialize(body, temps, list(exprs.values())), strict=True))

    w = dm_times(q, 1)              # Dm Gamma
    wd = dm_times(qd, alpha)        # Dm alpha Gammadot

    def gamma_t(other, i: int, j: int):
        (p, b), (qn, c) = divmod(i, d), divmod(j, d)
        return sum(gamma(q, a, p, b) * other[(a, qn, c)] for a in range(len(pairs))
                   if p in pairs[a])

    material = dict(zip(derive.pairs(ndof), materialize(
        body, temps, [gamma_t(w, i, j) for i, j in derive.pairs(ndof)]), strict=True))
    full = []
    for i in range(ndof):
        for j in range(ndof):
            (p, b), (qn, c) = divmod(i, d), divmod(j, d)
            value = 2 * gamma_t(wd, i, j) + 2 * material[(min(i, j), max(i, j))]
            if b == c:
                value += tprime(p, qn)
            full.append(-value)
    store(body, "jacobian", materialize(body, temps, full))
    upper = {(i, j): -alpha * (2 * value + (tprime(i // d, j // d, linear)
                                            if i % d == j % d else 0))
             for (i, j), value in material.items()}
    names = materialize(body, temps, list(upper.values()))
    store_symmetric(body, "jacobian_dot", ndof, dict(zip(upper, names, strict=True)), False)
    return kernel


def looped_damping_kernel(spec: ElementSpec, name: str, variant: str) -> Kernel:
    """``gram_damping_kernel`` as tight loops (large elements): gd = alpha (Qd Q^T + Q Qd^T),
    h = Dm (gd [+ g]), force -T'(h) Q, d/de = -(2 Gamma^T Dm (alpha Gammadot [+ Gamma])
    + T'(h) kron I), d/de_dot = -2 alpha Gamma^T Dm Gamma."""
    npairs, ndof = len(derive.pairs(spec.n_shape)), spec.ndof
    pattern = derive.patterns(spec, variant)
    e_dot, tail = damping_arrays(spec, name)
    alpha = ref("alpha", 0)
    combined = name == "damped_force_jacobians"
    body: list = []
    local = looped_start(spec, body, velocities=True)
    local += [Array("strain", npairs, "local", "alpha dG/dt (+ DeltaG), upper triangle"),
              Array("h", npairs, "local", "Dm strain")]
    body += [Loop("zero", "strain", (npairs,)), Loop("pair_products", "strain", ("QD", "Q"), alpha),
             Loop("pair_products", "strain", ("Q", "QD"), alpha)]
    if combined:
        body += [Loop("pair_products", "strain", ("Q0", "DQ")),
                 Loop("pair_products", "strain", ("DQ", "Q"))]
    body += [Loop("zero", "h", (npairs,)), Loop("sym_pattern", "h", ("gram", "strain"))]
    body.append(Loop("pair_force", "force", ("h", "Q"), -1))
    if combined:
        local.append(Array("W", npairs * ndof, "local", "Dm Gamma, then Dm (Gamma + alpha "
                           "Gammadot)"))
        body += [Loop("zero", "W", (npairs * ndof,)), Loop("gamma", "W", ("gram", "Q")),
                 Loop("gamma_t", "jacobian_dot", ("Q", "W"), -2 * alpha),
                 Loop("gamma", "W", ("gram", "QD"), alpha),
                 Loop("gamma_t", "jacobian", ("Q", "W"), -2),
                 Loop("kron_pair", "jacobian", ("h",), -1)]
    doc = {"damping_force": "Kelvin-Voigt damping force -T'(Dm alpha gd) Q",
           "damped_force_jacobians": "elastic plus damping force and its Jacobians with "
           "respect to e and e_dot, in one pass"}[name]
    arrays = [*coordinate_arrays(spec, True), e_dot,
              Array("gram", len(pattern.gram), "shared", "gram matrix Dm, gram-pattern order"),
              *tail, *local]
    return Kernel(name, doc + " (gram form, looped).", arrays, body,
                  loop_tables(spec, variant))


def build(spec: ElementSpec, variant: str) -> list[Kernel]:
    """The kernels of the ``damping_<variant>`` family, looped where ``looped`` says so."""
    builder = looped_damping_kernel if looped(spec, "damping", variant) else gram_damping_kernel
    return [builder(spec, name, variant) for name in DAMPING_KERNELS]
