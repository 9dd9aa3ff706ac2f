"""Second audit, JIT level: a cached shared object whose ready marker was rewritten to match
a truncated or otherwise mangled binary is never handed to the dynamic loader (which would
kill the process with SIGBUS); it is rebuilt."""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

import pytest
from test_jit_faults import CDEF, LOAD, needs_cc, run_child, unique_source

from runtime.kernels import jit


@pytest.fixture(autouse=True)
def cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("ANCF_CACHE_DIR", str(tmp_path / "cache"))


def forge(path: os.PathLike, data: bytes) -> None:
    """Replace the cached binary by ``data`` and rewrite its ready marker to match."""
    so = os.fspath(path)
    swap = so + ".swap"
    with open(swap, "wb") as fh:
        fh.write(data)
    os.chmod(swap, 0o755)
    os.replace(swap, so)
    name = os.path.basename(so)
    ready = os.path.join(os.path.dirname(so), name.split(".")[0] + ".ready")
    with open(ready, "w", encoding="ascii") as fh:
        fh.write(f"{hashlib.sha256(data).hexdigest()}  {name}\n")


@needs_cc
@pytest.mark.parametrize("keep", [0.5, 0.9, 0.999])
def test_truncated_binary_with_a_matching_marker_is_rebuilt_not_loaded(keep: float) -> None:
    src = unique_source(f"truncated {keep}")
    first = jit.compile_module("axpy", src, CDEF)
    data = first.path.read_bytes()
    forge(first.path, data[: int(len(data) * keep)])
    # a fresh process: this one already holds the module; run_child fails on any signal
    assert run_child(LOAD, src, CDEF) == {"compiled": True, "value": 10.0}
    assert len(first.path.read_bytes()) == len(data)
    assert run_child(LOAD, src, CDEF) == {"compiled": False, "value": 10.0}


@needs_cc
def test_binary_whose_headers_point_past_its_end_is_rebuilt_not_loaded() -> None:
    src = unique_source("headers")
    first = jit.compile_module("axpy", src, CDEF)
    data = bytearray(first.path.read_bytes())
    assert data[:4] == b"\x7fELF" and data[4] == 2  # 64-bit ELF, as on every CI machine
    data[0x28:0x30] = (len(data) * 4).to_bytes(8, "little" if data[5] == 1 else "big")
    forge(first.path, bytes(data))  # e_shoff beyond the file
    assert run_child(LOAD, src, CDEF) == {"compiled": True, "value": 10.0}
