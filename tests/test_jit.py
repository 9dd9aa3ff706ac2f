"""Tests of runtime.kernels.jit: cffi compile-once cache, multi-process locking, error messages."""

from __future__ import annotations

import json
import os
import re
import socket
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
# Where `runtime` was imported from (the source tree or site-packages), for subprocesses.
IMPORT_ROOT = str(Path(jit.__file__).resolve().parents[2])


def unique_source(tag: str) -> str:
    """A fresh C source per call, so neither the in-process memo nor the cache hides work."""
    return (
        f"/* {tag} {uuid.uuid4().hex} */\n"
        "double axpy(double a, double x, double y) { return a * x + y; }\n"
    )


@pytest.fixture
def cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    folder = tmp_path / "cache"
    monkeypatch.setenv("ANCF_CACHE_DIR", str(folder))
    return folder


def child_env() -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (IMPORT_ROOT, env.get("PYTHONPATH")) if p)
    return env


def leftovers(folder: Path, modname: str) -> list[str]:
    """Lock files, stale locks and build folders that should be gone after a build."""
    return sorted(
        p.name
        for p in folder.iterdir()
        if p.name.startswith(modname) and (".lock" in p.name or ".build." in p.name)
    )


def test_optimization_level_is_part_of_the_module_and_checked(cache: Path) -> None:
    src = unique_source("levels")
    assert naming.compile_flags(0)[0] == "-O0" and naming.compile_flags() == naming.COMPILE_FLAGS
    assert "-g0" in naming.COMPILE_FLAGS  # no debug information for generated code
    fast = jit.compile_module("axpy", src, CDEF, optimization=0)
    default = jit.compile_module("axpy", src, CDEF)
    assert fast.compiled and default.compiled and fast.path != default.path
    assert fast.module.lib.axpy(2.0, 3.0, 4.0) == default.module.lib.axpy(2.0, 3.0, 4.0) == 10
    for bad in (4, -1, True, "3"):
        with pytest.raises(ValueError, match="optimization: expected a level 0, 1, 2 or 3"):
            jit.compile_module("axpy", src, CDEF, optimization=bad)


def test_compile_then_load_from_cache_in_fresh_process(
    cache: Path, capfd: pytest.CaptureFixture[str]
) -> None:
    src = unique_source("fresh-process")
    first = jit.compile_module("axpy", src, CDEF)
    out, err = capfd.readouterr()
    assert (out, err) == ("", "")  # build logs are captured, not printed
    assert first.compiled is True and first.waited is False
    assert first.module.lib.axpy(2.0, 3.0, 4.0) == 10.0
    assert first.path.parent == cache and first.path.exists()
    modname = naming.module_name("axpy", src, CDEF)
    assert first.module.__name__ == modname
    assert (cache / f"{modname}.ready").exists()
    assert leftovers(cache, modname) == []

    again = jit.compile_module("axpy", src, CDEF)  # in-process memo
    assert again.compiled is False and again.module is first.module

    script = (
        "import json, sys\n"
        "from runtime.kernels import jit\n"
        "r = jit.compile_module('axpy', sys.argv[1], sys.argv[2])\n"
        "print(json.dumps({'compiled': r.compiled, 'seconds': r.seconds,"
        " 'value': r.module.lib.axpy(2.0, 3.0, 4.0), 'path': str(r.path)}))\n"
    )
    res = subprocess.run(
        [sys.executable, "-c", script, src, CDEF],
        capture_output=True,
        text=True,
        env=child_env(),
        timeout=60,
        check=False,
    )
    assert res.returncode == 0, res.stderr
    assert res.stderr == ""
    data = json.loads(res.stdout)
    assert data["compiled"] is False
    assert data["value"] == 10.0
    assert data["path"] == str(first.path)
    assert data["seconds"] < min(0.5, first.seconds)


