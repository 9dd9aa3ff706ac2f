"""Loads written as Python functions of the state (controllers, feedback torques).

A Python load is a generalised force ``f(t, q, v) -> (size,)`` in N (per coordinate) of the
time t (s) and the full coordinates q and velocities v (size,) of the model, called once
per force evaluation (every Newton iteration) by both engines through ``StateLoads``.  It
acts on, and depends on, the coordinates of its ``nodes`` (all coordinates by default);
its Jacobians df/dq and df/dv over those coordinates are the user's ``jacobian(t, q, v) ->
(df/dq, df/dv)`` (dense (size, size) or SciPy sparse; df/dv may be None: no velocity
dependence), or central finite differences of steps ``RATE_STEP * max(1, |x|)`` (4 k + 1
calls of f for k coordinates).  df/dq joins the load stiffness, df/dv the damping part of
the Newton matrix (as the Kelvin-Voigt damping Jacobian).
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse

from runtime.model.items.follower import Patches
from runtime.model.time_laws import RATE_STEP, LoadFunctionError, import_function

__all__ = ["MotionPatches", "PythonForce", "PythonFunction", "load_notes"]


@dataclass(frozen=True)
class PythonFunction:
    """A Python function named in a scene: ``spec`` is "module:function" (TOML) or the
    callable itself (Python API); ``call`` the function."""

    spec: str | Callable
    call: Callable

    @staticmethod
    def parse(value: Any, path: str, folder: str | None) -> PythonFunction:
        """The function of ``value`` ("module:function", a callable or a PythonFunction);
        SceneError naming ``path`` when it cannot be imported."""
        if isinstance(value, PythonFunction):
            return value
        return PythonFunction(value, import_function(value, path, folder))

    def to_dict(self) -> str | Callable:
        """Its scene value (``runtime.model.schema.plain``): the spec as given."""
        return self.spec

    @property
    def name(self) -> str:
        """How messages name it."""
        if isinstance(self.spec, str):
            return self.spec
        return getattr(self.spec, "__qualname__", repr(self.spec))


@dataclass
class MotionPatches(Patches):
    """``Patches`` of a load that depends on velocities too: ``jacobian_dot`` (m, k, k) =
    d force / d v[dofs] (None when not asked)."""

    jacobian_dot: np.ndarray | None = None


class PythonForce:
    """The state force of a Python load over the coordinates ``dofs`` (k,) of a model of
    ``size`` coordinates; ``where`` (its key path, "load[0]") names it in errors.  ``calls``
    and ``seconds`` count the calls of ``function`` and the time spent in them."""

    #: it reads the velocities: called as (q, jacobian, v, t), its patches ``MotionPatches``
    reads_velocity = True

    def __init__(self, function: PythonFunction, jacobian: PythonFunction | None,
                 dofs: np.ndarray, size: int, where: str) -> None:
        self.function, self.jacobian_function = function, jacobian
        self.dofs = np.asarray(dofs, np.int64)[None, :]
        self.size, self.where = size, where
        self._outside = np.ones(size, bool)
        self._outside[self.dofs[0]] = False
        self.calls, self.seconds = 0, 0.0

    @property
    def finite_differences(self) -> bool:
        """Whether its Jacobians are finite differences (no ``jacobian`` given)."""
        return self.jacobian_function is None

    def force(self, t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """f(t, q, v) (size,), checked (LoadFunctionError naming the key)."""
        key = f"{self.where}.function"
        start = time.perf_counter()
        try:
            out = self.function.call(float(t), q.copy(), v.copy())
        except Exception as error:
            raise LoadFunctionError(f"{key}: {self.function.name} raised "
                                    f"{type(error).__name__}: {error} at t = {t:.6g} s") from None
        finally:
            self.calls += 1
            self.seconds += time.perf_counter() - start
        force = _array(out, (self.size,), key, self.function.name, t,
                       "a generalised force over the model's coordinates")
        if np.any(force[self._outside]):
            i = int(np.flatnonzero(force * self._outside)[0])
            raise LoadFunctionError(f"{key}: {self.function.name} returned a force on "
                                    f"coordinate {i}, outside the coordinates of its nodes; "
                                    f"list that coordinate's node in {self.where}.nodes")
        return force

    def __call__(self, q: np.ndarray, jacobian: bool, v: np.ndarray | None = None,
                 t: float = 0.0) -> MotionPatches:
        v = np.zeros(self.size) if v is None else v
        dofs = self.dofs[0]
        force = self.force(t, q, v)
        if not jacobian:
            return MotionPatches(self.dofs, force[dofs][None], None, None)
        if self.jacobian_function is None:
            d_q, d_v = self._differences(t, q, v, force)
        else:
            d_q, d_v = self._given(t, q, v)
        return MotionPatches(self.dofs, force[dofs][None], d_q[None], d_v[None])

    def _given(self, t: float, q: np.ndarray, v: np.ndarray):
        """The user's (df/dq, df/dv) restricted to the load's coordinates, each (k, k)."""
        key, name = f"{self.where}.jacobian", self.jacobian_function.name
        try:
            out = self.jacobian_function.call(float(t), q.copy(), v.copy())
        except Exception as error:
            raise LoadFunctionError(f"{key}: {name} raised {type(error).__name__}: {error} "
                                    f"at t = {t:.6g} s") from None
        if not isinstance(out, tuple) or len(out) != 2:
            raise LoadFunctionError(f"{key}: {name} returned {type(out).__name__}; expected "
                                    "a pair (df/dq, df/dv) (df/dv may be None)")
        dofs = self.dofs[0]
        parts = []
        for part, what in zip(out, ("df/dq", "df/dv"), strict=True):
            if part is None and what == "df/dv":
                parts.append(np.zeros((dofs.size, dofs.size)))
                continue
            if scipy.sparse.issparse(part):
                if part.shape != (self.size, self.size):
                    raise LoadFunctionError(f"{key}: {name} returned {what} of shape "
                                            f"{part.shape}; expected ({self.size}, {self.size})")
                block = part.tocsr()[dofs][:, dofs].toarray()
            else:
                block = _array(part, (self.size, self.size), key, name, t, what)[
                    np.ix_(dofs, dofs)]
            if not np.all(np.isfinite(block)):
                raise LoadFunctionError(f"{key}: {name} returned a non-finite {what} at "
                                        f"t = {t:.6g} s")
            parts.append(block)
        return parts[0], parts[1]

    def _differences(self, t: float, q: np.ndarray, v: np.ndarray, force: np.ndarray):
        """Central differences of f over the load's coordinates, in q and in v, (k, k)."""
        dofs = self.dofs[0]
        out = []
        for wrt in (0, 1):
            columns = np.empty((dofs.size, dofs.size))
            for c, j in enumerate(dofs):
                state = [q.copy(), v.copy()]
                h = RATE_STEP * max(1.0, abs(state[wrt][j]))
                state[wrt][j] += h
                plus = self.force(t, *state)[dofs]
                state[wrt][j] -= 2 * h
                columns[:, c] = (plus - self.force(t, *state)[dofs]) / (2 * h)
            out.append(columns)
        return out[0], out[1]


