"""The elastic-line law of the fully parameterised 2-node beams (beam2d, beam3d): a
structural beam energy of strain measures on the centre line, no continuum strain.

After the elastic-line approach of Gerstmayr and Shabana (2006) and the structural-mechanics
3D beam of Gerstmayr, Matikainen and Mikkola (2008): every strain is a dot product of two
*directions*, derivatives of the position field ``r = sum_k s_k q_k`` on the centre line
(y = z = 0) at the point or at a node (``DIRECTIONS``: r_x, r_y, r_xx, ..., and the nodal
frames r_x, r_y[, r_z] at x = 0 and x = l), so each is linear in the gram matrix G = Q Q^T
(``u_a^T G u_b`` with ``u_a`` the shape derivatives of direction a) and the energy
``U = sum_i K_i/2 int eps_i^2 dx`` is the gram form: quadratic in DeltaG, pre-integrated once
(constant invariants, exact: the integrands are polynomials).  The strains (``_strains``),
each with its section stiffness ``K_i`` and where along x it is sampled:

* along the centre line, integrated exactly (``axis``, Gauss order ``quadrature[0]``):
  the axial strain ``(r_x.r_x - 1)/2`` (EA); the bending, r_xx projected on the frame
  {r_x, r_y[, r_z]} of each node with weight 1/2: ``EI_z (r_xx . r_y@j)^2 + EI_y (r_xx .
  r_z@j)^2 + EI_x (r_xx . r_x@j)^2`` (EI_x = EI in 2D, the mean (EI_y + EI_z)/2 in 3D); in 3D
  the torsion ``(r_xz . r_y)^2 + (r_xy . r_z)^2`` with GJ/2 each (the two section vectors
  twist alike);
* at the nodes (``axis_lobatto2``, the 2-point Lobatto rule x = 0, l): the transverse shear
  ``r_x . r_y`` (k GA; 3D also ``r_x . r_z`` with k1), the section stretches
  ``(r_y.r_y - 1)/2`` (EA; 3D also r_z) and, in 3D, the section shear ``r_y . r_z`` (GA).

Why these choices (docs/laws.md, ``elastic_line``, has the measurements):

* r_y, r_z are linear in x while the slope of the cubic centre line is quadratic: sampled
  along the element, ``r_x . r_y = 0`` would force a linear slope (constant curvature: shear
  locking returns) and the linearly interpolated section vectors of a rotating element, which
  shrink between the nodes, would resist the rotation (cross-section locking).  At the nodes
  they only keep each nodal frame unit and orthogonal;
* projected on the interpolated r_y, r_xx . r_y(x) loses the shrink of r_y: the bending is
  too soft by dphi^2/6 in an element that turns by dphi (+8e-3 on the elastica with 8
  elements).  Projected on the orthonormal nodal frames, the sum of the squares is
  |r_xx|^2 exactly, whatever the rotation inside the element, and the square section
  gets Berzeri and Shabana's bending EI/2 int r_xx . r_xx of the cable, without its linear
  term (every strain vanishes at the straight reference).

The element is an Euler-Bernoulli beam with cubic Hermite bending: the section follows the
slope at the nodes, and the shear does not enter the deflection.  The strains are dot
products, so the energy is invariant under rigid motions; they are measured from the
straight reference (unit, orthogonal directions, r_xx = 0), the only reference the law takes
(``CURVED_REFUSED``).  Section of height h (along y) and width w (along z; the thickness in
2D): A = h w, I_z = w h^3/12, I_y = h w^3/12 and the torsion constant
``J = h^3 w^3 / (3.6 (h^2 + w^2))`` (an approximation of Saint-Venant's constant of the
rectangle: -1.2 % for a square, -12 % at h/w = 10; tests/test_elastic_line.py).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import sympy as sp

from symgen import domains, laws
from symgen.domains import AXIS_LETTERS

if TYPE_CHECKING:      # symgen.element checks its energy through this module
    from symgen.element import ElementSpec

#: The directions of the centre line the strains dot, per dimension: names of the local
#: derivatives of r (``r_<name>``) at the point, or ``<name>@<node>`` at a node's x (``@0``:
#: x = 0, ``@1``: x = l: the nodal frames), in the order of the structural tables.
DIRECTIONS = {2: ("x", "y", "xx", "x@0", "x@1", "y@0", "y@1"),
              3: ("x", "y", "z", "xx", "xy", "xz", "x@0", "x@1", "y@0", "y@1", "z@0", "z@1")}

#: The nodal vectors of the elements the law applies to (cubic Hermite centre line, linear
#: section vectors), per dimension.
VECTORS = {2: ("r", "r_x", "r_y"), 3: ("r", "r_x", "r_y", "r_z")}

CURVED_REFUSED = ("the elastic-line law measures its strains from the straight reference "
                  "(unit, orthogonal section vectors and r_xx = 0): straight references only")


@dataclass(frozen=True)
class Strain:
    """One strain of the law: ``first . second`` (two ``DIRECTIONS``; minus 1 and halved when
    they are the same, a stretch), its section stiffness ``stiffness`` (in E, nu, the shear
    corrections, h and w) and the law ``domain`` it is sampled on (``axis``: exactly along
    the centre line; ``axis_lobatto2``: at the nodes)."""

    name: str
    first: str
    second: str
    stiffness: sp.Expr
    domain: str
    doc: str

    @property
    def stretch(self) -> bool:
        """Whether the strain is ``(r_a.r_a - 1)/2`` rather than a product of two directions."""
        return self.first == self.second


def torsion_constant(h: sp.Expr, w: sp.Expr) -> sp.Expr:
    """J (m^4) of the h x w rectangle: h^3 w^3 / (3.6 (h^2 + w^2)) (module docstring)."""
    return 5 * h**3 * w**3 / (18 * (h**2 + w**2))


def _bending(section: dict[str, sp.Expr]) -> tuple[Strain, ...]:
    """r_xx projected on the frame of each node (weight 1/2 each): ``section`` maps a frame
    vector (x, y, z) to the bending stiffness of r_xx along it."""
    return tuple(Strain(f"bending_{axis}@{node}", "xx", f"{axis}@{node}", stiffness / 2,
                        "axis", f"r_xx . r_{axis} of node {node}, {label} / 2")
                 for node in (0, 1) for axis, (stiffness, label) in section.items())


def _strains(dim: int) -> tuple[Strain, ...]:
    E, G = laws.young, laws.SHEAR
    h, w = domains.height, domains.width
    area = h * w
    if dim == 2:
        (k,) = laws.corrections(2)
        ei = E * w * h**3 / 12
        return (
            Strain("axial", "x", "x", E * area, "axis", "(r_x.r_x - 1)/2, EA"),
            *_bending({"y": (ei, "EI"), "x": (ei, "EI")}),
            Strain("shear", "x", "y", k * G * area, "axis_lobatto2", "r_x . r_y, k GA"),
            Strain("section", "y", "y", E * area, "axis_lobatto2", "(r_y.r_y - 1)/2, EA"),
        )
    k1, k2 = laws.corrections(3)   # ecm's order: k1 on the x-z shear, k2 on the x-y shear
    ei_z, ei_y = E * w * h**3 / 12, E * h * w**3 / 12
    return (
        Strain("axial", "x", "x", E * area, "axis", "(r_x.r_x - 1)/2, EA"),
        *_bending({"y": (ei_z, "EI_z"), "z": (ei_y, "EI_y"),
                   "x": ((ei_y + ei_z) / 2, "(EI_y + EI_z) / 2")}),
        Strain("torsion_y", "xz", "y", G * torsion_constant(h, w) / 2, "axis",
               "r_xz . r_y, GJ / 2"),
        Strain("torsion_z", "xy", "z", G * torsion_constant(h, w) / 2, "axis",
               "r_xy . r_z, GJ / 2"),
        Strain("shear_y", "x", "y", k2 * G * area, "axis_lobatto2", "r_x . r_y, k2 GA"),
        Strain("shear_z", "x", "z", k1 * G * area, "axis_lobatto2", "r_x . r_z, k1 GA"),
        Strain("section_y", "y", "y", E * area, "axis_lobatto2", "(r_y.r_y - 1)/2, EA"),
        Strain("section_z", "z", "z", E * area, "axis_lobatto2", "(r_z.r_z - 1)/2, EA"),
        Strain("section_shear", "y", "z", G * area, "axis_lobatto2", "r_y . r_z, GA"),
    )


def _parts(strains: Callable[[int], tuple[Strain, ...]]):
    """The law parts of a structural law: one per domain its strains are sampled on.  They
    name the domains (applicability, storage, element.json); the strains are not Voigt
    strains, so their Voigt matrices are zero (the stiffnesses are the strains')."""
    def parts(dim: int) -> tuple[laws.LawPart, ...]:
        size = laws.voigt_size(dim)
        on = dict.fromkeys(strain.domain for strain in strains(dim))
        return tuple(laws.LawPart(f"strains_{domain}", domain, sp.zeros(size, size))
                     for domain in on)
    return parts


@dataclass(frozen=True)
class StructuralLaw(laws.Law):
    """A law of structural strains of the centre line (``Strain``), rather than of the
    Green-Lagrange strain with a Voigt matrix."""

    strains: Callable[[int], tuple[Strain, ...]] = _strains


#: The structural laws of the fully parameterised 2-node beams.
STRUCTURAL_LAWS: dict[str, StructuralLaw] = {
    "elastic_line": StructuralLaw(
        "elastic_line", "structural beam of the centre line (Gerstmayr and Shabana's elastic "
        "line): axial strain and bending r_xx . r_y (and r_xx . r_z, torsion) along the axis, "
        "transverse shear and cross-section strains at the nodes", _parts(_strains),
        laws.timoshenko_correction, strains=_strains),
}


def is_structural(law: laws.Law) -> bool:
    """Whether ``law`` is a structural law (``StructuralLaw``)."""
    return isinstance(law, StructuralLaw)


def not_applicable(spec: ElementSpec) -> str | None:
    """Why the structural laws do not apply to ``spec`` (None when they do): they need a
    beam whose two nodes at x = 0, l carry r, r_x and the section vectors."""
    if spec.domain.name != "beam" or tuple(spec.vectors) != VECTORS[spec.dim] \
            or spec.n_nodes != 2:
        return (f"the elastic-line law needs a 2-node beam whose nodes carry "
                f"{', '.join(VECTORS[spec.dim])} (a cubic centre line with section vectors); "
                f"{spec.name} has {spec.n_nodes} nodes carrying {', '.join(spec.vectors)}")
    return None


def direction_axes(name: str) -> tuple[int, ...]:
    """The local axes a direction differentiates along: ``"xz"`` -> (0, 2)."""
    return tuple(AXIS_LETTERS.index(c) for c in name.split("@")[0])


def direction_values(spec: ElementSpec) -> list[list[sp.Expr]]:
    """Per direction of ``DIRECTIONS`` the n shape derivatives ``u_a`` on the centre line
    (y = z = 0), polynomials in x and the domain parameters (constants for a node's)."""
    x, *across = spec.coordinates
    out = []
    for name in DIRECTIONS[spec.dim]:
        at = {c: 0 for c in across}
        if "@" in name:
            at[x] = spec.nodes[int(name.split("@")[1])][0]
        row = []
        for s in spec.shape_functions:
            value = s
            for axis in direction_axes(name):
                value = sp.diff(value, spec.coordinates[axis])
            row.append(sp.expand(value.subs(at)))
        out.append(row)
    return out


def metadata(spec: ElementSpec, law: StructuralLaw) -> dict:
    """What element.json records about a structural law: its directions and strains."""
    names = DIRECTIONS[spec.dim]
    return {"directions": list(names), "variants": ["straight"], "curved": CURVED_REFUSED,
            "strains": [{"name": s.name, "directions": [names.index(s.first),
                                                        names.index(s.second)],
                         "domain": s.domain, "doc": s.doc} for s in law.strains(spec.dim)]}
