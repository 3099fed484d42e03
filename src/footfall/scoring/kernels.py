"""Compiled score-map kernels (numba): separable passes with contiguous inner loops.

Equivalent to :mod:`footfall.scoring.reference` (plain NumPy), which the tests compare
it with. Indices outside the grid are clamped for the filters; such cells are invalid
anyway, because their kernel window leaves the map.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, fastmath=True, nogil=True)
def score_grid(
    h,
    known,
    sigma,
    noise_sigmas,
    inv_8res,
    g,
    slope_weight,
    proximity_weight,
    threshold,
    slope,
    proximity,
    score,
    valid,
):
    """Fill ``slope``, ``proximity``, ``score`` and ``valid`` for heights ``h`` (0 where unknown).

    ``g`` is the 1-D Gaussian (peak 1) of odd length n; the proximity window is n x n.
    ``sigma`` is each cell's height noise [m] (0 for an exact map): the score counts only
    the slope and proximity beyond ``noise_sigmas`` times what that noise alone gives them
    (for independent cell noise: ``sqrt(12) sigma / (8 res)`` per Sobel axis, and
    ``sigma sqrt(sum K^2 - 1 + (sum K - 1)^2) / n^2`` for the proximity).
    No NaN enters the arithmetic (unknown heights arrive as 0), so fast-math is safe.
    """
    rows, cols = h.shape
    n = g.shape[0]
    half = n // 2
    g_sum_sq = g.sum() ** 2
    inv_n2 = 1.0 / (n * n)
    slope_unit = noise_sigmas * np.sqrt(12.0) * inv_8res
    k_sq = (g * g).sum() ** 2
    proximity_unit = noise_sigmas * np.sqrt(k_sq - 1.0 + (g_sum_sq - 1.0) ** 2) * inv_n2
    # Pad by `half` on both sides of j: clamped heights, and "unknown" outside the map.
    width = cols + 2 * half
    hp = np.empty(width)
    up = np.empty(width)
    along_j = np.empty((rows, cols))  # Gaussian along j
    smooth_j = np.empty((rows, cols))  # [1, 2, 1] along j
    diff_j = np.empty((rows, cols))  # [-1, 0, 1] along j
    unknown_j = np.empty((rows, cols))  # unknown cells in the n-window along j
    for i in range(rows):
        for j in range(width):
            jj = min(max(j - half, 0), cols - 1)
            hp[j] = h[i, jj]
            inside = half <= j < cols + half
            up[j] = 0.0 if inside and known[i, jj] else 1.0
        for j in range(cols):
            along_j[i, j] = 0.0
            unknown_j[i, j] = 0.0
        for k in range(n):
            gk = g[k]
            for j in range(cols):
                along_j[i, j] += gk * hp[j + k]
                unknown_j[i, j] += up[j + k]
        for j in range(cols):
            c = j + half
            smooth_j[i, j] = hp[c - 1] + 2.0 * hp[c] + hp[c + 1]
            diff_j[i, j] = hp[c + 1] - hp[c - 1]
    acc = np.empty(cols)
    count = np.empty(cols)
    for i in range(rows):
        im = max(i - 1, 0)
        ip = min(i + 1, rows - 1)
        for j in range(cols):
            acc[j] = 0.0
            count[j] = 0.0
        for k in range(n):
            ii = i - half + k
            if ii < 0 or ii >= rows:
                ic = min(max(ii, 0), rows - 1)
                for j in range(cols):
                    acc[j] += g[k] * along_j[ic, j]
                    count[j] += n
            else:
                gk = g[k]
                for j in range(cols):
                    acc[j] += gk * along_j[ii, j]
                    count[j] += unknown_j[ii, j]
        for j in range(cols):
            gx = (smooth_j[ip, j] - smooth_j[im, j]) * inv_8res
            gy = (diff_j[im, j] + 2.0 * diff_j[i, j] + diff_j[ip, j]) * inv_8res
            s = np.sqrt(gx * gx + gy * gy)
            p = abs(acc[j] - h[i, j] * g_sum_sq) * inv_n2
            noise = sigma[i, j]
            total = slope_weight * max(s - slope_unit * noise, 0.0)
            total += proximity_weight * max(p - proximity_unit * noise, 0.0)
            slope[i, j] = s
            proximity[i, j] = p
            score[i, j] = total
            valid[i, j] = count[j] == 0.0 and total < threshold
    for i in range(rows):
        for j in range(cols):
            if not known[i, j]:
                slope[i, j] = np.nan
                proximity[i, j] = np.nan
                score[i, j] = np.nan


@njit(cache=True, nogil=True)
def _never_hit(missing, sub, axis, last):
    """Parts along one side of a cell never hit, of the bits of those never hit.

    The side is ``a = 0`` or ``a = sub - 1`` for ``axis`` 0 (along x), ``b = 0`` or
    ``b = sub - 1`` for ``axis`` 1, ``last`` choosing the second.
    """
    count = 0
    fixed = sub - 1 if last else 0
    for p in range(sub):
        bit = sub * fixed + p if axis == 0 else sub * p + fixed
        count += (missing >> bit) & 1
    return count


@njit(cache=True, nogil=True)
def shadowed_cells(bits, points, shadow_points, sub, out):
    """Fill ``out`` with the cells partly in a shadow, and the neighbours across their sides.

    As :func:`footfall.scoring.walkability.shadowed_cells` defines them.
    """
    rows, cols = bits.shape
    full = (1 << (sub * sub)) - 1
    half = (sub + 1) // 2
    for i in range(rows):
        for j in range(cols):
            out[i, j] = False
    for i in range(rows):
        for j in range(cols):
            b = np.int64(bits[i, j]) & full
            if points[i, j] < shadow_points or b == full:
                continue
            out[i, j] = True
            missing = full & ~b
            if i > 0 and _never_hit(missing, sub, 0, False) >= half:
                out[i - 1, j] = True
            if i < rows - 1 and _never_hit(missing, sub, 0, True) >= half:
                out[i + 1, j] = True
            if j > 0 and _never_hit(missing, sub, 1, False) >= half:
                out[i, j - 1] = True
            if j < cols - 1 and _never_hit(missing, sub, 1, True) >= half:
                out[i, j + 1] = True


@njit(cache=True, nogil=True)
def shadow_rims(bits, points, seen, shadow_points, rim_cells, sub, out):
    """Fill ``out`` with the slivers of a rim before a shadow.

    As :func:`footfall.scoring.walkability.shadow_rims` defines them: beyond the grid
    counts as unknown for the shadow and as not well seen behind.
    """
    rows, cols = bits.shape
    full = (1 << (sub * sub)) - 1
    half = (sub + 1) // 2
    for i in range(rows):
        for j in range(cols):
            out[i, j] = False
    for i in range(rows):
        for j in range(cols):
            if not seen[i, j]:
                continue
            missing = full & ~(np.int64(bits[i, j]) & full)
            for side in range(4):
                axis = side // 2
                step = 1 if side % 2 else -1  # side 0: -x, 1: +x, 2: -y, 3: +y
                if _never_hit(missing, sub, axis, step == 1) < half:
                    continue
                dark = True
                for d in range(1, rim_cells + 1):
                    ii = i + step * d if axis == 0 else i
                    jj = j + step * d if axis == 1 else j
                    if 0 <= ii < rows and 0 <= jj < cols and seen[ii, jj]:
                        dark = False
                        break
                if not dark:
                    continue
                ii = i - step if axis == 0 else i
                jj = j - step if axis == 1 else j
                if 0 <= ii < rows and 0 <= jj < cols and points[ii, jj] >= shadow_points:
                    out[i, j] = True
                    break
