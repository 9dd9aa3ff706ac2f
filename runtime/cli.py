"""The ``ancf`` command line: generate, invariants, run, bench, study, report."""

from __future__ import annotations

import argparse
import concurrent.futures
import contextlib
import difflib
import multiprocessing
import os
import signal
import sys
import tempfile
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import NoReturn

from runtime import progress
from runtime.catalog import (
    BACKENDS,
    DEFAULT_LAW,
    ENGINES,
    LINEAR_SOLVERS,
    METHODS,
    NEWTON_MODES,
)
from runtime.kernels.errors import JitEnvironmentError
from runtime.studies.options import add_list_option, announce, default_out


def _generate_into(elements: list[str], backends: list[str], methods: list[str] | None,
                   out: Path) -> list[Path]:
    """Generate the kernels of ``elements`` into ``out``, one process per element and core
    (SymPy runs on one core; the elements write to their own folders)."""
    families = None
    if methods:
        from symgen.methods import METHOD_FAMILIES

        families = [f for m in methods for f in METHOD_FAMILIES[m]]
    workers = min(len(elements), os.cpu_count() or 1)
    if workers <= 1:
        return [path for name in elements
                for path in _generate_element(name, backends, families, out)]
    context = multiprocessing.get_context("spawn")   # no fork of a threaded parent
    with progress.phase(f"generating {', '.join(elements)} (SymPy derivations and "
                        f"rendering, {workers} processes)"), \
            concurrent.futures.ProcessPoolExecutor(workers, mp_context=context) as pool:
        jobs = [pool.submit(_generate_element, name, backends, families, out)
                for name in elements]
        return [path for job in jobs for path in job.result()]


def _generate_element(name: str, backends: list[str], families: list[str] | None,
                      out: Path) -> list[Path]:
    from symgen import emit, methods
    from symgen.elements import get

    spec = get(name)
    if families is not None:  # the method's families this element has (not every one has all)
        families = [f for f in families if f in methods.families(spec)]
    with progress.phase(f"generating {name} (SymPy derivations and rendering)"):
        return emit.generate(spec, out, backends=backends, families=families)


def generation_diff(elements: list[str] | None = None, folder: Path | None = None) -> str:
    """Unified diff between freshly generated kernels and ``folder`` ('' when identical)."""
    from runtime.catalog import generated_dir
    from symgen.elements import registry

    folder = folder or generated_dir()
    elements = elements or list(registry())
    with tempfile.TemporaryDirectory() as tmp:
        fresh = _generate_into(elements, list(BACKENDS), None, Path(tmp))
        chunks = []
        for path in sorted(fresh):
            relative = path.relative_to(tmp)
            old = folder / relative
            new_text = path.read_text()
            old_text = old.read_text() if old.exists() else ""
            if new_text != old_text:
                diff = difflib.unified_diff(old_text.splitlines(), new_text.splitlines(),
                                            f"checked-in/{relative}", f"regenerated/{relative}",
                                            lineterm="", n=1)
                chunks.append("\n".join(list(diff)[:200]))
        return "\n".join(chunks)


def cmd_generate(args) -> int:
    from runtime.catalog import generated_dir
    from symgen.elements import registry

    known = list(registry())
    elements = args.element or known
    for name in elements:
        if name not in known:
            print(f"ancf generate: unknown element {name!r}; known: {', '.join(known)}",
                  file=sys.stderr)
            return 2
    out = Path(args.out) if args.out else generated_dir()
    if args.check:
        diff = generation_diff(elements, out)
        if diff:
            print(diff)
            subset = f" --element {' '.join(args.element)}" if args.element else ""
            print(f"\ngenerated kernels in {out} differ from what symgen produces; update them "
                  f"with: ancf generate{subset}")
            return 1
        print(f"generated kernels in {out} are up to date")
        return 0
    start = time.perf_counter()
    written = _generate_into(elements, args.backend or list(BACKENDS), args.method, out)
    for path in written:
        print(path)
    print(f"generated {len(written)} files in {time.perf_counter() - start:.1f} s")
    return 0


