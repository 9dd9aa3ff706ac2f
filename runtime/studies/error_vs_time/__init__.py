"""``ancf study error-vs-time SCENE``: a work-precision study of a scene.

Every combination of mesh size (elements per body), time step (s), integrator and elastic
force method is run as an independent case (in parallel through ``runtime.studies.sweep``);
each run's error is measured

* ``static_tip``: against the Euler-Bernoulli tip deflection ``P L^3 / (3 E I)`` of a
  cantilever (relative error of the static value of a displacement sensor of the loaded tip);
* ``frequency``: against the first bending frequency ``1.8751^2 sqrt(E I / (rho A L^4))``
  (rad/s) of a cantilever (relative error of the dynamic response frequency of a sensor);
* ``reference``: against a converged reference run on a finer mesh and step (max abs
  difference of the sensor's time series on the reference's output times, divided by the
  reference's max abs value);

and its wall time is taken from the run's summary (``simulate_s``: the analyses, without
compilation and plots; ``total_s``: the whole run).  Outputs in the study folder:
``error_vs_time.csv`` (one row per run), ``error_vs_time.png`` (log-log error against
simulate time, one line per method and integrator) and ``error_vs_time.md`` (the table and a
paragraph on which choice is cheapest for a given accuracy).

The sweep comes from a ``[study]`` table of the scene and/or from command-line options, which
override the table::

    [study]
    elements = [2, 5, 10]                  # elements per body
    step = [1e-3, 5e-4]                    # s (dynamic errors only)
    integrator = ["trapezoidal", "generalized_alpha"]
    method = ["gram", "cij", "quadrature"]
    backend = "c"
    error = "frequency"                    # static_tip | frequency | reference
    sensor = "tip_y"                       # the sensor the error is computed from
    reference = { elements = 40, step = 2.5e-4 }   # reference runs (error = "reference")
    t_end = 4.0                            # s, overrides [analysis.dynamic].t_end
    repeat = 1                             # runs per case, the fastest kept (static: 5)
    targets = [1e-2, 1e-3]                 # accuracies of the summary (default: decades)

Every run keeps only the analysis and the sensor its error needs (the static analysis for
``static_tip``, the dynamic one otherwise), so the times measure what the error measures.

The package, by responsibility (imports one way: plan <- measure <- report <- run <- cli):
``plan`` (the [study] table and options validated, the cantilever's closed forms),
``measure`` (one run per case, its error measured), ``report`` (CSV, plot, Markdown),
``run`` (the study from end to end) and ``cli`` (``ancf study error-vs-time``).  This module
names the public interface.
"""

from runtime.studies.error_vs_time.cli import add_cli
from runtime.studies.error_vs_time.measure import run_case
from runtime.studies.error_vs_time.plan import MEASURES, StudyError, plan_study
from runtime.studies.error_vs_time.report import CSV_COLUMNS, plot
from runtime.studies.error_vs_time.run import study

__all__ = [
    "CSV_COLUMNS",
    "MEASURES",
    "StudyError",
    "add_cli",
    "plan_study",
    "plot",
    "run_case",
    "study",
]
