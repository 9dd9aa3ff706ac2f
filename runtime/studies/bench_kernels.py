"""``ancf bench kernels``: per-element cost of every method x backend, with operation counts."""

from __future__ import annotations

import functools
import time

import numpy as np

from runtime.catalog import BACKENDS, DEFAULT_LAW, METHODS, family_name, generated_kinds
from runtime.element.element import Element
from runtime.kernels.kind import element_kind
from runtime.progress import Bar

#: The paper's operation counts per element force (section 7): with and without invariants.
PAPER_OPERATIONS = {"cij": 5.52e4, "quadrature": 9.16e6}
QUANTITIES = {"force": "elastic_force", "jacobian": "elastic_jacobian",
              "energy": "strain_energy", "force_jacobian": "elastic_force_and_jacobian"}


def seconds_per_call(function, argument, budget_s: float = 0.2, repeats: int = 5) -> float:
    """Best-of-``repeats`` wall time of one call, each repeat looping for about budget_s/repeats."""
    function(argument)
    start = time.perf_counter()
    function(argument)
    once = max(time.perf_counter() - start, 1e-7)
    loops = max(1, int(budget_s / repeats / once))
    best = float("inf")
    for _ in range(repeats):
        start = time.perf_counter()
        for _ in range(loops):
            function(argument)
        best = min(best, (time.perf_counter() - start) / loops)
    return best


def configurations(element: Element, batch: int, seed: int = 0) -> np.ndarray:
    """``batch`` random large-rotation configurations of ``element`` (batch, ndof)."""
    rng = np.random.default_rng(seed)
    kind = element.kind
    q0 = element.e0.reshape(kind.n_shape, kind.dim)
    out = np.empty((batch, kind.ndof))
    for i in range(batch):
        rotation, _ = np.linalg.qr(rng.normal(size=(kind.dim, kind.dim)))
        rotation *= np.sign(np.linalg.det(rotation))
        q = q0 @ rotation.T + rng.normal(scale=1e-2, size=q0.shape)
        out[i] = q.ravel()
    return out


def measure(kind: str, batches=(1, 10_000), methods=METHODS, backends=BACKENDS,
            budget_s: float = 0.2) -> list[dict]:
    """Rows {method, backend, batch, force_us, jacobian_us, energy_us} in microseconds/element."""
    rows = []
    runs = [(backend, method) for backend in backends for method in methods]
    with Bar(f"bench kernels {kind}", len(runs), "cases") as bar:
        for backend, method in runs:
            rows += _measure_one(kind, method, backend, batches, budget_s)
            bar.advance(f"{method} {backend}")
    return rows


def _measure_one(kind: str, method: str, backend: str, batches, budget_s: float) -> list[dict]:
    """The rows of ``measure`` of one method and backend."""
    rows = []
    element = Element(kind, 1.0, 0.1, 0.1, 2.1e11, 0.3, 7800.0, method=method,
                      backend=backend)
    for batch in batches:
        e = configurations(element, batch)
        argument = e[0] if batch == 1 else e
        row = {"method": method, "backend": backend, "batch": batch}
        for quantity, name in QUANTITIES.items():
            method_ = getattr(element, name)
            if quantity == "force_jacobian":
                # a simulation reuses its buffers: keep page faults out of the timing
                force, jacobian = (np.empty_like(x) for x in method_(argument))
                method_ = functools.partial(method_, out_force=force, out_jacobian=jacobian)
            elif quantity != "energy":
                method_ = functools.partial(method_, out=np.empty_like(method_(argument)))
            per_call = seconds_per_call(method_, argument, budget_s)
            row[f"{quantity}_us"] = per_call / batch * 1e6
        rows.append(row)
    return rows


def family_of(method: str) -> str:
    """Kernel family of a method for straight elements of the default law."""
    return family_name(method, DEFAULT_LAW, "straight")


def table(kind: str, rows: list[dict]) -> str:
    """Markdown table of ``rows`` for one kind, with operation counts and ratios."""
    meta = element_kind(kind)
    lines = [f"### {kind} (straight, {meta.ndof} coordinates)", "",
             "| method | backend | batch | force us/el | jacobian us/el | energy us/el | "
             "force+jacobian us/el | force ops/el | jacobian ops/el | energy ops/el | "
             "force+jacobian ops/el |",
             "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for row in rows:
        family = family_of(row["method"])
        ops = [meta.operations(family, q) for q in QUANTITIES]
        lines.append(
            f"| {row['method']} | {row['backend']} | {row['batch']} | {row['force_us']:.4g} | "
            f"{row['jacobian_us']:.4g} | {row['energy_us']:.4g} | "
            f"{row['force_jacobian_us']:.4g} | {' | '.join(map(str, ops))} |")
    lines.append("")
    by_key = {(r["method"], r["backend"], r["batch"]): r for r in rows}
    for backend in sorted({r["backend"] for r in rows}):
        for batch in sorted({r["batch"] for r in rows}):
            gram, quad = by_key.get(("gram", backend, batch)), by_key.get(
                ("quadrature", backend, batch))
            if gram and quad:
                ratios = ", ".join(f"{q} {quad[f'{q}_us'] / gram[f'{q}_us']:.1f}x"
                                   for q in QUANTITIES)
                lines.append(f"- quadrature/gram time ratio, {backend}, batch {batch}: {ratios}")
    for batch in sorted({r["batch"] for r in rows}):
        slow, fast = by_key.get(("gram", "numpy", batch)), by_key.get(("gram", "c", batch))
        if slow and fast:
            lines.append(f"- numpy/C time ratio for gram force, batch {batch}: "
                         f"{slow['force_us'] / fast['force_us']:.1f}x")
    lines.append(f"- operations per element force: paper with invariants "
                 f"{PAPER_OPERATIONS['cij']:.3g}, without {PAPER_OPERATIONS['quadrature']:.3g}; "
                 f"here cij {meta.operations(family_of('cij'), 'force')}, gram "
                 f"{meta.operations(family_of('gram'), 'force')}, quadrature "
                 f"{meta.operations(family_of('quadrature'), 'force')}")
    return "\n".join(lines) + "\n"


#: coordinates of the element whose kernels are timed at the full ``batch``; larger elements
#: (the plate: 48) at a batch smaller by the square of the ratio, for a similar run time
BATCH_NDOF = 24


def run(kinds=None, batch: int = 10_000, methods=METHODS, backends=BACKENDS) -> str:
    """Benchmark every generated kind at batch 1 and ``batch`` (scaled down by
    (BATCH_NDOF / ndof)^2 for larger elements); returns the Markdown report."""
    parts = []
    for kind in kinds or generated_kinds():
        ndof = element_kind(kind).ndof
        size = batch if ndof <= BATCH_NDOF else max(1, int(batch * (BATCH_NDOF / ndof) ** 2))
        rows = measure(kind, batches=(1, size), methods=methods, backends=backends)
        parts.append(table(kind, rows))
    return "\n".join(parts)
