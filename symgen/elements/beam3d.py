"""Shear-deformable 3D ANCF beam (Shabana & Yakoub): 2 nodes, r, r_x, r_y, r_z per node."""

from symgen import domains
from symgen.element import ElementSpec, length, x, y, z

xi = x / length

ELEMENT = ElementSpec(
    name="beam3d",
    domain=domains.beam(3),
    nodes=((0, 0, 0), (length, 0, 0)),
    vectors=("r", "r_x", "r_y", "r_z"),
    shape_functions=(
        1 - 3 * xi**2 + 2 * xi**3,
        length * (xi - 2 * xi**2 + xi**3),
        y * (1 - xi),
        z * (1 - xi),
        3 * xi**2 - 2 * xi**3,
        length * (-(xi**2) + xi**3),
        y * xi,
        z * xi,
    ),
    quadrature=(5, 3, 3),
    description="3D shear-deformable beam (Shabana & Yakoub), 24 coordinates",
)
