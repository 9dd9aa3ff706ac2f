"""Scene errors and how a scene value is shown in their messages."""

from __future__ import annotations

import datetime
import math
from typing import Any


class SceneError(ValueError):
    """An invalid scene; the message starts with the key path (``body[1].elements: ...``)."""


def show(value: Any, depth: int = 0) -> str:
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
        items = ", ".join(show(x, depth + 1) for x in value[:6])
        return f"[{items}, ... ({len(value)} items)]" if len(value) > 6 else f"[{items}]"
    if isinstance(value, datetime.date | datetime.time):
        return f"{value.isoformat()} (a {type(value).__name__})"
    if isinstance(value, int) and value.bit_length() > 200:
        return f"an integer of about {int(value.bit_length() * math.log10(2)) + 1} digits"
    return repr(value)


def number_text(x: float) -> str:
    """A float in messages: 12 significant digits."""
    return f"{x:.12g}"


def is_number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


def is_finite(value: Any) -> bool:
    """A number (not a boolean) that is finite as a float (huge integers are not)."""
    if not is_number(value):
        return False
    try:
        return math.isfinite(value)
    except OverflowError:
        return False
