"""``ancf bench precision``: the command's options and its handler."""

from __future__ import annotations

import argparse

from runtime.studies.precision.run import DEFAULT_OUT, study


def cmd_precision(args: argparse.Namespace) -> int:
    """Run the comparison and print its Markdown; exit code 0."""
    print(study(quick=args.quick, out=args.out, repeats=args.repeats, only=args.problem,
                peer=not args.no_peer, progress=not args.quiet))
    return 0


def add_cli(subparsers: argparse._SubParsersAction) -> argparse.ArgumentParser:
    """Register ``precision`` in the ``ancf bench`` sub-command group (``subparsers``: what
    ``bench_parser.add_subparsers()`` returned); the command runs ``args.run(args)``."""
    parser = subparsers.add_parser(
        "precision", help="work-precision curves of the project and Exudyn side by side",
        description="Error against simulate time of every project configuration (line kinds, "
                    "meshes, steps, integrators, Newton modes) and of Exudyn's ANCFCable2D on "
                    "the rotating beam, the static elastica and the paper cantilever; writes "
                    "precision.csv, .png and .md and prints the Markdown.")
    parser.add_argument("--quick", action="store_true", help="a small subset (smoke test)")
    parser.add_argument("--out", metavar="DIR", help=f"output folder (default {DEFAULT_OUT})")
    parser.add_argument("--repeats", type=int, default=3, help="interleaved timed repeats")
    parser.add_argument("--problem", action="append",
                        help="run only this problem (repeatable; default all)")
    parser.add_argument("--no-peer", action="store_true", help="skip Exudyn")
    parser.add_argument("--quiet", action="store_true", help="no progress lines")
    parser.set_defaults(run=cmd_precision)
    return parser
