"""Second audit, drawings: the shape animation titles a plate in full and shows it bending out
of its plane (not edge-on), fits its frame to a slender beam's motion instead of a white page,
and the error-vs-time plot keeps every point within labelled ticks."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from test_plot_labels import saved

from runtime import load_scene
from runtime.app.shapes import Frames, write_animation
from runtime.model.model import Model
from runtime.studies import error_vs_time

__all__ = ["saved"]  # the fixture recording every figure saved

SCENES = Path(__file__).resolve().parents[1] / "scenes"


def bent_frames(scene: str, axis: int, tip: float) -> tuple[Frames, str]:
    """Frames of a scene's model bending along ``axis`` quadratically to ``tip`` (m) at its
    far end, and the scene's title (no run: the drawing is what is tested)."""
    loaded = load_scene(SCENES / scene)
    frames = Frames()
    frames.begin(Model(loaded))
    x = frames.reference[:, 0] / frames.reference[:, 0].max()
    for k, t in enumerate(np.linspace(0.0, 1.0, 5)):
        state = frames.reference.copy()
        state[:, axis] += tip * t * x**2
        frames.times.append(float(t))
        frames.frames.append(state)
        frames._outputs.append(k)
    return frames, loaded.title


def pixels(ax, x, y) -> np.ndarray:
    points = np.column_stack([x, y])
    return ax.transData.transform(points[~np.isnan(points).any(axis=1)])


def test_plate_animation_has_its_whole_title_and_is_not_edge_on(tmp_path, saved):
    frames, title = bent_frames("plate_cantilever.toml", 2, -2e-3)
    assert len(title) > 60
    write_animation(tmp_path / "a.gif", frames, title)
    fig = saved[-1]
    ax = fig.axes[0]
    heading = ax.title
    assert " ".join(heading.get_text().split()).startswith(title)
    box = heading.get_window_extent(fig.canvas.get_renderer())
    assert box.x0 >= 0 and box.x1 <= fig.bbox.width and box.y1 <= fig.bbox.height
    reference = pixels(ax, *ax.lines[0].get_data())
    assert np.ptp(reference[:, 1]) > 0.05 * fig.bbox.height  # the plate's width is seen


def test_slender_beam_animation_fills_its_frame(tmp_path, saved):
    frames, title = bent_frames("cantilever.toml", 1, -0.02)  # 2 cm on a 5 m beam
    write_animation(tmp_path / "a.gif", frames, title)
    fig = saved[-1]
    ax = fig.axes[0]
    drawn = pixels(ax, *ax.lines[1].get_data())  # the last frame, bent the most
    assert np.ptp(drawn[:, 0]) > 0.6 * fig.bbox.width
    assert np.ptp(drawn[:, 1]) > 0.3 * fig.bbox.height
    assert "displacements x" in ax.title.get_text()  # the magnification is said


def labelled(axis) -> list[float]:
    low, high = sorted(axis.get_view_interval())
    return [loc for minor in (False, True)
            for loc, label in zip(axis.get_ticklocs(minor=minor),
                                  axis.get_ticklabels(minor=minor), strict=True)
            if label.get_text() and low * (1 - 1e-9) <= loc <= high * (1 + 1e-9)]


@pytest.mark.parametrize("times, errors", [
    ((0.0912, 0.19, 0.29, 0.43, 1.5, 1.8), (0.022, 0.022, 0.022, 0.022, 0.052, 0.052)),
    ((3e-3, 2.0, 40.0), (1e-9, 1e-5, 0.3)),
    ((0.5,), (0.01,)),
])
def test_error_vs_time_points_lie_within_labelled_ticks(tmp_path, saved, times, errors):
    rows = [{"role": "sweep", "status": "ok", "method": "gram", "integrator": "trapezoidal",
             "elements": 2 + k, "step": 1e-3, "error": e, "simulate_s": t}
            for k, (t, e) in enumerate(zip(times, errors, strict=True))]
    plan = SimpleNamespace(measure="frequency", integrators=["trapezoidal"],
                           scene=SimpleNamespace(title="Cantilever"))
    error_vs_time.plot(plan, rows, tmp_path / "error_vs_time.png")
    ax = saved[-1].axes[0]
    for axis, values in ((ax.xaxis, times), (ax.yaxis, errors)):
        ticks = labelled(axis)
        assert len(ticks) >= 2
        assert min(ticks) <= min(values) and max(values) <= max(ticks), (ticks, values)
