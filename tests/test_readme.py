"""The README's Python examples run verbatim (from the repository root's scenes, in a
scratch folder), and what they print is what the README says."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import meshio
import pytest

ROOT = Path(__file__).resolve().parents[1]
BLOCKS = re.findall(r"```python\n(.*?)```", (ROOT / "README.md").read_text(), re.S)


def _run(code: str, folder: Path) -> str:
    shutil.copytree(ROOT / "scenes", folder / "scenes")
    env = dict(os.environ, MPLBACKEND="Agg")
    result = subprocess.run([sys.executable, "-c", code], cwd=folder, env=env,
                            capture_output=True, text=True, timeout=600, check=False)
    assert result.returncode == 0, result.stderr
    return result.stdout


def test_readme_has_the_python_examples():
    assert len(BLOCKS) >= 3
    assert any("run_scene(scene)" in b for b in BLOCKS)
    assert any("VtkSeries" in b for b in BLOCKS)


@pytest.mark.parametrize("index", range(len(BLOCKS)))
def test_readme_python_example_runs_verbatim(index, tmp_path):
    code = BLOCKS[index]
    out = _run(code, tmp_path)
    if "Paper cantilever" in code:   # the paper cantilever built in code
        lines = out.splitlines()
        status, tip = lines[0].split()
        assert status == "ok" and float(tip) == pytest.approx(-0.01134, rel=2e-3)
        assert float(lines[1]) == pytest.approx(16.27, rel=2e-3)   # paper: 16.28 rad/s
        assert (tmp_path / "tip_y.png").read_bytes()[:4] == b"\x89PNG"
    if "plate3d" in code:            # the plate strip against beam theory
        tip, theory = map(float, out.split())
        assert tip == pytest.approx(-0.001897, rel=1e-3)
        assert tip == pytest.approx(theory, rel=0.005)
    if "VtkSeries" in code:          # a ParaView series that meshio reads back
        folder = tmp_path / "cantilever_vtk"
        pvd = (folder / "dynamic.pvd").read_text()
        files = re.findall(r'file="([^"]+)"', pvd)
        assert len(files) > 100
        mesh = meshio.read(folder / files[-1])
        assert mesh.points.shape[1] == 3 and "displacement" in mesh.point_data
