"""The analysis and run settings of a scene: ``[analysis.static]``, ``[analysis.modal]``,
``[analysis.dynamic]``, ``[solver]`` and ``[output]`` as frozen dataclasses (units SI, times in
s), each writing its TOML table back (``to_dict``)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from runtime.model.schema import table

# relative tolerance on t_end / step and output_every / step being integers
MULTIPLE_TOLERANCE = 1e-9


@dataclass(frozen=True)
class Static:
    """Static analysis: Newton-Raphson, at most ``max_iterations`` per load increment,
    convergence ``tolerance`` (relative: corrections to the model's size, residuals to its
    forces).

    ``method``: ``load_stepping`` (the loads applied in ``load_steps`` equal increments) or
    ``arc_length`` (Crisfield's cylindrical arc length: the path of equilibria through limit
    points, the load factor an unknown).  Arc length: ``arc_length`` the first step's length
    (m, over the free coordinates; None: that of the linear predictor at 1/load_steps of the
    load), at most ``max_steps`` converged points; the path stops at the first point with a
    load factor of at least ``max_load_factor``, or whose sensor ``stop_sensor`` has passed
    ``stop_value`` (its unit) from its value at the start."""

    max_iterations: int = 50
    tolerance: float = 1e-10
    load_steps: int = 1
    method: str = "load_stepping"
    arc_length: float | None = None
    max_steps: int = 100
    max_load_factor: float = 1.0
    stop_sensor: str | None = None
    stop_value: float | None = None

    def to_dict(self) -> dict[str, Any]:
        """The TOML table ``[analysis.static]``."""
        return table(self)


@dataclass(frozen=True)
class Modal:
    """Modal analysis: the ``modes`` lowest frequencies about the reference configuration or
    the static solution."""

    modes: int = 4
    about: str = "reference"

    def to_dict(self) -> dict[str, Any]:
        """The TOML table ``[analysis.modal]``."""
        return table(self)


@dataclass(frozen=True)
class Dynamic:
    """Dynamic analysis from 0 to ``t_end`` (s) with time step ``step`` (s), ``t_end`` an integer
    multiple of ``step``; outputs every ``output_every`` s (a multiple of ``step``; None: every
    step); ``rho_inf`` in [0, 1] for generalized-alpha; ``newton``: ``full`` (a new Jacobian
    at every iteration), ``modified`` (Jacobian reused) or ``auto`` (the default: modified,
    and full for the steps after one that needed a new Jacobian where that is cheaper):
    runtime.solve.python_engine."""

    t_end: float
    step: float
    integrator: str = "trapezoidal"
    output_every: float | None = None
    rho_inf: float = 0.8
    tolerance: float = 1e-10
    max_iterations: int = 20
    frequency_of: str | None = None    # sensor whose oscillation frequency is measured ...
    frequency_after: float = 0.0       # ... from this time (s) to t_end
    newton: str = "auto"

    def to_dict(self) -> dict[str, Any]:
        """The TOML table ``[analysis.dynamic]``."""
        return table(self)


@dataclass(frozen=True)
class Solver:
    """Elastic force method (gram | cij | quadrature), kernel backend (c | numpy), engine
    (compiled | python; None: compiled when a C compiler is present and the backend is c, else
    python), linear solver of the Newton iterations (banded | sparse; None: chosen per
    model, ``runtime.solve.linear.choose``) and the compiled step's ``threads`` for the
    element kernels (None: chosen per model, ``runtime.solve.compiled_engine.threads``)."""

    method: str = "gram"
    backend: str = "c"
    engine: str | None = None
    linear_solver: str | None = None
    threads: int | None = None

    def to_dict(self) -> dict[str, Any]:
        """The TOML table ``[solver]``."""
        return table(self)


@dataclass(frozen=True)
class Output:
    """What a run writes beyond the summary and time series: ``vtk`` (VTU/PVD files of the
    deformed bodies), ``animation`` (a GIF), ``states`` (keep the nodal states in memory)."""

    vtk: bool = False
    animation: bool = False
    states: bool = False

    def to_dict(self) -> dict[str, Any]:
        """The TOML table ``[output]``."""
        return table(self)
