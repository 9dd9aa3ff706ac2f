"""``ancf study error-vs-time``: the command's options (sweeps are list options,
``runtime.studies.options``) and its handler, which runs the study and prints its Markdown.
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

from runtime.catalog import BACKENDS, INTEGRATORS, METHODS
from runtime.model.errors import SceneError
from runtime.studies.error_vs_time.plan import MEASURES, StudyError
from runtime.studies.error_vs_time.run import default_out, study
from runtime.studies.options import add_list_option, add_sweep_options, announce
from runtime.studies.sweep import SchedulerError

COMMAND = "ancf study error-vs-time"


def _converted(items: list[str] | None, convert) -> list | None:
    """List option values converted where possible (left as text otherwise, so that
    validation names the option and the culprit)."""
    if items is None:
        return None
    out: list = []
    for item in items:
        try:
            out.append(convert(item))
        except ValueError:
            out.append(item)
    return out


def cmd_error_vs_time(args: argparse.Namespace) -> int:
    """``ancf study error-vs-time``: run the study, print the Markdown; exit code 0, or 2
    with a one-line message for invalid input or an unreachable scheduler."""
    try:
        study(args.scene, args.out, elements=_converted(args.elements, int),
              step=_converted(args.step, float), integrator=args.integrator,
              method=args.method, backend=args.backend, error=args.error,
              sensor=args.sensor, reference=_converted(args.reference, _number_text),
              t_end=_converted([args.t_end], float)[0] if args.t_end else None,
              repeat=args.repeat, targets=_converted(args.targets, float),
              scheduler=args.scheduler, workers=args.workers, serial=args.serial,
              on_start=lambda folder: announce(COMMAND, folder))
    except (StudyError, SchedulerError, SceneError) as error:
        print(f"{COMMAND}: {str(error).splitlines()[0]}", file=sys.stderr)
        return 2
    out = Path(args.out) if args.out else default_out(args.scene)
    print((out / "error_vs_time.md").read_text(encoding="utf-8"))
    print(f"results in {out}/ (error_vs_time.csv, .png, .md)")
    return 0


def _number_text(text: str) -> int | float:
    return int(text) if re.fullmatch(r"[+-]?\d+", text) else float(text)


def add_cli(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Register ``error-vs-time`` in the ``ancf study`` sub-command group (``subparsers``:
    what ``study_parser.add_subparsers()`` returned); the command runs ``args.run(args)``."""
    parser = subparsers.add_parser(
        "error-vs-time", help="work-precision study: error against run time",
        description="Work-precision study: run every combination of mesh size, time step, "
                    "integrator and elastic force method, measure each run's error (closed form "
                    "or a reference run) and wall time; write error_vs_time.csv, .png and .md "
                    "and print the Markdown.")
    parser.add_argument("scene", help="scene TOML file (may hold a [study] table)")
    add_list_option(parser, "--elements", "mesh sizes, e.g. 2 5 10", metavar="N")
    add_list_option(parser, "--step", "time steps in s, e.g. 1e-3 5e-4", metavar="H")
    add_list_option(parser, "--integrator", f"integrators: {', '.join(INTEGRATORS)}",
                    metavar="NAME")
    add_list_option(parser, "--method", f"elastic force methods: {', '.join(METHODS)}",
                    metavar="NAME")
    parser.add_argument("--backend", help=f"kernel backend: {', '.join(BACKENDS)}")
    parser.add_argument("--error", help=f"error measure: {', '.join(MEASURES)}")
    parser.add_argument("--sensor", help="the sensor the error is computed from")
    add_list_option(parser, "--reference", "reference run of error 'reference': ELEMENTS "
                    "STEP (default: twice the finest mesh, half the finest step)",
                    metavar="VALUE")
    parser.add_argument("--t-end", dest="t_end", metavar="T",
                        help="end time in s (overrides [analysis.dynamic].t_end)")
    parser.add_argument("--repeat", type=int, help="runs per case; the fastest is kept")
    add_list_option(parser, "--targets", "accuracies of the summary (default: up to four "
                    "levels 1e-k, 3e-k between the errors)", metavar="E")
    add_sweep_options(parser)
    parser.add_argument("--out", metavar="DIR",
                        help="output folder (default: results/error-vs-time/<scene stem>)")
    parser.set_defaults(run=cmd_error_vs_time)
    return parser