WORKER = """
import json, os, sys, time
from pathlib import Path
import cffi  # noqa: F401  (import before the start signal, so all start compiling together)
from runtime.kernels import jit, naming

src, cdef, sync, i = sys.argv[1], sys.argv[2], Path(sys.argv[3]), sys.argv[4]
naming.module_name("axpy", src, cdef)  # warm the compiler-identity memo
(sync / f"ready-{i}").touch()
while not (sync / "go").exists():
    time.sleep(0.001)
r = jit.compile_module("axpy", src, cdef)
print(json.dumps({"compiled": r.compiled, "value": r.module.lib.axpy(2.0, 3.0, 4.0),
                  "name": r.module.__name__}))
"""


def test_four_processes_compile_the_same_module_once(cache: Path, tmp_path: Path) -> None:
    src = unique_source("four-processes")
    sync = tmp_path / "sync"
    sync.mkdir()
    procs = [
        subprocess.Popen(
            [sys.executable, "-c", WORKER, src, CDEF, str(sync), str(i)],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env=child_env(),
        )
        for i in range(4)
    ]
    try:
        deadline = time.monotonic() + 60
        while len(list(sync.glob("ready-*"))) < 4:
            assert time.monotonic() < deadline, "workers did not start"
            assert all(p.poll() is None for p in procs), [p.communicate() for p in procs]
            time.sleep(0.005)
        (sync / "go").touch()
        outputs = [p.communicate(timeout=120) for p in procs]
    finally:
        for p in procs:
            if p.poll() is None:
                p.kill()
    for p, (_out, err) in zip(procs, outputs, strict=True):
        assert p.returncode == 0, err
        # nothing on stderr but, on a slow machine, one notice that it waits for the builder
        assert all(line.startswith("ancf: waiting for") for line in err.splitlines()), err
    results = [json.loads(out) for out, _ in outputs]
    assert [r["value"] for r in results] == [10.0] * 4
    assert sum(r["compiled"] for r in results) == 1
    modname = naming.module_name("axpy", src, CDEF)
    assert {r["name"] for r in results} == {modname}
    assert len(list(cache.glob(f"{modname}*.so"))) == 1
    assert leftovers(cache, modname) == []
    assert (cache / f"{modname}.ready").exists()


def test_compile_error_reports_compiler_output_and_leaves_failed_marker(cache: Path) -> None:
    src = f"/* {uuid.uuid4().hex} */\ndouble axpy(double a, double x, double y) {{ return q; }}\n"
    with pytest.raises(errors.CompilationError) as info:
        jit.compile_module("broken", src, CDEF)
    msg = str(info.value)
    assert "error" in msg and "'q' undeclared" in msg.replace("‘", "'").replace("’", "'")
    modname = naming.module_name("broken", src, CDEF)
    failed = cache / f"{modname}.failed"
    assert failed.exists()
    assert "undeclared" in failed.read_text()
    assert not (cache / f"{modname}.ready").exists()
    assert not list(cache.glob(f"{modname}*.so"))
    assert leftovers(cache, modname) == []

    # A later call does not trust the old marker: it tries again (and fails again).
    failed.write_text("old failure")
    with pytest.raises(errors.CompilationError, match="undeclared"):
        jit.compile_module("broken", src, CDEF)
    assert "undeclared" in failed.read_text()


def test_waiter_raises_when_lock_owner_fails(cache: Path) -> None:
    src = unique_source("waiter-fails")
    modname = naming.module_name("axpy", src, CDEF)
    cache.mkdir(parents=True, exist_ok=True)
    lock = cache / f"{modname}.lock"
    lock.write_text(f"{os.getpid()} {socket.gethostname()} {time.time()}\n")

    def owner_fails() -> None:
        time.sleep(0.2)
        lock.write_text("boom: the other process could not compile")
        os.replace(lock, cache / f"{modname}.failed")

    thread = threading.Thread(target=owner_fails)
    thread.start()
    try:
        with pytest.raises(errors.CompilationError, match="boom"):
            jit.compile_module("axpy", src, CDEF)
    finally:
        thread.join()


