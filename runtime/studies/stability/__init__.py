"""``ancf study stability``: extreme cases of the toolchain, each with its measured outcome.

Four groups of rows, each row pass / fail against a stated tolerance (or informational):

* ``kernel_accuracy``: force and strain energy of every method (gram, cij, quadrature; C
  backend) against the 50-digit mpmath reference of ``runtime.studies.highprecision``
  (direct quadrature, no code shared with the kernels) at strains of 1e-3 .. 1e-9, far from
  the origin, under a large rotation, for very stiff and very soft materials, slender
  sections and nearly incompressible materials;
* ``integrator``: the paper's trapezoidal rule against generalized-alpha on a slender beam2d
  whose axial and thickness modes are far faster than its bending modes, released from a
  static deflection: energy drift, Newton iterations, and the steps at which each fails;
* ``newton``: the convergence order of Newton's method on a large-deflection cantilever with
  the analytic Jacobian, and with finite-difference Jacobians (cost and order);
* ``poisson_locking``: the 2D cantilever L = 2 m, h = 0.5 m, w = 0.1 m, tip load 62.5 kN
  against its shear-deformable beam-theory deflection 8.099e-4 m, at nu = 0.3 and nu = 0,
  with the svk law (which locks) and the ecm law (the remedy);
* ``chrono_beam``: Project Chrono's ANCF-3243 unit-test beam (aluminium, nu = 0.33, 20
  beam3d elements) under an axial load, a tip load and gravity, against P L / EA,
  P L^3 / 3EI and q L^4 / 8EI, with both laws.

Independent cases run through ``runtime.studies.sweep.run_cases`` (dask.distributed: a local
cluster by default, or an existing scheduler).  Case functions are module-level so that dask
can ship them; each returns plain dicts.

The package, by responsibility (imports one way: plan <- the groups <- measure <- report <-
cli): ``plan`` (the rows, the groups, the problems and the list of cases), one module per
group measuring its cases (``kernel_accuracy``, ``integrators``, ``newton``, ``locking``:
Poisson locking and Chrono's beam), ``measure`` (every case run, the rows collected),
``report`` (Markdown, JSON, CSV) and ``cli`` (``ancf study stability``).  This module names
the public interface.
"""

from runtime.studies.stability.cli import add_cli
from runtime.studies.stability.kernel_accuracy import kernel_accuracy_case
from runtime.studies.stability.measure import run_case, stability_study
from runtime.studies.stability.newton import convergence_order
from runtime.studies.stability.plan import GROUPS, Row, cases
from runtime.studies.stability.report import markdown, summary, write

__all__ = [
    "GROUPS",
    "Row",
    "add_cli",
    "cases",
    "convergence_order",
    "kernel_accuracy_case",
    "markdown",
    "run_case",
    "stability_study",
    "summary",
    "write",
]
