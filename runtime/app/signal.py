"""Post-processing of sensor time series."""

from __future__ import annotations

import numpy as np
import scipy.optimize


def _fit(t: np.ndarray, y: np.ndarray, omega: float) -> tuple[float, np.ndarray]:
    """Least-squares residual of y ~ c + a cos(omega t) + b sin(omega t), and (c, a, b)."""
    basis = np.column_stack([np.ones_like(t), np.cos(omega * t), np.sin(omega * t)])
    coeffs, *_ = np.linalg.lstsq(basis, y, rcond=None)
    return float(np.sum((basis @ coeffs - y) ** 2)), coeffs


def dominant_frequency(t, y) -> float:
    """Angular frequency (rad/s) of the sinusoid (plus offset) that best fits y(t).

    Works from about one period of data: a scan of the residual over a log grid of
    frequencies (from half a cycle per record to a quarter of the sampling rate), then a
    bounded refinement around the best grid point.  Raises ValueError for too few samples
    or a flat signal.
    """
    t, y = np.asarray(t, float), np.asarray(y, float)
    if t.size < 8:
        raise ValueError(f"frequency estimate: expected at least 8 samples, got {t.size}")
    if np.ptp(y) == 0:
        raise ValueError("frequency estimate: the signal is constant")
    t = t - t[0]
    span = t[-1]
    low, high = np.pi / span, 0.5 * np.pi / np.median(np.diff(t))
    grid = np.geomspace(low, high, 800)  # ~1 % apart: the refinement does the rest
    residuals = np.array([_fit(t, y, w)[0] for w in grid])
    best = int(np.argmin(residuals))
    lo, hi = grid[max(best - 1, 0)], grid[min(best + 1, grid.size - 1)]
    result = scipy.optimize.minimize_scalar(lambda w: _fit(t, y, w)[0], bounds=(lo, hi),
                                            method="bounded", options={"xatol": 1e-10})
    return float(result.x)
