"""Time laws of scenes: load factors and prescribed angles as functions of time.

Every law is a frozen dataclass with ``value(t)``, ``rate(t)`` (d/dt) and ``acceleration(t)``
(d^2/dt^2), exact (analytic), taking the time ``t`` in s and returning a float.  The unit of
the value is the one of its use: a dimensionless factor that multiplies a load vector, or an
angle in rad (``rate`` in 1/s or rad/s, ``acceleration`` in 1/s^2 or rad/s^2).

Ramps (``cosine_ramp``, ``linear_ramp``, ``spin_up``) are zero, at rest, for t < 0; at the end
of a ramp the formula of the ramp is used (``t <= duration``), as in eqs. 42 and 45.

``parse_law`` builds one from a scene's TOML table ``{type = "...", ...}``; its errors are
``SceneError`` naming the key path.
"""

from __future__ import annotations

import bisect
import dataclasses
import datetime
import math
from dataclasses import dataclass
from typing import Any, ClassVar

__all__ = [
    "LAWS",
    "Constant",
    "ConstantRate",
    "CosineRamp",
    "Law",
    "LinearRamp",
    "SceneError",
    "Sine",
    "SpinUp",
    "Table",
    "parse_law",
]


class SceneError(ValueError):
    """An invalid scene; the message starts with the key path (``body[1].elements: ...``)."""


@dataclass(frozen=True)
class Law:
    """Base class of the time laws; ``type`` is the name used in scenes."""

    type: ClassVar[str] = ""
    # per field: "number" (finite), "positive" (finite > 0) or "points" (table points)
    checks: ClassVar[dict[str, str]] = {}

    def value(self, t: float) -> float:
        """The law at time t (s)."""
        raise NotImplementedError

    def rate(self, t: float) -> float:
        """First time derivative at t (s), per second."""
        raise NotImplementedError

    def acceleration(self, t: float) -> float:
        """Second time derivative at t (s), per second squared."""
        raise NotImplementedError

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

    def value(self, t: float) -> float:
        return self.scale

    def rate(self, t: float) -> float:
        return 0.0

    def acceleration(self, t: float) -> float:
        return 0.0


@dataclass(frozen=True)
class CosineRamp(Law):
    """Eq. 42: ``scale * (1 - cos(pi t / duration)) / 2`` for 0 <= t <= duration, then
    ``scale``; ``duration`` (s) is the paper's t_c; ``scale`` is the TOML key ``value``."""

    type: ClassVar[str] = "cosine_ramp"
    checks: ClassVar[dict[str, str]] = {"duration": "positive", "value": "number"}
    duration: float
    scale: float = dataclasses.field(default=1.0, metadata={"key": "value"})

    def value(self, t: float) -> float:
        if t <= 0.0:
            return 0.0
        if t <= self.duration:
            return 0.5 * self.scale * (1.0 - math.cos(math.pi * t / self.duration))
        return self.scale

    def rate(self, t: float) -> float:
        if t <= 0.0 or t > self.duration:
            return 0.0
        w = math.pi / self.duration
        return 0.5 * self.scale * w * math.sin(w * t)

    def acceleration(self, t: float) -> float:
        if t < 0.0 or t > self.duration:
            return 0.0
        w = math.pi / self.duration
        return 0.5 * self.scale * w * w * math.cos(w * t)


@dataclass(frozen=True)
class LinearRamp(Law):
    """``scale * t / duration`` for 0 <= t <= duration, then ``scale`` (TOML key ``value``)."""

    type: ClassVar[str] = "linear_ramp"
    checks: ClassVar[dict[str, str]] = {"duration": "positive", "value": "number"}
    duration: float
    scale: float = dataclasses.field(default=1.0, metadata={"key": "value"})

    def value(self, t: float) -> float:
        if t <= 0.0:
            return 0.0
        return self.scale * t / self.duration if t <= self.duration else self.scale

    def rate(self, t: float) -> float:
        return self.scale / self.duration if 0.0 <= t <= self.duration else 0.0

    def acceleration(self, t: float) -> float:
        return 0.0


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

    def _angle(self, t: float) -> float:
        return 2.0 * math.pi * self.frequency_hz * t + math.radians(self.phase_deg)

    def value(self, t: float) -> float:
        return self.offset + self.amplitude * math.sin(self._angle(t))

    def rate(self, t: float) -> float:
        w = 2.0 * math.pi * self.frequency_hz
        return self.amplitude * w * math.cos(self._angle(t))

    def acceleration(self, t: float) -> float:
        w = 2.0 * math.pi * self.frequency_hz
        return -self.amplitude * w * w * math.sin(self._angle(t))


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
        object.__setattr__(self, "_times", [p[0] for p in points])

    def _segment(self, t: float) -> int:
        """Index i of the segment [t_i, t_i+1] holding t; -1 before, len-1 from the end."""
        return bisect.bisect_right(self._times, t) - 1  # type: ignore[attr-defined]

    def value(self, t: float) -> float:
        i = self._segment(t)
        if i < 0:
            return self.points[0][1]
        if i >= len(self.points) - 1:
            return self.points[-1][1]
        (t0, v0), (t1, v1) = self.points[i], self.points[i + 1]
        return v0 + (v1 - v0) * (t - t0) / (t1 - t0)

    def rate(self, t: float) -> float:
        i = self._segment(t)
        if i < 0 or i >= len(self.points) - 1:
            return 0.0
        (t0, v0), (t1, v1) = self.points[i], self.points[i + 1]
        return (v1 - v0) / (t1 - t0)

    def acceleration(self, t: float) -> float:
        return 0.0