def test_stale_lock_is_broken(cache: Path) -> None:
    src = unique_source("stale-lock")
    modname = naming.module_name("axpy", src, CDEF)
    cache.mkdir(parents=True, exist_ok=True)
    lock = cache / f"{modname}.lock"
    lock.write_text(f"{os.getpid()} {socket.gethostname()} 0\n")
    old = time.time() - 3600
    os.utime(lock, (old, old))
    r = jit.compile_module("axpy", src, CDEF, timeout_s=60)
    assert r.compiled and r.module.lib.axpy(1.0, 2.0, 3.0) == 5.0
    assert leftovers(cache, modname) == []


def test_lock_of_dead_process_is_broken(cache: Path) -> None:
    src = unique_source("dead-owner")
    modname = naming.module_name("axpy", src, CDEF)
    cache.mkdir(parents=True, exist_ok=True)
    dead = subprocess.run(
        [sys.executable, "-c", "import os; print(os.getpid())"],
        capture_output=True,
        text=True,
        check=True,
    )
    lock = cache / f"{modname}.lock"
    lock.write_text(f"{dead.stdout.strip()} {socket.gethostname()} {time.time()}\n")
    start = time.perf_counter()
    r = jit.compile_module("axpy", src, CDEF)  # fresh lock, but its owner is gone
    assert r.compiled and r.module.lib.axpy(1.0, 2.0, 3.0) == 5.0
    assert time.perf_counter() - start < 30
    assert leftovers(cache, modname) == []


def test_no_compiler_gives_one_clear_sentence(
    cache: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    empty = tmp_path / "empty-bin"
    empty.mkdir()
    missing = tmp_path / "no-such-cc"
    monkeypatch.setenv("CC", str(missing))
    monkeypatch.setenv("PATH", str(empty))
    src = unique_source("no-compiler")
    with pytest.raises(errors.CompilerNotFoundError) as info:
        jit.compile_module("axpy", src, CDEF)
    msg = str(info.value)
    assert "install gcc" in msg and "backend='numpy'" in msg and "--backend numpy" in msg
    assert "no-such-cc" in msg and "gcc, cc" in msg
    assert msg.count(". ") == 0 and msg.endswith(".")
    assert not [p for p in cache.iterdir() if ".lock" in p.name]


def test_module_name_tracks_everything_that_changes_the_binary(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    src = unique_source("key")
    name = naming.module_name("axpy", src, CDEF)
    assert re.fullmatch(r"_ancf_axpy_[0-9a-f]{16}", name)
    assert naming.module_name("axpy", src, CDEF) == name  # deterministic
    assert naming.module_name("axpy", src + "\n", CDEF) != name
    assert naming.module_name("axpy", src, CDEF + " ") != name
    assert naming.module_name("other", src, CDEF) != name
    assert naming.module_name("axpy", src, CDEF, flags=("-O2",)) != name
    monkeypatch.setattr(naming, "COMPILE_FLAGS", (*naming.COMPILE_FLAGS, "-fno-math-errno"))
    assert naming.module_name("axpy", src, CDEF) != name
    monkeypatch.undo()
    monkeypatch.setenv("CFLAGS", "-DSOMETHING")
    assert naming.module_name("axpy", src, CDEF) != name
    assert len(naming.cache_key(src, CDEF)) == 64
    with pytest.raises(ValueError):
        naming.module_name("bad name", src, CDEF)


def test_cache_dir_location(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("ANCF_CACHE_DIR", str(tmp_path / "a" / "b"))
    assert cache_dir() == tmp_path / "a" / "b"
    assert (tmp_path / "a" / "b").is_dir()
    if sys.platform.startswith("linux"):
        monkeypatch.delenv("ANCF_CACHE_DIR")
        monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
        assert cache_dir() == tmp_path / "xdg" / "ancf"
        assert (tmp_path / "xdg" / "ancf").is_dir()
