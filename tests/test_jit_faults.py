"""Tests of runtime.kernels.jit under attack and faults: planted shared objects, unsafe or unusable
cache folders, broken compilers, long or stale locks, killed compiles."""

from __future__ import annotations

import hashlib
import importlib.machinery
import json
import os
import shutil
import socket
import stat
import subprocess
import sys
import threading
import time
import uuid
from pathlib import Path

import pytest

from runtime.kernels import errors, jit, naming
from runtime.kernels.cache import cache_dir

CDEF = "double axpy(double a, double x, double y);"
IMPORT_ROOT = str(Path(jit.__file__).resolve().parents[2])
CC = shutil.which("gcc") or shutil.which("cc")
needs_cc = pytest.mark.skipif(CC is None, reason="needs a C compiler")


def unique_source(tag: str) -> str:
    """A fresh C source per call, so neither the in-process memo nor the cache hides work."""
    return (
        f"/* {tag} {uuid.uuid4().hex} */\n"
        "double axpy(double a, double x, double y) { return a * x + y; }\n"
    )


def child_env() -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (IMPORT_ROOT, env.get("PYTHONPATH")) if p)
    return env


def run_child(script: str, *args: str, prefix: tuple[str, ...] = ()) -> dict:
    res = subprocess.run(
        [*prefix, sys.executable, "-c", script, *args],
        capture_output=True, text=True, env=child_env(), timeout=120, check=False,
    )
    assert res.returncode == 0, res.stderr
    return json.loads(res.stdout)


def one_sentence(exc: BaseException) -> str:
    msg = str(exc)
    assert "\n" not in msg and "Traceback" not in msg, msg
    return msg


def leftovers(folder: Path) -> list[str]:
    return sorted(
        p.name for p in folder.iterdir()
        if any(tag in p.name for tag in (".lock", ".build.", ".failed"))
    )


@pytest.fixture
def cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    folder = tmp_path / "cache"
    monkeypatch.setenv("ANCF_CACHE_DIR", str(folder))
    return folder


# --------------------------------------------------------------------------- environment


