"""3D quintic ANCF cable: r, r_x, r_xx at x = 0 and l, the quintic Hermite functions of
``cable2d_quintic``, the cable energy of ``cable3d`` (one bending stiffness;
``symgen/energies.py``)."""

from symgen import domains
from symgen.element import ElementSpec, length
from symgen.elements.cable2d_quintic import QUINTIC_HERMITE, QUINTIC_ORDER

ELEMENT = ElementSpec(
    name="cable3d_quintic",
    domain=domains.beam(3),
    nodes=((0, 0, 0), (length, 0, 0)),
    vectors=("r", "r_x", "r_xx"),
    shape_functions=QUINTIC_HERMITE,
    quadrature=(QUINTIC_ORDER, 1, 1),
    description="3D quintic ANCF cable, r, r_x, r_xx per node, 18 coordinates",
    energy="cable",
)
