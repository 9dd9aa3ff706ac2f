"""Project Chrono's ANCF-3843 brick (Orzechowski, Matikainen and Mikkola): r, r_x, r_y, r_z at
the eight corners of the box x, y, z in [0, a] x [0, b] x [0, c], 96 coordinates.

In Chrono's normalised coordinates xi_c = 2x/a - 1, eta_c = 2y/b - 1, zeta_c = 2z/c - 1 the
corners A, B, C, D are (-1, -1, -1), (1, -1, -1), (1, 1, -1), (-1, 1, -1) (counter-clockwise
on the bottom face) and E, F, G, H the same points on the top face (zeta_c = 1).  With the
corner's signs (p, q, s) and the trilinear factor L = (1 + p xi_c)(1 + q eta_c)(1 + s zeta_c),
the position function is -L (xi_c^2 + eta_c^2 + zeta_c^2 - p xi_c - q eta_c - s zeta_c - 2)/16
and the slope function along x is a/32 (xi_c^2 - 1)(xi_c + p)(1 + q eta_c)(1 + s zeta_c)
(along y and z the same with the roles exchanged): Chrono's ``Calc_Sxi_compact`` written by
the corners' signs.  The functions are cubic in each axis, so 4 x 4 x 4 Gauss points
integrate the mass and 7 x 7 x 7 the straight force exactly.
"""

from symgen import domains
from symgen.element import ElementSpec, x, y, z

a, b, c = domains.side_a, domains.side_b, domains.side_c
u, v, w = 2 * x / a - 1, 2 * y / b - 1, 2 * z / c - 1     # Chrono's xi, eta, zeta in [-1, 1]
# corner signs (p, q, s): A, B, C, D on the bottom face, then E, F, G, H on the top (Chrono)
SIGNS = ((-1, -1, -1), (1, -1, -1), (1, 1, -1), (-1, 1, -1),
         (-1, -1, 1), (1, -1, 1), (1, 1, 1), (-1, 1, 1))


def corner_functions(p: int, q: int, s: int) -> tuple:
    """The four shape functions (r, r_x, r_y, r_z) of the corner with signs (p, q, s)."""
    along = ((1 + p * u), (1 + q * v), (1 + s * w))
    trilinear = along[0] * along[1] * along[2]
    position = -trilinear * (u**2 + v**2 + w**2 - p * u - q * v - s * w - 2) / 16
    slopes = tuple(side / 32 * (t**2 - 1) * (t + sign) * trilinear / along[axis]
                   for axis, (side, t, sign) in enumerate(((a, u, p), (b, v, q), (c, w, s))))
    return (position, *slopes)


ELEMENT = ElementSpec(
    name="brick3d_3843",
    domain=domains.box(),
    nodes=tuple(((p + 1) * a / 2, (q + 1) * b / 2, (s + 1) * c / 2) for p, q, s in SIGNS),
    vectors=("r", "r_x", "r_y", "r_z"),
    shape_functions=tuple(f for signs in SIGNS for f in corner_functions(*signs)),
    quadrature=(7, 7, 7),
    description="8-node brick (Chrono ANCF-3843), r, r_x, r_y, r_z per corner, 96 coordinates",
)
