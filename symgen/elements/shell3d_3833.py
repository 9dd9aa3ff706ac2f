"""Project Chrono's ANCF-3833 shell (Ebel, Matikainen, Hurskainen and Mikkola 2017): r, r_z and
r_zz at the four corners and the four mid-sides of x in [0, a], y in [0, b], 72 coordinates.

The 8-node serendipity layout of ``shell3d_8node`` (Chrono's node order: corners A, B, C, D
counter-clockwise from (0, 0), then mid-sides E, F, G, H) with a third nodal vector, the
second thickness derivative r_zz, which lets a fibre through the thickness bend and stretch
quadratically (no Poisson thickness locking).  With the node's serendipity function S_i
(in Chrono's normalised coordinates xi_c = 2x/a - 1, eta_c = 2y/b - 1) the node's three shape
functions are S_i, z S_i and z^2 / 2 S_i (Chrono's zeta = 2z/t: z = t zeta / 2 for a single
layer on the mid-surface), so d^2/dz^2 of the last is S_i.  At a flat reference r_zz = 0.
Gauss orders 5 x 5 x 5 integrate the straight element's force exactly (Chrono's "full
integration"; its element defaults to a reduced 3 x 3 x 2, its unit-test data are exact).
"""

from symgen import domains
from symgen.element import ElementSpec, z
from symgen.elements.shell3d_8node import POINTS, serendipity

a, b = domains.side_a, domains.side_b

ELEMENT = ElementSpec(
    name="shell3d_3833",
    domain=domains.plate(),
    nodes=tuple(((p + 1) * a / 2, (q + 1) * b / 2, 0) for p, q in POINTS),
    vectors=("r", "r_z", "r_zz"),
    shape_functions=tuple(f * serendipity(p, q) for p, q in POINTS
                          for f in (1, z, z**2 / 2)),
    quadrature=(5, 5, 5),
    description="8-node shell (Chrono ANCF-3833), r, r_z, r_zz per corner and mid-side, "
                "72 coordinates",
)
