"""Every list of names of the interchangeable parts of a run, and the rule that names kernel
families: the only place they are typed.  Scene validation, CLI choices, registries, studies
and benchmarks read them from here (``tests/test_catalog.py`` checks that no other module
spells one of these lists), so a new part is added in one place.

Element kinds and material laws are not typed at all: they are read from the generated
``element.json`` files (what ``symgen`` emitted is what exists).  Registries keyed by these
names (engines, integrators) assert that they hold exactly the catalog's names.
"""

from __future__ import annotations

import json
from functools import cache
from importlib import resources
from pathlib import Path

#: Elastic force methods of ``runtime.Element`` (DESIGN: docs/design.md, "three ways").
METHODS = ("gram", "cij", "quadrature")
#: Kernel backends: compiled C through cffi, or NumPy.
BACKENDS = ("c", "numpy")
#: Reference variants of the invariants: closed forms of straight elements, quadrature of any.
VARIANTS = ("straight", "general")
#: Time integrators of dynamic analyses (registry: ``runtime.solve.python_engine``).
INTEGRATORS = ("trapezoidal", "generalized_alpha")
#: Dynamic engines (registry: ``runtime.solve.engines.ENGINES``).
ENGINES = ("compiled", "python")
#: Methods of static analyses (``[analysis.static] method``): the default first.
STATIC_METHODS = ("load_stepping", "arc_length")
#: Newton modes of the dynamic integrators (both engines; ``auto``: modified Newton that
#: turns to full Newton for steps after one whose kept Jacobian went stale,
#: ``runtime.solve.python_engine``).
NEWTON_MODES = ("full", "modified", "auto")
#: Linear solvers of the Newton iterations (registry: ``runtime.solve.linear.LINEAR_SOLVERS``;
#: chosen per model when a scene names none).
LINEAR_SOLVERS = ("banded", "sparse")
#: Bending models of the cable energy (``symgen.energies.BENDING_MODELS``; element.json
#: ``laws.<law>.bending``): Berzeri and Shabana's pre-integrated simple model, and the exact
#: curvature by Gauss quadrature along the axis.
BENDING_MODELS = ("simple", "exact_curvature")
#: The material law of a material that names none.
DEFAULT_LAW = "svk"
#: The continuum laws with St. Venant-Kirchhoff's normal block over the whole thickness
#: (``symgen.laws``: svk; svk_sri reduces the surface rule only), which lock in bending at
#: nu != 0 as ``ElementKind.svk_locking`` states (the run warns).
POISSON_LOCKING_LAWS = ("svk", "svk_sri")


def generated_dir() -> Path:
    """The folder of the generated kernels (inside the installed package)."""
    return Path(str(resources.files("generated")))


def generated_kinds() -> list[str]:
    """Every element kind with generated kernels (``runtime.Element`` takes any), sorted."""
    return sorted(p.parent.name for p in generated_dir().glob("*/element.json"))


@cache
def material_laws() -> tuple[str, ...]:
    """Every material law some generated kind has, the default first, then by name."""
    laws = set()
    for kind in generated_kinds():
        laws |= set(json.loads((generated_dir() / kind / "element.json").read_text())["laws"])
    return tuple(sorted(laws, key=lambda law: (law != DEFAULT_LAW, law)))


def family_name(method: str, law: str, variant: str, damped: bool = False,
                bending: str | None = None, structural: bool = False) -> str:
    """The kernel family that evaluates ``method`` for material law ``law`` on elements of
    reference ``variant`` (``VARIANTS``): the elastic kernels, or with ``damped`` the
    Kelvin-Voigt damping kernels; ``bending`` is the law's bending model on a cable
    (``BENDING_MODELS``, None for a continuum).

    gram: ``gram_<variant>`` (damping ``damping_<variant>``); cij: ``cij`` (damping through
    the gram invariant, ``damping_<variant>``); quadrature: ``quadrature`` for the default
    law, ``quadrature_law`` for any other law and for damping.  The exact-curvature bending:
    ``gram_curvature_<variant>``, ``cij_curvature``, ``quadrature_curvature`` (damping
    ``damping_curvature_<variant>``, in ``quadrature_curvature`` for quadrature).  A
    ``structural`` law (strains of the centre line, ``LawInfo.structural``): gram and cij as
    any law, ``quadrature_structural`` (elastic and damping) for quadrature.
    """
    if method not in METHODS:
        raise ValueError(f"method: expected one of {', '.join(METHODS)}, got {method!r}")
    if variant not in VARIANTS:
        raise ValueError(f"variant: expected one of {', '.join(VARIANTS)}, got {variant!r}")
    if bending not in (None, *BENDING_MODELS):
        raise ValueError(f"bending: expected one of {', '.join(BENDING_MODELS)}, got "
                         f"{bending!r}")
    if bending == "exact_curvature":
        if method == "quadrature" or (method == "cij" and not damped):
            return f"{method}_curvature"
        return f"{'damping' if damped else method}_curvature_{variant}"
    if method == "quadrature" and structural:
        return "quadrature_structural"
    if method == "quadrature":
        return "quadrature" if law == DEFAULT_LAW and not damped else "quadrature_law"
    if damped:
        return f"damping_{variant}"
    return f"gram_{variant}" if method == "gram" else method