def test_compiler_that_fails_on_everything_is_one_clear_sentence(
    cache: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    false = shutil.which("false")
    if false is None:
        pytest.skip("no false program")
    monkeypatch.setenv("CC", false)
    with pytest.raises(errors.CompilerNotWorkingError) as info:
        jit.compile_module("axpy", unique_source("cc-false"), CDEF)
    assert isinstance(info.value, errors.CompilerNotFoundError)  # "no usable compiler"
    msg = one_sentence(info.value)
    assert f"the C compiler {false} does not work" in msg
    assert "backend='numpy'" in msg and "--backend numpy" in msg
    assert leftovers(cache) == []  # no .failed: every process diagnoses its own compiler


@needs_cc
def test_compiler_without_python_headers_is_one_clear_sentence(
    cache: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("CC", f"{CC} -nostdinc")  # compiles plain C, not Python.h
    with pytest.raises(errors.CompilerNotWorkingError) as info:
        jit.compile_module("axpy", unique_source("no-headers"), CDEF)
    msg = one_sentence(info.value)
    assert "Python's headers" in msg and "python3-dev" in msg and "--backend numpy" in msg


def test_cache_path_that_is_a_file_is_one_clear_sentence(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    afile = tmp_path / "afile"
    afile.write_text("")
    monkeypatch.setenv("ANCF_CACHE_DIR", str(afile))
    with pytest.raises(errors.CacheError) as info:
        jit.compile_module("axpy", unique_source("file"), CDEF)
    msg = one_sentence(info.value)
    assert str(afile) in msg and "not a folder" in msg and "ANCF_CACHE_DIR" in msg

    monkeypatch.setenv("ANCF_CACHE_DIR", str(afile / "cache"))
    with pytest.raises(errors.CacheError) as info:
        cache_dir()
    msg = one_sentence(info.value)
    assert str(afile / "cache") in msg and "ANCF_CACHE_DIR" in msg


READ_ONLY = """
import json, sys
from runtime.kernels import errors, jit
r = jit.compile_module('axpy', sys.argv[1], sys.argv[2])
out = {'cached': [r.compiled, r.module.lib.axpy(2.0, 3.0, 4.0)]}
try:
    jit.compile_module('axpy', sys.argv[3], sys.argv[2])
except errors.JitEnvironmentError as exc:
    out['error'] = [type(exc).__name__, str(exc)]
print(json.dumps(out))
"""


def test_read_only_cache_loads_what_it_holds_and_refuses_new_builds_clearly(
    cache: Path,
) -> None:
    prefix: tuple[str, ...] = ()
    if os.geteuid() == 0:  # root writes anywhere: drop that privilege in the child
        setpriv = shutil.which("setpriv")
        if setpriv is None:
            pytest.skip("running as root without setpriv")
        prefix = (setpriv, "--bounding-set=-dac_override")
    old, new = unique_source("read-only-old"), unique_source("read-only-new")
    jit.compile_module("axpy", old, CDEF)
    os.chmod(cache, 0o500)
    try:
        out = run_child(READ_ONLY, old, CDEF, new, prefix=prefix)
    finally:
        os.chmod(cache, 0o700)
    assert out["cached"] == [False, 10.0]
    kind, msg = out["error"]
    assert kind == "CacheError" and "\n" not in msg
    assert str(cache) in msg and "writable" in msg and "ANCF_CACHE_DIR" in msg


# --------------------------------------------------------------------------- planted code


PLANTED_C = r"""
#include <stdio.h>
#include <stdlib.h>
__attribute__((constructor)) static void planted(void) {
    const char *mark = getenv("ANCF_TEST_PLANTED");
    FILE *f = mark ? fopen(mark, "w") : NULL;
    if (f) { fputs("planted code ran\n", f); fclose(f); }
}
"""



def so_name(modname: str) -> str:
    return modname + importlib.machinery.EXTENSION_SUFFIXES[0]


@pytest.fixture
def planted(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> tuple[Path, Path]:
    """A shared object whose constructor writes the returned mark file when loaded."""
    assert CC is not None
    src = tmp_path / "planted.c"
    src.write_text(PLANTED_C)
    so = tmp_path / "planted.so"
    subprocess.run([CC, "-shared", "-fPIC", "-o", str(so), str(src)], check=True)
    mark = tmp_path / "planted-code-ran"
    monkeypatch.setenv("ANCF_TEST_PLANTED", str(mark))
    return so, mark


def other_user(path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Make ``path`` belong to another user (really as root, else by faking our uid)."""
    if os.geteuid() == 0:
        os.chown(path, 65534, 65534)
    else:
        uid = os.geteuid() + 1
        monkeypatch.setattr(os, "geteuid", lambda: uid)


@needs_cc
def test_planted_module_in_a_cache_folder_others_can_write_is_never_loaded(
    cache: Path, planted: tuple[Path, Path]
) -> None:
    planted_so, mark = planted
    cache.mkdir()
    os.chmod(cache, 0o777)
    src = unique_source("planted")
    modname = naming.module_name("axpy", src, CDEF)
    so = cache / so_name(modname)
    shutil.copy(planted_so, so)
    digest = hashlib.sha256(so.read_bytes()).hexdigest()
    (cache / f"{modname}.ready").write_text(f"{digest}  {so.name}\n")  # even a right hash
    with pytest.raises(errors.CacheError) as info:
        jit.compile_module("axpy", src, CDEF)
    msg = one_sentence(info.value)
    assert str(cache) in msg and "writable by group or others" in msg
    assert "ANCF_CACHE_DIR" in msg
    assert not mark.exists()


LOAD = """
import json, sys
from runtime.kernels import jit
r = jit.compile_module('axpy', sys.argv[1], sys.argv[2])
print(json.dumps({'compiled': r.compiled, 'value': r.module.lib.axpy(2.0, 3.0, 4.0)}))
"""


@needs_cc
def test_binary_not_matching_its_ready_marker_is_rebuilt_never_loaded(
    cache: Path, planted: tuple[Path, Path]
) -> None:
    planted_so, mark = planted
    src = unique_source("swapped")
    first = jit.compile_module("axpy", src, CDEF)
    ready = first.path.with_name(f"{first.module.__name__}.ready")
    assert hashlib.sha256(first.path.read_bytes()).hexdigest() in ready.read_text()

    # Same owner, same name, but not the binary the marker names (loaded in a fresh process,
    # because this one already holds the module).
    swap = cache / "swap.tmp"
    shutil.copy(planted_so, swap)
    os.replace(swap, first.path)
    assert run_child(LOAD, src, CDEF) == {"compiled": True, "value": 10.0}
    assert not mark.exists()
    assert hashlib.sha256(first.path.read_bytes()).hexdigest() in ready.read_text()

    # A partially written binary is rebuilt too.
    data = first.path.read_bytes()
    swap.write_bytes(data[: len(data) // 2])
    os.replace(swap, first.path)
    assert run_child(LOAD, src, CDEF) == {"compiled": True, "value": 10.0}
    assert run_child(LOAD, src, CDEF) == {"compiled": False, "value": 10.0}


def test_cached_files_others_can_write_or_that_are_links_are_refused(
    cache: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    src = unique_source("cached-file")
    first = jit.compile_module("axpy", src, CDEF)
    ready = first.path.with_name(f"{first.module.__name__}.ready")

    monkeypatch.setattr(jit, "_MEMO", {})
    os.chmod(first.path, 0o777)
    with pytest.raises(errors.CacheError) as info:
        jit.compile_module("axpy", src, CDEF)
    msg = one_sentence(info.value)
    assert str(first.path) in msg and "writable by group or others" in msg
    assert "delete it" in msg
    os.chmod(first.path, 0o755)

    moved = ready.with_name("elsewhere")
    os.replace(ready, moved)
    ready.symlink_to(moved)
    with pytest.raises(errors.CacheError, match="symbolic link") as info:
        jit.compile_module("axpy", src, CDEF)
    assert str(ready) in one_sentence(info.value)
    os.replace(moved, ready)
    assert jit.compile_module("axpy", src, CDEF).compiled is False

    if os.geteuid() == 0:
        monkeypatch.setattr(jit, "_MEMO", {})
        os.chown(first.path, 65534, 65534)
        with pytest.raises(errors.CacheError, match="belongs to another user"):
            jit.compile_module("axpy", src, CDEF)


def test_cache_folder_of_another_user_or_open_to_others_is_refused(
    cache: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    cache.mkdir()
    os.chmod(cache, 0o775)
    with pytest.raises(errors.CacheError) as info:
        cache_dir()
    msg = one_sentence(info.value)
    assert str(cache) in msg and "chmod go-w" in msg and "ANCF_CACHE_DIR" in msg
    os.chmod(cache, 0o700)
    assert cache_dir() == cache

    other_user(cache, monkeypatch)
    with pytest.raises(errors.CacheError) as info:
        cache_dir()
    msg = one_sentence(info.value)
    assert str(cache) in msg and "belongs to another user" in msg and "ANCF_CACHE_DIR" in msg


def test_cache_folders_are_private_whatever_the_umask(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    folder = tmp_path / "a" / "b"
    monkeypatch.setenv("ANCF_CACHE_DIR", str(folder))
    old = os.umask(0)
    try:
        assert cache_dir() == folder
        jit.compile_module("axpy", unique_source("umask"), CDEF)
    finally:
        os.umask(old)
    for p in (folder, folder.parent):
        assert stat.S_IMODE(p.stat().st_mode) == 0o700, p
    for p in folder.iterdir():
        assert not p.stat().st_mode & 0o022, p


def test_cache_below_a_folder_others_can_write_is_refused(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    shared = tmp_path / "shared"
    shared.mkdir()
    os.chmod(shared, 0o777)
    monkeypatch.setenv("ANCF_CACHE_DIR", str(shared / "cache"))
    with pytest.raises(errors.CacheError) as info:
        cache_dir()
    msg = one_sentence(info.value)
    assert str(shared) in msg and "sticky" in msg and "ANCF_CACHE_DIR" in msg
    os.chmod(shared, 0o1777)  # like /tmp: others cannot rename what is ours
    assert cache_dir() == shared / "cache"


# --------------------------------------------------------------------------- waiting


def release_after(seconds: float, lock: Path) -> threading.Timer:
    """Remove ``lock`` after a while, so that code without a fix ends (late) instead of
    hanging."""
    timer = threading.Timer(seconds, lambda: lock.unlink(missing_ok=True))
    timer.start()
    return timer


SLOW_OWNER = """
import sys, time
from runtime.kernels import jit
build = jit._build
def slow_build(*args):
    time.sleep(float(sys.argv[3]))
    build(*args)
jit._build = slow_build
print(jit.compile_module('axpy', sys.argv[1], sys.argv[2]).compiled)
"""


def test_waiter_reports_its_wait_and_says_once_whom_it_waits_for(
    cache: Path, capfd: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    src = unique_source("waiter")
    lock = cache / f"{naming.module_name('axpy', src, CDEF)}.lock"
    owner = subprocess.Popen(
        [sys.executable, "-c", SLOW_OWNER, src, CDEF, "2.0"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=child_env(),
    )
    try:
        deadline = time.monotonic() + 60
        while not lock.exists():
            assert owner.poll() is None, owner.communicate()
            assert time.monotonic() < deadline, "the owner never took the lock"
            time.sleep(0.01)
        monkeypatch.setattr("runtime.kernels.lock._NOTICE_S", 0.3)
        r = jit.compile_module("axpy", src, CDEF)
        out, err = owner.communicate(timeout=60)
    finally:
        if owner.poll() is None:
            owner.kill()
    assert owner.returncode == 0 and out.strip() == "True", err
    assert r.compiled is False and r.waited is True
    assert r.seconds > 0.5  # the wait counts: callers report it as compile time
    assert r.module.lib.axpy(2.0, 3.0, 4.0) == 10.0
    stderr = capfd.readouterr().err
    assert stderr.count("ancf: waiting for") == 1, stderr
    assert f"process {owner.pid} on {socket.gethostname()}" in stderr and str(lock) in stderr


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs Linux /proc")
def test_lock_naming_a_reused_pid_is_broken_at_once(cache: Path) -> None:
    src = unique_source("reused-pid")
    lock = cache / f"{naming.module_name('axpy', src, CDEF)}.lock"
    cache.mkdir()
    newcomer = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    # The lock was written a minute before the process now holding its PID started.
    lock.write_text(f"{newcomer.pid} {socket.gethostname()} {time.time() - 60:.3f}\n")
    timer = release_after(10, lock)
    try:
        start = time.perf_counter()
        r = jit.compile_module("axpy", src, CDEF)
        elapsed = time.perf_counter() - start
    finally:
        timer.cancel()
        newcomer.kill()
        newcomer.wait()
    assert r.compiled and r.module.lib.axpy(1.0, 2.0, 3.0) == 5.0
    assert elapsed < 8


def test_wait_is_bounded_by_an_error_naming_the_lock_file(
    cache: Path, capfd: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    src = unique_source("bounded-wait")
    lock = cache / f"{naming.module_name('axpy', src, CDEF)}.lock"
    cache.mkdir()
    lock.write_text(f"{os.getpid()} {socket.gethostname()} {time.time():.3f}\n")
    future = time.time() + 3600  # e.g. a clock skewed file server: never old enough
    os.utime(lock, (future, future))
    monkeypatch.setattr("runtime.kernels.lock._NOTICE_S", 0.2)
    timer = release_after(10, lock)
    try:
        start = time.perf_counter()
        with pytest.raises(errors.CacheError) as info:
            jit.compile_module("axpy", src, CDEF, timeout_s=1.0)
        elapsed = time.perf_counter() - start
    finally:
        timer.cancel()
    msg = one_sentence(info.value)
    assert f"delete the lock file {lock}" in msg and f"process {os.getpid()}" in msg
    assert elapsed < 8
    assert capfd.readouterr().err.count("ancf: waiting for") == 1


# --------------------------------------------------------------------------- leftovers


def test_build_folders_of_killed_compiles_are_swept(cache: Path) -> None:
    src = unique_source("sweep")
    modname = naming.module_name("axpy", src, CDEF)
    cache.mkdir()
    gone = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True).stdout.strip()
    host, now = socket.gethostname(), time.time()
    dead = cache / f"{modname}.build.dead"
    old = cache / f"{modname}.build.old"
    live = cache / f"{modname}.build.live"
    for folder, pid in ((dead, gone), (old, str(os.getpid())), (live, str(os.getpid()))):
        folder.mkdir()
        (folder / "owner").write_text(f"{pid} {host} {now:.3f}\n")
        (folder / "half.o").write_bytes(b"\0" * 100)
    os.utime(old, (now - 7200, now - 7200))
    assert jit.compile_module("axpy", src, CDEF, timeout_s=600).compiled
    assert leftovers(cache) == [live.name]  # a compile still running is left alone


def test_interrupted_compile_leaves_no_lock_or_build_folder(
    cache: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import cffi

    def interrupted(self: object, *args: object, **kwargs: object) -> str:
        raise KeyboardInterrupt

    monkeypatch.setattr(cffi.FFI, "compile", interrupted)
    with pytest.raises(KeyboardInterrupt):
        jit.compile_module("axpy", unique_source("interrupt"), CDEF)
    assert list(cache.iterdir()) == []


def test_owner_whose_lock_was_broken_leaves_the_new_lock_alone(
    cache: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    build = jit._build
    lock: list[Path] = []

    def build_while_lock_is_taken_over(*args: object) -> object:
        # Meanwhile a waiter broke our lock as stale and another process took it.
        lock[0].unlink()
        lock[0].write_text(f"{os.getpid()} {socket.gethostname()} {time.time():.3f}\n")
        return build(*args)

    monkeypatch.setattr(jit, "_build", build_while_lock_is_taken_over)
    good = unique_source("taken-over")
    lock.append(cache / f"{naming.module_name('axpy', good, CDEF)}.lock")
    assert jit.compile_module("axpy", good, CDEF).compiled
    assert lock[0].exists()

    bad = f"/* {uuid.uuid4().hex} */\ndouble axpy(double a, double x, double y) {{ return q; }}\n"
    modname = naming.module_name("axpy", bad, CDEF)
    lock[0] = cache / f"{modname}.lock"
    with pytest.raises(errors.CompilationError):
        jit.compile_module("axpy", bad, CDEF)
    assert lock[0].exists() and not (cache / f"{modname}.failed").exists()
