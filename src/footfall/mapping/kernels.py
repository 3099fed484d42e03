"""Compiled inner loops of the height map (numba): depth or points -> cells -> fusion.

One pass over the pixels back-projects, transforms, bins and keeps the highest point per
cell of the frame; a second pass over the touched cells fuses the frame into the map. The
plain-NumPy equivalent is :mod:`footfall.mapping.reference`. They release the GIL: a
robot's mapping thread fuses while its control loop runs.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

# Slots of the counts array.
VALID, ZERO, NON_FINITE, NEGATIVE, OUT_OF_RANGE, OUTSIDE = range(6)
N_COUNTS = 6

# Points of one cell in one frame whose noise counts as independent (a 3 x 3 patch).
MAX_INDEPENDENT_POINTS = 9

# Each cell records which of its SUB x SUB parts a point has fallen in, one bit per part
# (bit ``SUB * a + b`` for part ``a`` along x and ``b`` along y).
SUB = 4

# Fusion rules, as integers for the compiled code.
FUSE_LATEST, FUSE_MAX, FUSE_VARIANCE = 0, 1, 2


@njit(cache=True, nogil=True)
def _bin_point(
    wx,
    wy,
    wz,
    r2,
    inv_res,
    origin,
    n,
    frame_h,
    frame_lo,
    frame_r2,
    frame_sum,
    frame_n,
    frame_parts,
    stamp,
    frame_id,
    touched,
    n_touched,
):
    """Keep the point in its cell's frame maximum (and minimum) and mark its part.

    Returns the new touched count, or -1 when the point lies outside the window.
    """
    fi = np.floor(wx * inv_res)
    fj = np.floor(wy * inv_res)
    gi = np.int64(fi) - origin[0]
    gj = np.int64(fj) - origin[1]
    if gi < 0 or gi >= n or gj < 0 or gj >= n:
        return -1
    part = _part_bit(wx * inv_res - fi, wy * inv_res - fj)
    # Buffer index (g + origin) mod n, with origin mod n precomputed in origin[2:].
    bi = gi + origin[2]
    if bi >= n:
        bi -= n
    bj = gj + origin[3]
    if bj >= n:
        bj -= n
    if stamp[bi, bj] != frame_id:
        stamp[bi, bj] = frame_id
        frame_h[bi, bj] = wz
        frame_lo[bi, bj] = wz
        frame_r2[bi, bj] = r2
        frame_sum[bi, bj] = wz
        frame_n[bi, bj] = 1
        frame_parts[bi, bj] = part
        touched[n_touched] = bi * n + bj
        n_touched += 1
    else:
        if wz > frame_h[bi, bj]:
            frame_h[bi, bj] = wz
        if wz < frame_lo[bi, bj]:
            frame_lo[bi, bj] = wz
        if r2 < frame_r2[bi, bj]:
            frame_r2[bi, bj] = r2
        frame_sum[bi, bj] += wz
        frame_n[bi, bj] += 1
        frame_parts[bi, bj] |= part
    return n_touched


@njit(cache=True, nogil=True)
def _part_bit(u, v):
    """The bit of the cell part holding a point at fractions ``u``, ``v`` of the cell."""
    a = min(max(np.int64(u * SUB), 0), SUB - 1)
    b = min(max(np.int64(v * SUB), 0), SUB - 1)
    return np.uint16(1) << np.uint16(SUB * a + b)


@njit(cache=True, nogil=True)
def bin_depth(
    depth,
    scale,
    units,
    stride,
    fx,
    fy,
    cx,
    cy,
    min_range,
    max_range,
    rot,
    trans,
    inv_res,
    origin,
    frame_h,
    frame_lo,
    frame_r2,
    frame_sum,
    frame_n,
    frame_parts,
    keep_mean,
    stamp,
    frame_id,
    touched,
    counts,
):
    """Back-project a depth image, move it into the world and keep each cell's highest point.

    Each cell also counts its points and marks the parts of it they fell in. ``origin``
    holds the window's global origin cell (i, j) and the same modulo n. With ``keep_mean``
    the cells also sum their points (a noisy camera's cells take the mean).
    Returns the number of touched cells (their flat buffer indices are in ``touched``).
    """
    n = frame_h.shape[0]
    n_touched = 0
    rows, cols = depth.shape
    column_factor = (np.arange(0, cols, stride) - cx) / fx
    o_i, o_j, wrap_i, wrap_j = origin[0], origin[1], origin[2], origin[3]
    valid = 0
    outside = 0
    for v in range(0, rows, stride):
        yv = (v - cy) / fy
        for k in range(column_factor.shape[0]):
            # Whole units per metre divide (see PinholeCamera.units_per_metre_for).
            z = depth[v, k * stride] / units if units > 0.0 else depth[v, k * stride] * scale
            if not (z > 0.0 and z >= min_range and z <= max_range):
                # Rare path: say why the pixel is dropped.
                if math.isnan(z) or math.isinf(z):
                    counts[NON_FINITE] += 1
                elif z == 0.0:
                    counts[ZERO] += 1
                elif z < 0.0:
                    counts[NEGATIVE] += 1
                else:
                    counts[OUT_OF_RANGE] += 1
                continue
            x = column_factor[k] * z
            y = yv * z
            wx = rot[0, 0] * x + rot[0, 1] * y + rot[0, 2] * z + trans[0]
            wy = rot[1, 0] * x + rot[1, 1] * y + rot[1, 2] * z + trans[1]
            wz = rot[2, 0] * x + rot[2, 1] * y + rot[2, 2] * z + trans[2]
            # Bin (inlined by hand: a helper call here costs a factor of four).
            si = wx * inv_res
            sj = wy * inv_res
            fi = np.floor(si)
            fj = np.floor(sj)
            gi = np.int64(fi) - o_i
            gj = np.int64(fj) - o_j
            if gi < 0 or gi >= n or gj < 0 or gj >= n:
                outside += 1
                continue
            bi = gi + wrap_i
            if bi >= n:
                bi -= n
            bj = gj + wrap_j
            if bj >= n:
                bj -= n
            r2 = x * x + y * y + z * z
            # The point's part (as _part_bit, inlined too).
            a = min(max(np.int64((si - fi) * SUB), 0), SUB - 1)
            b = min(max(np.int64((sj - fj) * SUB), 0), SUB - 1)
            part = np.uint16(1) << np.uint16(SUB * a + b)
            if stamp[bi, bj] != frame_id:
                stamp[bi, bj] = frame_id
                frame_h[bi, bj] = wz
                frame_lo[bi, bj] = wz
                frame_r2[bi, bj] = r2
                frame_n[bi, bj] = 1
                frame_parts[bi, bj] = part
                if keep_mean:
                    frame_sum[bi, bj] = wz
                touched[n_touched] = bi * n + bj
                n_touched += 1
            else:
                if wz > frame_h[bi, bj]:
                    frame_h[bi, bj] = wz
                if wz < frame_lo[bi, bj]:
                    frame_lo[bi, bj] = wz
                if r2 < frame_r2[bi, bj]:
                    frame_r2[bi, bj] = r2
                frame_n[bi, bj] += 1
                frame_parts[bi, bj] |= part
                if keep_mean:  # only a noisy camera's cells take their mean
                    frame_sum[bi, bj] += wz
            valid += 1
    counts[VALID] += valid
    counts[OUTSIDE] += outside
    return n_touched


@njit(cache=True, nogil=True)
def bin_points(
    points,
    sensor,
    inv_res,
    origin,
    frame_h,
    frame_lo,
    frame_r2,
    frame_sum,
    frame_n,
    frame_parts,
    stamp,
    frame_id,
    touched,
    counts,
):
    """Keep each cell's highest world point; non-finite points are counted and skipped."""
    n = frame_h.shape[0]
    n_touched = 0
    for k in range(points.shape[0]):
        wx, wy, wz = points[k, 0], points[k, 1], points[k, 2]
        if not (math.isfinite(wx) and math.isfinite(wy) and math.isfinite(wz)):
            counts[NON_FINITE] += 1
            continue
        dx, dy, dz = wx - sensor[0], wy - sensor[1], wz - sensor[2]
        result = _bin_point(
            wx,
            wy,
            wz,
            dx * dx + dy * dy + dz * dz,
            inv_res,
            origin,
            n,
            frame_h,
            frame_lo,
            frame_r2,
            frame_sum,
            frame_n,
            frame_parts,
            stamp,
            frame_id,
            touched,
            n_touched,
        )
        if result < 0:
            counts[OUTSIDE] += 1
        else:
            n_touched = result
            counts[VALID] += 1
    return n_touched


@njit(cache=True, nogil=True)
def fuse(
    touched,
    n_touched,
    frame_h,
    frame_lo,
    frame_r2,
    frame_sum,
    frame_n,
    frame_parts,
    heights,
    spread,
    variance,
    known,
    parts,
    points,
    new_view,
    evidence_noise,
    rule,
    range_noise,
    process_noise,
    gate,
    noise,
    spread_sigmas,
):
    """Fuse the frame's per-cell heights into the map by ``rule``.

    ``FUSE_LATEST`` replaces, ``FUSE_MAX`` keeps the highest, ``FUSE_VARIANCE`` is a scalar
    Kalman update whose measurement noise is the sensor's at the nearest range seen in
    the cell (``noise`` = base, quadratic, offset of :class:`DepthNoiseModel`; for an ideal
    sensor ``range_noise * r^2``), with ``process_noise`` added per update; a measurement
    more than ``gate`` standard deviations off replaces the cell (the scene changed).

    A cell's ``spread`` is the largest in-frame height range of its points beyond
    ``spread_sigmas`` times the sensor's noise (the noise alone spans that much); its
    ``parts`` gather the parts its points fell in and ``points`` count them, since the cell
    became known (from a ``new_view`` only: a camera standing still repeats its points; and
    only while the sensor's noise at the cell is below ``evidence_noise``: noisier points
    scatter over the parts, and quantized depth lays them on stripes).

    An ideal sensor's cell takes the frame's highest point (the top of what is there); a
    noisy sensor's takes the mean of its points, whose noise is the reading's over the
    square root of their number (at most ``MAX_INDEPENDENT_POINTS``: neighbouring pixels
    share their noise, through disparity quantization and the sensor's matching window),
    where the highest point would be the top of the noise.
    """
    n = heights.shape[0]
    ideal = noise[0] == 0.0 and noise[1] == 0.0
    for k in range(n_touched):
        i = touched[k] // n
        j = touched[k] % n
        if ideal:
            z = frame_h[i, j]
            sensor_sigma = 0.0
            # An exact reading has no variance; the variance rule still needs a prior one.
            s = range_noise * frame_r2[i, j] if rule == FUSE_VARIANCE else 0.0
            m_var = s * s
        else:
            count = frame_n[i, j]
            z = frame_sum[i, j] / count
            d = math.sqrt(frame_r2[i, j]) - noise[2]
            sensor_sigma = noise[0] + noise[1] * d * d
            m_var = sensor_sigma * sensor_sigma / min(count, MAX_INDEPENDENT_POINTS)
        # The largest height range seen inside the cell: an edge or a groove shows itself in
        # some views and hides (occluded) in others.
        frame_spread = max(frame_h[i, j] - frame_lo[i, j] - spread_sigmas * sensor_sigma, 0.0)
        if not known[i, j] or frame_spread > spread[i, j]:
            spread[i, j] = frame_spread
        if not known[i, j]:
            heights[i, j] = z
            variance[i, j] = m_var
            known[i, j] = True
            parts[i, j] = frame_parts[i, j]
            points[i, j] = frame_n[i, j] if sensor_sigma <= evidence_noise else 0
            continue
        parts[i, j] |= frame_parts[i, j]
        if new_view and sensor_sigma <= evidence_noise:
            points[i, j] += frame_n[i, j]
        if rule == FUSE_LATEST:
            heights[i, j] = z
            variance[i, j] = m_var
        elif rule == FUSE_MAX:
            if z > heights[i, j]:
                heights[i, j] = z
                variance[i, j] = m_var
        else:
            p_var = variance[i, j] + process_noise * process_noise
            innovation = z - heights[i, j]
            if innovation * innovation > gate * gate * (p_var + m_var):
                heights[i, j] = z
                variance[i, j] = m_var
            else:
                gain = p_var / (p_var + m_var)
                heights[i, j] += gain * innovation
                variance[i, j] = (1.0 - gain) * p_var


@njit(cache=True, nogil=True)
def unroll(wrap_i, wrap_j, layers, out):
    """The circular buffer's layers in world order, unknown cells emptied.

    ``layers`` and ``out`` are ``(known, heights, spread, variance, parts, points)``; cell
    ``[i, j]`` of ``out`` is buffer cell ``[(i + wrap_i) mod N, (j + wrap_j) mod N]`` (the
    window's corner at ``[0, 0]``); an unknown one gets NaN heights, spread and variance
    and no parts or points.
    """
    known, heights, spread, variance, parts, points = layers
    o_known, o_heights, o_spread, o_variance, o_parts, o_points = out
    n = known.shape[0]
    for i in range(n):
        bi = i + wrap_i
        if bi >= n:
            bi -= n
        for j in range(n):
            bj = j + wrap_j
            if bj >= n:
                bj -= n
            k = known[bi, bj]
            o_known[i, j] = k
            if k:
                o_heights[i, j] = heights[bi, bj]
                o_spread[i, j] = spread[bi, bj]
                o_variance[i, j] = variance[bi, bj]
                o_parts[i, j] = parts[bi, bj]
                o_points[i, j] = points[bi, bj]
            else:
                o_heights[i, j] = np.nan
                o_spread[i, j] = np.nan
                o_variance[i, j] = np.nan
                o_parts[i, j] = 0
                o_points[i, j] = 0
