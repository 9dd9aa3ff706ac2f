"""The kernel cache folder and its security checks: loading a shared object runs its code,
so folders are created with mode 0700, a folder or cached file that belongs to another user,
is writable by group or others or is a symbolic link is refused (:class:`CacheError`), and a
``.so`` is trusted only if its SHA-256 matches its ready marker and, where shared objects are
ELF files, its headers, segments and sections lie within the file: the dynamic loader maps a
truncated file past its end and the process dies of SIGBUS, which no handler can turn into a
rebuild or a message."""

from __future__ import annotations

import contextlib
import hashlib
import importlib.machinery
import os
import stat
import struct
import sys
from pathlib import Path

from runtime.kernels.errors import CacheError

__all__ = ["cache_dir", "so_path", "verified"]


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


def so_path(folder: Path, modname: str) -> Path:
    """The shared object of ``modname`` in the cache ``folder``."""
    suffix = importlib.machinery.EXTENSION_SUFFIXES[0]
    return folder / f"{modname}{suffix}"


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


#: Shared objects are ELF files everywhere but on macOS (Mach-O) and Windows (PE).
_ELF_PLATFORM = sys.platform not in ("darwin", "win32")
_SHT_NOBITS = 8  # a section that occupies no bytes of the file (.bss)
#: Per ELF class (1: 32-bit, 2: 64-bit): the formats of the file header, a program header
#: and a section header, and the field indices of (offset, size) in the latter two.
_ELF_LAYOUT = {
    1: ("16sHHIIIIIHHHHHH", "IIIIIIII", (1, 4), "IIIIIIIIII", (4, 5)),
    2: ("16sHHIQQQIHHHHHH", "IIQQQQQQ", (2, 5), "IIQQQQIIQQ", (4, 5)),
}


def _extents_within(binary: bytes, order: str, fmt: str, start: int, count: int,
                    entsize: int, fields: tuple[int, int], skip_nobits: bool) -> bool:
    """True if a table of ``count`` headers at ``start`` and the file extents they name,
    (offset, size) at indices ``fields``, lie within ``binary``."""
    size = struct.calcsize(order + fmt)
    if count and (entsize < size or start + count * entsize > len(binary)):
        return False
    for i in range(count):
        header = struct.unpack_from(order + fmt, binary, start + i * entsize)
        if skip_nobits and header[1] == _SHT_NOBITS:
            continue
        offset, length = header[fields[0]], header[fields[1]]
        if offset + length > len(binary):
            return False
    return True


def _whole_shared_object(binary: bytes) -> bool:
    """True if ``binary`` is a whole shared object: on ELF platforms, a dynamic ELF file whose
    program headers, segments, section headers and sections all lie within it (a truncated
    or mangled file fails); elsewhere always True (the loader there does not map past the
    end)."""
    if not _ELF_PLATFORM:
        return True
    if len(binary) < 52 or binary[:4] != b"\x7fELF" or binary[4] not in _ELF_LAYOUT \
            or binary[5] not in (1, 2):
        return False
    order = "<" if binary[5] == 1 else ">"
    header_fmt, ph_fmt, ph_fields, sh_fmt, sh_fields = _ELF_LAYOUT[binary[4]]
    if len(binary) < struct.calcsize(order + header_fmt):
        return False
    (_, e_type, _, _, _, phoff, shoff, _, _, phentsize, phnum, shentsize, shnum,
     _) = struct.unpack_from(order + header_fmt, binary)
    return (e_type == 3  # ET_DYN
            and phnum > 0
            and _extents_within(binary, order, ph_fmt, phoff, phnum, phentsize, ph_fields,
                                skip_nobits=False)
            and _extents_within(binary, order, sh_fmt, shoff, shnum, shentsize, sh_fields,
                                skip_nobits=True))


def verified(so: Path, ready: Path) -> bool:
    """True if the ready marker exists and names the SHA-256 of the shared object, and the
    shared object is whole (:func:`_whole_shared_object`)."""
    marker = _read_private(ready)
    if marker is None:
        return False
    fields = marker.decode("ascii", "replace").split()
    if len(fields) != 2 or fields[1] != so.name:
        return False
    binary = _read_private(so)
    return (binary is not None and hashlib.sha256(binary).hexdigest() == fields[0]
            and _whole_shared_object(binary))
