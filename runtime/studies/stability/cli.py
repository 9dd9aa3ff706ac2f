"""``ancf study stability``: the command's options and its handler (run the study, write the
files, print the Markdown).
"""

from __future__ import annotations

import argparse
import time

from runtime.studies.options import add_sweep_options, announce, default_out
from runtime.studies.stability.measure import stability_study
from runtime.studies.stability.report import markdown, write


def cmd_stability(args: argparse.Namespace) -> int:
    """``ancf study stability``: run, print the Markdown, write the files; exit code 0 even
    when rows fail (the table reports them)."""
    announce("ancf study stability", args.out)
    start = time.perf_counter()
    rows = stability_study(scheduler=args.scheduler, workers=args.workers, quick=args.quick,
                           serial=args.serial)
    wall = time.perf_counter() - start
    paths = write(rows, args.out, wall)
    print(markdown(rows, wall))
    print(f"written: {', '.join(str(p) for p in paths.values())}")
    return 0


def add_cli(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Register ``stability`` in the ``study`` sub-command group ``subparsers`` (the object
    returned by ``add_subparsers``); the handler is set as ``run`` (``args.run(args)``)."""
    parser = subparsers.add_parser(
        "stability", help="extreme cases: kernel accuracy, integrators, Newton, locking")
    add_sweep_options(parser)
    parser.add_argument("--out", default=str(default_out("stability")),
                        help="results folder (default: results/stability)")
    parser.add_argument("--quick", action="store_true", help="a small subset (seconds)")
    parser.set_defaults(run=cmd_stability)
    return parser
