"""Compile C source once through cffi (API mode) into a cache folder and load it.

The module name is a hash of everything that changes the binary (source, cdef, compiler
identity, flags, Python ABI, machine, cffi version, and the CPU because of ``-march=native``),
so a cached ``.so`` is never stale.  Several processes may ask for the same new module at the
same moment: the first to create ``<modname>.lock`` exclusively compiles in a private temporary
folder, moves the ``.so`` into place atomically and writes ``<modname>.ready`` (the SHA-256 of
the ``.so``) last; the others poll for the marker.  A failed build renames the lock to
``<modname>.failed`` (holding the compiler log); waiters raise from it and a later fresh call
removes it and tries again.  No lock library is used (the scheme follows FEniCS FFCx's JIT
cache).

Loading a shared object runs its code, so the cache is private: folders are created with mode
0700, a folder or cached file that belongs to another user, is writable by group or others or
is a symbolic link is refused (:class:`CacheError`), and a ``.so`` is loaded only if its
SHA-256 matches its ready marker (otherwise it is rebuilt).
"""

from __future__ import annotations

import contextlib
import functools
import glob
import hashlib
import importlib.machinery
import importlib.util
import os
import platform
import re
import shlex
import shutil
import socket
import stat
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

__all__ = [
    "COMPILE_FLAGS",
    "CacheError",
    "CompilationError",
    "CompiledModule",
    "CompilerNotFoundError",
    "CompilerNotWorkingError",
    "JitEnvironmentError",
    "cache_dir",
    "cache_key",
    "compile_flags",
    "compile_module",
    "module_name",
]

#: Flags of every module after its optimisation level.  ``-g0`` overrides the ``-g`` of
#: Python's build flags: debug information of generated code in a cache serves no one and cost
#: a quarter of the compile time of the large kernels.
_FLAGS = ("-g0", "-march=native", "-ffp-contract=fast", "-std=gnu11")
#: The optimisation level of a module whose caller does not choose one (kernel families
#: declare theirs in element.json ``optimization``, docs/new-element.md section 6).
OPTIMIZATION = 3


def compile_flags(optimization: int = OPTIMIZATION) -> tuple[str, ...]:
    """The compiler flags of a module at ``optimization`` level 0 to 3 (``-O0`` ... ``-O3``)."""
    if isinstance(optimization, bool) or optimization not in (0, 1, 2, 3):
        raise ValueError(f"optimization: expected a level 0, 1, 2 or 3, got {optimization!r}")
    return (f"-O{optimization}", *_FLAGS)


COMPILE_FLAGS: tuple[str, ...] = compile_flags()

#: Bump when the way modules are built changes (invalidates every cached binary).
#: 2: the ready marker holds the SHA-256 of the shared object.
_JIT_FORMAT = "2"
#: Environment variables that distutils folds into the compile or link command.
_BUILD_ENV = ("CFLAGS", "CPPFLAGS", "LDFLAGS", "LDSHARED")
_POLL_S = 0.05
#: A waiter says once on stderr whom it waits for after this many seconds.
_NOTICE_S = 2.0
#: A lock whose owner process started this much later than the lock was written names a
#: reused PID (the owner died and the PID went to another process).
_PID_REUSE_SLACK_S = 2.0
_LOG_TAIL_CHARS = 6000
_NAME_RE = re.compile(r"[A-Za-z0-9_]+")
_NUMPY_HINT = "use backend='numpy' (--backend numpy on the command line)"

# One build or load at a time per process: compiling redirects fds 1/2, changes the working
# directory (cffi) and sets $CC, which are all process-wide.
_LOCK = threading.RLock()
_MEMO: dict[str, CompiledModule] = {}


class JitEnvironmentError(RuntimeError):
    """The C backend cannot be used on this machine (compiler or cache folder); a run that
    meets it ends with exit code 3 (environment)."""


class CompilerNotFoundError(JitEnvironmentError):
    """No usable C compiler could be found for ``backend='c'``."""


