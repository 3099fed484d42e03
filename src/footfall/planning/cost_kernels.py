"""Compiled passes of the route cost grid (numba).

- The greatest value within an octagon of each cell, as the cost grid takes the tops of
  walls within the legs' span: the octagon of ``r`` alternating 3 x 3 cross and square
  dilations (the shape :func:`scipy.ndimage.maximum_filter` grows when applied ``r``
  times with those footprints), taken in two separable passes instead of ``r`` whole-grid
  filters. Beyond the grid counts as its nearest cell (``mode="nearest"``), which the
  ``r`` passes and the one octagon agree on.
- The unseen cells enclosed along a row or a column by seen ground without a foothold, one
  side deep (a trench's floor between its rims), in one scan of each row and column.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
from numba import njit


def octagon_half_widths(radius_cells: int) -> npt.NDArray[np.int64]:
    """Half-width along the second axis of the octagon's rows ``-R..R`` (``R`` its reach).

    ``radius_cells`` dilations alternate a cross (first) and a square: after ``c`` crosses
    and ``s`` squares a row ``d`` cells off the centre reaches ``s + max(c - max(|d| - s,
    0), 0)`` cells either side, up to ``|d| <= c + s``.
    """
    crosses = (radius_cells + 1) // 2
    squares = radius_cells // 2
    d = np.abs(np.arange(-radius_cells, radius_cells + 1))
    return squares + np.maximum(crosses - np.maximum(d - squares, 0), 0)


@njit(cache=True, nogil=True)
def octagon_max(a, half_widths, rows_max, out):
    """Fill ``out`` with the greatest value of ``a`` (no NaN) in each cell's octagon.

    ``half_widths[k]`` is the octagon's half-width on the row ``k - R`` cells off along the
    first axis; indices beyond the grid are clamped to it. ``rows_max`` is scratch of shape
    ``(max(half_widths) + 1, *a.shape)``: ``rows_max[w, i, j]`` becomes the greatest of
    ``a[i, j - w .. j + w]``.
    """
    rows, cols = a.shape
    reach = half_widths.shape[0] // 2
    for i in range(rows):
        for j in range(cols):
            rows_max[0, i, j] = a[i, j]
    for w in range(1, rows_max.shape[0]):
        for i in range(rows):
            for j in range(cols):
                m = rows_max[w - 1, i, j]
                v = a[i, max(j - w, 0)]
                if v > m:
                    m = v
                v = a[i, min(j + w, cols - 1)]
                if v > m:
                    m = v
                rows_max[w, i, j] = m
    for i in range(rows):
        for j in range(cols):
            out[i, j] = -np.inf
        for k in range(2 * reach + 1):
            ii = min(max(i + k - reach, 0), rows - 1)
            w = half_widths[k]
            for j in range(cols):
                v = rows_max[w, ii, j]
                if v > out[i, j]:
                    out[i, j] = v


@njit(cache=True, nogil=True)
def enclosed_unseen(known, usable, deep, max_run, out):
    """Fill ``out`` with the unseen cells enclosed along a row or a column.

    An unseen run of at most ``max_run`` cells whose nearest seen cells on both sides are
    not ``usable``, one of them ``deep``; a run reaching the grid's side is not enclosed.
    """
    rows, cols = known.shape
    for i in range(rows):
        for j in range(cols):
            out[i, j] = False
    for axis in range(2):
        lines = rows if axis == 0 else cols
        length = cols if axis == 0 else rows
        for line in range(lines):
            k = 0
            while k < length:
                i, j = (line, k) if axis == 0 else (k, line)
                if known[i, j]:
                    k += 1
                    continue
                start = k
                while k < length:
                    i, j = (line, k) if axis == 0 else (k, line)
                    if known[i, j]:
                        break
                    k += 1
                if start == 0 or k == length or k - start > max_run:
                    continue
                a = (line, start - 1) if axis == 0 else (start - 1, line)
                b = (line, k) if axis == 0 else (k, line)
                if usable[a] or usable[b]:
                    continue
                if not (deep[a] or deep[b]):
                    continue
                for m in range(start, k):
                    if axis == 0:
                        out[line, m] = True
                    else:
                        out[m, line] = True
