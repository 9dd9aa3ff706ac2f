"""The exact-curvature families of cable elements (bending model ``exact_curvature`` of
``symgen.energies``): the bending energy EI/2 int |kappa|^2 dx, kappa = r_x x r_xx / |r_x|^2,
is rational in the coordinates, so it is integrated by Gauss quadrature along the axis at
every call, while the axial part keeps its method:

* ``gram_curvature_<variant>``    - the gram kernels of the axial part (no linear term; the
                                   storage pattern of ``variant``) plus the bending
                                   quadrature loop;
* ``cij_curvature``               - the cij kernels of the axial part (K1 without bending)
                                   plus the bending loop;
* ``damping_curvature_<variant>`` - the gram damping kernels of the axial part plus the
                                   bending loop with its Kelvin-Voigt damping (the
                                   curvature rate);
* ``quadrature_curvature`` - both parts by quadrature, elastic and damping kernels (as
                             ``quadrature_law``).

The bending loop reads the cable's quadrature table (``cable_table_array``: ds/dx, d2s/dx2,
the axial and bending weights) and its statements come from ``cable_point``, the code of the
cable's quadrature kernels.
"""

from __future__ import annotations

from symgen.element import ElementSpec
from symgen.ir import Kernel, PointLoop, Temporaries
from symgen.methods.cij import cij_kernel
from symgen.methods.common import DAMPING_KERNELS, KERNELS, kernel_name, translate
from symgen.methods.damping import gram_damping_kernel
from symgen.methods.gram import gram_kernel
from symgen.methods.quadrature import cable_point, cable_quadrature_kernel, cable_table_array

#: The bending model of these families (``symgen.energies.BENDING_MODELS``).
BENDING = "exact_curvature"


def with_bending_loop(spec: ElementSpec, kernel: Kernel) -> Kernel:
    """``kernel`` (of the axial part) with the table input and, after its statements, the
    bending part accumulated over the axis points into its outputs."""
    first_output = next(i for i, a in enumerate(kernel.arrays) if a.role == "output")
    kernel.arrays.insert(first_output, cable_table_array(spec, BENDING))
    temps = Temporaries("b")  # the kernel's own temporaries are t...
    q, _, _ = translate(spec, kernel.body, temps, with_reference=False)
    zero = [0] * spec.ndof
    point = cable_point(spec, kernel.name, zero, q, temps, BENDING, axial=False)
    kernel.body.append(PointLoop("table", tuple(point), spec.quadrature[0]))
    kernel.doc = f"{kernel.doc[:-1]}, plus the exact-curvature bending by Gauss quadrature."
    return kernel


def build_gram(spec: ElementSpec, variant: str) -> list[Kernel]:
    """The kernels of ``gram_curvature_<variant>``."""
    return [with_bending_loop(spec, gram_kernel(spec, quantities, variant, BENDING))
            for quantities in KERNELS]


def build_cij(spec: ElementSpec) -> list[Kernel]:
    """The kernels of ``cij_curvature``."""
    return [with_bending_loop(spec, cij_kernel(spec, quantities, "straight"))
            for quantities in KERNELS]


def build_damping(spec: ElementSpec, variant: str) -> list[Kernel]:
    """The kernels of ``damping_curvature_<variant>``."""
    return [with_bending_loop(spec, gram_damping_kernel(spec, name, variant, BENDING))
            for name in DAMPING_KERNELS]


def build_quadrature(spec: ElementSpec) -> list[Kernel]:
    """The kernels of ``quadrature_curvature`` (elastic and damping)."""
    names = [kernel_name(q) for q in KERNELS] + list(DAMPING_KERNELS)
    return [cable_quadrature_kernel(spec, name, BENDING) for name in names]
