"""Element registry: every module in this package that defines ``ELEMENT`` is an element.

Adding an element means adding one file here; nothing else.
"""

from __future__ import annotations

import importlib
import pkgutil

from symgen.element import ElementSpec


def registry() -> dict[str, ElementSpec]:
    """All element definitions, by name, in name order."""
    found: dict[str, ElementSpec] = {}
    for info in pkgutil.iter_modules(__path__):
        module = importlib.import_module(f"{__name__}.{info.name}")
        spec = getattr(module, "ELEMENT", None)
        if isinstance(spec, ElementSpec):
            found[spec.name] = spec
    return dict(sorted(found.items()))


def get(name: str) -> ElementSpec:
    """The element called ``name``; ValueError listing the known ones otherwise."""
    elements = registry()
    if name not in elements:
        raise ValueError(f"unknown element kind {name!r}; known kinds: {', '.join(elements)}")
    return elements[name]
