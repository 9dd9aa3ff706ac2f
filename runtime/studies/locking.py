"""Convergence of clamped cantilevers against beam theory, per element kind and material law:
the locking of the fully parameterised beams and its remedy (docs/laws.md, ``ecm_sri``).

Two cases, each for 2, 4, 8, 16 and 32 elements:

* ``elastica``: a tip load ``P L^2 / EI = 10`` (large deflection, L/h = 100, nu = 0, static
  with load steps) against the inextensible elastica, the boundary-value problem
  ``theta'' = -alpha cos(theta)`` solved here with SciPy (Mattiasson 1981 tabulates
  ``v/L = 0.81061`` at alpha = 10);
* ``linear``: a small tip load (tip deflection 1e-4 L, L/h = 50) against ``P L^3 / 3EI``, at
  nu = 0 and nu = 0.3.

``python -m runtime.studies.locking [--kinds K,...] [--laws L,...] [--cases C,...]`` prints
the markdown table of the relative errors of the tip deflection (default: every law of the
kinds the remedies apply to, the 2-node beams: svk, ecm, ecm_sri and the elastic line).
``--cable`` adds the rows of the gradient-deficient cable of the same dimension (law svk,
its simple bending), the element the elastic line is compared with.
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_bvp

ELEMENTS = (2, 4, 8, 16, 32)
#: the remedy (docs/laws.md): its kinds and laws are the study's defaults
REMEDY = "ecm_sri"
E_MODULUS, RHO, LENGTH = 2.1e11, 7800.0, 1.0      # Pa, kg/m^3, m
#: (slenderness L/h, nu, load parameter P L^2 / EI, load steps) of each case
CASES = {"elastica": (100.0, 0.0, 10.0, 20), "linear": (50.0, 0.0, 3e-4, 1),
         "linear_nu03": (50.0, 0.3, 3e-4, 1)}


def elastica(alpha: float) -> tuple[float, float]:
    """(v/L, u/L): transverse and axial tip displacement of the inextensible cantilever under
    the dead tip load ``alpha = P L^2 / EI``, from ``theta'' = -alpha cos(theta)``,
    ``theta(0) = 0``, ``theta'(L) = 0`` (arc length s/L in [0, 1])."""
    def rates(s, y):
        return np.vstack([y[1], -alpha * np.cos(y[0]), np.sin(y[0]), np.cos(y[0])])

    def ends(start, end):
        return np.array([start[0], end[1], start[2], start[3]])

    s = np.linspace(0.0, 1.0, 201)
    guess = np.vstack([alpha / 2 * s * (2 - s), alpha / 2 * (2 - 2 * s), s * s, s])
    solution = solve_bvp(rates, ends, s, guess, tol=1e-10, max_nodes=100_000)
    if not solution.success:
        raise RuntimeError(f"elastica: {solution.message}")
    return float(solution.y[2, -1]), float(1.0 - solution.y[3, -1])


def reference(case: str) -> float:
    """Tip deflection over L of beam theory for ``case``: the elastica, or P L^2 / 3EI."""
    _, _, alpha, _ = CASES[case]
    return elastica(alpha)[0] if case == "elastica" else alpha / 3


def tip_deflection(kind: str, law: str, case: str, elements: int) -> float:
    """Tip deflection over L of the cantilever of ``case`` (square section, clamped at
    x = 0, transverse tip load along -y) with ``elements`` elements of ``kind`` and ``law``
    (any kind: the 2-node beams, their 3-node relatives, the cables)."""
    from runtime.kernels.kind import element_kind
    from runtime.model.bodies import Body, Material
    from runtime.model.items.constraints import Clamp
    from runtime.model.items.loads import PointForce
    from runtime.model.model import Model
    from runtime.model.scene import Scene
    from runtime.model.settings import Static
    from runtime.solve.static import solve_static

    slenderness, nu, alpha, steps = CASES[case]
    height = LENGTH / slenderness
    load = alpha * E_MODULUS * height**4 / 12 / LENGTH**2
    origin = (0.0,) * element_kind(kind).dim
    force = (0.0, -load) + origin[2:]
    scene = Scene(title=f"locking study cantilever, {kind}, {law}",
                  materials=[Material("steel", E=E_MODULUS, nu=nu, rho=RHO, law=law)],
                  bodies=[Body("beam", kind, "steel", height, height, elements, origin,
                               (LENGTH, *origin[1:]))],
                  constraints=[Clamp("beam:0")], loads=[PointForce("beam:-1", force)])
    model = Model(scene)
    result = solve_static(model, Static(load_steps=steps))
    return -float(result.q[model.node_dofs(elements, "r")][1]) / LENGTH


#: the dynamic check: the paper's cantilever (scenes/cantilever.toml, 4 s, tip load ramped
#: over 3.5 s), its element counts and the converged reference (kind, law, elements)
DYNAMIC_ELEMENTS = (2, 5, 10)
DYNAMIC_REFERENCE = ("cable3d", "svk", 40)


