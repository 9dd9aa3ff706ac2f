"""The lock protocol of the cache: the first process to create ``<modname>.lock`` exclusively
builds the module; the others wait, polling.  A lock (or a build folder's ``owner`` file)
names its owner (PID, host, time); a lock older than the timeout, or whose owner died (or
whose PID went to a newer process), is broken, and so are the build folders of killed
compiles.  No lock library is used (the scheme follows FEniCS FFCx's JIT cache)."""

from __future__ import annotations

import contextlib
import functools
import glob
import os
import shutil
import socket
import stat
import sys
import time
from pathlib import Path

from runtime.kernels.errors import CacheError

__all__ = ["Wait", "break_stale_lock", "owner_line", "still_ours", "sweep_builds", "take_lock"]

_POLL_S = 0.05
#: A waiter says once on stderr whom it waits for after this many seconds.
_NOTICE_S = 2.0
#: A lock whose owner process started this much later than the lock was written names a
#: reused PID (the owner died and the PID went to another process).
_PID_REUSE_SLACK_S = 2.0


def owner_line() -> bytes:
    """The line a lock (or build owner) file holds: PID, host and time."""
    return f"{os.getpid()} {socket.gethostname()} {time.time():.3f}\n".encode()


def take_lock(lock: Path) -> int | None:
    """Create the lock file exclusively; return its fd, or None if someone holds it."""
    try:
        fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
    except FileExistsError:
        return None
    try:
        os.write(fd, owner_line())
    except BaseException:  # e.g. a full disk: leave no lock that names no owner
        os.close(fd)
        lock.unlink()
        raise
    return fd


def still_ours(fd: int, lock: Path) -> bool:
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


def break_stale_lock(lock: Path, timeout_s: float) -> None:
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


def sweep_builds(folder: Path, modname: str, timeout_s: float) -> None:
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


class Wait:
    """A wait for the lock of ``modname`` that another process holds: each :meth:`step`
    breaks the lock if it is stale, says once on stderr whom it waits for after
    ``_NOTICE_S``, raises :class:`CacheError` after ``timeout_s`` and sleeps one poll."""

    def __init__(self, lock: Path, modname: str, timeout_s: float) -> None:
        self.lock, self.modname, self.timeout_s = lock, modname, timeout_s
        self.start: float | None = None  # when the wait began (time.monotonic)
        self.noticed = False

    @property
    def waited(self) -> bool:
        """Whether this call has waited for another process."""
        return self.start is not None

    def step(self) -> None:
        """One poll of the wait (see the class docstring)."""
        now = time.monotonic()
        self.start = now if self.start is None else self.start
        break_stale_lock(self.lock, self.timeout_s)
        if not self.noticed and now - self.start >= _NOTICE_S and self.lock.exists():
            sys.stderr.write(_wait_notice(self.lock, self.modname))
            sys.stderr.flush()
            self.noticed = True
        if now - self.start > self.timeout_s and self.lock.exists():
            raise CacheError(_wait_timeout_message(self.lock, self.modname, self.timeout_s))
        time.sleep(_POLL_S)