def _array(value: Any, shape: tuple[int, ...], key: str, name: str, t: float,
           what: str) -> np.ndarray:
    """``value`` as a float array of ``shape`` with finite entries (LoadFunctionError)."""
    try:
        array = np.asarray(value, float)
    except (TypeError, ValueError):
        array = None
    if array is None or array.shape != shape:
        found = "?" if array is None else array.shape
        raise LoadFunctionError(f"{key}: {name} returned shape {found}; expected {what} of "
                                f"shape {shape}")
    bad = ~np.isfinite(array)
    if bad.any():
        raise LoadFunctionError(f"{key}: {name} returned a non-finite value {array[bad][0]} "
                                f"at t = {t:.6g} s")
    return array


def load_notes(loads) -> list[str]:
    """A note per Python load of a scene's ``loads`` whose Jacobians are finite differences
    (the run summary's ``loads``)."""
    notes = []
    for i, load in enumerate(loads):
        if load.type == "python" and load.jacobian is None:
            over = "every coordinate" if load.nodes is None else \
                f"the coordinates of {', '.join(ref.spelled() for ref in load.nodes)}"
            notes.append(f"load[{i}] ({load.function.name}): Jacobians df/dq and df/dv by "
                         f"central finite differences over {over} (4 k + 1 calls of the "
                         "function for k coordinates); give jacobian = \"module:function\" "
                         "for exact ones")
    return notes
