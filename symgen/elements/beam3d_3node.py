"""3-node 3D ANCF beam (Project Chrono's ANCF-3333): r, r_y, r_z at x = 0, l/2, l.

Quadratic along the axis, linear across the section; no r_x (the axial slope comes from the
positions of the three nodes).  With xi = x/l the node functions are the quadratic Lagrange
polynomials N0 = (2 xi - 1)(xi - 1), N1 = 4 xi (1 - xi), N2 = xi (2 xi - 1) and every node
carries N r + y N r_y + z N r_z (Chrono's normalised coordinates: xi_c = 2 xi - 1, nodes
A, B, C at xi_c = -1, 1, 0; here the nodes are in axis order).
"""

from symgen import domains
from symgen.element import ElementSpec, length, x, y, z

xi = x / length
N = ((2 * xi - 1) * (xi - 1), 4 * xi * (1 - xi), xi * (2 * xi - 1))

ELEMENT = ElementSpec(
    name="beam3d_3node",
    domain=domains.beam(3),
    nodes=((0, 0, 0), (length / 2, 0, 0), (length, 0, 0)),
    vectors=("r", "r_y", "r_z"),
    shape_functions=tuple(f * n for n in N for f in (1, y, z)),
    quadrature=(5, 3, 3),
    description="3-node 3D beam (Chrono ANCF-3333), r, r_y, r_z per node, 27 coordinates",
)
