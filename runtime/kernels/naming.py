"""What names a compiled module: the compile flags of each optimisation level, the compiler
(``$CC``, ``gcc``, ``cc``) and its identity, the CPU and cffi identity, and the cache key
hashed over everything that changes the binary (source, cdef, compiler, flags, Python ABI,
machine, cffi version, and the CPU because of ``-march=native``), so a cached ``.so`` is
never stale."""

from __future__ import annotations

import contextlib
import functools
import hashlib
import os
import platform
import re
import shlex
import shutil
import subprocess
import sys
from collections.abc import Sequence

__all__ = [
    "COMPILE_FLAGS",
    "OPTIMIZATION",
    "cache_key",
    "compile_flags",
    "module_name",
    "resolve_compiler",
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
_NAME_RE = re.compile(r"[A-Za-z0-9_]+")


def resolve_compiler() -> tuple[tuple[str, ...] | None, list[str]]:
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
    cmd, _ = resolve_compiler()
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
