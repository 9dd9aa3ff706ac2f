"""Second audit: the README's first snippet (one Element) prints its results when run as a
script."""

from __future__ import annotations

import pytest
from test_readme import BLOCKS, _run


def test_the_element_snippet_prints_force_energy_and_shape(tmp_path):
    (code,) = [b for b in BLOCKS if b.startswith("from runtime import Element")]
    force, energy, *shape = _run(code, tmp_path).split()
    assert float(force) == pytest.approx(1584010.86, rel=1e-8)
    assert float(energy) == pytest.approx(792.0027, rel=1e-6)
    assert " ".join(shape) == "(24, 24)"