def cmd_compile(args) -> int:
    """Compile the C kernel families of the given kinds into the kernel cache now (what a
    first run would compile on use), one process per core."""
    from runtime.catalog import generated_kinds
    from runtime.kernels.kind import element_kind

    known = generated_kinds()
    kinds = args.element or known
    unknown = [k for k in kinds if k not in known]
    if unknown:
        raise ValueError(f"--element: unknown {', '.join(unknown)}; known: {', '.join(known)}")
    jobs = [(kind, family) for kind in kinds for family in element_kind(kind).families]
    start = time.perf_counter()
    context = multiprocessing.get_context("spawn")
    with progress.phase(f"compiling {len(jobs)} kernel families of {', '.join(kinds)} "
                        f"({os.cpu_count() or 1} processes)"), \
            concurrent.futures.ProcessPoolExecutor(os.cpu_count() or 1,
                                                   mp_context=context) as pool:
        seconds = sum(pool.map(_compile_family, jobs))
    print(f"ancf compile: {len(jobs)} kernel families ready in the cache "
          f"({seconds:.0f} s of compiling, {time.perf_counter() - start:.0f} s)")
    return 0


def _compile_family(job: tuple[str, str]) -> float:
    from runtime.kernels.loader import kernel_family

    return kernel_family(*job, "c").compile_s


def cmd_invariants(args) -> int:
    from runtime.studies.invariant_comparison import compare, report

    orders = tuple(args.quadrature) if args.quadrature else None
    print(report(compare(args.element, args.reference, orders, args.backend, args.law)))
    return 0


def cmd_bench(args) -> int:
    from runtime.studies import bench_kernels as bench

    print(bench.run(args.element, batch=args.batch, methods=args.method or METHODS,
                    backends=args.backend or BACKENDS))
    return 0


def _first_line(text: str) -> str:
    return text.strip().split("\n", 1)[0]


