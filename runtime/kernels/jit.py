"""Compile C source once through cffi (API mode) into the cache folder and load it.

The module is named by ``runtime.kernels.naming`` (a hash of everything that changes the
binary), so a cached ``.so`` is never stale.  Several processes may ask for the same new
module at the same moment: the one that takes ``<modname>.lock`` (``runtime.kernels.lock``)
compiles in a private temporary folder, moves the ``.so`` into place atomically and writes
``<modname>.ready`` (the SHA-256 of the ``.so``) last; the others poll for the marker.  A
failed build renames the lock to ``<modname>.failed`` (holding the compiler log); waiters
raise from it and a later fresh call removes it and tries again.  A ``.so`` is loaded only
if the cache (``runtime.kernels.cache``) verifies it against its marker and finds it a whole
ELF file (otherwise it is rebuilt).  The faults are those of ``runtime.kernels.errors``.
"""

from __future__ import annotations

import contextlib
import hashlib
import importlib.util
import os
import shlex
import shutil
import subprocess
import sys
import sysconfig
import tempfile
import threading
import time
import types
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path

from runtime import progress
from runtime.kernels.cache import cache_dir, so_path, verified
from runtime.kernels.errors import (
    CacheError,
    CompilationError,
    CompilerNotFoundError,
    CompilerNotWorkingError,
)
from runtime.kernels.lock import Wait, owner_line, still_ours, sweep_builds, take_lock
from runtime.kernels.naming import OPTIMIZATION, compile_flags, module_name, resolve_compiler

__all__ = ["CompiledModule", "compile_module"]

_LOG_TAIL_CHARS = 6000
_NUMPY_HINT = "use backend='numpy' (--backend numpy on the command line)"

# One build or load at a time per process: compiling redirects fds 1/2, changes the working
# directory (cffi) and sets $CC, which are all process-wide.
_LOCK = threading.RLock()
_MEMO: dict[str, CompiledModule] = {}


@dataclass(frozen=True)
class CompiledModule:
    """A loaded cffi extension module and how it was obtained."""

    module: types.ModuleType  # the cffi extension module (has .ffi and .lib)
    compiled: bool  # True if this call compiled it, False if loaded from cache/memo
    seconds: float  # wall time spent in this call (compile, wait for another process, load)
    path: Path  # the .so file
    waited: bool = False  # True if `seconds` includes waiting for another process's compile


def _import_so(modname: str, path: Path) -> types.ModuleType:
    spec = importlib.util.spec_from_file_location(modname, path)
    if spec is None or spec.loader is None:
        raise ImportError(f"cannot load extension module {modname} from {path}")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    sys.modules[modname] = module
    return module


# --------------------------------------------------------------------------- building


@contextlib.contextmanager
def _captured_output(log_path: Path) -> Iterator[None]:
    """Send fds 1 and 2 and sys.stdout/sys.stderr to ``log_path`` (compiler and build logs)."""
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    fd = os.open(log_path, os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o644)
    saved = [os.dup(1), os.dup(2)]
    try:
        with open(log_path, "a", encoding="utf-8", errors="replace") as text:
            os.dup2(fd, 1)
            os.dup2(fd, 2)
            try:
                with contextlib.redirect_stdout(text), contextlib.redirect_stderr(text):
                    yield
            finally:
                text.flush()
                os.dup2(saved[0], 1)
                os.dup2(saved[1], 2)
    finally:
        for f in (*saved, fd):
            os.close(f)


@contextlib.contextmanager
def _compiler_env(cmd: tuple[str, ...]) -> Iterator[None]:
    """Make distutils use exactly the compiler that went into the cache key."""
    old = os.environ.get("CC")
    os.environ["CC"] = shlex.join(cmd)
    try:
        yield
    finally:
        if old is None:
            os.environ.pop("CC", None)
        else:
            os.environ["CC"] = old


def _tail(text: str) -> str:
    text = text.strip()
    if len(text) > _LOG_TAIL_CHARS:
        text = "...\n" + text[-_LOG_TAIL_CHARS:]
    return text


