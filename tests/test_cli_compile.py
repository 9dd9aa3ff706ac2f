"""``ancf compile``: the C kernel families of the chosen kinds land in the kernel cache (a later
load compiles nothing), unknown kinds are a named option error."""

from __future__ import annotations

import pytest

from runtime.cli import main
from runtime.kernels.kind import element_kind
from runtime.kernels.loader import KernelFamily


@pytest.mark.slow
def test_compile_fills_the_cache_for_the_chosen_kinds(capsys, tmp_path, monkeypatch):
    monkeypatch.setenv("ANCF_CACHE_DIR", str(tmp_path / "cache"))
    assert main(["compile", "--element", "cable2d", "--quiet"]) == 0
    families = element_kind("cable2d").families
    assert f"{len(families)} kernel families ready" in capsys.readouterr().out
    # a fresh load (not the process memo) finds every family compiled
    for family in families:
        assert KernelFamily(element_kind("cable2d"), family, "c").compile_s == 0.0


def test_compile_names_an_unknown_kind(capsys):
    assert main(["compile", "--element", "plate9"]) == 2
    assert "--element: unknown plate9" in capsys.readouterr().err
