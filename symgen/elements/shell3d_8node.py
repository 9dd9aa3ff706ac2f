"""8-node serendipity ANCF shell (Project Chrono's ANCF-3833 without its r_zz gradient): r, r_z
at the four corners and the four mid-sides of x in [0, a], y in [0, b], 48 coordinates.

In Chrono's normalised coordinates xi_c = 2x/a - 1, eta_c = 2y/b - 1 (corners A, B, C, D at
(-1, -1), (1, -1), (1, 1), (-1, 1), counter-clockwise; mid-sides E, F, G, H at (0, -1),
(1, 0), (0, 1), (-1, 0)) the position functions are the quadratic serendipity functions
(1 + xi_c xi_i)(1 + eta_c eta_i)(xi_c xi_i + eta_c eta_i - 1) / 4 at the corners,
(1 - xi_c^2)(1 + eta_c eta_i) / 2 and (1 + xi_c xi_i)(1 - eta_c^2) / 2 at the mid-sides, and
the r_z functions z times them.  Mesh grids of this kind are its node lattice: half an element
per grid step, no node at an element's centre.
"""

from symgen import domains
from symgen.element import ElementSpec, x, y, z

a, b = domains.side_a, domains.side_b
u, v = 2 * x / a - 1, 2 * y / b - 1       # Chrono's xi, eta in [-1, 1]
# node points (xi_c, eta_c): corners A, B, C, D, then mid-sides E, F, G, H (Chrono's order)
POINTS = ((-1, -1), (1, -1), (1, 1), (-1, 1), (0, -1), (1, 0), (0, 1), (-1, 0))


def serendipity(p: int, q: int):
    """The quadratic serendipity function of the node at (p, q) in normalised coordinates."""
    if p == 0:
        return (1 - u**2) * (1 + q * v) / 2
    if q == 0:
        return (1 + p * u) * (1 - v**2) / 2
    return (1 + p * u) * (1 + q * v) * (p * u + q * v - 1) / 4


ELEMENT = ElementSpec(
    name="shell3d_8node",
    domain=domains.plate(),
    nodes=tuple(((p + 1) * a / 2, (q + 1) * b / 2, 0) for p, q in POINTS),
    vectors=("r", "r_z"),
    shape_functions=tuple(f * serendipity(p, q) for p, q in POINTS for f in (1, z)),
    quadrature=(5, 5, 3),
    description="8-node serendipity shell (Chrono ANCF-3833 without r_zz), r, r_z per corner "
                "and mid-side, 48 coordinates",
)
