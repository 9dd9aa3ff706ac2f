"""Time laws of scenes: load factors and prescribed angles as functions of time.

Every law is a frozen dataclass with ``value(t)``, ``rate(t)`` (d/dt) and ``acceleration(t)``
(d^2/dt^2), exact (analytic), taking the time ``t`` in s and returning a float.  The unit of
the value is the one of its use: a dimensionless factor that multiplies a load vector, or an
angle in rad (``rate`` in 1/s or rad/s, ``acceleration`` in 1/s^2 or rad/s^2).

Ramps (``cosine_ramp``, ``linear_ramp``, ``spin_up``) are zero, at rest, for t < 0; at the end
of a ramp the formula of the ramp is used (``t <= duration``), as in eqs. 42 and 45.

``python`` laws are Python functions of time, ``f(t: ndarray) -> ndarray`` (s -> value),
evaluated vectorised over the step times of a block as the other laws are sampled: in TOML
``{type = "python", function = "module:function"}`` (the module imported from the scene's
folder, then ``sys.path``), in the Python API the callable itself (``time_law=f``).

``parse_law`` builds one from a scene's TOML table ``{type = "...", ...}``; its errors are
``SceneError`` naming the key path.
"""

from __future__ import annotations

import dataclasses
import importlib
import math
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, ClassVar

import numpy as np

from runtime.model.errors import SceneError, is_finite, show

__all__ = [
    "LAWS",
    "Constant",
    "ConstantRate",
    "CosineRamp",
    "Law",
    "LinearRamp",
    "LoadFunctionError",
    "PythonLaw",
    "Sine",
    "SpinUp",
    "Table",
    "import_function",
    "parse_law",
]