class CompilerNotWorkingError(CompilerNotFoundError):
    """A C compiler was found but cannot build extensions (it fails on a trivial C file, or
    on Python's headers), so the fault is the machine's, not the source's."""


class CompilationError(JitEnvironmentError):
    """The C compiler failed on the source; the message ends with the tail of its output."""


class CacheError(JitEnvironmentError):
    """The kernel cache folder is unusable (not a folder, not writable, a wait for another
    process's compile timed out) or unsafe (owned by another user or writable by others)."""


@dataclass(frozen=True)
class CompiledModule:
    """A loaded cffi extension module and how it was obtained."""

    module: types.ModuleType  # the cffi extension module (has .ffi and .lib)
    compiled: bool  # True if this call compiled it, False if loaded from cache/memo
    seconds: float  # wall time spent in this call (compile, wait for another process, load)
    path: Path  # the .so file
    waited: bool = False  # True if `seconds` includes waiting for another process's compile


# --------------------------------------------------------------------------- cache folder


def _euid() -> int | None:
    """The effective user id, None where the platform has none (Windows: no checks)."""
    return os.geteuid() if hasattr(os, "geteuid") else None


def _check_private(path: Path, st: os.stat_result, folder: bool) -> None:
    """Raise :class:`CacheError` unless ``st`` (of the cache folder, or of a cached file)
    belongs to us and only we can write it."""
    euid = _euid()
    if euid is None:
        return
    what = "kernel cache folder" if folder else "cached file"
    if st.st_uid != euid:
        fix = "set ANCF_CACHE_DIR to a folder of your own" if folder else (
            "delete it (it is rebuilt) or set ANCF_CACHE_DIR to a folder of your own")
        raise CacheError(
            f"{what} {path} belongs to another user (uid {st.st_uid}, you are uid {euid}), "
            f"who could plant code in it: {fix}"
        )
    if st.st_mode & 0o022:
        fix = f"run 'chmod go-w {path}' or set ANCF_CACHE_DIR to a private folder" if folder \
            else "delete it (it is rebuilt) or set ANCF_CACHE_DIR to a private folder"
        raise CacheError(
            f"{what} {path} is writable by group or others (mode "
            f"{stat.S_IMODE(st.st_mode):04o}), so another user could plant code in it: {fix}"
        )


def _check_path_to(path: Path) -> None:
    """Refuse a cache path another user could redirect: a folder above it that others may
    write without the sticky bit, or a symbolic link on the way that another user owns."""
    euid = _euid()
    if euid is None:
        return
    logical = Path(os.path.abspath(path))
    for p in [logical, *logical.parents, *Path(os.path.realpath(path)).parents]:
        try:
            st = os.lstat(p)
        except OSError:
            continue
        if stat.S_ISLNK(st.st_mode) and st.st_uid not in (0, euid):
            raise CacheError(
                f"symbolic link {p} on the way to the kernel cache folder {path} belongs to "
                f"another user (uid {st.st_uid}), who could redirect the cache: set "
                "ANCF_CACHE_DIR to a path without it"
            )
        if (stat.S_ISDIR(st.st_mode) and p != logical and st.st_mode & stat.S_IWOTH
                and not st.st_mode & stat.S_ISVTX):
            raise CacheError(
                f"folder {p} above the kernel cache folder {path} is writable by others "
                "without the sticky bit, so another user could swap the cache: set "
                "ANCF_CACHE_DIR to a folder on a private path"
            )


def _make_folder(path: Path) -> None:
    """Create ``path`` and its missing parents with mode 0700 (whatever the umask)."""
    missing = []
    p = path
    while not os.path.lexists(p) and p != p.parent:
        missing.append(p)
        p = p.parent
    for p in reversed(missing):
        with contextlib.suppress(FileExistsError):
            os.mkdir(p, 0o700)


