"""Plain-NumPy reference of the score map and its shadow rules: benchmark baseline, test oracle.

Shifted slices instead of compiled loops; same definitions as
:mod:`footfall.scoring.walkability`.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from footfall.mapping.kernels import SUB


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


def shadowed_cells_numpy(
    parts: npt.ArrayLike, points: npt.ArrayLike, shadow_points: int
) -> npt.NDArray[np.bool_]:
    """:func:`footfall.scoring.walkability.shadowed_cells` in shifted whole-array passes."""
    bits = np.asarray(parts, dtype=np.uint16)
    full = (1 << (SUB * SUB)) - 1
    shadow = (np.asarray(points) >= shadow_points) & (bits != full)
    if not shadow.any():
        return shadow
    missing = np.where(shadow, ~bits & full, 0)
    part = np.arange(SUB)

    def open_side(bit_numbers: npt.NDArray[np.int64]) -> npt.NDArray[np.bool_]:
        never_hit = sum(((missing >> int(b)) & 1) for b in bit_numbers)
        return never_hit >= (SUB + 1) // 2

    out = shadow.copy()
    out[:-1, :] |= open_side(part)[1:, :]  # parts a = 0: the low-x side
    out[1:, :] |= open_side(SUB * (SUB - 1) + part)[:-1, :]
    out[:, :-1] |= open_side(SUB * part)[:, 1:]  # parts b = 0: the low-y side
    out[:, 1:] |= open_side(SUB * part + SUB - 1)[:, :-1]
    return out


def _side_bits(side: str) -> npt.NDArray[np.int64]:
    """Bit numbers of the parts along one side of a cell: ``"-x"``, ``"+x"``, ``"-y"``, ``"+y"``."""
    part = np.arange(SUB)
    return {
        "-x": part,
        "+x": SUB * (SUB - 1) + part,
        "-y": SUB * part,
        "+y": SUB * part + SUB - 1,
    }[side]


def shadow_rims_numpy(
    parts: npt.ArrayLike,
    points: npt.ArrayLike,
    known: npt.ArrayLike,
    shadow_points: int,
    shadow_rim_cells: int,
) -> npt.NDArray[np.bool_]:
    """:func:`footfall.scoring.walkability.shadow_rims` in shifted whole-array passes."""
    bits = np.asarray(parts, dtype=np.uint16)
    seen = np.asarray(known, dtype=bool)
    well_seen = np.asarray(points) >= shadow_points
    full = (1 << (SUB * SUB)) - 1
    missing = np.where(seen, ~bits & full, 0)
    opposite = {"+x": "-x", "-x": "+x", "+y": "-y", "-y": "+y"}

    def open_side(side: str) -> npt.NDArray[np.bool_]:
        never_hit = sum(((missing >> int(b)) & 1) for b in _side_bits(side))
        return seen & (never_hit >= (SUB + 1) // 2)

    out = np.zeros(seen.shape, dtype=bool)
    for side in opposite:  # open on +x: a shadow beyond along +x, well seen behind; ...
        shadow = np.logical_and.reduce(
            [_across(~seen, side, d, True) for d in range(1, shadow_rim_cells + 1)]
        )
        out |= open_side(side) & shadow & _across(well_seen, opposite[side], 1, False)
    return out


def _across(a: npt.NDArray[np.bool_], side: str, cells: int, beyond: bool) -> npt.NDArray[np.bool_]:
    """For each cell, the value of ``a`` that many ``cells`` across its ``side``.

    ``side`` is ``+x``, ``-x``, ``+y`` or ``-y``; ``beyond`` where that lies outside the window.
    """
    axis = 0 if side[1] == "x" else 1
    out = np.full(a.shape, beyond)
    n = a.shape[axis]
    if cells >= n:
        return out
    src = [slice(None), slice(None)]
    dst = [slice(None), slice(None)]
    if side[0] == "+":
        src[axis], dst[axis] = slice(cells, n), slice(0, n - cells)
    else:
        src[axis], dst[axis] = slice(0, n - cells), slice(cells, n)
    out[tuple(dst)] = a[tuple(src)]
    return out
