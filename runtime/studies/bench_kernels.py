"""``ancf bench kernels``: per-element cost of every method x backend, with operation counts;
for cable kinds, of each bending model (every law of the kind: the simple model of ``svk`` and
the exact curvature by quadrature of ``svk_exact_curvature``)."""

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
#: What is timed, by the Element method timed (the Jacobian alone is the combined kernel's).
QUANTITIES = {"force": "elastic_force", "energy": "strain_energy",
              "force_jacobian": "elastic_force_and_jacobian"}


def seconds_per_call(function, argument, budget_s: float = 0.2, repeats: int = 5) -> float:
    """Best-of-``repeats`` wall time of one call, each repeat looping for about budget_s/repeats.
    The first call is timed too: a call longer than the budget is repeated once and the
    better of the two taken (the brick's NumPy quadrature at batch 625 takes seconds a
    call), one longer than a repeat's share counts among the repeats."""
    start = time.perf_counter()
    function(argument)
    first = max(time.perf_counter() - start, 1e-7)
    loops = max(1, int(budget_s / repeats / first))
    repeats = min(repeats, max(1, int(budget_s / first)))
    best = first if loops == 1 else float("inf")
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


def benched_laws(kind: str) -> list[str]:
    """The laws benchmarked for ``kind``: each bending model of a cable (its laws), the
    default law of a continuum."""
    meta = element_kind(kind)
    return list(meta.laws) if meta.energy.structural else [DEFAULT_LAW]


def measure(kind: str, batches=(1, 10_000), methods=METHODS, backends=BACKENDS,
            budget_s: float = 0.2) -> list[dict]:
    """Rows {method, law, backend, batch, force_us, energy_us, force_jacobian_us} in
    microseconds/element."""
    rows = []
    runs = [(backend, method, law) for backend in backends for method in methods
            for law in benched_laws(kind)]
    with Bar(f"bench kernels {kind}", len(runs), "cases") as bar:
        for backend, method, law in runs:
            rows += _measure_one(kind, method, backend, batches, budget_s, law)
            bar.advance(f"{method} {backend} {law}")
    return rows


def _measure_one(kind: str, method: str, backend: str, batches, budget_s: float,
                 law: str = DEFAULT_LAW) -> list[dict]:
    """The rows of ``measure`` of one method, backend and law."""
    rows = []
    element = Element(kind, 1.0, 0.1, 0.1, 2.1e11, 0.3, 7800.0, method=method,
                      backend=backend, law=law)
    for batch in batches:
        e = configurations(element, batch)
        argument = e[0] if batch == 1 else e
        row = {"method": method, "law": law, "backend": backend, "batch": batch}
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


def family_of(method: str, kind: str | None = None, law: str = DEFAULT_LAW) -> str:
    """Kernel family of a method for straight elements of ``law`` (the default law, or a law
    of ``kind``, whose bending model it reads)."""
    bending = element_kind(kind).laws[law].bending if kind is not None else None
    return family_name(method, law, "straight", bending=bending)


def table(kind: str, rows: list[dict]) -> str:
    """Markdown table of ``rows`` for one kind, with operation counts and ratios."""
    meta = element_kind(kind)
    laws = len({row.get("law", DEFAULT_LAW) for row in rows}) > 1
    lines = [f"### {kind} (straight, {meta.ndof} coordinates)", "",
             f"| method |{' law |' if laws else ''} backend | batch | force us/el | "
             "energy us/el | force+jacobian us/el | force ops/el | energy ops/el | "
             "force+jacobian ops/el |",
             f"|---|{'---|' if laws else ''}---|---:|---:|---:|---:|---:|---:|---:|"]
    rows = [row for row in rows if row.get("law", DEFAULT_LAW) == DEFAULT_LAW] + [
        row for row in rows if row.get("law", DEFAULT_LAW) != DEFAULT_LAW]
    for row in rows:
        law = row.get("law", DEFAULT_LAW)
        family = family_of(row["method"], kind, law)
        ops = [meta.operations(family, q) for q in QUANTITIES]
        lines.append(
            f"| {row['method']} |{f' {law} |' if laws else ''} {row['backend']} | "
            f"{row['batch']} | {row['force_us']:.4g} | {row['energy_us']:.4g} | "
            f"{row['force_jacobian_us']:.4g} | {' | '.join(map(str, ops))} |")
    lines.append("")
    by_key = {(r["method"], r["backend"], r["batch"]): r for r in rows
              if r.get("law", DEFAULT_LAW) == DEFAULT_LAW}
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
    for law in dict.fromkeys(r["law"] for r in rows if r.get("law", DEFAULT_LAW) != DEFAULT_LAW):
        other = {(r["method"], r["backend"], r["batch"]): r for r in rows
                 if r.get("law") == law}
        for (method, backend, batch), row in other.items():
            base = by_key.get((method, backend, batch))
            if base:
                lines.append(f"- {law}/{DEFAULT_LAW} time ratio, {method}, {backend}, batch "
                             f"{batch}: "
                             + ", ".join(f"{q} {row[f'{q}_us'] / base[f'{q}_us']:.1f}x"
                                         for q in ("force", "force_jacobian")))
    lines.append(f"- operations per element force: paper with invariants "
                 f"{PAPER_OPERATIONS['cij']:.3g}, without {PAPER_OPERATIONS['quadrature']:.3g}; "
                 f"here cij {meta.operations(family_of('cij'), 'force')}, gram "
                 f"{meta.operations(family_of('gram'), 'force')}, quadrature "
                 f"{meta.operations(family_of('quadrature'), 'force')}")
    return "\n".join(lines) + "\n"


#: coordinates of the element whose kernels are timed at the full ``batch``; larger elements
#: (the plate: 48) at a batch smaller by the square of the ratio, for a similar run time
BATCH_NDOF = 24


def run(kinds=None, batch: int = 10_000, methods=METHODS, backends=BACKENDS,
        budget_s: float = 0.2) -> str:
    """Benchmark every generated kind at batch 1 and ``batch`` (scaled down by
    (BATCH_NDOF / ndof)^2 for larger elements), each figure timed for about ``budget_s``
    seconds (``seconds_per_call``); returns the Markdown report."""
    parts = []
    for kind in kinds or generated_kinds():
        ndof = element_kind(kind).ndof
        size = batch if ndof <= BATCH_NDOF else max(1, int(batch * (BATCH_NDOF / ndof) ** 2))
        rows = measure(kind, batches=(1, size), methods=methods, backends=backends,
                       budget_s=budget_s)
        parts.append(table(kind, rows))
    return "\n".join(parts)
