"""Material laws as data: each law is a sum of parts, a constant Voigt matrix with its domain.

Strains are Green-Lagrange strains in the local element frame (axis 1 = the beam axis x), in
Voigt order ``[E11, E22, E33, 2E23, 2E13, 2E12]`` (3D) or ``[E11, E22, 2E12]`` (2D).  The
energy density of a part is ``eps^T D eps / 2``; the element energy is the sum over parts of
that density integrated over the part's domain:

* ``volume``: the whole reference volume (area times thickness in 2D);
* ``axis``:   the beam axis y = z = 0, a line integral over x scaled by the cross-section
  area ``h w`` (height times width, or times thickness in 2D);
* ``volume_gauss2``, ``volume_lobatto2``, ``axis_lobatto2``: the same with x integrated by a
  2-point rule instead of exactly (Gauss-Legendre; Gauss-Lobatto: the ends x = 0, l);
* ``volume_gauss2x2``: the plates' volume with x and y by the 2-point Gauss rule (z exactly).

Every part has the *orthotropic form*: a full symmetric block on the normal strains and a
diagonal block on the shear strains, nothing coupling the two.  Its numbers, the *law
coefficients*, are stored as the upper triangle of the normal block (row-major) followed by
the shear diagonal (``coefficient_layout``).  The derivations of the invariants
(``symgen.derive``), the Gauss-point evaluation (``quadrature_law`` kernels) and the runtime
only see coefficients per domain, so a new law is one entry of ``LAWS``.

Laws (docs/laws.md has the formulas):

* ``svk``: St. Venant-Kirchhoff, the isotropic D over the volume (the default);
* ``ecm``: enhanced continuum mechanics (Nachbagauer, Gruber and Gerstmayr), as in Project
  Chrono's ``ChMaterialBeamANCF``: ``D0 = diag(E, E, E, G, k1 G, k2 G)`` over the volume and
  the Poisson part ``Dv`` (the isotropic normal block minus E on its diagonal) on the axis,
  which removes Poisson locking.  ``k1`` scales 2E13 and ``k2`` scales 2E12 (Chrono's order);
  in 2D one ``k`` scales 2E12.  Default ``k = 10 (1 + nu) / (12 + 11 nu)`` (Timoshenko,
  rectangular section);
* ``ecm_sri``: ``ecm`` with selective reduced integration along x, against the locking of
  slender beams in large rotations: E11 and the transverse shears (2E12, 2E13) by the 2-point
  Gauss rule (membrane and shear locking), the cross-section strains (E22, E33, 2E23) and the
  Poisson part at the element ends by the 2-point Lobatto rule (the linearly interpolated
  r_y, r_z of a rotated element shrink between the ends, which E22, E33 would resist);
* ``svk_sri``: ``svk`` split exactly into a plane-stress part (E11, E22 with the plane-stress
  moduli ``E / (1 - nu^2)``, and every shear with G) on the surface's 2 x 2 Gauss points and
  the thickness-normal part ``(lam + 2G) (E33 + nu / (1 - nu) (E11 + E22))^2 / 2`` over the
  volume, against the membrane and transverse-shear locking of thin shells (the quadratic
  serendipity shells; plate3d, corner nodes only, refuses it: ``_without_mid_side_nodes``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import cache

import sympy as sp

#: Integration domains of law parts, in storage order: subdomains of an element's reference
#: domain (symgen/domains.py).  ``volume`` is every element's; ``axis`` (y = z = 0) is the
#: beams'; ``midsurface`` (z = 0) is the plates'.  A law with a part on a subdomain that an
#: element's domain lacks does not apply to that element (``not_applicable``).
DOMAINS = ("volume", "axis", "midsurface", "volume_gauss2", "volume_lobatto2", "axis_lobatto2",
           "volume_gauss2x2")

young, poisson = sp.symbols("E nu", positive=True)
#: Lame parameters in terms of E and nu.
LAME = young * poisson / ((1 + poisson) * (1 - 2 * poisson))
SHEAR = young / (2 * (1 + poisson))


def voigt_size(dim: int) -> int:
    """Number of strain components: 3 in 2D, 6 in 3D."""
    return dim * (dim + 1) // 2


def shear_pairs(dim: int) -> list[tuple[int, int]]:
    """The local axes (a, b) of each shear strain 2E_ab, in Voigt order."""
    return [(0, 1)] if dim == 2 else [(1, 2), (0, 2), (0, 1)]


def coefficient_layout(dim: int) -> list[tuple[int, int]]:
    """Voigt entries (I, J) of the law coefficients: normal upper triangle, shear diagonal."""
    normal = [(i, j) for i in range(dim) for j in range(i, dim)]
    return normal + [(dim + s, dim + s) for s in range(len(shear_pairs(dim)))]


def coefficient_names(dim: int) -> list[str]:
    """Labels ``D11``, ``D12``, ... of the law coefficients (1-based Voigt indices)."""
    return [f"D{i + 1}{j + 1}" for i, j in coefficient_layout(dim)]


def correction_names(dim: int) -> list[str]:
    """Shear-correction factors of the transverse shears (those involving the axis x)."""
    return ["k"] if dim == 2 else ["k1", "k2"]


def corrections(dim: int) -> tuple[sp.Symbol, ...]:
    """Symbols of the shear-correction factors, in ``correction_names`` order."""
    return tuple(sp.Symbol(name, positive=True) for name in correction_names(dim))


def _isotropic_normal(dim: int) -> sp.Matrix:
    return sp.Matrix(dim, dim, lambda i, j: LAME + (2 * SHEAR if i == j else 0))


def _block(dim: int, normal: sp.Matrix, shear: list[sp.Expr]) -> sp.Matrix:
    size = voigt_size(dim)
    matrix = sp.zeros(size, size)
    matrix[:dim, :dim] = normal
    for s, value in enumerate(shear):
        matrix[dim + s, dim + s] = value
    return matrix


@dataclass(frozen=True)
class LawPart:
    """One part of a law: the Voigt matrix ``voigt`` (in E, nu, corrections) on ``domain``."""

    name: str
    domain: str
    voigt: sp.Matrix

    def coefficients(self, dim: int) -> list[sp.Expr]:
        """The part's law coefficients (``coefficient_layout`` order)."""
        return [sp.simplify(self.voigt[i, j]) for i, j in coefficient_layout(dim)]