def _compiles(cmd: tuple[str, ...], code: str, tmp: Path, extra: Sequence[str] = ()) -> bool:
    """True if ``cmd`` compiles ``code`` to an object file."""
    probe = tmp / "probe.c"
    probe.write_text(code)
    try:
        res = subprocess.run(
            [*cmd, *extra, "-c", str(probe), "-o", str(tmp / "probe.o")],
            capture_output=True, timeout=120, check=False,
        )
    except (OSError, subprocess.SubprocessError):
        return False
    return res.returncode == 0


def _diagnose_compiler(cmd: tuple[str, ...], tmp: Path) -> None:
    """After a failed build, raise :class:`CompilerNotWorkingError` if the compiler fails on
    a trivial C file or on Python's headers (a machine fault, not the source's)."""
    if not _compiles(cmd, "int ancf_probe(void) { return 0; }\n", tmp):
        raise CompilerNotWorkingError(
            f"the C compiler {shlex.join(cmd)} does not work (it cannot compile an empty C "
            f"function): set CC to a working compiler, install gcc, or {_NUMPY_HINT}."
        )
    includes = dict.fromkeys(
        filter(None, (sysconfig.get_path("include"), sysconfig.get_path("platinclude")))
    )
    if not _compiles(cmd, "#include <Python.h>\n", tmp, [f"-I{d}" for d in includes]):
        raise CompilerNotWorkingError(
            f"the C compiler {shlex.join(cmd)} cannot compile against Python's headers "
            f"(Python.h in {', '.join(includes)}): install the Python development package "
            f"(python3-dev or python3-devel) or {_NUMPY_HINT}."
        )


def _build(modname: str, source: str, cdef: str, flags: tuple[str, ...], cmd: tuple[str, ...],
           so: Path, ready: Path) -> None:
    """Compile in a private temporary folder (removed whatever happens), move the .so into
    place atomically, then write its ready marker (its SHA-256) atomically."""
    import cffi

    tmp = Path(tempfile.mkdtemp(prefix=f"{modname}.build.", dir=so.parent))
    try:
        (tmp / "owner").write_bytes(owner_line())  # lets a later lock holder sweep it
        log_path = tmp / "build.log"
        error: BaseException | None = None
        built: str | None = None
        with _captured_output(log_path), _compiler_env(cmd):
            try:
                ffi = cffi.FFI()
                ffi.cdef(cdef)
                ffi.set_source(modname, source, extra_compile_args=list(flags),
                               extra_link_args=[OPENMP] if OPENMP in flags else [])
                built = ffi.compile(tmpdir=str(tmp), verbose=False)
            except Exception as exc:  # cffi.VerificationError, CDefError, distutils errors
                error = exc
        if error is not None or built is None:
            _diagnose_compiler(cmd, tmp)
            log = log_path.read_text(encoding="utf-8", errors="replace")
            raise CompilationError(
                f"compiling C module {modname} with {shlex.join(cmd)} failed: {error}\n"
                f"--- compiler output (tail) ---\n{_tail(log)}"
            ) from error
        os.chmod(built, 0o755)  # whatever the umask: only we may write it
        digest = hashlib.sha256(Path(built).read_bytes()).hexdigest()
        os.replace(built, so)
        marker = tmp / "ready"
        fd = os.open(marker, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644)
        with os.fdopen(fd, "w", encoding="ascii") as fh:
            fh.write(f"{digest}  {so.name}\n")
        os.replace(marker, ready)
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def _no_compiler_message(tried: list[str]) -> str:
    return (
        f"backend='c' needs a C compiler and none was found (tried {', '.join(tried)}): "
        "install gcc or use backend='numpy' (--backend numpy on the command line)."
    )


