"""Conventions every ``ancf`` command follows, kept in one place: list options and output
folders.

* A list option takes one or more values separated by spaces, ``--elements 2 5 10``; a value
  may itself be comma-separated, ``--elements 2,5,10``, and repeating the option adds values,
  ``--elements 2 --elements 5``: the three read the same.
* A command that writes files writes them into ``--out DIR``, by default
  ``results/<command>`` of the current folder, and says where on stdout before writing.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

__all__ = ["RESULTS", "add_list_option", "announce", "default_out"]

#: The folder of every command's default output folder, relative to the current folder.
RESULTS = Path("results")


class _ListOption(argparse.Action):
    """Values separated by spaces or commas; a repeated option adds to the list; each value
    converted by ``convert`` and checked against ``allowed`` (a parser error otherwise)."""

    def __init__(self, option_strings: Sequence[str], dest: str,
                 convert: Callable[[str], Any] = str, allowed: Sequence[Any] | None = None,
                 **kwargs: Any) -> None:
        super().__init__(option_strings, dest, nargs="+", **kwargs)
        self.convert = convert
        self.allowed = allowed

    def __call__(self, parser: argparse.ArgumentParser, namespace: argparse.Namespace,
                 values: Any, option_string: str | None = None) -> None:
        items = list(getattr(namespace, self.dest) or [])
        for value in values:
            for part in filter(None, (p.strip() for p in value.split(","))):
                try:
                    item = self.convert(part)
                except ValueError:
                    parser.error(f"argument {option_string}: invalid value {part!r}")
                if self.allowed is not None and item not in self.allowed:
                    parser.error(f"argument {option_string}: invalid choice: {part!r} (choose "
                                 f"from {', '.join(map(str, self.allowed))})")
                items.append(item)
        setattr(namespace, self.dest, items)


def add_list_option(parser: argparse.ArgumentParser, flag: str, help: str, *,
                    convert: Callable[[str], Any] = str, choices: Sequence[Any] | None = None,
                    metavar: str | None = None, dest: str | None = None) -> None:
    """Add the list option ``flag`` (the convention of the module docstring) to ``parser``:
    its value is a list, or None when the option is not given."""
    if metavar is None and choices is not None:
        metavar = "|".join(map(str, choices))
    parser.add_argument(flag, action=_ListOption, convert=convert, allowed=choices,
                        metavar=metavar, dest=dest,
                        help=f"{help} (one or more, separated by spaces or commas)")


def add_sweep_options(parser: argparse.ArgumentParser) -> None:
    """The options of a study whose cases run through ``runtime.studies.sweep``: a dask
    scheduler, the workers of a local cluster, or every case in this process."""
    parser.add_argument("--scheduler", metavar="ADDRESS",
                        help="dask scheduler, e.g. tcp://host:8786 (default: a local cluster)")
    parser.add_argument("--workers", type=int, metavar="N",
                        help="workers of the local cluster (default: one per core)")
    parser.add_argument("--serial", action="store_true", help="run every case in this process")


def default_out(*command: str) -> Path:
    """The default output folder of a command: ``results/<command>`` (words as folders)."""
    return RESULTS.joinpath(*command)


def announce(command: str, folder: Path) -> None:
    """Say on stdout, before anything is written, where ``command`` writes."""
    print(f"{command}: writing into {Path(folder).resolve()}", flush=True)
