"""Planar ANCF cable (gradient-deficient beam; Berzeri and Shabana; Exudyn's
ObjectANCFCable2D): r, r_x at x = 0 and l, cubic Hermite along the axis, the cable energy
(axial strain EA, bending EI/2 int r_xx . r_xx dx; ``symgen/energies.py``)."""

from symgen import domains
from symgen.element import ElementSpec, length, x

xi = x / length

ELEMENT = ElementSpec(
    name="cable2d",
    domain=domains.beam(2),
    nodes=((0, 0), (length, 0)),
    vectors=("r", "r_x"),
    shape_functions=(
        1 - 3 * xi**2 + 2 * xi**3,
        length * (xi - 2 * xi**2 + xi**3),
        3 * xi**2 - 2 * xi**3,
        length * (-(xi**2) + xi**3),
    ),
    quadrature=(5, 1),
    description="planar ANCF cable (Berzeri & Shabana), r, r_x per node, 8 coordinates",
    energy="cable",
)
