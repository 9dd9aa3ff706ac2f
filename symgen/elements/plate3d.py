"""4-node ANCF plate (Mikkola and Shabana; Project Chrono's ANCF-3443): r, r_x, r_y, r_z at
the four corners of x in [0, a], y in [0, b], 48 coordinates.

In Chrono's normalised coordinates xi_c = 2x/a - 1, eta_c = 2y/b - 1 (corners A, B, C, D at
(-1, -1), (1, -1), (1, 1), (-1, 1), counter-clockwise) the position functions are the
incomplete cubics -1/8 (xi_c - 1)(eta_c - 1)(eta_c^2 + eta_c + xi_c^2 + xi_c - 2) and their
mirror images, the slope functions a/16 and b/16 times cubic-linear products, and the r_z
functions z times the bilinear corner functions.
"""

from symgen import domains
from symgen.element import ElementSpec, x, y, z

a, b = domains.side_a, domains.side_b
u, v = 2 * x / a - 1, 2 * y / b - 1       # Chrono's xi, eta in [-1, 1]

ELEMENT = ElementSpec(
    name="plate3d",
    domain=domains.plate(),
    nodes=((0, 0, 0), (a, 0, 0), (a, b, 0), (0, b, 0)),
    vectors=("r", "r_x", "r_y", "r_z"),
    shape_functions=(
        # corner A (0, 0)
        -(u - 1) * (v - 1) * (v**2 + v + u**2 + u - 2) / 8,
        -a * (u + 1) * (u - 1) ** 2 * (v - 1) / 16,
        -b * (v + 1) * (v - 1) ** 2 * (u - 1) / 16,
        z * (u - 1) * (v - 1) / 4,
        # corner B (a, 0)
        (u + 1) * (v - 1) * (v**2 + v + u**2 - u - 2) / 8,
        -a * (u - 1) * (u + 1) ** 2 * (v - 1) / 16,
        b * (v + 1) * (v - 1) ** 2 * (u + 1) / 16,
        -z * (u + 1) * (v - 1) / 4,
        # corner C (a, b)
        -(u + 1) * (v + 1) * (v**2 - v + u**2 - u - 2) / 8,
        a * (u - 1) * (u + 1) ** 2 * (v + 1) / 16,
        b * (v - 1) * (v + 1) ** 2 * (u + 1) / 16,
        z * (u + 1) * (v + 1) / 4,
        # corner D (0, b)
        (u - 1) * (v + 1) * (v**2 - v + u**2 + u - 2) / 8,
        a * (u + 1) * (u - 1) ** 2 * (v + 1) / 16,
        -b * (v - 1) * (v + 1) ** 2 * (u - 1) / 16,
        -z * (u - 1) * (v + 1) / 4,
    ),
    quadrature=(7, 7, 3),
    description="4-node plate (Mikkola & Shabana, Chrono ANCF-3443), r, r_x, r_y, r_z per "
                "corner, 48 coordinates",
)
