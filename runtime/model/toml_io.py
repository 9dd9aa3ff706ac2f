"""Scene files and TOML text: reading a scene file safely (UTF-8, a byte order mark skipped,
at most 16 MiB, a regular file, not empty; errors name the file and the byte offset or the
line) and writing TOML data back as text (``toml_text``; ``tomllib`` reads it back equal)."""

from __future__ import annotations

import re
import tomllib
from pathlib import Path
from typing import Any

from runtime.model.errors import SceneError
from runtime.model.sizes import LIMITS


def read_scene_file(path: str | Path) -> dict:
    """The TOML table of a scene file, unvalidated.

    SceneError naming the file for a missing, unreadable or oversized file, a directory,
    bytes that are not UTF-8 (with the byte offset, line and column), invalid TOML (with the
    line) and an empty scene.  A UTF-8 byte order mark is skipped.
    """
    path = Path(path)
    limit = LIMITS["scene_bytes"]
    try:
        if path.is_dir():
            raise SceneError(f"{path}: is a directory; expected a scene file (TOML)")
        if path.exists() and not path.is_file():
            raise SceneError(f"{path}: not a regular file; expected a scene file (TOML)")
        with path.open("rb") as f:
            raw = f.read(limit + 1)
    except OSError as exc:
        raise SceneError(f"{path}: cannot read the scene file ({exc.strerror or exc})") from None
    if len(raw) > limit:
        raise SceneError(f"{path}: expected a scene file of at most {limit // 2**20} MiB, got "
                         f"a larger file")
    bom = 3 if raw.startswith(b"\xef\xbb\xbf") else 0
    if raw.startswith((b"\xff\xfe", b"\xfe\xff")):
        raise SceneError(f"{path}: UTF-16 text (byte order mark at offset 0); expected UTF-8: "
                         f"save the scene as UTF-8")
    try:
        text = raw[bom:].decode("utf-8")
    except UnicodeDecodeError as exc:
        offset = bom + exc.start
        line = raw.count(b"\n", 0, offset) + 1
        column = offset - (raw.rfind(b"\n", 0, offset) + 1) + 1
        raise SceneError(f"{path}: not UTF-8 text: byte 0x{raw[offset]:02x} at offset {offset} "
                         f"(line {line}, column {column}); expected a UTF-8 TOML file") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(f"{path}: TOML syntax error: {exc}") from None
    except RecursionError:
        raise SceneError(f"{path}: TOML error: arrays or tables nested too deeply") from None
    except ValueError:          # an integer of more than 4300 digits
        raise SceneError(f"{path}: TOML error: an integer with too many digits (at most 4300 "
                         f"are read)") from None
    if not data:
        raise SceneError(f"{path}: the scene file is empty (no keys); expected a TOML scene "
                         f"with at least one [[body]]")
    return data


BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")


ESCAPES = {'"': '\\"', "\\": "\\\\", "\b": "\\b", "\t": "\\t", "\n": "\\n", "\f": "\\f",
           "\r": "\\r"}


def _toml_string(text: str) -> str:
    """A TOML basic string (control characters escaped)."""
    return '"' + "".join(ESCAPES.get(c) or (f"\\u{ord(c):04x}" if ord(c) < 0x20 or c == "\x7f"
                                            else c) for c in text) + '"'


def _toml_key(key: str) -> str:
    return key if BARE_KEY.fullmatch(key) else _toml_string(key)


def _toml_value(value: Any) -> str:
    """One TOML value on one line (tables inline)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int | float):
        return repr(value)      # floats: the shortest text that reads back the same float
    if isinstance(value, str):
        return _toml_string(value)
    if isinstance(value, list):
        return "[" + ", ".join(map(_toml_value, value)) + "]"
    if isinstance(value, dict):
        return "{" + ", ".join(f"{_toml_key(k)} = {_toml_value(v)}" for k, v in value.items()) \
            + "}"
    raise TypeError(f"no TOML value for {value!r}")


def _is_table_array(value: Any) -> bool:
    return isinstance(value, list) and bool(value) and all(isinstance(v, dict) for v in value)


def _emit(data: dict, path: tuple[str, ...], lines: list[str]) -> None:
    inline = {k: v for k, v in data.items() if not isinstance(v, dict) and
              not _is_table_array(v)}
    header = ".".join(map(_toml_key, path))
    if path and (inline or len(inline) == len(data)):   # an empty table is written too
        lines.append(f"\n[{header}]")
    lines.extend(f"{_toml_key(k)} = {_toml_value(v)}" for k, v in inline.items())
    for k, value in data.items():
        if isinstance(value, dict):
            _emit(value, (*path, k), lines)
        elif _is_table_array(value):
            for item in value:   # items of arrays of tables: their tables are inline
                lines.append(f"\n[[{'.'.join(map(_toml_key, (*path, k)))}]]")
                lines.extend(f"{_toml_key(n)} = {_toml_value(v)}" for n, v in item.items())


def toml_text(data: dict) -> str:
    """TOML text of a table of TOML data (``tomllib.loads`` of it gives ``data`` back): tables
    as ``[a.b]``, arrays of tables as ``[[a]]`` with their own tables inline."""
    lines: list[str] = []
    _emit(data, (), lines)
    return "\n".join(lines).lstrip("\n") + "\n"
