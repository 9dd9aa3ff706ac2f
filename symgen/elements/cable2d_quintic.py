"""Planar quintic ANCF cable: r, r_x, r_xx at x = 0 and l, quintic Hermite along the axis,
the cable energy of ``cable2d`` (axial strain EA, bending EI/2 int r_xx . r_xx dx or the exact
curvature; ``symgen/energies.py``). The nodes carry the curvature, so an element bends with a
cubic curvature field where the cubic cable's is linear."""

from symgen import domains
from symgen.element import ElementSpec, length, x

xi = x / length

#: Quintic Hermite functions on [0, l], node-major (r, r_x, r_xx at x = 0, then at x = l); the
#: gradient functions carry l and the curvature functions l^2 so that d s / dx and
#: d^2 s / dx^2 are 1 at their node.
QUINTIC_HERMITE = (
    1 - 10 * xi**3 + 15 * xi**4 - 6 * xi**5,
    length * (xi - 6 * xi**3 + 8 * xi**4 - 3 * xi**5),
    length**2 * (xi**2 - 3 * xi**3 + 3 * xi**4 - xi**5) / 2,
    10 * xi**3 - 15 * xi**4 + 6 * xi**5,
    length * (-4 * xi**3 + 7 * xi**4 - 3 * xi**5),
    length**2 * (xi**3 - 2 * xi**4 + xi**5) / 2,
)

#: Gauss points along the axis: the axial Green strain eps = (r_x.r_x - 1)/2 is of degree 8,
#: eps^2 of degree 16 (9 points integrate degree 17 exactly; the cubic cable's 5 points do its
#: degree 8), and the exact curvature's numerator |r_x x r_xx|^2 is of degree 14.
QUINTIC_ORDER = 9

ELEMENT = ElementSpec(
    name="cable2d_quintic",
    domain=domains.beam(2),
    nodes=((0, 0), (length, 0)),
    vectors=("r", "r_x", "r_xx"),
    shape_functions=QUINTIC_HERMITE,
    quadrature=(QUINTIC_ORDER, 1),
    description="planar quintic ANCF cable, r, r_x, r_xx per node, 12 coordinates",
    energy="cable",
)
