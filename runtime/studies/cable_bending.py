"""The two bending models of the ANCF cable (``symgen/energies.py``: the simple
``EI/2 int r_xx . r_xx dx`` of law ``svk`` and the exact curvature of law
``svk_exact_curvature``) on the elastica of ``ancf bench precision`` (P L^2 / EI = 10, L / h =
200): the tip error against the exact elastica by element count, and Exudyn's ANCFCable2D
(exact curvature too) on the same meshes.

``python -m runtime.studies.cable_bending elastica [counts...]`` prints the elastica table of
docs/laws.md, ``... costs`` the kernel costs of both models (``kernel_costs``).
"""

from __future__ import annotations

import functools
import sys
import time

import numpy as np

from runtime import (
    Body,
    Clamp,
    Displacement,
    Element,
    Material,
    PointForce,
    Scene,
    Static,
    run_scene,
)
from runtime.catalog import METHODS, generated_kinds
from runtime.kernels.kind import element_kind
from runtime.studies import peers
from runtime.studies.bench_kernels import configurations
from runtime.studies.precision import elastica
from runtime.studies.precision.plan import ELASTICA

#: Young's modulus of the study (Pa); the tip displacement over L depends on P L^2 / EI and
#: on the (tiny) axial strain P / EA only.
YOUNG = 2.1e11
#: Element counts of the table.
COUNTS = (4, 8, 16, 32)
#: Load steps of every static solve (the project's and Exudyn's).
LOAD_STEPS = 20


def tip_force() -> float:
    """The tip force P (N) with P L^2 / EI = ELASTICA's alpha, EI = E w h^3 / 12."""
    inertia = ELASTICA["width"] * ELASTICA["height"] ** 3 / 12.0
    return ELASTICA["alpha"] * YOUNG * inertia / ELASTICA["length"] ** 2


def cable_tip(law: str, elements: int, quadrature: int | None = None) -> tuple[float, float]:
    """(x, y) tip displacement (m) of a clamped ``cable2d`` cantilever of ``elements`` elements
    with material law ``law`` (Gauss order ``quadrature`` along the axis, default the kind's)
    under the fixed tip force -P y, static in LOAD_STEPS increments."""
    length, h, w = ELASTICA["length"], ELASTICA["height"], ELASTICA["width"]
    material = Material("steel", YOUNG, 0.0, 7800.0, law=law)
    orders = None if quadrature is None else (quadrature, 1)
    scene = Scene(title="elastica", materials=[material],
                  bodies=[Body("cable", "cable2d", "steel", h, w, elements, (0.0, 0.0),
                               (length, 0.0), quadrature=orders)],
                  constraints=[Clamp("cable:0")],
                  loads=[PointForce("cable:-1", (0.0, -tip_force()))],
                  sensors=[Displacement("tip_x", "cable:-1", "x"),
                           Displacement("tip_y", "cable:-1", "y")],
                  static=Static(load_steps=LOAD_STEPS))
    result = run_scene(scene, progress=False)
    if result.status != "ok":
        raise RuntimeError(f"elastica with {elements} x cable2d ({law}): {result.status}")
    values = result.summary["static"]["sensors"]
    return values["tip_x"], values["tip_y"]


def exudyn_tip(elements: int) -> tuple[float, float]:
    """(x, y) tip displacement (m) of the same cantilever as Exudyn ANCFCable2D elements."""
    run = peers.exudyn_elastica(elements, LOAD_STEPS, length=ELASTICA["length"],
                                height=ELASTICA["height"], width=ELASTICA["width"],
                                E=YOUNG, force=(0.0, -tip_force()))
    return run.tip


def error(tip: tuple[float, float]) -> float:
    """max(|x - exact x|, |y - exact y|) / L against the exact elastica."""
    u, w = elastica.by_quadrature(ELASTICA["alpha"])
    length = ELASTICA["length"]
    return max(abs(tip[0] + u * length), abs(tip[1] + w * length)) / length


def table(counts=COUNTS) -> str:
    """The markdown table: per element count the error of both bending models (the exact
    curvature with the kind's 5 Gauss points along the axis and with Exudyn's 3), of Exudyn's
    ANCFCable2D (when installed) and the distance between the 3-point exact-curvature tip
    and Exudyn's (over L)."""
    peer = peers.exudyn_available()
    head = "| elements | simple (svk) | exact curvature | exact curvature, 3 points | " + (
        "Exudyn ANCFCable2D | exact curvature (3 points) - Exudyn |" if peer else "")
    lines = [head, "|" + "---:|" * (head.count("|") - 1)]
    for n in counts:
        exact3 = cable_tip("svk_exact_curvature", n, quadrature=3)
        row = (f"| {n} | {error(cable_tip('svk', n)):.2e} | "
               f"{error(cable_tip('svk_exact_curvature', n)):.2e} | {error(exact3):.2e} |")
        if peer:
            theirs = exudyn_tip(n)
            gap = max(abs(a - b) for a, b in zip(exact3, theirs, strict=True))
            row += f" {error(theirs):.2e} | {gap / ELASTICA['length']:.1e} |"
        lines.append(row)
    return "\n".join(lines) + "\n"


def kernel_costs(kinds=None, batch: int = 10_000, repeats: int = 15) -> str:
    """Markdown table of the force + Jacobian cost (us per element, C backend, ``batch``
    large-rotation configurations) of every method with the simple bending and with the
    exact curvature at 5 and 3 Gauss points, for ``kinds`` (default every cable kind): the
    min over ``repeats`` rounds that run every case once each (interleaved, so a load of the
    machine hits all cases alike)."""
    lines = ["| kind | method | svk (simple) | svk_exact_curvature, 5 points | 3 points |",
             "|---|---|---:|---:|---:|"]
    cables = [k for k in generated_kinds() if element_kind(k).energy.structural]
    for kind in kinds or cables:
        cases, ones = {}, (1,) * (element_kind(kind).dim - 1)
        for method in METHODS:
            for law, order in (("svk", 5), ("svk_exact_curvature", 5),
                               ("svk_exact_curvature", 3)):
                element = Element(kind, 1.0, 0.1, 0.1, 2.1e11, 0.3, 7800.0, method=method,
                                  law=law, quadrature=(order, *ones))
                e = configurations(element, batch)
                force, jacobian = (np.empty_like(x)
                                   for x in element.elastic_force_and_jacobian(e))
                cases[(method, law, order)] = functools.partial(
                    element.elastic_force_and_jacobian, e, out_force=force,
                    out_jacobian=jacobian)
        best = dict.fromkeys(cases, float("inf"))
        for _ in range(repeats):
            for key, run in cases.items():
                start = time.perf_counter()
                run()
                best[key] = min(best[key], time.perf_counter() - start)
        for method in METHODS:
            us = [best[(method, law, order)] / batch * 1e6 for law, order in
                  (("svk", 5), ("svk_exact_curvature", 5), ("svk_exact_curvature", 3))]
            lines.append(f"| {kind} | {method} | " + " | ".join(f"{u:.2g}" for u in us) + " |")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    if sys.argv[1:2] == ["costs"]:
        print(kernel_costs())
    else:
        print(table(tuple(int(a) for a in sys.argv[2:]) or COUNTS))
