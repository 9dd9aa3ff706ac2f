"""3-node planar ANCF beam (the planar counterpart of Chrono's ANCF-3333): r, r_y at
x = 0, l/2, l; quadratic along the axis (N0, N1, N2 the quadratic Lagrange polynomials of
xi = x/l), linear across the height."""

from symgen import domains
from symgen.element import ElementSpec, length, x, y

xi = x / length
N = ((2 * xi - 1) * (xi - 1), 4 * xi * (1 - xi), xi * (2 * xi - 1))

ELEMENT = ElementSpec(
    name="beam2d_3node",
    domain=domains.beam(2),
    nodes=((0, 0), (length / 2, 0), (length, 0)),
    vectors=("r", "r_y"),
    shape_functions=tuple(f * n for n in N for f in (1, y)),
    quadrature=(5, 3),
    description="3-node planar beam (planar ANCF-3333), r, r_y per node, 12 coordinates",
)