def _obtain(
    modname: str, source: str, cdef: str, flags: tuple[str, ...], folder: Path,
    timeout_s: float, label: str
) -> tuple[types.ModuleType, bool, bool, Path]:
    """Load ``modname`` from the cache, compiling it (or waiting for another process) first.

    Returns the module, whether this call compiled it, whether it waited for another
    process, and the .so path.
    """
    so = so_path(folder, modname)
    ready = folder / f"{modname}.ready"
    lock = folder / f"{modname}.lock"
    failed = folder / f"{modname}.failed"
    fresh = True  # a fresh call clears an old .failed; a waiter raises from a new one
    trust_cache = True  # False once a verified cached binary failed to import: rebuild it
    wait = Wait(lock, modname, timeout_s)
    while True:
        if trust_cache and verified(so, ready):
            try:
                return _import_so(modname, so), False, wait.waited, so
            except ImportError:
                trust_cache = False
                continue
        if failed.exists():
            if not fresh:
                log = failed.read_text(encoding="utf-8", errors="replace")
                raise CompilationError(
                    f"compiling C module {modname} failed in another process:\n{_tail(log)}"
                )
            with contextlib.suppress(FileNotFoundError):
                failed.unlink()
        cmd, tried = resolve_compiler()
        if cmd is None:
            raise CompilerNotFoundError(_no_compiler_message(tried))
        fd = take_lock(lock)
        if fd is None:
            fresh = False
            wait.step()
            continue
        # We own the lock: build, publish the .so and its ready marker, release.
        try:
            sweep_builds(folder, modname, timeout_s)
            if trust_cache and verified(so, ready):
                continue  # finished by someone else between our checks
            with contextlib.suppress(FileNotFoundError):
                ready.unlink()  # corrupt, planted or unloadable: never trust it again
            try:
                with progress.phase(f"compiling {label} (first use on this machine, cached "
                                    "afterwards)"):
                    _build(modname, source, cdef, flags, cmd, so, ready)
            except CompilerNotWorkingError:
                raise  # a machine fault: no .failed, every process diagnoses it itself
            except CompilationError as exc:
                if still_ours(fd, lock):
                    os.write(fd, str(exc).encode("utf-8", "replace"))
                    os.close(fd)
                    fd = -1
                    os.replace(lock, failed)
                raise
            return _import_so(modname, so), True, wait.waited, so
        finally:
            if fd != -1:
                if still_ours(fd, lock):
                    with contextlib.suppress(FileNotFoundError):
                        lock.unlink()
                os.close(fd)


# --------------------------------------------------------------------------- public entry


#: the flag that compiles and links a module with OpenMP (its ``#pragma omp`` loops)
OPENMP = "-fopenmp"


def compile_module(name: str, source: str, cdef: str, timeout_s: float = 600.0,
                   label: str | None = None,
                   optimization: int = OPTIMIZATION, openmp: bool = False) -> CompiledModule:
    """Compile ``source`` (declarations ``cdef``) once into the cache and load it.

    ``name`` becomes part of the module name ``_ancf_{name}_{hash}``; ``label`` names the
    module in the progress line of a compile (default ``name``).  Returns the loaded
    module; ``compiled`` tells whether this call ran the compiler and ``waited`` whether it
    waited for another process's compile (``seconds`` includes that wait).  ``timeout_s`` is
    the age after which another process's lock counts as stale, and the longest this call
    waits for one.  ``optimization`` is the level of :func:`compile_flags` (ValueError
    outside 0 to 3); ``openmp``: compiled and linked with OpenMP (``OPENMP``).  Raises
    :class:`CompilerNotFoundError` when no C compiler exists,
    :class:`CompilerNotWorkingError` when it cannot build extensions,
    :class:`CompilationError` when the source fails to compile and :class:`CacheError` when
    the cache folder is unsafe or unusable (all :class:`JitEnvironmentError`).
    """
    t0 = time.perf_counter()
    flags = compile_flags(optimization) + ((OPENMP,) if openmp else ())
    modname = module_name(name, source, cdef, flags)
    with _LOCK:
        memo = _MEMO.get(modname)
        if memo is not None:
            return CompiledModule(memo.module, False, time.perf_counter() - t0, memo.path)
        folder = cache_dir()
        try:
            module, compiled, waited, path = _obtain(modname, source, cdef, flags, folder,
                                                     timeout_s, label or name)
        except OSError as exc:
            where = f": {exc.filename}" if exc.filename else ""
            raise CacheError(
                f"kernel cache folder {folder} is not usable ({exc.strerror or exc}{where}): "
                "make it writable or set ANCF_CACHE_DIR to a writable folder of your own"
            ) from exc
        result = CompiledModule(module, compiled, time.perf_counter() - t0, path, waited)
        _MEMO[modname] = result
        return result
