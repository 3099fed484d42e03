"""Plain-NumPy reference of the score map: the benchmark baseline and a test oracle.

Shifted slices instead of compiled loops; same definitions as
:mod:`footfall.scoring.walkability`.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt


def score_grid_numpy(
    heights: npt.ArrayLike,
    resolution: float,
    kernel_1d: npt.ArrayLike,
    slope_weight: float,
    proximity_weight: float,
    threshold: float,
) -> tuple[
    npt.NDArray[np.float64], npt.NDArray[np.float64], npt.NDArray[np.float64], npt.NDArray[np.bool_]
]:
    """``(slope, proximity, score, valid)`` of a height grid with NaN for unknown cells."""
    h = np.asarray(heights, dtype=np.float64)
    g = np.asarray(kernel_1d, dtype=np.float64)
    n = g.size
    half = n // 2
    known = np.isfinite(h)
    h0 = np.where(known, h, 0.0)
    rows, cols = h.shape
    padded = np.pad(h0, half, mode="edge")
    unknown = np.pad(~known, half, mode="constant", constant_values=True)

    def window(a: npt.NDArray, di: int, dj: int) -> npt.NDArray:
        return a[half + di : half + di + rows, half + dj : half + dj + cols]

    gx = sum(
        w * (window(padded, 1, dj) - window(padded, -1, dj)) for dj, w in ((-1, 1), (0, 2), (1, 1))
    )
    gy = sum(
        w * (window(padded, di, 1) - window(padded, di, -1)) for di, w in ((-1, 1), (0, 2), (1, 1))
    )
    slope = np.hypot(gx, gy) / (8.0 * resolution)
    weighted = np.zeros_like(h0)
    near_unknown = np.zeros_like(known)
    for di in range(-half, half + 1):
        for dj in range(-half, half + 1):
            weighted += g[di + half] * g[dj + half] * window(padded, di, dj)
            near_unknown |= window(unknown, di, dj)
    proximity = np.abs(weighted - h0 * g.sum() ** 2) / (n * n)
    score = slope_weight * slope + proximity_weight * proximity
    valid = ~near_unknown & (score < threshold)
    for a in (slope, proximity, score):
        a[~known] = np.nan
    return slope, proximity, score, valid
