"""``ancf bench precision``: how long it takes to get an answer to a given accuracy, the
project and its peer Exudyn measured side by side in one run.

Three problems: the rotating beam spin-up (scenes/rotating_beam.toml, 20 s, tip deflection in
the hub frame), the static elastica (a slender cantilever under a fixed-direction tip load,
P L^2 / EI = 10, load steps) and the paper cantilever (scenes/cantilever.toml, 4 s dynamic).
Every line kind of the problem's dimension, element count, time step (or load steps),
integrator and Newton mode of the project runs on the compiled engine; Exudyn's ANCFCable2D
runs the same meshes and steps with modified and full Newton.  Each run is timed in
interleaved repeats (min and median) and its error measured against its code's converged
reference (dynamic) or the exact elastica (static, ``elastica``: two independent solutions
and Mattiasson's table).

The package, by responsibility (imports one way: plan <- measure <- report <- run <- cli):
``elastica`` (the exact solution), ``plan`` (problems and configurations from the catalog),
``measure`` (scenes, runs, error measures), ``report`` (CSV, plot, Markdown), ``run`` (end to
end) and ``cli`` (the subcommand).
"""

from runtime.studies.precision.cli import add_cli
from runtime.studies.precision.run import study

__all__ = ["add_cli", "study"]
