"""What ``ancf bench precision`` runs: the three problems, the configurations of each code
on them (the project's from the catalog and the generated kinds, so that a new line kind or
integrator is picked up without being named here; Exudyn's ANCFCable2D with the same meshes
and steps), and the reference run of each code.
"""

from __future__ import annotations

import dataclasses
import itertools
from dataclasses import dataclass

import scenes
from runtime.catalog import INTEGRATORS, NEWTON_MODES, generated_kinds
from runtime.kernels.kind import element_kind
from runtime.model.scene import load_scene
from runtime.studies import peers

#: The two codes compared.
CODES = ("project", "exudyn")
#: Accuracies of the summary table.
TARGETS = (1e-2, 1e-3, 1e-4)
#: The elastica: P L^2 / EI, length (m), slender square section (m; 2D: height and thickness)
#: on the paper cantilever's material; L / h = 200 keeps the stretch and shear of the
#: continuum and cable models (about 2e-5 L at the tip) below the finest target.
ELASTICA = {"alpha": 10.0, "length": 1.0, "height": 5e-3, "width": 5e-3}
#: The Newton of the project's static analysis (exact Jacobian, no mode to choose).
STATIC_NEWTON = NEWTON_MODES[0]
#: The integrator of the reference runs (numerical damping of the spurious high frequencies:
#: Exudyn's trapezoidal rule loses Newton convergence on the rotating beam).
REFERENCE_INTEGRATOR = INTEGRATORS[1]


@dataclass(frozen=True)
class Problem:
    """One problem: ``name``, ``title``, the shipped ``scene`` it comes from, ``dim`` (the
    kinds that apply have it), ``static`` (else dynamic over ``t_end`` s with outputs every
    ``every`` s), the ``sensor`` the error is measured on, the sweep (``elements``;
    ``steps`` in s, or load steps when static) and the reference (``reference_elements``,
    ``reference_step``; none when static: the exact elastica)."""

    name: str
    title: str
    scene: str
    dim: int
    static: bool
    sensor: str
    elements: tuple[int, ...]
    steps: tuple[float, ...]
    t_end: float | None = None
    every: float | None = None
    reference_elements: int | None = None
    reference_step: float | None = None


@dataclass(frozen=True)
class Config:
    """One configuration of one code on one problem: ``kind`` (an element kind of the
    project, or the peer's element), ``elements``, the time ``step`` (s) and ``integrator``
    (dynamic) or the ``load_steps`` (static), the ``newton`` mode, and whether it is the
    code's ``reference`` run."""

    problem: str
    code: str
    kind: str
    elements: int
    newton: str
    step: float | None = None
    integrator: str | None = None
    load_steps: int | None = None
    reference: bool = False

    def label(self) -> str:
        """A short description: 'beam2d x 8, h 1e-3, generalized_alpha, modified Newton'."""
        how = (f"{self.load_steps} load steps" if self.load_steps is not None
               else f"h {self.step:g} s, {self.integrator}")
        return f"{self.kind} x {self.elements}, {how}, {self.newton} Newton"


def line_kinds(dim: int) -> list[str]:
    """Every generated kind meshed along one axis (beams, cables) of dimension ``dim``."""
    return [kind for kind in generated_kinds()
            if element_kind(kind).dim == dim
            and sum(axis.meshed for axis in element_kind(kind).domain.axes) == 1]