def cache_dir() -> Path:
    """Return the cache folder, created with mode 0700 if missing and checked to be private.

    ``$ANCF_CACHE_DIR`` if set, else the platform's user cache folder: ``$XDG_CACHE_HOME/ancf``
    or ``~/.cache/ancf`` on Linux, ``~/Library/Caches/ancf`` on macOS,
    ``%LOCALAPPDATA%\\ancf\\Cache`` on Windows.  Raises :class:`CacheError` (one sentence
    naming the path, the fault and the fix) if it cannot be created, is not a folder, belongs
    to another user or can be written by group or others.
    """
    env = os.environ.get("ANCF_CACHE_DIR")
    try:
        if env:
            path = Path(env).expanduser()
        elif sys.platform == "win32":
            base = os.environ.get("LOCALAPPDATA") or str(Path.home() / "AppData" / "Local")
            path = Path(base) / "ancf" / "Cache"
        elif sys.platform == "darwin":
            path = Path.home() / "Library" / "Caches" / "ancf"
        else:
            xdg = os.environ.get("XDG_CACHE_HOME")
            base = Path(xdg) if xdg and os.path.isabs(xdg) else Path.home() / ".cache"
            path = base / "ancf"
    except RuntimeError as exc:  # Path.home() without a home folder
        raise CacheError(
            f"cannot locate the kernel cache folder ({exc}): set ANCF_CACHE_DIR to a folder"
        ) from exc
    try:
        _make_folder(path)
        st = os.stat(path)
    except OSError as exc:
        raise CacheError(
            f"cannot create the kernel cache folder {path} ({exc.strerror or exc}): create it "
            "or set ANCF_CACHE_DIR to a writable folder"
        ) from exc
    if not stat.S_ISDIR(st.st_mode):
        raise CacheError(
            f"kernel cache folder {path} exists but is not a folder: remove it or set "
            "ANCF_CACHE_DIR to a folder"
        )
    _check_private(path, st, folder=True)
    _check_path_to(path)
    return path


# --------------------------------------------------------------------------- compiler, key


def _resolve_compiler() -> tuple[tuple[str, ...] | None, list[str]]:
    """Find the C compiler: ``$CC`` (may hold arguments), then ``gcc``, then ``cc``.

    Returns the command (program resolved to an absolute path) or None, and the names tried.
    """
    candidates: list[tuple[str, list[str]]] = []
    env_cc = os.environ.get("CC", "").strip()
    if env_cc:
        with contextlib.suppress(ValueError):
            argv = shlex.split(env_cc)
            if argv:
                candidates.append((f"$CC={env_cc!r}", argv))
        if not candidates:
            candidates.append((f"$CC={env_cc!r}", []))
    candidates += [("gcc", ["gcc"]), ("cc", ["cc"])]
    tried: list[str] = []
    for label, argv in candidates:
        tried.append(label)
        exe = shutil.which(argv[0]) if argv else None
        if exe:
            return (os.path.abspath(exe), *argv[1:]), tried
    return None, tried


@functools.lru_cache(maxsize=16)
def _compiler_identity(cmd: tuple[str, ...] | None) -> str:
    """``CC --version`` output (memoized per process and command)."""
    if cmd is None:
        return "<no compiler>"
    try:
        res = subprocess.run(
            [*cmd, "--version"], capture_output=True, text=True, timeout=60, check=False
        )
        out = (res.stdout + res.stderr).strip()
    except (OSError, subprocess.SubprocessError) as exc:
        out = f"<{type(exc).__name__}>"
    return f"{shlex.join(cmd)}\n{out}"


@functools.lru_cache(maxsize=1)
def _cpu_identity() -> str:
    """CPU model name and feature flags from /proc/cpuinfo (memoized), '' if unavailable."""
    keys = ("model name", "flags", "features", "cpu implementer", "cpu part", "cpu model")
    found: dict[str, str] = {}
    try:
        with open("/proc/cpuinfo", encoding="utf-8", errors="replace") as fh:
            for line in fh:
                key, sep, value = line.partition(":")
                key = key.strip().lower()
                if sep and key in keys and key not in found:
                    found[key] = " ".join(value.split())
    except OSError:
        return platform.processor()
    return "\n".join(f"{k}: {found[k]}" for k in keys if k in found)


