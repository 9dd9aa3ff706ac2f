"""Kernel builders by evaluation method, and the table of the kernel families they build.

Families (one generated module each, so a scene compiles only what it uses):

* ``invariants``       - shape-function tables, closed-form straight integrals, and the map
                         from integrals to stored invariants (straight pattern);
* ``invariants_general``  - the same map for the general (curved) pattern;
* ``quadrature``       - Gauss quadrature of eq. 23 at every call (the paper's baseline);
* ``cij``              - the paper's invariants C^ij, K1, U0 (eqs. 27-41); the storage
                         pattern only changes the sparse operators built at run time;
* ``gram_<variant>``   - the compact gram tensor Dm with U = g^T Dm g, g = DeltaG;
* ``laws``             - the material laws (symgen/laws.py): each law's coefficients per
                         domain, default shear corrections, and the closed-form straight
                         invariants of any law from its coefficients;
* ``quadrature_law``   - Gauss quadrature of any material law (symgen/laws.py) at every call,
                         with Kelvin-Voigt damping;
* ``quadrature_structural`` - Gauss quadrature of the structural (elastic-line) law of the
                         2-node beams (symgen/structural.py) along the centre line at every
                         call, with Kelvin-Voigt damping;
* ``damping_<variant>``   - Kelvin-Voigt damping through the gram tensor Dm (its own family,
                         so undamped models never compile it);
* ``<method>_curvature[_<variant>]`` - cable elements with the exact-curvature bending:
                         the gram, cij, damping and quadrature kernels with the bending by
                         quadrature along the axis (``curvature``); the general (curved)
                         variants where the exact curvature takes curved references.

Each method family has ``force``, ``jacobian`` and ``energy`` kernels.  All translate the
positions to the element's first node first; ``gram`` and ``quadrature`` work in the
DeltaG / displacement-gradient form so the reference state cancels exactly.  ``FAMILIES``
says which families exist, the method each belongs to, its optimisation level and when an
element has it; the modules of this package build them (imported when a family is built).
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

if TYPE_CHECKING:  # the table is read without SymPy (``ancf`` builds its parser from it)
    from symgen.element import ElementSpec
    from symgen.ir import Kernel

#: Families that run once per element type before a simulation (invariants, law
#: coefficients): their speed hardly matters, so their C is compiled at -O0, in a fraction of
#: a second (beam3d's invariants_general: 0.3 s, 10 s at -O3); every other family at -O3.
#: The levels go to element.json ``optimization`` (runtime.kernels.loader passes them to the
#: JIT) and decide which kernels the C emitter splits into parts (symgen.emit).
PREPROCESSING = 0
OPTIMIZED = 3


@dataclass(frozen=True)
class Family:
    """One kernel family: its ``name``, the ``method`` it belongs to, the function
    ``builder`` of the ``module`` of this package that builds it (given the storage
    ``variant``, if any), its C optimisation level (0 to 3) and, if not every element has it,
    the rule ``when``."""

    name: str
    method: str
    module: str
    builder: str = "build"
    variant: str | None = None
    optimization: int = OPTIMIZED
    when: Callable[[ElementSpec], bool] | None = None

    def build(self, spec: ElementSpec) -> list[Kernel]:
        """All kernels of this family for ``spec``."""
        build = getattr(importlib.import_module(f"symgen.methods.{self.module}"), self.builder)
        return build(spec) if self.variant is None else build(spec, self.variant)


def _curved(spec: ElementSpec) -> bool:
    """Families of curved references only where the energy takes them (not cables:
    ``symgen.energies.CURVED_REFUSED``)."""
    from symgen import energies

    return not energies.is_cable(spec)


def _cable(spec: ElementSpec) -> bool:
    """The exact-curvature families where the energy has bending models (cables)."""
    from symgen import energies

    return energies.is_cable(spec)


def _curved_cable(spec: ElementSpec) -> bool:
    """The general exact-curvature families where that law takes curved references."""
    from symgen import energies

    return energies.is_cable(spec) and any(
        "general" in energies.law_variants(spec, law) for law in energies.CABLE_LAWS.values()
        if law.bending == "exact_curvature")


def _structural(spec: ElementSpec) -> bool:
    """The structural laws' quadrature family where one applies (the 2-node beams)."""
    from symgen import energies, structural

    return any(structural.is_structural(law) for law in energies.applicable_laws(spec).values())


def _small_general_map(spec: ElementSpec) -> bool:
    """The general (curved) svk map only where it is small (unrolled, it is the i4 -> stored
    map of the whole general pattern); otherwise curved references take the law path."""
    from symgen import derive
    from symgen.methods.common import LOOPED_PATTERN_ABOVE, closed_as_data

    return _curved(spec) and not closed_as_data(spec) and len(
        derive.patterns(spec, "general").gram) <= LOOPED_PATTERN_ABOVE["gram"]


FAMILIES: tuple[Family, ...] = (
    Family("invariants", "invariants", "invariants", variant="straight",
           optimization=PREPROCESSING),
    Family("invariants_general", "invariants", "invariants", variant="general",
           optimization=PREPROCESSING, when=_small_general_map),
    Family("quadrature", "quadrature", "quadrature"),
    Family("cij", "cij", "cij"),
    Family("gram_straight", "gram", "gram", variant="straight"),
    Family("gram_general", "gram", "gram", variant="general", when=_curved),
    Family("laws", "laws", "laws", optimization=PREPROCESSING),
    Family("quadrature_law", "quadrature_law", "quadrature", builder="build_law"),
    Family("quadrature_structural", "quadrature", "structural", when=_structural),
    Family("damping_straight", "damping", "damping", variant="straight"),
    Family("damping_general", "damping", "damping", variant="general", when=_curved),
    Family("gram_curvature_straight", "gram", "curvature", builder="build_gram",
           variant="straight", when=_cable),
    Family("gram_curvature_general", "gram", "curvature", builder="build_gram",
           variant="general", when=_curved_cable),
    Family("cij_curvature", "cij", "curvature", builder="build_cij", when=_cable),
    Family("damping_curvature_straight", "damping", "curvature", builder="build_damping",
           variant="straight", when=_cable),
    Family("damping_curvature_general", "damping", "curvature", builder="build_damping",
           variant="general", when=_curved_cable),
    Family("quadrature_curvature", "quadrature", "curvature", builder="build_quadrature",
           when=_cable),
)
_BY_NAME = {family.name: family for family in FAMILIES}

#: The families ``ancf generate --method`` regenerates, by method.
METHOD_FAMILIES: dict[str, list[str]] = {
    method: [family.name for family in FAMILIES if family.method == method]
    for method in ("invariants", "quadrature", "cij", "gram")
}


def optimization(family: str) -> int:
    """The C optimisation level (0 to 3) of ``family``."""
    return _BY_NAME[family].optimization


def families(spec: ElementSpec) -> list[str]:
    """Names of every kernel family generated for an element."""
    return [family.name for family in FAMILIES if family.when is None or family.when(spec)]


def build_family(spec: ElementSpec, family: str) -> list[Kernel]:
    """All kernels of one family."""
    return _BY_NAME[family].build(spec)