@dataclass(frozen=True)
class Law:
    """A material law: ``parts(dim)`` gives its parts for an element dimension.

    ``default_corrections(dim)``: expressions in nu of the shear corrections when the user
    gives none; ``None`` for laws without shear corrections.  ``refuses(domain, nodes)``:
    why the law does not apply to an element with these nodes (points of the domain), or
    None; ``None`` for laws that apply wherever their parts' subdomains exist.
    """

    name: str
    description: str
    parts: Callable[[int], tuple[LawPart, ...]]
    default_corrections: Callable[[int], tuple[sp.Expr, ...]] | None = None
    refuses: Callable[[object, tuple], str | None] | None = None

    def domain_coefficients(self, dim: int) -> dict[str, list[sp.Expr]]:
        """Summed law coefficients per domain (zeros where the law has no part)."""
        out = {domain: [sp.Integer(0)] * len(coefficient_layout(dim)) for domain in DOMAINS}
        for part in self.parts(dim):
            if part.domain not in DOMAINS:
                raise ValueError(f"law {self.name!r}: unknown domain {part.domain!r}")
            _check_orthotropic_form(self.name, part, dim)
            out[part.domain] = [a + b for a, b in zip(out[part.domain],
                                                       part.coefficients(dim), strict=True)]
        return out


def _check_orthotropic_form(law: str, part: LawPart, dim: int) -> None:
    size = voigt_size(dim)
    if part.voigt.shape != (size, size) or part.voigt != part.voigt.T:
        raise ValueError(f"law {law!r}, part {part.name!r}: expected a symmetric "
                         f"{size} x {size} Voigt matrix")
    allowed = set(coefficient_layout(dim))
    for i in range(size):
        for j in range(i, size):
            if (i, j) not in allowed and sp.simplify(part.voigt[i, j]) != 0:
                raise ValueError(f"law {law!r}, part {part.name!r}: entry ({i}, {j}) couples "
                                 "normal and shear strains or two shears (not supported)")


def timoshenko_correction(dim: int) -> tuple[sp.Expr, ...]:
    """k = 10 (1 + nu) / (12 + 11 nu) on every transverse shear (rectangular section)."""
    k = 10 * (1 + poisson) / (12 + 11 * poisson)
    return (k,) * len(correction_names(dim))


def _svk(dim: int) -> tuple[LawPart, ...]:
    shear = [SHEAR] * len(shear_pairs(dim))
    return (LawPart("isotropic", "volume", _block(dim, _isotropic_normal(dim), shear)),)


def _ecm(dim: int) -> tuple[LawPart, ...]:
    # the transverse shears (2E13 with k1, 2E12 with k2; 2E12 with k in 2D) are the last ones
    ks = corrections(dim)
    shear = [SHEAR] * (len(shear_pairs(dim)) - len(ks)) + [k * SHEAR for k in ks]
    d0 = _block(dim, young * sp.eye(dim), shear)
    dv = _block(dim, _isotropic_normal(dim) - young * sp.eye(dim), [0] * len(shear))
    return (LawPart("D0", "volume", d0), LawPart("Dv", "axis", dv))


def _ecm_sri(dim: int) -> tuple[LawPart, ...]:
    # ecm's D0 (diagonal) split by strains: E11 and the transverse shears (those involving x)
    # on the 2-point Gauss rule along x, the cross-section strains and Dv at the ends
    d0, dv = _ecm(dim)
    along_x = sp.diag(1, *[0] * (dim - 1), *[int(0 in pair) for pair in shear_pairs(dim)])
    return (LawPart("D0_axial_shear", "volume_gauss2", along_x * d0.voigt),
            LawPart("D0_section", "volume_lobatto2", d0.voigt - along_x * d0.voigt),
            LawPart("Dv", "axis_lobatto2", dv.voigt))


