"""Engines that run a dynamic analysis: the registry (the only list of them).

* ``compiled``: the whole time step in generated C (``runtime.solve.compiled_engine``), the default
  wherever the C backend works;
* ``python``: the readable reference (``runtime.solve.python_engine``), the only one with the
  NumPy backend.

Both take ``(model, settings, q_full)`` and offer ``run(t_end, step, observe, progress)``
and ``counters``; they agree to round-off.
"""

from __future__ import annotations

import numpy as np

from runtime import catalog
from runtime.model.model import Model
from runtime.solve.python_engine import INTEGRATORS


def _python(model: Model, settings, q_full: np.ndarray):
    return INTEGRATORS[settings.integrator](model, settings, q_full)


def _compiled(model: Model, settings, q_full: np.ndarray):
    from runtime.solve.compiled_engine import CompiledEngine

    return CompiledEngine(model, settings, q_full)


ENGINES = {"compiled": _compiled, "python": _python}
assert tuple(ENGINES) == catalog.ENGINES


def choose(requested: str | None, backend: str) -> str:
    """The engine to use: ``requested``, or by default ``compiled`` with the C backend and
    ``python`` with NumPy.  ValueError naming the option when they do not fit."""
    if requested is None:
        return "compiled" if backend == "c" else "python"
    if requested not in ENGINES:
        raise ValueError(f"engine: expected one of {', '.join(ENGINES)}, got {requested!r}")
    if requested == "compiled" and backend != "c":
        raise ValueError(f"engine: the compiled engine needs backend \"c\", got backend "
                         f"{backend!r}; use engine \"python\" or backend \"c\"")
    return requested


def make(name: str, model: Model, settings, q_full: np.ndarray):
    """The engine ``name`` for a dynamic analysis of ``model`` from ``q_full``."""
    return ENGINES[name](model, settings, q_full)


def static_newton(name: str, model: Model, settings, integrator: str):
    """The Newton solve of one static load increment of engine ``name`` (see
    ``runtime.solve.static.solve_static``): None for the Python one, the generated step's
    for ``compiled`` (its module the one of a dynamic analysis with ``integrator``).
    A model with rigid items of their own coordinates takes the Python solve with either
    engine: their coordinates have no elastic stiffness, so the compiled step's Schur
    complement (which needs the stiffness regular) cannot solve its saddle point."""
    if name == "python" or any(r.dofs.size for r in model.rigid.values()):
        return None
    from runtime.solve.compiled_engine import CompiledStatic

    return CompiledStatic(model, settings, integrator)
