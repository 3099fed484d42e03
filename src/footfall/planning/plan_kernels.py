"""Compiled inner loops of the foothold planner (numba).

The planner asks these for every candidate foothold at every body height it tries:
thousands of calls a walk, each on a handful to a few hundred points, where NumPy's cost
per call (a few microseconds per array operation, twenty operations) outweighed the
arithmetic itself. Each computes what its NumPy form did, in the same order of operations:

- :func:`highest_within`: the highest mapped height within a foot's radius of points (the
  terrain a swing, a knee or a tibia must clear).
- :func:`polygon_margin`: how far a point lies inside the convex hull of the supporting
  feet (the stability margin of a support polygon).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True, nogil=True)
def highest_within(points, offsets, heights, origin_x, origin_y, resolution, out):
    """Fill ``out`` with the highest known height at ``points`` shifted by each offset.

    Args:
        points: World points, shape (m, 2) [m].
        offsets: Shifts sampled around each point, shape (k, 2) [m].
        heights: The map window's heights, shape (N, N), NaN where unknown [m].
        origin_x: World x of the corner of cell ``[0, 0]`` [m].
        origin_y: World y of that corner [m].
        resolution: Cell side [m].
        out: Result, shape (m,): ``-inf`` where no sample is on a known cell [m].
    """
    for i in range(points.shape[0]):
        out[i] = highest_at(
            points[i, 0], points[i, 1], offsets, heights, origin_x, origin_y, resolution
        )


@njit(cache=True, nogil=True)
def highest_at(x, y, offsets, heights, origin_x, origin_y, resolution):
    """The highest known height at ``(x, y)`` shifted by each offset; ``-inf`` if none [m]."""
    n = heights.shape[0]
    best = -np.inf
    for k in range(offsets.shape[0]):
        fi = math.floor((x + offsets[k, 0] - origin_x) / resolution)
        fj = math.floor((y + offsets[k, 1] - origin_y) / resolution)
        if 0 <= fi < n and 0 <= fj < n:
            value = heights[int(fi), int(fj)]
            if value > best:  # False for NaN
                best = value
    return best


def foot_ring(radius: float) -> np.ndarray:
    """The offsets sampled around a point: itself and four at ``radius``, shape (5, 2) [m]."""
    return np.array([(0.0, 0.0), (radius, 0.0), (-radius, 0.0), (0.0, radius), (0.0, -radius)])


@njit(cache=True, nogil=True)
def _cross(o, a, b):
    """The z of ``(a - o) x (b - o)``."""
    return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])


@njit(cache=True, nogil=True)
def _convex_hull(points):
    """Counter-clockwise convex hull of points, shape (h, 2).

    A monotone chain over the distinct points sorted by x, then y.
    """
    k = points.shape[0]
    order = np.arange(k)
    for i in range(1, k):  # insertion sort: a support polygon has at most six vertices
        j = i
        while j > 0:
            a, b = points[order[j - 1]], points[order[j]]
            if a[0] > b[0] or (a[0] == b[0] and a[1] > b[1]):
                order[j - 1], order[j] = order[j], order[j - 1]
                j -= 1
            else:
                break
    pts = np.empty((k, 2))
    m = 0
    for i in range(k):
        p = points[order[i]]
        if m == 0 or p[0] != pts[m - 1, 0] or p[1] != pts[m - 1, 1]:
            pts[m] = p
            m += 1
    if m < 3:
        return pts[:m].copy()
    chain = np.empty((2 * m, 2))
    n = 0
    for i in range(m):
        while n >= 2 and _cross(chain[n - 2], chain[n - 1], pts[i]) <= 1e-15:
            n -= 1
        chain[n] = pts[i]
        n += 1
    lower = n - 1
    start = n
    for i in range(m - 1, -1, -1):
        while n - start >= 2 and _cross(chain[n - 2], chain[n - 1], pts[i]) <= 1e-15:
            n -= 1
        chain[n] = pts[i]
        n += 1
    hull = np.empty((lower + n - start - 1, 2))
    hull[:lower] = chain[:lower]
    hull[lower:] = chain[start : n - 1]
    return hull


@njit(cache=True, nogil=True)
def polygon_margin(px, py, polygon):
    """Signed distance from ``(px, py)`` to the edges of the convex hull of ``polygon`` [m].

    Positive inside, negative outside; ``-inf`` for fewer than three distinct vertices.
    ``polygon`` has shape (k, 2).
    """
    hull = _convex_hull(polygon)
    h = hull.shape[0]
    if h < 3:
        return -np.inf
    margin = np.inf
    for i in range(h):
        ex = hull[(i + 1) % h, 0] - hull[i, 0]
        ey = hull[(i + 1) % h, 1] - hull[i, 1]
        norm = math.sqrt(ey * ey + ex * ex)
        nx, ny = ey / norm, -ex / norm
        margin = min(margin, -((px - hull[i, 0]) * nx + (py - hull[i, 1]) * ny))
    return margin