@functools.lru_cache(maxsize=1)
def _cffi_version() -> str:
    import cffi

    return cffi.__version__


def cache_key(source: str, cdef: str, flags: Sequence[str] | None = None) -> str:
    """SHA-256 (hex) over everything that changes the compiled binary.

    ``flags`` defaults to the current value of :data:`COMPILE_FLAGS`.
    """
    flags = COMPILE_FLAGS if flags is None else tuple(flags)
    cmd, _ = _resolve_compiler()
    parts = [
        f"ancf-jit {_JIT_FORMAT}",
        source,
        cdef,
        _compiler_identity(cmd),
        "\0".join(flags),
        sys.implementation.cache_tag or "",
        platform.machine(),
        sys.platform,
        _cffi_version(),
        _cpu_identity(),
        "\0".join(f"{k}={os.environ.get(k, '')}" for k in _BUILD_ENV),
    ]
    h = hashlib.sha256()
    for part in parts:
        data = part.encode("utf-8", "surrogateescape")
        h.update(len(data).to_bytes(8, "little"))
        h.update(data)
    return h.hexdigest()


def module_name(name: str, source: str, cdef: str, flags: Sequence[str] | None = None) -> str:
    """The extension module name ``_ancf_{name}_{key[:16]}`` for this source and cdef."""
    if not _NAME_RE.fullmatch(name):
        raise ValueError(f"module name part must match [A-Za-z0-9_]+, got {name!r}")
    return f"_ancf_{name}_{cache_key(source, cdef, flags)[:16]}"


# --------------------------------------------------------------------------- loading


def _so_path(folder: Path, modname: str) -> Path:
    suffix = importlib.machinery.EXTENSION_SUFFIXES[0]
    return folder / f"{modname}{suffix}"


def _import_so(modname: str, path: Path) -> types.ModuleType:
    spec = importlib.util.spec_from_file_location(modname, path)
    if spec is None or spec.loader is None:
        raise ImportError(f"cannot load extension module {modname} from {path}")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    sys.modules[modname] = module
    return module


