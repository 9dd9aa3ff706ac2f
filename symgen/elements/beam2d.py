"""Shear-deformable planar ANCF beam (Omar & Shabana): 2 nodes, r, r_x, r_y per node."""

from symgen import domains
from symgen.element import ElementSpec, length, x, y

xi = x / length

ELEMENT = ElementSpec(
    name="beam2d",
    domain=domains.beam(2),
    nodes=((0, 0), (length, 0)),
    vectors=("r", "r_x", "r_y"),
    shape_functions=(
        1 - 3 * xi**2 + 2 * xi**3,
        length * (xi - 2 * xi**2 + xi**3),
        y * (1 - xi),
        3 * xi**2 - 2 * xi**3,
        length * (-(xi**2) + xi**3),
        y * xi,
    ),
    quadrature=(5, 3),
    description="planar shear-deformable beam (Omar & Shabana), 12 coordinates",
)
