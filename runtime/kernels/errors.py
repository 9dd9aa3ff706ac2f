"""The faults of the C backend's environment (compiler, cache folder): one hierarchy under
:class:`JitEnvironmentError`, which a run reports with exit code 3."""

from __future__ import annotations

__all__ = [
    "CacheError",
    "CompilationError",
    "CompilerNotFoundError",
    "CompilerNotWorkingError",
    "JitEnvironmentError",
]


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