def paper_cantilever(kind: str, law: str, elements: int) -> tuple[np.ndarray, np.ndarray]:
    """(t, tip_y) in s and m of the paper's cantilever (scenes/cantilever.toml, dynamic
    analysis only, the compiled engine) with ``elements`` elements of ``kind`` and ``law``."""
    import dataclasses
    from importlib import resources

    from runtime.app.simulation import run_scene
    from runtime.model.scene import load_scene

    scene = load_scene(resources.files("scenes") / "cantilever.toml")
    body = dataclasses.replace(scene.bodies[0], element=kind, elements=elements)
    materials = [dataclasses.replace(m, law=law) for m in scene.materials.values()]
    scene = dataclasses.replace(scene, bodies=(body,), materials=materials, static=None,
                                modal=None, sensors=tuple(s for s in scene.sensors
                                                          if s.name == "tip_y"))
    result = run_scene(scene, engine="compiled", progress=False)
    return result.sensors["t"], result.sensors["tip_y"]


def dynamic_errors(cases, elements=DYNAMIC_ELEMENTS) -> dict[tuple[str, str, int], float]:
    """{(kind, law, elements): max |tip_y - reference| / max |reference|} over the paper
    cantilever's 4 s for ``cases`` (kind, law) against ``DYNAMIC_REFERENCE``."""
    _, reference = paper_cantilever(*DYNAMIC_REFERENCE)
    scale = np.abs(reference).max()
    return {(kind, law, n): float(np.abs(paper_cantilever(kind, law, n)[1] - reference).max()
                                  / scale)
            for kind, law in cases for n in elements}


@dataclass(frozen=True)
class Row:
    """Relative errors of the tip deflection, one per mesh of ``ELEMENTS``."""

    kind: str
    law: str
    case: str
    errors: tuple[float, ...]


def default_kinds() -> list[str]:
    """The generated kinds the remedy applies to."""
    from runtime.catalog import generated_kinds
    from runtime.kernels.kind import element_kind

    return [kind for kind in generated_kinds() if REMEDY in element_kind(kind).laws]


def default_laws() -> list[str]:
    """Every material law of the kinds of ``default_kinds`` (the default law first)."""
    from runtime.catalog import material_laws
    from runtime.kernels.kind import element_kind

    return [law for law in material_laws()
            if all(law in element_kind(kind).laws for kind in default_kinds())]


def cable_kinds() -> list[str]:
    """The generated kinds of the cable energy (the gradient-deficient beams)."""
    from runtime.catalog import generated_kinds
    from runtime.kernels.kind import element_kind

    return [kind for kind in generated_kinds() if element_kind(kind).energy.structural]


def measure(kinds=None, laws=None, cases=tuple(CASES), elements=ELEMENTS) -> list[Row]:
    """Every (kind, law, case) row of relative errors against ``reference`` (kinds and laws
    default to ``default_kinds`` and ``default_laws``)."""
    kinds, laws = kinds or default_kinds(), laws or default_laws()
    rows = []
    for case in cases:
        exact = reference(case)
        for kind in kinds:
            for law in laws:
                rows.append(Row(kind, law, case, tuple(
                    tip_deflection(kind, law, case, n) / exact - 1 for n in elements)))
    return rows


def report(rows: list[Row], elements=ELEMENTS) -> str:
    """The markdown table of ``rows`` (relative errors, 3 digits)."""
    titles = {"elastica": "elastica P L^2/EI = 10, L/h = 100, nu = 0",
              "linear": "P L^3/3EI, L/h = 50, nu = 0",
              "linear_nu03": "P L^3/3EI, L/h = 50, nu = 0.3"}
    lines = ["| case | kind | law | " + " | ".join(f"{n} el." for n in elements) + " |",
             "| --- | --- | --- |" + " ---: |" * len(elements)]
    for row in rows:
        lines.append(f"| {titles[row.case]} | {row.kind} | {row.law} | "
                     + " | ".join(f"{e:+.2e}" for e in row.errors) + " |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> None:
    """Print the convergence table (``--kinds``, ``--laws``, ``--cases``: comma lists)."""
    parser = argparse.ArgumentParser(prog="python -m runtime.studies.locking",
                                     description=__doc__.splitlines()[0])
    parser.add_argument("--kinds", default="", help="comma list (default: default_kinds)")
    parser.add_argument("--laws", default="", help="comma list (default: default_laws)")
    parser.add_argument("--cases", default=",".join(CASES))
    parser.add_argument("--cable", action="store_true",
                        help="add the rows of the cable kinds (law svk)")
    parser.add_argument("--dynamic", action="store_true",
                        help="instead: the paper's cantilever (scenes/cantilever.toml) with "
                        "beam3d svk and elastic_line and cable3d, against cable3d x 40")
    args = parser.parse_args(argv)
    if args.dynamic:
        errors = dynamic_errors([("beam3d", "svk"), ("beam3d", "elastic_line"),
                                 ("cable3d", "svk")])
        print("| kind | law | " + " | ".join(f"{n} el." for n in DYNAMIC_ELEMENTS) + " |")
        print("| --- | --- |" + " ---: |" * len(DYNAMIC_ELEMENTS))
        for kind, law in dict.fromkeys((k, a) for k, a, _ in errors):
            print(f"| {kind} | {law} | " + " | ".join(
                f"{errors[(kind, law, n)]:.2e}" for n in DYNAMIC_ELEMENTS) + " |")
        return
    cases = args.cases.split(",")
    rows = measure([k for k in args.kinds.split(",") if k], [a for a in args.laws.split(",") if a],
                   cases)
    if args.cable:
        rows += measure(cable_kinds(), ["svk"], cases)
    print(report(rows))


if __name__ == "__main__":
    main()