@dataclass(frozen=True)
class Law:
    """Base class of the time laws; ``type`` is the name used in scenes.  A law implements
    ``sample`` (vectorised over an array of times, one formula per law); ``value``, ``rate``
    and ``acceleration`` at one time are read from it."""

    type: ClassVar[str] = ""
    # per field: "number" (finite), "positive" (finite > 0) or "points" (table points)
    checks: ClassVar[dict[str, str]] = {}

    def sample(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(value, rate, acceleration) at every time of the array ``t`` (s), each t.shape."""
        raise NotImplementedError

    def value(self, t: float) -> float:
        """The law at time t (s)."""
        return float(self.sample(np.array([t], float))[0][0])

    def rate(self, t: float) -> float:
        """First time derivative at t (s), per second."""
        return float(self.sample(np.array([t], float))[1][0])

    def acceleration(self, t: float) -> float:
        """Second time derivative at t (s), per second squared."""
        return float(self.sample(np.array([t], float))[2][0])

    def to_dict(self) -> dict[str, Any]:
        """The TOML table that builds this law (``parse_law(law.to_dict(), ...) == law``)."""
        out: dict[str, Any] = {"type": self.type}
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            key = f.metadata.get("key", f.name)
            out[key] = [list(p) for p in value] if key == "points" else value
        return out


@dataclass(frozen=True)
class Constant(Law):
    """``scale`` (TOML key ``value``) at every time."""

    type: ClassVar[str] = "constant"
    checks: ClassVar[dict[str, str]] = {"value": "number"}
    scale: float = dataclasses.field(default=1.0, metadata={"key": "value"})

    def sample(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        zero = np.zeros_like(t)
        return zero + self.scale, zero, zero


@dataclass(frozen=True)
class CosineRamp(Law):
    """Eq. 42: ``scale * (1 - cos(pi t / duration)) / 2`` for 0 <= t <= duration, then
    ``scale``; ``duration`` (s) is the paper's t_c; ``scale`` is the TOML key ``value``."""

    type: ClassVar[str] = "cosine_ramp"
    checks: ClassVar[dict[str, str]] = {"duration": "positive", "value": "number"}
    duration: float
    scale: float = dataclasses.field(default=1.0, metadata={"key": "value"})

    def sample(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        w = math.pi / self.duration
        inside = (t > 0.0) & (t <= self.duration)
        value = np.where(t <= 0.0, 0.0, np.where(inside, 0.5 * self.scale
                                                  * (1.0 - np.cos(w * t)), self.scale))
        rate = np.where(inside, 0.5 * self.scale * w * np.sin(w * t), 0.0)
        acceleration = np.where((t >= 0.0) & (t <= self.duration),
                                0.5 * self.scale * w * w * np.cos(w * t), 0.0)
        return value, rate, acceleration


@dataclass(frozen=True)
class LinearRamp(Law):
    """``scale * t / duration`` for 0 <= t <= duration, then ``scale`` (TOML key ``value``)."""

    type: ClassVar[str] = "linear_ramp"
    checks: ClassVar[dict[str, str]] = {"duration": "positive", "value": "number"}
    duration: float
    scale: float = dataclasses.field(default=1.0, metadata={"key": "value"})

    def sample(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        value = np.where(t <= 0.0, 0.0, np.where(t <= self.duration,
                                                  self.scale * t / self.duration, self.scale))
        rate = np.where((t >= 0.0) & (t <= self.duration), self.scale / self.duration, 0.0)
        return value, rate, np.zeros_like(t)


@dataclass(frozen=True)
class Sine(Law):
    """``offset + amplitude * sin(2 pi frequency_hz t + phase_deg * pi / 180)``."""

    type: ClassVar[str] = "sine"
    checks: ClassVar[dict[str, str]] = {"amplitude": "number", "frequency_hz": "positive",
                                        "phase_deg": "number", "offset": "number"}
    amplitude: float
    frequency_hz: float
    phase_deg: float = 0.0
    offset: float = 0.0

    def sample(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        w = 2.0 * math.pi * self.frequency_hz
        angle = w * t + math.radians(self.phase_deg)
        sin, cos = np.sin(angle), np.cos(angle)
        return (self.offset + self.amplitude * sin, self.amplitude * w * cos,
                -self.amplitude * w * w * sin)


@dataclass(frozen=True)
class Table(Law):
    """Linear interpolation of ``points`` ((t, v) pairs, t strictly increasing), constant
    beyond the ends.  ``rate`` is the slope of the segment that contains t (at a breakpoint,
    the segment that starts there), 0 beyond the ends; ``acceleration`` is 0."""

    type: ClassVar[str] = "table"
    checks: ClassVar[dict[str, str]] = {"points": "points"}
    points: tuple[tuple[float, float], ...]

    def __post_init__(self) -> None:
        points = tuple((float(t), float(v)) for t, v in self.points)
        if not points:
            raise ValueError("points: expected at least one (t, v) pair")
        if any(b[0] <= a[0] for a, b in zip(points, points[1:], strict=False)):
            raise ValueError("points: times must be strictly increasing")
        object.__setattr__(self, "points", points)

    def sample(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        times = np.array([p[0] for p in self.points])
        values = np.array([p[1] for p in self.points])
        # segment [t_i, t_i+1] holding t: -1 before the first point, last index after
        segment = np.searchsorted(times, t, side="right") - 1
        inside = (segment >= 0) & (segment < len(times) - 1)
        i = np.clip(segment, 0, max(len(times) - 2, 0))
        j = np.minimum(i + 1, len(times) - 1)
        span = np.where(j > i, times[j] - times[i], 1.0)
        slope = (values[j] - values[i]) / span
        value = np.where(inside, values[i] + (values[j] - values[i]) * (t - times[i]) / span,
                         np.where(segment < 0, values[0], values[-1]))
        return value, np.where(inside, slope, 0.0), np.zeros_like(t)


@dataclass(frozen=True)
class SpinUp(Law):
    """Eq. 45: angle (rad) of a hub spun up smoothly to ``omega`` (rad/s) in ``t_ramp`` (s):
    ``(omega/T) [t^2/2 + (T/(2 pi))^2 (cos(2 pi t/T) - 1)]`` for 0 <= t <= T,
    ``omega (t - T/2)`` after (T = t_ramp)."""

    type: ClassVar[str] = "spin_up"
    checks: ClassVar[dict[str, str]] = {"omega": "number", "t_ramp": "positive"}
    omega: float
    t_ramp: float

    def sample(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        T, omega = self.t_ramp, self.omega
        c = T / (2.0 * math.pi)
        ramp = (t > 0.0) & (t <= T)
        half = np.sin(math.pi * t / T)
        # (cos x - 1) = -2 sin^2(x/2): no cancellation for small t
        value = np.where(t <= 0.0, 0.0, np.where(
            ramp, (omega / T) * (0.5 * t * t - 2.0 * c * c * half**2), omega * (t - 0.5 * T)))
        rate = np.where(t <= 0.0, 0.0, np.where(
            ramp, (omega / T) * (t - c * np.sin(2.0 * math.pi * t / T)), omega))
        acceleration = np.where(ramp, (omega / T) * 2.0 * half**2, 0.0)
        return value, rate, acceleration


@dataclass(frozen=True)
class ConstantRate(Law):
    """Angle ``omega * t`` (rad) at the constant rate ``omega`` (rad/s), for every t."""

    type: ClassVar[str] = "constant_rate"
    checks: ClassVar[dict[str, str]] = {"omega": "number"}
    omega: float

    def sample(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        zero = np.zeros_like(t)
        return self.omega * t, zero + self.omega, zero


class LoadFunctionError(ValueError):
    """A Python load function or time law that cannot be used (it raised, or returned a
    wrong shape or non-finite values); the message names its scene key (and the time)."""


def import_function(spec: Any, path: str, folder: str | Path | None = None) -> Callable:
    """The function named ``"module:function"`` by ``spec`` (or ``spec`` itself when it is a
    callable), its module imported from ``folder`` (the scene's) first, then ``sys.path``.

    Raises SceneError naming the key path ``path`` for a malformed name, a missing module or
    function, an import that fails, or something that is not callable.
    """
    if callable(spec):
        return spec
    parts = spec.split(":") if isinstance(spec, str) else []
    if len(parts) != 2 or not all(part.strip() for part in parts):
        raise SceneError(f'{path}: expected "module:function" (a Python function), got '
                         f"{show(spec)}")
    module_name, name = (part.strip() for part in parts)
    where = f"the scene's folder {folder} and sys.path" if folder else "sys.path"
    added = [str(folder)] if folder else []
    sys.path[:0] = added
    try:
        module = importlib.import_module(module_name)
    except ModuleNotFoundError as error:
        if error.name is not None and module_name.startswith(error.name):
            raise SceneError(f"{path}: no module {show(module_name)} (looked in {where})") \
                from None
        raise SceneError(f"{path}: importing module {show(module_name)} failed: {error}") \
            from None
    except Exception as error:
        raise SceneError(f"{path}: importing module {show(module_name)} failed: "
                         f"{type(error).__name__}: {error}") from None
    finally:
        del sys.path[:len(added)]
    function = getattr(module, name, None)
    if function is None:
        raise SceneError(f"{path}: module {show(module_name)} "
                         f"({getattr(module, '__file__', '?')}) has no function {show(name)}")
    if not callable(function):
        raise SceneError(f"{path}: {show(spec)} is not a function (a "
                         f"{type(function).__name__})")
    return function


#: relative steps of the central differences that give a Python law's rate and acceleration
RATE_STEP = float(np.cbrt(np.finfo(float).eps))
ACCELERATION_STEP = float(np.finfo(float).eps ** 0.25)


@dataclass(frozen=True)
class PythonLaw(Law):
    """A Python function of time ``function(t: ndarray (n,)) -> ndarray (n,)`` (the unit of
    its use), called once per block of step times.  It may return ``(value, rate,
    acceleration)`` (three such arrays); given only the value, the rate and acceleration
    (prescribed angles need them) are central differences of steps ``RATE_STEP`` and
    ``ACCELERATION_STEP`` times max(1, |t|) s.  ``function`` is a callable or
    ``"module:function"``; ``where`` (the key path) names it in errors."""

    type: ClassVar[str] = "python"
    function: Callable | str
    where: str = dataclasses.field(default="time_law", compare=False, repr=False)
    call: Callable | None = dataclasses.field(default=None, compare=False, repr=False)

    def __post_init__(self) -> None:
        if self.call is None:
            object.__setattr__(self, "call", import_function(self.function,
                                                             f"{self.where}.function"))

    def _values(self, t: np.ndarray):
        try:
            out = self.call(t.copy())
        except Exception as error:
            raise LoadFunctionError(f"{self.where}.function: {_named(self.function)} raised "
                                    f"{type(error).__name__}: {error}") from None
        parts = out if isinstance(out, tuple) else (out,)
        if len(parts) not in (1, 3):
            raise LoadFunctionError(f"{self.where}.function: {_named(self.function)} returned "
                                    f"{len(parts)} arrays; expected the value (or value, "
                                    "rate and acceleration)")
        arrays = []
        for part in parts:
            try:
                array = np.asarray(part, float)
            except (TypeError, ValueError):
                array = None
            if array is None or array.shape != t.shape:
                shape = "?" if array is None else array.shape
                raise LoadFunctionError(
                    f"{self.where}.function: {_named(self.function)} returned shape {shape} "
                    f"for times of shape {t.shape}; expected one value per time "
                    "(f(t: ndarray) -> ndarray of the same shape)")
            bad = ~np.isfinite(array)
            if bad.any():
                raise LoadFunctionError(
                    f"{self.where}.function: {_named(self.function)} returned a non-finite "
                    f"value {array[bad][0]} at t = {t[bad][0]:.6g} s")
            arrays.append(array)
        return arrays

    def sample(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        t = np.asarray(t, float)
        arrays = self._values(t)
        if len(arrays) == 3:
            return tuple(arrays)
        value = arrays[0]
        scale = np.maximum(1.0, np.abs(t))
        h, k = RATE_STEP * scale, ACCELERATION_STEP * scale
        rate = (self._values(t + h)[0] - self._values(t - h)[0]) / (2 * h)
        acceleration = (self._values(t + k)[0] - 2 * value + self._values(t - k)[0]) / (k * k)
        return value, rate, acceleration

    def to_dict(self) -> dict[str, Any]:
        return {"type": self.type, "function": self.function}


def _named(function: Callable | str) -> str:
    """How a Python function is named in messages: its "module:function" or its name."""
    if isinstance(function, str):
        return show(function)
    return getattr(function, "__qualname__", repr(function))


LAWS: dict[str, type[Law]] = {cls.type: cls for cls in (
    Constant, CosineRamp, LinearRamp, Sine, Table, SpinUp, ConstantRate, PythonLaw)}


def _check_number(value: Any, path: str, check: str) -> float:
    if check == "positive":
        if not is_finite(value) or value <= 0:
            raise SceneError(f"{path}: expected a positive number, got {show(value)}")
    elif not is_finite(value):
        raise SceneError(f"{path}: expected a finite number, got {show(value)}")
    return float(value)


def _check_points(value: Any, path: str) -> tuple[tuple[float, float], ...]:
    if not isinstance(value, list) or not value:
        raise SceneError(f"{path}: expected a non-empty list of [t, v] pairs, got {show(value)}")
    points = []
    for i, pair in enumerate(value):
        if (not isinstance(pair, list) or len(pair) != 2
                or not all(is_finite(x) for x in pair)):
            raise SceneError(f"{path}[{i}]: expected a pair [t, v] of finite numbers, "
                             f"got {show(pair)}")
        if points and pair[0] <= points[-1][0]:
            raise SceneError(f"{path}[{i}]: times must be strictly increasing, got "
                             f"{show(pair[0])} after {show(points[-1][0])}")
        points.append((float(pair[0]), float(pair[1])))
    return tuple(points)


def _python_law(function: Any, path: str, folder: str | Path | None) -> PythonLaw:
    """A ``PythonLaw`` of ``function`` (a callable or "module:function"), tried at t = 0 and
    1 s (its shape and finiteness; SceneError naming ``path``)."""
    law = PythonLaw(function, path, import_function(function, f"{path}.function", folder))
    try:
        law.sample(np.array([0.0, 1.0]))
    except LoadFunctionError as error:
        raise SceneError(str(error)) from None
    return law


def parse_law(data: Any, path: str, folder: str | Path | None = None) -> Law:
    """Build a law from its TOML table ``{type = "...", ...}`` found at key path ``path``
    (or from a Python callable: a ``python`` law); ``folder``: the scene's, where the modules
    of ``python`` laws are looked for first.

    Raises SceneError naming the key path for a non-table, a missing or unknown ``type``, an
    unknown or missing key, or a value of the wrong kind.
    """
    if callable(data):
        return _python_law(data, path, folder)
    known = ", ".join(LAWS)
    if not isinstance(data, dict):
        raise SceneError(f'{path}: expected a table like {{type = "constant"}} (types: {known}), '
                         f"got {show(data)}")
    if "type" not in data:
        raise SceneError(f"{path}.type: missing required key; expected one of {known}")
    name = data["type"]
    if not isinstance(name, str) or name not in LAWS:
        raise SceneError(f"{path}.type: unknown time law {show(name)}; expected one of {known}")
    cls = LAWS[name]
    if cls is PythonLaw:
        for key in data:
            if key not in ("type", "function"):
                raise SceneError(f"{path}.{key}: unknown key for a python law; expected one "
                                 "of type, function")
        if "function" not in data:
            raise SceneError(f'{path}.function: missing required key of a python law '
                             f'("module:function")')
        return _python_law(data["function"], path, folder)
    fields = {f.metadata.get("key", f.name): f for f in dataclasses.fields(cls)}
    for key in data:
        if key != "type" and key not in fields:
            allowed = ", ".join(["type", *fields])
            raise SceneError(f"{path}.{key}: unknown key for a {name} law; "
                             f"expected one of {allowed}")
    kwargs: dict[str, Any] = {}
    for key, f in fields.items():
        if key not in data:
            if f.default is dataclasses.MISSING:
                raise SceneError(f"{path}.{key}: missing required key of a {name} law")
            continue
        check = cls.checks[key]
        if check == "points":
            kwargs[f.name] = _check_points(data[key], f"{path}.{key}")
        else:
            kwargs[f.name] = _check_number(data[key], f"{path}.{key}", check)
    return cls(**kwargs)
