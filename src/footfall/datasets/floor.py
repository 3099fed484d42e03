"""The floor of a mapped recording: its level, its flatness, how much of it scores valid.

A real scene's floor is not its lowest cells (a sensor scatters a few below it) nor its
most common level (in an office that can be the desk): it is the lowest strong mode of
the height histogram. The open floor, the floor cells whose whole score window is floor
too, is where a flat floor must score valid whatever the sensor's noise.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from footfall.errors import DatasetError
from footfall.mapping.snapshot import MapSnapshot


def floor_level(heights: npt.ArrayLike, bin_m: float = 0.01, min_share: float = 0.25) -> float:
    """The floor's height: the lowest strong mode of the height histogram [m].

    The histogram's modes (1 cm bins, smoothed over three) holding at least ``min_share``
    of the largest one's cells are the big level surfaces; the floor is the lowest of them.
    Not the lowest populated bin: a real sensor scatters a few cells below the floor
    (reflections, holes), and those must not pull the level down; and not simply the
    largest mode, which in an office can be the desk.
    """
    h = np.asarray(heights, dtype=np.float64)
    h = h[np.isfinite(h)]
    if h.size == 0:
        raise DatasetError("no known cell to find the floor in")
    bins = np.arange(h.min(), h.max() + 2 * bin_m, bin_m)
    if bins.size < 4:
        return float(np.median(h))
    counts, edges = np.histogram(h, bins=bins)
    smooth = np.convolve(counts, np.ones(3), mode="same")
    padded = np.r_[-1.0, smooth, -1.0]
    peaks = np.flatnonzero((smooth >= padded[:-2]) & (smooth >= padded[2:]))
    strong = peaks[smooth[peaks] >= min_share * smooth.max()]
    k = int(strong[0])
    near = h[(h >= edges[k] - bin_m) & (h <= edges[k + 1] + bin_m)]
    return float(np.median(near))


def _all_around(mask: npt.NDArray[np.bool_], reach: int) -> npt.NDArray[np.bool_]:
    """Cells whose whole (2 reach + 1)^2 window lies in ``mask`` (outside counts as not)."""
    padded = np.pad(mask, reach, constant_values=False)
    out = np.ones_like(mask)
    n, m = mask.shape
    for di in range(2 * reach + 1):
        for dj in range(2 * reach + 1):
            out &= padded[di : di + n, dj : dj + m]
    return out


def floor_flatness(
    snapshot: MapSnapshot,
    valid: npt.ArrayLike | None = None,
    band: float = 0.03,
    window_cells: int = 5,
) -> dict[str, float | int]:
    """Spread of the floor's cell heights, and how much of the open floor scores valid.

    The floor is the lowest strong mode of the height histogram (:func:`floor_level`); its
    cells are those within ``band`` of that level [m]. The open floor is the floor cells
    whose whole score window
    (``window_cells`` square) is floor too: away from the furniture, whose nearness makes a
    cell invalid by design, and from the edge of what was seen. A flat floor that a
    sensor's noise does not fool scores valid there.

    Args:
        snapshot: The map.
        valid: The score map's valid cells, shape (N, N), for the valid fractions.
        band: Half-width of the floor band [m].
        window_cells: Side of the score's window [cells].
    """
    if not snapshot.known.any():
        return {"floor_cells": 0}
    level = floor_level(snapshot.heights[snapshot.known])
    heights = np.nan_to_num(snapshot.heights, nan=np.inf)
    on_floor = snapshot.known & (np.abs(heights - level) <= band)
    floor = snapshot.heights[on_floor]
    out: dict[str, float | int] = {
        "floor_cells": int(floor.size),
        "floor_height_median_m": float(np.median(floor)),
        "floor_height_std_m": float(np.std(floor)),
        "floor_height_spread_m": float(np.percentile(floor, 95) - np.percentile(floor, 5)),
    }
    if valid is not None:
        v = np.asarray(valid, dtype=bool)
        open_floor = _all_around(on_floor, window_cells // 2)
        out["floor_cells_open"] = int(open_floor.sum())
        out["floor_valid_fraction"] = float(v[open_floor].mean()) if open_floor.any() else 0.0
        out["floor_valid_fraction_all"] = float(v[on_floor].mean())
    return out
