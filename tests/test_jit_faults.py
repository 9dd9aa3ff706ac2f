"""Tests of runtime.jit under environment faults: compilers that do not work and cache
folders that cannot be used must each give one clear sentence."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import uuid
from pathlib import Path

import pytest

from runtime import jit

CDEF = "double axpy(double a, double x, double y);"
IMPORT_ROOT = str(Path(jit.__file__).resolve().parents[1])
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
    with pytest.raises(jit.CompilerNotWorkingError) as info:
        jit.compile_module("axpy", unique_source("cc-false"), CDEF)
    assert isinstance(info.value, jit.CompilerNotFoundError)  # "no usable compiler"
    msg = one_sentence(info.value)
    assert f"the C compiler {false} does not work" in msg
    assert "backend='numpy'" in msg and "--backend numpy" in msg
    assert leftovers(cache) == []  # no .failed: every process diagnoses its own compiler


@needs_cc
def test_compiler_without_python_headers_is_one_clear_sentence(
    cache: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setenv("CC", f"{CC} -nostdinc")  # compiles plain C, not Python.h
    with pytest.raises(jit.CompilerNotWorkingError) as info:
        jit.compile_module("axpy", unique_source("no-headers"), CDEF)
    msg = one_sentence(info.value)
    assert "Python's headers" in msg and "python3-dev" in msg and "--backend numpy" in msg


def test_cache_path_that_is_a_file_is_one_clear_sentence(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    afile = tmp_path / "afile"
    afile.write_text("")
    monkeypatch.setenv("ANCF_CACHE_DIR", str(afile))
    with pytest.raises(jit.CacheError) as info:
        jit.compile_module("axpy", unique_source("file"), CDEF)
    msg = one_sentence(info.value)
    assert str(afile) in msg and "not a folder" in msg and "ANCF_CACHE_DIR" in msg

    monkeypatch.setenv("ANCF_CACHE_DIR", str(afile / "cache"))
    with pytest.raises(jit.CacheError) as info:
        jit.cache_dir()
    msg = one_sentence(info.value)
    assert str(afile / "cache") in msg and "ANCF_CACHE_DIR" in msg


READ_ONLY = """
import json, sys
from runtime import jit
r = jit.compile_module('axpy', sys.argv[1], sys.argv[2])
out = {'cached': [r.compiled, r.module.lib.axpy(2.0, 3.0, 4.0)]}
try:
    jit.compile_module('axpy', sys.argv[3], sys.argv[2])
except jit.JitEnvironmentError as exc:
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