@cache  # factored once: applicability checks ask for the parts of every law
def _svk_sri(dim: int) -> tuple[LawPart, ...]:
    # the isotropic normal block C with the thickness axis last, C = [[Cpp, c], [c^T, C33]]:
    # eps^T C eps = e_p^T (Cpp - c c^T / C33) e_p + C33 (E33 + c^T e_p / C33)^2 exactly, the
    # plane-stress matrix (E / (1 - nu^2) [[1, nu], [nu, 1]] in 3D) and a square, each >= 0
    normal = _isotropic_normal(dim)
    thickness_row = normal[dim - 1, :] / normal[dim - 1, dim - 1]
    thickness = _block(dim, normal[dim - 1, dim - 1] * thickness_row.T * thickness_row,
                       [0] * len(shear_pairs(dim)))
    plane = _block(dim, normal, [SHEAR] * len(shear_pairs(dim))) - thickness
    return (LawPart("plane_stress_shear", "volume_gauss2x2", plane.applyfunc(sp.factor)),
            LawPart("thickness_normal", "volume", thickness.applyfunc(sp.factor)))


def _without_mid_side_nodes(domain, nodes: tuple) -> str | None:
    """Why 2 x 2 Gauss points of the surface do not suit elements with only corner nodes:
    on those (plate3d: r, r_x, r_y, r_z at the corners) they leave deformation modes of no
    energy that spread through a mesh (spurious frequencies between the bending ones); the
    quadratic serendipity shells, three nodes along each side, keep none."""
    for axis in domain.reduced_axes("volume_gauss2x2"):
        a = domain.axes[axis]
        along = sorted({sp.nsimplify(node[axis] / a.scale) for node in nodes})
        if len(along) < 3:
            return (f"its plane-stress and shear part samples the surface at 2 x 2 Gauss "
                    f"points, which leaves zero-energy modes that spread through a mesh unless "
                    f"a mid-side node sits on each side (the nodes sit at {a.coordinate} = "
                    f"{', '.join(str(u * a.scale) for u in along)} only)")
    return None


LAWS: dict[str, Law] = {
    "svk": Law("svk", "St. Venant-Kirchhoff, isotropic D over the volume", _svk),
    "ecm": Law("ecm", "enhanced continuum mechanics: D0 over the volume, the Poisson part "
               "on the beam axis (no Poisson locking)", _ecm, timoshenko_correction),
    "ecm_sri": Law("ecm_sri", "ecm with selective reduced integration along x: E11 and the "
                   "transverse shears by 2-point Gauss, the cross-section strains and the "
                   "Poisson part at the ends (no locking of slender beams)", _ecm_sri,
                   timoshenko_correction),
    "svk_sri": Law("svk_sri", "svk with selective reduced integration of the surface: the "
                   "plane-stress part and the shears at 2 x 2 Gauss points, the thickness-"
                   "normal part over the volume (no membrane or shear locking of thin shells)",
                   _svk_sri, refuses=_without_mid_side_nodes),
}


def not_applicable(law: Law, domain, nodes: tuple = ()) -> str | None:
    """Why ``law`` does not apply to elements on ``domain`` (a ``symgen.domains.Domain``) with
    ``nodes`` (points of the domain), or None when it does: one of its parts integrates over
    a subdomain the domain lacks, or at the ends of an axis (Lobatto) that are not all the
    nodes along it (``_not_at_nodes``), or the law's own ``refuses`` says why."""
    for part in law.parts(domain.dim):
        if part.domain not in domain.subdomain_names:
            return (f"law {law.name!r} does not apply to the {domain.name} domain: its part "
                    f"{part.name!r} integrates over the {part.domain}, which a {domain.name} "
                    f"has not (subdomains: {', '.join(domain.subdomain_names)})")
        reason = _not_at_nodes(part, domain, nodes)
        if reason is not None:
            return f"law {law.name!r} does not apply: {reason}"
    reason = law.refuses(domain, nodes) if law.refuses is not None else None
    return None if reason is None else f"law {law.name!r} does not apply: {reason}"


def _not_at_nodes(part: LawPart, domain, nodes: tuple) -> str | None:
    """Why the Lobatto axes of ``part``'s subdomain miss nodes: sampling only the ends of an
    axis along which interior nodes sit would leave their cross-section free (a mechanism)."""
    for axis, rule in domain.reduced_axes(part.domain).items():
        a = domain.axes[axis]
        along = sorted({sp.nsimplify(node[axis] / a.scale) for node in nodes})
        if rule.startswith("lobatto") and along != [a.low, a.high]:
            return (f"its part {part.name!r} integrates at the ends of {a.coordinate} (the "
                    f"{rule} rule of the {part.domain}), but the nodes sit at {a.coordinate} = "
                    f"{', '.join(str(u * a.scale) for u in along)}")
    return None


def get(name: str) -> Law:
    """The law called ``name``; ValueError listing the known ones otherwise."""
    if name not in LAWS:
        raise ValueError(f"unknown law {name!r}; known laws: {', '.join(LAWS)}")
    return LAWS[name]