def problems(quick: bool = False) -> tuple[Problem, ...]:
    """The three problems (``quick``: short runs, two meshes, one step, CI-fast)."""
    full = (
        Problem("rotating_beam", "Rotating beam spin-up (paper Figs. 7-9), tip deflection in "
                "the hub frame", "rotating_beam", 2, False, "tip_transverse",
                (2, 4, 8, 16, 32), (1e-2, 5e-3, 2e-3, 1e-3), t_end=20.0, every=0.05,
                reference_elements=64, reference_step=5e-4),
        Problem("elastica", f"Static elastica, P L^2 / EI = {ELASTICA['alpha']:g}, L / h = "
                f"{ELASTICA['length'] / ELASTICA['height']:g}, tip displacement",
                "cantilever", 2, True, "tip", (2, 4, 8, 16, 32, 64, 128, 256),
                (20, 5, 10, 40)),
        Problem("cantilever", "Paper cantilever, 4 s dynamic (load ramped 3.5 s), tip "
                "deflection", "cantilever", 3, False, "tip_y", (2, 4, 8, 16, 32),
                (1e-2, 5e-3, 2e-3, 1e-3), t_end=4.0, every=0.05, reference_elements=64,
                reference_step=5e-4))
    if not quick:
        return full
    short = {"rotating_beam": 1.0, "cantilever": 0.5}
    return tuple(dataclasses.replace(
        p, elements=(2, 4), steps=p.steps[:1],
        **({} if p.static else {"t_end": short[p.name], "reference_elements": 8,
                                "reference_step": 5e-3})) for p in full)


def configurations(problem: Problem, with_peer: bool) -> list[Config]:
    """Every configuration of the sweep of ``problem`` for the project and, with
    ``with_peer``, for Exudyn (its planar cable models every problem here: the cantilever
    bends in a plane); the reference runs are not included (``references``)."""
    configs = []
    codes = [("project", line_kinds(problem.dim), NEWTON_MODES)]
    if with_peer:
        codes.append(("exudyn", [peers.PEER_ELEMENT], peers.NEWTON))
    for code, kinds, newtons in codes:
        if problem.static:
            modes = newtons if code == "exudyn" else (STATIC_NEWTON,)
            configs += [Config(problem.name, code, kind, n, newton, load_steps=steps)
                        for kind, n, steps, newton in itertools.product(
                            kinds, problem.elements, problem.steps, modes)]
        else:
            configs += [Config(problem.name, code, kind, n, newton, step=h, integrator=integ)
                        for kind, n, h, integ, newton in itertools.product(
                            kinds, problem.elements, problem.steps, INTEGRATORS, newtons)]
    return configs


#: the mechanical model of the peer's element (an Euler-Bernoulli cable)
PEER_MODEL = "cable"


def model(config: Config) -> str:
    """The mechanical model a configuration discretises: the project kind's energy
    (``continuum``: shear-deformable beams; ``cable``: Euler-Bernoulli), the peer's cable."""
    return element_kind(config.kind).energy.name if config.code == "project" else PEER_MODEL


def references(problem: Problem, with_peer: bool) -> list[Config]:
    """The converged reference run of each code and model, so that each run is measured
    against the converged solution of the model it discretises (dynamic problems: the scene's
    kind for the project's continuum beams and the first kind of each other energy, the
    peer's element; on the finest mesh and step, REFERENCE_INTEGRATOR, full Newton); for the
    static elastica, whose reference is exact, the finest run of each code, to show how close
    the converged models come to it."""
    if problem.static:
        kinds = [reference_kind(problem)]
    else:
        by_model = {element_kind(k).energy.name: k for k in reversed(line_kinds(problem.dim))}
        by_model[element_kind(reference_kind(problem)).energy.name] = reference_kind(problem)
        kinds = [by_model[name] for name in sorted(by_model)]
    codes = [("project", kind) for kind in kinds]
    if with_peer:
        codes.append(("exudyn", peers.PEER_ELEMENT))
    if problem.static:
        return [Config(problem.name, code, k, max(problem.elements), "full",
                       load_steps=problem.steps[0], reference=True) for code, k in codes]
    return [Config(problem.name, code, k, problem.reference_elements, "full",
                   step=problem.reference_step, integrator=REFERENCE_INTEGRATOR, reference=True)
            for code, k in codes]


def reference_kind(problem: Problem) -> str:
    """The project's kind of the reference run: the scene's, when of the problem's
    dimension, else the first line kind of it."""
    kind = load_scene(scenes.path(problem.scene)).bodies[0].element
    return kind if element_kind(kind).dim == problem.dim else line_kinds(problem.dim)[0]