@contextlib.contextmanager
def _interrupt_on_signals() -> Iterator[None]:
    """SIGINT and SIGTERM raise KeyboardInterrupt naming the signal while the block runs
    (main thread only; a signal ignored by whoever started us, such as SIGINT of a
    background job, stays ignored)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return

    def interrupt(signum, frame):
        raise KeyboardInterrupt(signal.Signals(signum).name)

    previous = {s: signal.signal(s, interrupt) for s in (signal.SIGINT, signal.SIGTERM)
                if signal.getsignal(s) is not signal.SIG_IGN}
    try:
        yield
    finally:
        for s, handler in previous.items():
            signal.signal(s, signal.SIG_DFL if handler is None else handler)


def cmd_run(args) -> int:
    from runtime.app.run import SUMMARY, ExitCode, RunInterrupted, run

    try:
        with _interrupt_on_signals():
            summary, code = run(args.scene, args.out, args.method, args.backend, args.quiet,
                                plots=not args.no_plots, engine=args.engine,
                                vtk=args.vtk or None, animation=args.gif or None,
                                plane=args.plane)
    except RunInterrupted as stop:
        print(f"ancf run: {_first_line(stop.summary['message'])}", file=sys.stderr)
        return ExitCode.INTERRUPTED
    written = SUMMARY in summary.get("files", ())
    if code == ExitCode.OK:
        warnings = summary["warnings"]
        if warnings:
            more = f" (and {len(warnings) - 1} more in {SUMMARY})" if len(warnings) > 1 else ""
            print(f"ancf run: warning: {_first_line(warnings[0])}{more}", file=sys.stderr)
        if not args.quiet:
            timing = summary["timing"]
            print(f"{summary['scene']}: ok, total {timing['total_s']:.2f} s (compile "
                  f"{timing['compile_s']:.2f}, preprocess {timing['preprocess_s']:.3f}, "
                  f"simulate {timing['simulate_s']:.2f}); results in {args.out}")
        return code
    line = _first_line(summary["message"])
    if code == ExitCode.DIVERGED:
        line += f" (results up to then in {args.out})"
    elif code == ExitCode.INTERNAL:
        where = f" with {Path(args.out) / SUMMARY}, which holds the traceback" if written else ""
        line += f"; this is a bug, please report it{where}"
    print(f"ancf run: {line}", file=sys.stderr)
    return code


def cmd_bench_paper(args) -> int:
    from runtime.studies import paper

    announce("ancf bench paper", args.out)
    results = paper.bench_paper(args.quick, args.scheduler, args.workers, args.serial,
                                args.backend)
    paths = paper.write(results, args.out)
    print(paths["md"].read_text())
    print(f"written: {', '.join(str(p) for p in paths.values())}")
    return 0


def report_folder(out: str | None, quick: bool) -> Path:
    """Where ``ancf report`` writes (created): ``out``; by default ``docs`` (the tracked
    report), or ``results/report`` for ``--quick`` (a smoke test never overwrites the
    report)."""
    folder = Path(out) if out is not None else default_out("report") if quick else Path("docs")
    folder.mkdir(parents=True, exist_ok=True)
    return folder


def cmd_report(args) -> int:
    from runtime.studies import report

    folder = report_folder(args.out, args.quick)
    announce("ancf report", folder)
    path = report.build(folder, quick=args.quick,
                        scheduler=args.scheduler, workers=args.workers)
    print(f"written: {path}")
    return 0


def _positive(text: str) -> int:
    """A positive integer option value (ValueError otherwise: a parser error)."""
    value = int(text)
    if value < 1:
        raise ValueError(f"expected a positive integer, got {text}")
    return value


def cmd_bench_steps(args) -> int:
    import scenes
    from runtime.studies import bench_steps

    if args.scenes is not None:
        names = args.scenes or scenes.names()
        unknown = sorted(set(names) - set(scenes.names()))
        if unknown:
            raise ValueError(f"--scenes: unknown scene {unknown[0]!r}; shipped: "
                             f"{', '.join(scenes.names())}")
        text = bench_steps.scene_table(bench_steps.scene_runs(
            names, tuple(args.newton or NEWTON_MODES), args.repeats, not args.quiet))
        print(text)
        if args.out:
            Path(args.out).write_text(text)
        return 0
    cases = bench_steps.plan(
        plates=tuple(args.plates if args.plates is not None else (4, 8, 16, 32)),
        chains=tuple(args.elements if args.elements is not None else (1000, 10_000)),
        solvers=tuple(args.linear_solver or (bench_steps.AUTO, *LINEAR_SOLVERS)),
        newtons=tuple(args.newton or ("full",)), banded_limit=args.banded_limit,
        joints=tuple(args.joints if args.joints is not None else (50, 200)),
        blocks=tuple(args.blocks if args.blocks is not None else (2, 4, 6)))
    rows = bench_steps.measure(cases, method=args.method, repeats=args.repeats,
                               progress=not args.quiet)
    text = bench_steps.table(rows)
    print(text)
    if args.out:
        Path(args.out).write_text(text)
    if args.plot:
        bench_steps.plot(rows, args.plot)
        print(f"written: {args.plot}")
    return 0


def cmd_bench_solvers(args) -> int:
    from runtime.studies import bench_solvers

    text = bench_solvers.run(quick=args.quick, repeats=args.repeats, progress=not args.quiet)
    print(text)
    if args.out:
        Path(args.out).write_text(text)
    return 0


class _Parser(argparse.ArgumentParser):
    """An argument parser that reports an error in one line (exit code 2)."""

    def error(self, message: str) -> NoReturn:
        self.exit(2, f"{self.prog}: {message} (see {self.prog} --help)\n")


def parser() -> argparse.ArgumentParser:
    """The argument parser of ``ancf``."""
    from runtime.app.shapes import AUTO_PLANE, PLANES
    from symgen.methods import METHOD_FAMILIES

    main = _Parser(prog="ancf", description=__doc__)
    sub = main.add_subparsers(dest="command", required=True)

    gen = sub.add_parser("generate", help="regenerate kernels from symgen into generated/")
    add_list_option(gen, "--element", "element kinds (default all)", metavar="NAME")
    add_list_option(gen, "--backend", "backends (default all)", choices=list(BACKENDS))
    add_list_option(gen, "--method", "kernel families of these methods (default all)",
                    choices=list(METHOD_FAMILIES))
    gen.add_argument("--out", help="output folder (default: the package's generated/)")
    gen.add_argument("--check", action="store_true",
                     help="compare with the output folder instead of writing; exit 1 on a diff")
    gen.set_defaults(run=cmd_generate)

    compile_ = sub.add_parser("compile", help="compile the C kernels into the cache now "
                              "(what first runs would compile on use)")
    add_list_option(compile_, "--element", "element kinds (default all)", metavar="NAME")
    compile_.add_argument("--quiet", action="store_true", help="no progress lines")
    compile_.set_defaults(run=cmd_compile)

    invariants = sub.add_parser("invariants", help="symbolic vs quadrature invariants")
    invariants.add_argument("--element", default="beam3d")
    invariants.add_argument("--reference", choices=["straight", "curved"], default="straight")
    add_list_option(invariants, "--quadrature", "Gauss orders per direction, e.g. 5 3 3",
                    convert=int, metavar="N")
    invariants.add_argument("--backend", choices=list(BACKENDS), default="numpy")
    invariants.add_argument("--law", default=DEFAULT_LAW,
                            help="material law of the element kind (docs/laws.md)")
    invariants.set_defaults(run=cmd_invariants)

    run = sub.add_parser("run", help="run a scene: static, modal and dynamic analyses")
    run.add_argument("scene", help="scene TOML file")
    run.add_argument("--out", required=True, help="results folder")
    run.add_argument("--method", choices=list(METHODS), help="override the scene's [solver]")
    run.add_argument("--backend", choices=list(BACKENDS), help="override the scene's [solver]")
    run.add_argument("--engine", choices=list(ENGINES),
                     help="dynamic engine (default: compiled with the C backend)")
    run.add_argument("--quiet", action="store_true", help="no progress bar or summary line")
    run.add_argument("--no-plots", action="store_true", help="write no PNG plots of sensors")
    run.add_argument("--vtk", action="store_true",
                     help="also write ParaView files in OUT/vtk (default: the scene's [output])")
    run.add_argument("--gif", action="store_true",
                     help="also write shape_animation.gif and shape_static.png (default: the "
                          "scene's [output])")
    run.add_argument("--plane", choices=[AUTO_PLANE, *PLANES], default=AUTO_PLANE,
                     help="projection of the animation and snapshot (default auto: the "
                          "model's longest axis across, the direction it moves most along up; "
                          "plates seen obliquely)")
    run.set_defaults(run=cmd_run)

    from runtime.studies import error_vs_time, precision, stability

    study = sub.add_parser("study", help="work-precision and stability studies")
    study_sub = study.add_subparsers(dest="what", required=True)
    error_vs_time.add_cli(study_sub)
    stability.add_cli(study_sub)

    report = sub.add_parser("report", help="measure everything and write docs/report.md")
    report.add_argument("--out", help="folder of report.md and its figures (default: docs; "
                                      "with --quick results/report)")
    report.add_argument("--quick", action="store_true",
                        help="small versions (smoke test: four of the shipped scenes), never into "
                             "docs/ unless --out says")
    report.add_argument("--scheduler", help="address of an existing dask scheduler")
    report.add_argument("--workers", type=int, help="local dask workers (default: cores)")
    report.set_defaults(run=cmd_report)

    bench = sub.add_parser("bench", help="benchmarks")
    bench_sub = bench.add_subparsers(dest="what", required=True)
    kernels = bench_sub.add_parser("kernels", help="per-element kernel cost, every method")
    add_list_option(kernels, "--element", "element kinds (default all)", metavar="NAME")
    kernels.add_argument("--batch", type=int, default=10_000)
    add_list_option(kernels, "--method", "methods (default all)", choices=list(METHODS))
    add_list_option(kernels, "--backend", "backends (default all)", choices=list(BACKENDS))
    kernels.set_defaults(run=cmd_bench)
    paper = bench_sub.add_parser("paper", help="the paper's Tables I and II on this machine")
    paper.add_argument("--out", default=str(default_out("paper")),
                       help="folder for paper.md/json/csv (default: results/paper)")
    paper.add_argument("--scheduler", help="address of an existing dask scheduler")
    paper.add_argument("--workers", type=int, help="local dask workers (default: cores)")
    paper.add_argument("--serial", action="store_true", help="run in this process")
    paper.add_argument("--quick", action="store_true", help="two short rows (smoke test)")
    paper.add_argument("--backend", choices=list(BACKENDS), default="c")
    paper.set_defaults(run=cmd_bench_paper)
    steps = bench_sub.add_parser(
        "steps", help="cost of one dynamic step against model size, body type, linear solver")
    add_list_option(steps, "--plates", "plate3d grids N (N x N elements; default 4 8 16 32)",
                    convert=_positive, metavar="N")
    add_list_option(steps, "--elements", "beam3d chain elements (default 1000 10000)",
                    convert=_positive, metavar="N")
    add_list_option(steps, "--joints", "spherical joints of the joint-chain mechanism "
                    "(default 50 200)", convert=_positive, metavar="N")
    add_list_option(steps, "--blocks", "brick3d_3843 blocks N (N x N x N elements; default "
                    "2 4 6)", convert=_positive, metavar="N")
    add_list_option(steps, "--linear-solver", "linear solvers (default auto banded sparse)",
                    choices=["auto", *LINEAR_SOLVERS])
    add_list_option(steps, "--newton", "Newton modes (default full)", choices=NEWTON_MODES)
    steps.add_argument("--scenes", nargs="*", metavar="NAME",
                       help="instead: whole runs of these shipped scenes (default all with a "
                            "dynamic analysis) per Newton mode (default all modes), the modes "
                            "interleaved")
    steps.add_argument("--banded-limit", type=_positive, default=32, metavar="N",
                       help="banded plates up to N x N (default 32)")
    steps.add_argument("--repeats", type=_positive, default=3, help="runs of each case (min 1)")
    steps.add_argument("--out", metavar="FILE", help="also write the table to FILE")
    steps.add_argument("--plot", metavar="PNG", help="plot us per element-step to PNG")
    steps.add_argument("--method", choices=list(METHODS), default="gram")
    steps.add_argument("--quiet", action="store_true", help="no progress lines")
    steps.set_defaults(run=cmd_bench_steps)
    solvers = bench_sub.add_parser(
        "solvers", help="whole runs: engines, Newton modes, quadrature, Exudyn; step cost")
    solvers.add_argument("--repeats", type=int, default=3, help="interleaved repeats (min 1)")
    solvers.add_argument("--quick", action="store_true", help="short runs (smoke test)")
    solvers.add_argument("--out", help="also write the Markdown tables to this file")
    solvers.add_argument("--quiet", action="store_true", help="no progress lines")
    solvers.set_defaults(run=cmd_bench_solvers)
    precision.add_cli(bench_sub)
    return main


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``ancf`` console script; returns the exit code.  Errors are one line
    on stderr: 2 for options and inputs, 3 for the environment (files, C compiler, kernel
    cache), 130 for an interruption."""
    command = "ancf"
    try:
        try:
            args = parser().parse_args(argv)
        except SystemExit as done:  # --help, or an option error already reported
            return done.code if isinstance(done.code, int) else 2
        command = f"ancf {args.command}"
        with progress.enabled(not getattr(args, "quiet", False)):
            return int(args.run(args))
    except KeyboardInterrupt:
        print(f"{command}: interrupted", file=sys.stderr)
        return 130
    except ValueError as error:  # includes scene, study and scheduler errors
        print(f"{command}: {_first_line(str(error))}", file=sys.stderr)
        return 2
    except (JitEnvironmentError, OSError) as error:
        print(f"{command}: {_first_line(str(error))}", file=sys.stderr)
        return 3


if __name__ == "__main__":
    sys.exit(main())
