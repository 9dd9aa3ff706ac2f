"""What a run of a scene gives back: the whole :class:`Result` of ``run_scene``, with its
:class:`States` and :class:`Modes`, and the :class:`Observer` that receives the results as
they are computed (``ancf run``'s writers, the VTU series, the animation frames).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from runtime.model.model import Model

__all__ = ["Modes", "Observer", "Result", "States"]


@dataclass
class States:
    """Coordinates and velocities of the whole model at the dynamic output times:
    ``t`` (n,) s, ``q`` (n, size) m (gradients unitless), ``v`` (n, size) m/s (1/s)."""

    t: np.ndarray
    q: np.ndarray
    v: np.ndarray


@dataclass
class Modes:
    """Modal analysis: ``frequencies_rad_s`` (k,) ascending, ``shapes`` (k, size) full
    coordinate vectors (fixed and prescribed coordinates zero) normalised to a largest
    position component (nodes, rigid origins) of +1, ``about`` (size,) the linearisation
    point."""

    frequencies_rad_s: np.ndarray
    shapes: np.ndarray
    about: np.ndarray


@dataclass
class Result:
    """What ``run_scene`` computed.

    summary: the document of ``summary.json`` (``Summary.to_dict``), less what the writers
    add (``files``, the plots' ``timing.postprocess_s`` and warnings); sensors: {"t": output
    times (n,) s, sensor name: values (n,)} of the dynamic analysis ({} without one; static
    values are in ``summary["static"]["sensors"]``); static: equilibrium coordinates (size,)
    or None; modes: :class:`Modes` or None; states: :class:`States` when asked, else None;
    model: the ``Model`` (indexing, reference, sampling of shapes); exit_code: 0 ok, 1
    diverged (results kept up to then); path: the arc-length path of the static analysis,
    {"load_factor": (k,), sensor name: values (k,)} over its converged points, the start
    first ({} with load stepping).
    """

    summary: dict
    sensors: dict[str, np.ndarray]
    static: np.ndarray | None
    modes: Modes | None
    states: States | None
    model: Model
    exit_code: int
    path: dict[str, np.ndarray] = field(default_factory=dict)

    @property
    def status(self) -> str:
        """``ok`` or ``diverged``."""
        return self.summary["status"]


class Observer:
    """Receives a run's results as they are computed; every hook does nothing by default.

    Order: ``begin`` once the model is built; ``static_path`` (arc length only), ``static``,
    ``modal`` after those analyses;
    ``dynamic_start``, ``samples`` for every block of output times (t = 0 included; by
    default ``sample`` at each), then
    ``dynamic_end`` however the dynamic analysis ends (when it ends by an exception, errors
    of ``dynamic_end`` are ignored).  An exception of a hook stops the run.
    """

    def begin(self, model: Model) -> None:
        """The model is built (kernels compiled); analyses follow."""

    def static(self, q: np.ndarray) -> None:
        """Static equilibrium coordinates (size,)."""

    def static_path(self, path: dict[str, np.ndarray]) -> None:
        """The arc-length path: {"load_factor": (k,), sensor name: values (k,)}."""

    def modal(self, modes: Modes) -> None:
        """Frequencies and mode shapes."""

    def dynamic_start(self, names: list[str]) -> None:
        """The dynamic analysis starts; ``names``: sensors in scene order."""

    def sample(self, t: float, q: np.ndarray, v: np.ndarray, values: dict[str, float]) -> None:
        """Output time t (s): coordinates, velocities (size,) and sensor values."""

    def samples(self, times: np.ndarray, q: np.ndarray, v: np.ndarray,
                values: dict[str, np.ndarray]) -> None:
        """A block of output times (k,) in s: coordinates and velocities (k, size), sensor
        values (k,) each.  By default ``sample`` at each time in turn; an observer that can
        take a whole block at once (a CSV writer) overrides it."""
        for row, t in enumerate(times):
            self.sample(float(t), q[row], v[row],
                        {name: float(value[row]) for name, value in values.items()})

    def dynamic_end(self) -> None:
        """The dynamic analysis ended (completed, diverged, interrupted or failed)."""