@dataclass(frozen=True)
class SpinUp(Law):
    """Eq. 45: angle (rad) of a hub spun up smoothly to ``omega`` (rad/s) in ``t_ramp`` (s):
    ``(omega/T) [t^2/2 + (T/(2 pi))^2 (cos(2 pi t/T) - 1)]`` for 0 <= t <= T,
    ``omega (t - T/2)`` after (T = t_ramp)."""

    type: ClassVar[str] = "spin_up"
    checks: ClassVar[dict[str, str]] = {"omega": "number", "t_ramp": "positive"}
    omega: float
    t_ramp: float

    def value(self, t: float) -> float:
        T = self.t_ramp
        if t <= 0.0:
            return 0.0
        if t <= T:
            c = T / (2.0 * math.pi)
            # (cos x - 1) = -2 sin^2(x/2): no cancellation for small t
            return (self.omega / T) * (0.5 * t * t - 2.0 * c * c * math.sin(math.pi * t / T) ** 2)
        return self.omega * (t - 0.5 * T)

    def rate(self, t: float) -> float:
        T = self.t_ramp
        if t <= 0.0:
            return 0.0
        if t <= T:
            return (self.omega / T) * (t - T / (2.0 * math.pi) * math.sin(2.0 * math.pi * t / T))
        return self.omega

    def acceleration(self, t: float) -> float:
        T = self.t_ramp
        if t <= 0.0 or t > T:
            return 0.0
        return (self.omega / T) * 2.0 * math.sin(math.pi * t / T) ** 2


@dataclass(frozen=True)
class ConstantRate(Law):
    """Angle ``omega * t`` (rad) at the constant rate ``omega`` (rad/s), for every t."""

    type: ClassVar[str] = "constant_rate"
    checks: ClassVar[dict[str, str]] = {"omega": "number"}
    omega: float

    def value(self, t: float) -> float:
        return self.omega * t

    def rate(self, t: float) -> float:
        return self.omega

    def acceleration(self, t: float) -> float:
        return 0.0


LAWS: dict[str, type[Law]] = {cls.type: cls for cls in (
    Constant, CosineRamp, LinearRamp, Sine, Table, SpinUp, ConstantRate)}


def _show(value: Any, depth: int = 0) -> str:
    """A value as the scene spells it, for error messages: one line, at most about 80
    characters (control characters escaped, long strings, lists and integers shortened)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        text = "".join(c if c.isprintable() else f"\\u{ord(c):04x}" for c in value[:60])
        more = f"... ({len(value)} characters)" if len(value) > 60 else ""
        return f'"{text}"{more}'
    if isinstance(value, dict):
        return "a table"
    if isinstance(value, list):
        if depth >= 2 and value:
            return "[...]"
        items = ", ".join(_show(x, depth + 1) for x in value[:6])
        return f"[{items}, ... ({len(value)} items)]" if len(value) > 6 else f"[{items}]"
    if isinstance(value, datetime.date | datetime.time):
        return f"{value.isoformat()} (a {type(value).__name__})"
    if isinstance(value, int) and value.bit_length() > 200:
        return f"an integer of about {int(value.bit_length() * math.log10(2)) + 1} digits"
    return repr(value)


def _is_number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def _is_finite(value: Any) -> bool:
    """A number (not a boolean) that is finite as a float (huge integers are not)."""
    if not _is_number(value):
        return False
    try:
        return math.isfinite(value)
    except OverflowError:
        return False


def _check_number(value: Any, path: str, check: str) -> float:
    if check == "positive":
        if not _is_finite(value) or value <= 0:
            raise SceneError(f"{path}: expected a positive number, got {_show(value)}")
    elif not _is_finite(value):
        raise SceneError(f"{path}: expected a finite number, got {_show(value)}")
    return float(value)


def _check_points(value: Any, path: str) -> tuple[tuple[float, float], ...]:
    if not isinstance(value, list) or not value:
        raise SceneError(f"{path}: expected a non-empty list of [t, v] pairs, got {_show(value)}")
    points = []
    for i, pair in enumerate(value):
        if (not isinstance(pair, list) or len(pair) != 2
                or not all(_is_finite(x) for x in pair)):
            raise SceneError(f"{path}[{i}]: expected a pair [t, v] of finite numbers, "
                             f"got {_show(pair)}")
        if points and pair[0] <= points[-1][0]:
            raise SceneError(f"{path}[{i}]: times must be strictly increasing, got "
                             f"{_show(pair[0])} after {_show(points[-1][0])}")
        points.append((float(pair[0]), float(pair[1])))
    return tuple(points)


def parse_law(data: Any, path: str) -> Law:
    """Build a law from its TOML table ``{type = "...", ...}`` found at key path ``path``.

    Raises SceneError naming the key path for a non-table, a missing or unknown ``type``, an
    unknown or missing key, or a value of the wrong kind.
    """
    known = ", ".join(LAWS)
    if not isinstance(data, dict):
        raise SceneError(f'{path}: expected a table like {{type = "constant"}} (types: {known}), '
                         f"got {_show(data)}")
    if "type" not in data:
        raise SceneError(f"{path}.type: missing required key; expected one of {known}")
    name = data["type"]
    if not isinstance(name, str) or name not in LAWS:
        raise SceneError(f"{path}.type: unknown time law {_show(name)}; expected one of {known}")
    cls = LAWS[name]
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
