"""The error-vs-time plot (runtime.studies.error_vs_time.plot): point labels never overlap,
even where several methods' points coincide, and the first line keeps all of its labels."""

from __future__ import annotations

import itertools
from types import SimpleNamespace

import pytest

from runtime.studies import error_vs_time


@pytest.fixture
def saved(monkeypatch):
    from matplotlib.figure import Figure

    figures = []
    real = Figure.savefig

    def savefig(self, *args, **kwargs):
        figures.append(self)
        return real(self, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", savefig)
    return figures


def crowded_rows() -> list[dict]:
    """Six lines whose points nearly coincide (the crowded corner of the shipped study)."""
    rows = []
    lines = itertools.product(["gram", "cij", "quadrature"], ["trapezoidal",
                                                               "generalized_alpha"])
    for k, (method, integrator) in enumerate(lines):
        for elements, error in ((2, 0.05), (5, 0.0053), (10, 0.0006)):
            for step in (0.01, 0.001):
                rows.append({"role": "sweep", "status": "ok", "method": method,
                             "integrator": integrator, "elements": elements, "step": step,
                             "error": error * (1 + 0.001 * k),
                             "simulate_s": 0.15 * (1 + 0.02 * k) * (1 if step == 0.01 else 8)
                             * (1 + elements / 20)})
    return rows


def test_labels_do_not_overlap(tmp_path, saved):
    plan = SimpleNamespace(measure="frequency", integrators=["trapezoidal",
                                                             "generalized_alpha"],
                           scene=SimpleNamespace(title="Cantilever"))
    error_vs_time.plot(plan, crowded_rows(), tmp_path / "error_vs_time.png")
    assert (tmp_path / "error_vs_time.png").exists()
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    (fig,) = saved
    renderer = FigureCanvasAgg(fig).get_renderer()
    notes = fig.axes[0].texts
    boxes = [note.get_window_extent(renderer) for note in notes]
    for (i, a), (j, b) in itertools.combinations(enumerate(boxes), 2):
        assert not a.overlaps(b), (notes[i].get_text(), notes[j].get_text())
    # the first line (drawn first) keeps a label on each of its three front points
    first = [n for n in notes if n.get_color() == "C0"]
    assert sorted(n.get_text() for n in first) == ["10, 0.01", "2, 0.01", "5, 0.01"]
    assert len(notes) >= 9
