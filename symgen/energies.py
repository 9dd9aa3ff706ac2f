"""Strain energies of elements: what an element file's ``energy`` names.

* ``continuum`` (the default): ``U = int_V0 W(E) dV0`` with the Green-Lagrange strain of the
  full deformation gradient and the density ``W`` of a material law (``symgen.laws.LAWS``).
* ``cable``: a structural beam for elements whose nodes carry r and r_x (the
  gradient-deficient ANCF cable; Berzeri and Shabana's simple bending model), or r, r_x and
  r_xx (the quintic cable, ``CABLE_VECTORS``):

      U = EA/2 int eps^2 dx + EI/2 int r_xx . r_xx dx,    eps = (r_x . r_x - 1) / 2,

  with the reference parameterised by arc length (|r0_x| = 1).  The axial part is a law part
  with only the E11 coefficient on the beam ``axis`` (the gram form with the single gradient
  r_x: quartic energy, constant invariants), integrated by the law machinery
  (``symgen.derive``).  The bending part is linear in the gram matrix G = Q Q^T:
  ``EI/2 sum_kl K_kl G_kl`` with the constant shape-level matrix ``K_kl = int s_k'' s_l'' dx``,
  so it adds ``EI K`` to K1 (cij) and a linear term to the gram kernels (``gram_linear``).
  Its modulus is the law's axial one: the E11 coefficient on the axis (E for ``svk``, the
  1D St. Venant-Kirchhoff law, which is exactly EA eps^2 / 2 with the Green strain), an input
  of the straight invariants (``bending``: 0 for the exact curvature).
  ``I = w h^3 / 12`` in 2D (h the height in the bending plane, w the thickness); a 3D cable
  has no section orientation, so it takes one bending stiffness, the mean of the two
  principal moments of the h x w rectangle, ``I = h w (h^2 + w^2) / 24`` (exact for square
  sections).  The simple model is not rotation invariant for a curved reference, so its law
  takes straight references only (``curved_refused``).

Kelvin-Voigt damping (stress = D (eps + alpha eps_dot)) applies to both parts: the axial one
through the gram tensor as for any law, the bending one as ``-alpha EI K r_dot``.

The cable laws choose the bending model (``BENDING_MODELS``): ``svk`` the simple one above,
``svk_exact_curvature`` the exact curvature of Gerstmayr and Irschik (Exudyn's ANCFCable2D),

    U_bending = EI/2 int |kappa|^2 dx,    kappa = r_x x r_xx / |r_x|^2

(a scalar in 2D), rational in the coordinates, so it is integrated by Gauss quadrature along
the axis in the kernels (``symgen.methods.curvature``) while the axial part stays
pre-integrated; its Kelvin-Voigt damping is ``alpha EI/2 int |kappa_dot|^2 dx`` (the
curvature rate: objective in 2D; in 3D the curvature vector turns with a rigid rotation of a
bent cable).  The planar exact curvature is rotation invariant for any reference, so it takes
curved ones: with a0 = |r0_x| the reference metric and s0 the reference arc length,

    U = EA/2 int E11^2 a0 dx + EI/2 int (kappa - kappa0)^2 / a0 dx,
    E11 = (r_x.r_x - r0_x.r0_x) / (2 a0^2),  kappa0 = r0_x x r0_xx / |r0_x|^2

(the material curvature d theta / d s0 is kappa / a0; Exudyn's ANCFCable2D with
``strainIsRelativeToReference``), the axial part a gram form of the general pattern with the
weights 1 / a0^3, the bending weights EI / a0 and kappa0 in the quadrature table
(``reference_curvature``).  The 3D exact curvature is a vector in the global frame, whose
difference from a curved reference's is not rotation invariant: straight references only.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from symgen import laws, structural
from symgen.domains import x

#: The strain energies an element file may declare.
ENERGIES = ("continuum", "cable")

#: Why a cable law refuses curved references, by bending model and dimension (element.json
#: ``laws.<law>.curved``; ``energy.curved`` when some law of the kind does).
_CURVED_REFUSED = {
    "simple": ("the cable energy's simple bending model EI/2 int r_xx . r_xx dx is not "
               "rotation invariant for a curved reference (it is only for straight ones); "
               "the planar exact curvature (law svk_exact_curvature) takes curved ones"),
    "exact_curvature": ("the 3D exact curvature r_x x r_xx / |r_x|^2 is a vector in the "
                        "global frame, whose difference from a curved reference's is not "
                        "rotation invariant (straight references only in 3D)"),
}


def _cable_svk(dim: int) -> tuple[laws.LawPart, ...]:
    voigt = sp.zeros(laws.voigt_size(dim), laws.voigt_size(dim))
    voigt[0, 0] = laws.young
    return (laws.LawPart("axial", "axis", voigt),)


#: Bending models of the cable energy: Berzeri and Shabana's pre-integrated r_xx . r_xx, and
#: the exact curvature by quadrature (module docstring).
BENDING_MODELS = ("simple", "exact_curvature")


@dataclass(frozen=True)
class CableLaw(laws.Law):
    """A law of the cable energy: the axial law parts and the ``bending`` model
    (``BENDING_MODELS``)."""

    bending: str = "simple"

    def __post_init__(self) -> None:
        if self.bending not in BENDING_MODELS:
            raise ValueError(f"law {self.name!r}: bending must be one of {BENDING_MODELS}, got "
                             f"{self.bending!r}")


#: The laws of the cable energy: the 1D St. Venant-Kirchhoff law (E on E11 along the axis)
#: with either bending model.
CABLE_LAWS: dict[str, CableLaw] = {
    "svk": CableLaw("svk", "1D St. Venant-Kirchhoff: EA eps^2/2 on the axis with the Green "
                    "strain eps = (r_x.r_x - 1)/2, bending EI/2 r_xx.r_xx", _cable_svk),
    "svk_exact_curvature": CableLaw(
        "svk_exact_curvature", "1D St. Venant-Kirchhoff axial part as svk, bending EI/2 "
        "|kappa|^2 with the exact curvature kappa = r_x x r_xx / |r_x|^2 by Gauss quadrature",
        _cable_svk, bending="exact_curvature"),
}

#: The nodal vectors a cable's nodes may carry: the cubic cable's r, r_x and the quintic
#: one's r, r_x, r_xx (the curvature; ``symgen/elements/cable2d_quintic.py``).
CABLE_VECTORS = (("r", "r_x"), ("r", "r_x", "r_xx"))

_CABLE_REFUSES = ("law {name!r} does not apply to the cable energy: it corrects the shear "
                  "and Poisson strains of a continuum, which a cable (axial strain and bending "
                  "of r, r_x) has not")


def check(spec) -> None:
    """ValueError unless ``spec`` (an ``ElementSpec``) fits its declared energy."""
    if spec.energy not in ENERGIES:
        raise ValueError(f"element {spec.name!r}: energy must be one of {ENERGIES}, got "
                         f"{spec.energy!r}")
    if spec.energy != "cable":
        return
    if spec.domain.name != "beam" or tuple(spec.vectors) not in CABLE_VECTORS:
        raise ValueError(f"element {spec.name!r}: the cable energy needs a beam domain and "
                         "nodes carrying " + " or ".join(", ".join(v) for v in CABLE_VECTORS))
    if any(s.free_symbols & set(spec.coordinates[1:]) for s in spec.shape_functions):
        raise ValueError(f"element {spec.name!r}: cable shape functions depend on x only")


def is_cable(spec) -> bool:
    """Whether ``spec`` has the cable energy (bending, straight references only)."""
    return spec.energy == "cable"


def offered_laws(spec) -> dict[str, laws.Law]:
    """The laws of the element's energy, before domain applicability: a continuum's material
    laws and the structural laws of the 2-node beams (``symgen.structural``)."""
    return CABLE_LAWS if is_cable(spec) else {**laws.LAWS, **structural.STRUCTURAL_LAWS}


def _law_refused(spec, law: laws.Law) -> str | None:
    """Why ``law`` (of the element's energy) does not apply to ``spec``, or None."""
    if structural.is_structural(law):
        reason = structural.not_applicable(spec)
        if reason is not None:
            return f"law {law.name!r} does not apply: {reason}"
    return laws.not_applicable(law, spec.domain, spec.nodes)


def not_applicable(spec) -> dict[str, str]:
    """{law: why it does not apply to ``spec``} over every known law name."""
    out = {}
    for name, law in {**laws.LAWS, **structural.STRUCTURAL_LAWS}.items():
        if is_cable(spec) and structural.is_structural(law):
            out[name] = _law_refused(spec, law)
        elif is_cable(spec) and name not in CABLE_LAWS:
            out[name] = _CABLE_REFUSES.format(name=name)
        elif not is_cable(spec) and _law_refused(spec, law) is not None:
            out[name] = _law_refused(spec, law)
    return out


def applicable_laws(spec) -> dict[str, laws.Law]:
    """The laws of the element's energy that apply to ``spec`` (every part's subdomain in
    the domain; a structural law's element layout, ``symgen.structural.not_applicable``)."""
    return {name: law for name, law in offered_laws(spec).items()
            if _law_refused(spec, law) is None}


def second_moment(spec) -> sp.Expr:
    """Bending second moment of area (m^4) in the domain parameters (module docstring)."""
    h, w = spec.domain.parameters[1:]
    return w * h**3 / 12 if spec.dim == 2 else h * w * (h**2 + w**2) / 24


def area(spec) -> sp.Expr:
    """Cross-section area h w (m^2)."""
    h, w = spec.domain.parameters[1:]
    return h * w


def bending_matrix(spec) -> sp.Matrix:
    """K_kl = int_0^l s_k'' s_l'' dx (n x n), exact, in the domain parameters."""
    second = [sp.expand(sp.diff(s, x, 2)) for s in spec.shape_functions]
    length = spec.domain.parameters[0]
    n = spec.n_shape
    return sp.Matrix(n, n, lambda k, m: sp.factor(sp.integrate(second[k] * second[m],
                                                               (x, 0, length))))


def bending_terms(spec, pairs, modulus) -> dict[str, list]:
    """The bending part as stored invariants for the pairs (k, l), k <= l, of shape functions:
    ``k1`` (EI K_kl, added to K1) and ``gram_linear`` (EI mu_kl K_kl / 4, mu = 1 on the
    diagonal and 2 off it: U_bending = 2 gram_linear . DeltaG), with EI = ``modulus`` I."""
    stiffness = modulus * second_moment(spec)
    matrix = bending_matrix(spec)
    return {"k1": [stiffness * matrix[k, m] for k, m in pairs],
            "gram_linear": [stiffness * (1 if k == m else 2) * matrix[k, m] / 4
                            for k, m in pairs]}


def bending_model(spec, law: laws.Law) -> str | None:
    """The bending model of ``law`` on ``spec`` (None for a continuum)."""
    return law.bending if is_cable(spec) else None


def curved_refused(spec, law: laws.Law) -> str | None:
    """Why ``law`` on ``spec`` refuses curved references (None when it takes them: every
    continuum law, the planar exact curvature)."""
    if not is_cable(spec) or (law.bending == "exact_curvature" and spec.dim == 2):
        return None
    return _CURVED_REFUSED[law.bending]


def law_variants(spec, law: laws.Law) -> list[str]:
    """The reference variants ``law`` takes on ``spec``: straight, and general (curved) unless
    ``curved_refused``."""
    return ["straight"] + (["general"] if curved_refused(spec, law) is None else [])


def reference_curvature(spec, bending: str) -> bool:
    """Whether the quadrature table of ``bending`` on ``spec`` carries the reference curvature
    kappa0 (the planar exact curvature, which takes curved references)."""
    return bending == "exact_curvature" and spec.dim == 2


def _along(weights, vec, dim: int) -> list:
    """sum_k weights_k q_k of the node-major coordinates ``vec`` (a dim-vector)."""
    return [sum(w * vec[k * dim + c] for k, w in enumerate(weights)) for c in range(dim)]


def cross(a, b) -> list:
    """a x b: one entry in 2D (the scalar cross product), three in 3D."""
    if len(a) == 2:
        return [a[0] * b[1] - a[1] * b[0]]
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def _dot(a, b):
    return sum(x * y for x, y in zip(a, b, strict=True))


def point_energy(s1, s2, q0, dq, dim: int, w_axial, w_bending):
    """The polynomial cable energy density at one point times its weight: ``w_axial eps^2 / 2
    + w_bending r_xx.r_xx / 2`` (the simple bending; ``w_bending = 0``: the axial part alone,
    which the exact curvature's kernels add to their closed-form bending,
    ``symgen.methods.quadrature._exact_bending``), with eps = r0_x.dr_x + dr_x.dr_x / 2
    (exact at the reference; the metric of a curved reference is in the weights) from the
    shape derivatives ``s1`` (ds/dx) and ``s2`` (d2s/dx2) and the node-major reference
    ``q0`` and displacements ``dq``."""
    r0x, drx = _along(s1, q0, dim), _along(s1, dq, dim)
    rxx = [a + b for a, b in zip(_along(s2, q0, dim), _along(s2, dq, dim), strict=True)]
    eps = _dot(r0x, drx) + _dot(drx, drx) / 2
    return w_axial * eps**2 / 2 + w_bending * _dot(rxx, rxx) / 2


def point_dissipation(s1, s2, q, qd, dim: int, w_axial, w_bending):
    """The Kelvin-Voigt dissipation potential of ``point_energy`` at one point over alpha:
    ``w_axial eps_dot^2 / 2 + w_bending rd_xx.rd_xx / 2`` with eps_dot = r_x . rd_x."""
    rx, rdx, rdxx = _along(s1, q, dim), _along(s1, qd, dim), _along(s2, qd, dim)
    eps_dot = _dot(rx, rdx)
    return w_axial * eps_dot**2 / 2 + w_bending * _dot(rdxx, rdxx) / 2


def metadata(spec) -> dict | None:
    """What element.json records about a non-default energy (None for ``continuum``, whose
    element.json has no ``energy`` entry)."""
    if not is_cable(spec):
        return None
    refused = [curved_refused(spec, law) for law in CABLE_LAWS.values()]
    return {"name": "cable", "variants": ["straight"],
            "curved": next(reason for reason in refused if reason is not None),
            "second_moment": "w h^3 / 12" if spec.dim == 2 else "h w (h^2 + w^2) / 24"}
