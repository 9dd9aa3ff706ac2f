"""3D ANCF cable (gradient-deficient beam; Project Chrono's ChElementCableANCF): r, r_x at
x = 0 and l, cubic Hermite along the axis, the cable energy (axial strain EA, bending
EI/2 int r_xx . r_xx dx with one bending stiffness; ``symgen/energies.py``)."""

from symgen import domains
from symgen.element import ElementSpec, length, x

xi = x / length

ELEMENT = ElementSpec(
    name="cable3d",
    domain=domains.beam(3),
    nodes=((0, 0, 0), (length, 0, 0)),
    vectors=("r", "r_x"),
    shape_functions=(
        1 - 3 * xi**2 + 2 * xi**3,
        length * (xi - 2 * xi**2 + xi**3),
        3 * xi**2 - 2 * xi**3,
        length * (-(xi**2) + xi**3),
    ),
    quadrature=(5, 1, 1),
    description="3D ANCF cable (Chrono ChElementCableANCF), r, r_x per node, 12 coordinates",
    energy="cable",
)
