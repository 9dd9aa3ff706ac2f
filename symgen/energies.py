"""Strain energies of elements: what an element file's ``energy`` names.

* ``continuum`` (the default): ``U = int_V0 W(E) dV0`` with the Green-Lagrange strain of the
  full deformation gradient and the density ``W`` of a material law (``symgen.laws.LAWS``).
* ``cable``: a structural beam for elements whose nodes carry r and r_x only (the
  gradient-deficient ANCF cable; Berzeri and Shabana's simple bending model):

      U = EA/2 int eps^2 dx + EI/2 int r_xx . r_xx dx,    eps = (r_x . r_x - 1) / 2,

  with the reference parameterised by arc length (|r0_x| = 1).  The axial part is a law part
  with only the E11 coefficient on the beam ``axis`` (the gram form with the single gradient
  r_x: quartic energy, constant invariants), integrated by the law machinery
  (``symgen.derive``).  The bending part is linear in the gram matrix G = Q Q^T:
  ``EI/2 sum_kl K_kl G_kl`` with the constant shape-level matrix ``K_kl = int s_k'' s_l'' dx``,
  so it adds ``EI K`` to K1 (cij) and a linear term to the gram kernels (``gram_linear``).
  Its modulus is the law's axial one: the E11 coefficient on the axis (E for ``svk``, the
  1D St. Venant-Kirchhoff law, which is exactly EA eps^2 / 2 with the Green strain).
  ``I = w h^3 / 12`` in 2D (h the height in the bending plane, w the thickness); a 3D cable
  has no section orientation, so it takes one bending stiffness, the mean of the two
  principal moments of the h x w rectangle, ``I = h w (h^2 + w^2) / 24`` (exact for square
  sections).  The simple model is not rotation invariant for a curved reference, so cable
  elements take straight references only (``CURVED_REFUSED``).

Kelvin-Voigt damping (stress = D (eps + alpha eps_dot)) applies to both parts: the axial one
through the gram tensor as for any law, the bending one as ``-alpha EI K r_dot``.
"""

from __future__ import annotations

import sympy as sp

from symgen import laws
from symgen.domains import x

#: The strain energies an element file may declare.
ENERGIES = ("continuum", "cable")

#: Why cable elements refuse curved references (element.json ``energy.curved``).
CURVED_REFUSED = ("the cable energy's simple bending model EI/2 int r_xx . r_xx dx is not "
                  "rotation invariant for a curved reference (it is only for straight ones)")


def _cable_svk(dim: int) -> tuple[laws.LawPart, ...]:
    voigt = sp.zeros(laws.voigt_size(dim), laws.voigt_size(dim))
    voigt[0, 0] = laws.young
    return (laws.LawPart("axial", "axis", voigt),)


#: The laws of the cable energy: the 1D St. Venant-Kirchhoff law (E on E11 along the axis).
CABLE_LAWS: dict[str, laws.Law] = {
    "svk": laws.Law("svk", "1D St. Venant-Kirchhoff: EA eps^2/2 on the axis with the Green "
                    "strain eps = (r_x.r_x - 1)/2, bending EI/2 r_xx.r_xx", _cable_svk),
}

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
    if spec.domain.name != "beam" or tuple(spec.vectors) != ("r", "r_x"):
        raise ValueError(f"element {spec.name!r}: the cable energy needs a beam domain and "
                         "nodes carrying r, r_x")
    if any(s.free_symbols & set(spec.coordinates[1:]) for s in spec.shape_functions):
        raise ValueError(f"element {spec.name!r}: cable shape functions depend on x only")


def is_cable(spec) -> bool:
    """Whether ``spec`` has the cable energy (bending, straight references only)."""
    return spec.energy == "cable"


def offered_laws(spec) -> dict[str, laws.Law]:
    """The laws of the element's energy, before domain applicability."""
    return CABLE_LAWS if is_cable(spec) else laws.LAWS


def not_applicable(spec) -> dict[str, str]:
    """{law: why it does not apply to ``spec``} over every known law name."""
    out = {}
    for name, law in laws.LAWS.items():
        if is_cable(spec) and name not in CABLE_LAWS:
            out[name] = _CABLE_REFUSES.format(name=name)
        elif not is_cable(spec) and laws.not_applicable(law, spec.domain, spec.nodes) \
                is not None:
            out[name] = laws.not_applicable(law, spec.domain, spec.nodes)
    return out


def applicable_laws(spec) -> dict[str, laws.Law]:
    """The laws of the element's energy whose every part has its subdomain in the domain."""
    return {name: law for name, law in offered_laws(spec).items()
            if laws.not_applicable(law, spec.domain, spec.nodes) is None}


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


def bending_modulus(coefficients: dict):
    """The modulus of the bending part: the law's E11 coefficient on the axis."""
    return coefficients["axis"][0]


def _along(weights, vec, dim: int) -> list:
    """sum_k weights_k q_k of the node-major coordinates ``vec`` (a dim-vector)."""
    return [sum(w * vec[k * dim + c] for k, w in enumerate(weights)) for c in range(dim)]


def point_energy(s1, s2, q0, dq, dim: int, w_axial, w_bending):
    """The cable energy density at one point times its weight: ``w_axial eps^2 / 2 +
    w_bending r_xx.r_xx / 2``, with eps = r0_x.dr_x + dr_x.dr_x / 2 (exact at the reference)
    from the shape derivatives ``s1`` (ds/dx) and ``s2`` (d2s/dx2) and the node-major
    reference ``q0`` and displacements ``dq``."""
    r0x, drx = _along(s1, q0, dim), _along(s1, dq, dim)
    rxx = [a + b for a, b in zip(_along(s2, q0, dim), _along(s2, dq, dim), strict=True)]
    eps = sum(a * b for a, b in zip(r0x, drx, strict=True)) + sum(b * b for b in drx) / 2
    return w_axial * eps**2 / 2 + w_bending * sum(c * c for c in rxx) / 2


def point_dissipation(s1, s2, q, qd, dim: int, w_axial, w_bending):
    """The Kelvin-Voigt dissipation potential at one point over alpha: ``w_axial eps_dot^2 / 2
    + w_bending rd_xx.rd_xx / 2`` with eps_dot = r_x . rd_x."""
    rx, rdx, rdxx = _along(s1, q, dim), _along(s1, qd, dim), _along(s2, qd, dim)
    eps_dot = sum(a * b for a, b in zip(rx, rdx, strict=True))
    return w_axial * eps_dot**2 / 2 + w_bending * sum(c * c for c in rdxx) / 2


def metadata(spec) -> dict | None:
    """What element.json records about a non-default energy (None for ``continuum``, whose
    element.json has no ``energy`` entry)."""
    if not is_cable(spec):
        return None
    return {"name": "cable", "bending": "simple", "variants": ["straight"],
            "curved": CURVED_REFUSED,
            "second_moment": "w h^3 / 12" if spec.dim == 2 else "h w (h^2 + w^2) / 24"}
