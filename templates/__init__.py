"""The Jinja2 templates of generated code (kernels of ``symgen.emit``, the stepper of
``runtime.solve.compiled_engine``) and the one environment that renders them."""

from __future__ import annotations

from functools import cache
from importlib import resources

import jinja2


@cache
def environment() -> jinja2.Environment:
    """The Jinja2 environment of every template of this package (strict undefined names,
    trimmed blocks, trailing newlines kept, the ``append_suffix`` filter)."""
    loader = jinja2.FunctionLoader(
        lambda name: resources.files(__name__).joinpath(name).read_text())
    env = jinja2.Environment(loader=loader, undefined=jinja2.StrictUndefined,
                             trim_blocks=True, lstrip_blocks=True, keep_trailing_newline=True)
    env.filters["append_suffix"] = lambda text, suffix: f"{text}{suffix}"
    return env