def _read_private(path: Path) -> bytes | None:
    """The content of a cached file, None if missing; :class:`CacheError` if it is a symbolic
    link or not a regular file, belongs to another user or can be written by others."""
    try:
        st = os.lstat(path)
    except FileNotFoundError:
        return None
    if not stat.S_ISREG(st.st_mode):
        kind = "a symbolic link" if stat.S_ISLNK(st.st_mode) else "not a regular file"
        raise CacheError(
            f"cached file {path} is {kind}, which the cache never creates: delete it (it is "
            "rebuilt) or set ANCF_CACHE_DIR to a folder of your own"
        )
    _check_private(path, st, folder=False)
    fd = os.open(path, os.O_RDONLY | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_BINARY", 0))
    with os.fdopen(fd, "rb") as fh:
        if os.fstat(fh.fileno()).st_ino != st.st_ino:
            return None  # replaced since the check: look again
        return fh.read()


def _verified(so: Path, ready: Path) -> bool:
    """True if the ready marker exists and names the SHA-256 of the shared object."""
    marker = _read_private(ready)
    if marker is None:
        return False
    fields = marker.decode("ascii", "replace").split()
    if len(fields) != 2 or fields[1] != so.name:
        return False
    binary = _read_private(so)
    return binary is not None and hashlib.sha256(binary).hexdigest() == fields[0]


# --------------------------------------------------------------------------- locking


def _owner_line() -> bytes:
    return f"{os.getpid()} {socket.gethostname()} {time.time():.3f}\n".encode()


def _take_lock(lock: Path) -> int | None:
    """Create the lock file exclusively; return its fd, or None if someone holds it."""
    try:
        fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
    except FileExistsError:
        return None
    try:
        os.write(fd, _owner_line())
    except BaseException:  # e.g. a full disk: leave no lock that names no owner
        os.close(fd)
        lock.unlink()
        raise
    return fd


def _still_ours(fd: int, lock: Path) -> bool:
    """True if ``lock`` is still the file behind ``fd`` (not broken and taken by another)."""
    try:
        mine, there = os.fstat(fd), os.stat(lock)
    except OSError:
        return False
    return (mine.st_dev, mine.st_ino) == (there.st_dev, there.st_ino)


def _lock_owner(lock: Path) -> tuple[int, str, float] | None:
    """PID, host and time written in a lock (or build owner) file; None if unreadable."""
    try:
        pid_s, host, time_s = lock.read_text().split()
        return int(pid_s), host, float(time_s)
    except (OSError, ValueError):
        return None  # gone, or not written yet


@functools.lru_cache(maxsize=1)
def _boot_time() -> float | None:
    try:
        with open("/proc/stat", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("btime "):
                    return float(line.split()[1])
    except (OSError, ValueError):
        pass
    return None


def _process_start(pid: int) -> float | None:
    """Wall-clock start time of process ``pid`` (Linux /proc), None if unknown."""
    boot = _boot_time()
    if boot is None:
        return None
    try:
        with open(f"/proc/{pid}/stat", encoding="ascii", errors="replace") as fh:
            fields = fh.read().rpartition(")")[2].split()
        return boot + int(fields[19]) / os.sysconf("SC_CLK_TCK")
    except (OSError, ValueError, IndexError):
        return None


def _owner_is_dead(lock: Path) -> bool:
    """True if the lock names a process on this host that no longer exists, or whose PID now
    belongs to a process started after the lock was written."""
    owner = _lock_owner(lock)
    if owner is None:
        return False
    pid, host, written = owner
    if host != socket.gethostname() or pid == os.getpid():
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    except OSError:
        pass  # alive, owned by another user
    started = _process_start(pid)
    return started is not None and started > written + _PID_REUSE_SLACK_S


def _break_stale_lock(lock: Path, timeout_s: float) -> None:
    """Remove the lock if it is older than ``timeout_s`` or its owner process died."""
    try:
        st = lock.stat()
    except FileNotFoundError:
        return
    if time.time() - st.st_mtime <= timeout_s and not _owner_is_dead(lock):
        return
    # Rename first so that we never delete a lock that another waiter re-created meanwhile.
    grave = lock.with_name(f"{lock.name}.stale.{os.getpid()}.{time.monotonic_ns()}")
    try:
        os.rename(lock, grave)
    except FileNotFoundError:
        return
    try:
        if grave.stat().st_ino != st.st_ino:  # took a fresh lock by mistake: put it back
            with contextlib.suppress(OSError):
                os.link(grave, lock)
    finally:
        with contextlib.suppress(OSError):
            grave.unlink()


def _sweep_builds(folder: Path, modname: str, timeout_s: float) -> None:
    """Remove build folders of ``modname`` left by a killed compile (owner dead, or older
    than ``timeout_s``).  Called while holding the module's lock."""
    for entry in folder.glob(f"{glob.escape(modname)}.build.*"):
        try:
            st = os.lstat(entry)
        except OSError:
            continue
        if stat.S_ISDIR(st.st_mode) and (
            time.time() - st.st_mtime > timeout_s or _owner_is_dead(entry / "owner")
        ):
            shutil.rmtree(entry, ignore_errors=True)


def _wait_notice(lock: Path, modname: str) -> str:
    owner = _lock_owner(lock)
    who = f"process {owner[0]} on {owner[1]}" if owner else "another process"
    return (
        f"ancf: waiting for {who} to finish compiling C module {modname} (lock file {lock}; "
        "delete it if that process is gone)\n"
    )


def _wait_timeout_message(lock: Path, modname: str, timeout_s: float) -> str:
    owner = _lock_owner(lock)
    who = f"process {owner[0]} on {owner[1]}" if owner else "another process"
    return (
        f"gave up after {timeout_s:.0f} s waiting for {who} to compile C module {modname}: "
        f"if no such compile is running, delete the lock file {lock} and try again"
    )


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
        (tmp / "owner").write_bytes(_owner_line())  # lets a later lock holder sweep it
        log_path = tmp / "build.log"
        error: BaseException | None = None
        built: str | None = None
        with _captured_output(log_path), _compiler_env(cmd):
            try:
                ffi = cffi.FFI()
                ffi.cdef(cdef)
                ffi.set_source(modname, source, extra_compile_args=list(flags))
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
    so = _so_path(folder, modname)
    ready = folder / f"{modname}.ready"
    lock = folder / f"{modname}.lock"
    failed = folder / f"{modname}.failed"
    fresh = True  # a fresh call clears an old .failed; a waiter raises from a new one
    trust_cache = True  # False once a verified cached binary failed to import: rebuild it
    wait_start: float | None = None
    noticed = False
    while True:
        if trust_cache and _verified(so, ready):
            try:
                return _import_so(modname, so), False, wait_start is not None, so
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
        cmd, tried = _resolve_compiler()
        if cmd is None:
            raise CompilerNotFoundError(_no_compiler_message(tried))
        fd = _take_lock(lock)
        if fd is None:
            fresh = False
            now = time.monotonic()
            wait_start = now if wait_start is None else wait_start
            _break_stale_lock(lock, timeout_s)
            if not noticed and now - wait_start >= _NOTICE_S and lock.exists():
                sys.stderr.write(_wait_notice(lock, modname))
                sys.stderr.flush()
                noticed = True
            if now - wait_start > timeout_s and lock.exists():
                raise CacheError(_wait_timeout_message(lock, modname, timeout_s))
            time.sleep(_POLL_S)
            continue
        # We own the lock: build, publish the .so and its ready marker, release.
        try:
            _sweep_builds(folder, modname, timeout_s)
            if trust_cache and _verified(so, ready):
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
                if _still_ours(fd, lock):
                    os.write(fd, str(exc).encode("utf-8", "replace"))
                    os.close(fd)
                    fd = -1
                    os.replace(lock, failed)
                raise
            return _import_so(modname, so), True, wait_start is not None, so
        finally:
            if fd != -1:
                if _still_ours(fd, lock):
                    with contextlib.suppress(FileNotFoundError):
                        lock.unlink()
                os.close(fd)


# --------------------------------------------------------------------------- public entry


def compile_module(name: str, source: str, cdef: str, timeout_s: float = 600.0,
                   label: str | None = None,
                   optimization: int = OPTIMIZATION) -> CompiledModule:
    """Compile ``source`` (declarations ``cdef``) once into the cache and load it.

    ``name`` becomes part of the module name ``_ancf_{name}_{hash}``; ``label`` names the
    module in the progress line of a compile (default ``name``).  Returns the loaded
    module; ``compiled`` tells whether this call ran the compiler and ``waited`` whether it
    waited for another process's compile (``seconds`` includes that wait).  ``timeout_s`` is
    the age after which another process's lock counts as stale, and the longest this call
    waits for one.  ``optimization`` is the level of :func:`compile_flags` (ValueError
    outside 0 to 3).  Raises :class:`CompilerNotFoundError` when no C compiler exists,
    :class:`CompilerNotWorkingError` when it cannot build extensions,
    :class:`CompilationError` when the source fails to compile and :class:`CacheError` when
    the cache folder is unsafe or unusable (all :class:`JitEnvironmentError`).
    """
    t0 = time.perf_counter()
    flags = compile_flags(optimization)
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
