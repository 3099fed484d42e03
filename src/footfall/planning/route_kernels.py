"""Compiled route search (numba): Dijkstra over an 8-connected cost grid.

A move between neighbouring cells costs its length times the mean of the two cells'
costs per metre; an infinite cost is a cell that cannot be entered. The search runs from
one start cell over the whole grid (the navigator picks its target from the distances, see
:mod:`footfall.planning.navigation`), with a binary heap and lazy deletion. It holds no
Python object, so it runs without the GIL: a replan on another thread leaves the control
thread free.
"""

from __future__ import annotations

import numpy as np
from numba import njit

# Neighbour offsets (di, dj) of the 8-connected grid, and their lengths in cells.
_DI = np.array([1, -1, 0, 0, 1, 1, -1, -1], dtype=np.int64)
_DJ = np.array([0, 0, 1, -1, 1, -1, 1, -1], dtype=np.int64)
_LENGTH = np.array([1.0, 1.0, 1.0, 1.0, np.sqrt(2.0), np.sqrt(2.0), np.sqrt(2.0), np.sqrt(2.0)])


@njit(cache=True, nogil=True)
def _push(keys, values, size, key, value):
    """Push onto the min-heap held in ``keys``/``values``; returns the new size."""
    k = size
    keys[k] = key
    values[k] = value
    while k > 0:
        parent = (k - 1) >> 1
        if keys[parent] <= keys[k]:
            break
        keys[parent], keys[k] = keys[k], keys[parent]
        values[parent], values[k] = values[k], values[parent]
        k = parent
    return size + 1


@njit(cache=True, nogil=True)
def _pop(keys, values, size):
    """Remove the heap's least entry; returns ``(key, value, new size)``."""
    key, value = keys[0], values[0]
    size -= 1
    keys[0], values[0] = keys[size], values[size]
    k = 0
    while True:
        left = 2 * k + 1
        if left >= size:
            break
        child = left
        if left + 1 < size and keys[left + 1] < keys[left]:
            child = left + 1
        if keys[k] <= keys[child]:
            break
        keys[child], keys[k] = keys[k], keys[child]
        values[child], values[k] = values[k], values[child]
        k = child
    return key, value, size


@njit(cache=True, nogil=True)
def dijkstra(cost, start_i, start_j, cell_m, distance, parent):
    """Least route cost from ``(start_i, start_j)`` to every cell.

    Args:
        cost: Cost per metre of each cell, shape (n, m); ``inf`` cannot be entered.
        start_i: Start row.
        start_j: Start column.
        cell_m: Cell side [m].
        distance: Output, shape (n, m): least route cost to each cell (``inf``: none).
        parent: Output, shape (n, m): flat index of the previous cell on that route (-1 at
            the start and where there is none).

    Returns:
        The number of cells settled.
    """
    rows, cols = cost.shape
    distance[:, :] = np.inf
    parent[:, :] = -1
    capacity = 8 * rows * cols + 1
    keys = np.empty(capacity)
    values = np.empty(capacity, dtype=np.int64)
    done = np.zeros((rows, cols), dtype=np.bool_)
    distance[start_i, start_j] = 0.0
    size = _push(keys, values, 0, 0.0, start_i * cols + start_j)
    settled = 0
    while size > 0:
        d, flat, size = _pop(keys, values, size)
        i, j = flat // cols, flat % cols
        if done[i, j]:
            continue
        done[i, j] = True
        settled += 1
        here = cost[i, j]
        for k in range(8):
            ni, nj = i + _DI[k], j + _DJ[k]
            if ni < 0 or nj < 0 or ni >= rows or nj >= cols or done[ni, nj]:
                continue
            there = cost[ni, nj]
            if not np.isfinite(there):
                continue
            nd = d + _LENGTH[k] * cell_m * 0.5 * (here + there)
            if nd < distance[ni, nj]:
                distance[ni, nj] = nd
                parent[ni, nj] = flat
                size = _push(keys, values, size, nd, ni * cols + nj)
    return settled


@njit(cache=True, nogil=True)
def segment_points(origin_x, origin_y, cell_m, ax, ay, bx, by):
    """One point inside every cell the segment ``a``-``b`` passes through [m], shape (k, 2).

    The segment is cut where it crosses a grid line; the middle of each piece lies in the
    cell that piece crosses, so no cell it clips at a corner is missed (as samples at a
    fixed spacing can). The ends are included, for an end on a cell's edge.
    """
    u = ((ax - origin_x) / cell_m, (ay - origin_y) / cell_m)
    v = ((bx - origin_x) / cell_m, (by - origin_y) / cell_m)
    cuts = [0.0, 1.0]
    for k in range(2):
        if abs(v[k] - u[k]) > 1e-12:
            lo, hi = min(u[k], v[k]), max(u[k], v[k])
            for line in range(int(np.floor(lo)) + 1, int(np.ceil(hi))):
                cuts.append((float(line) - u[k]) / (v[k] - u[k]))
    t = np.sort(np.minimum(np.maximum(np.array(cuts), 0.0), 1.0))
    unique = [t[0]]
    for k in range(1, len(t)):
        if t[k] != t[k - 1]:
            unique.append(t[k])
    out = np.empty((len(unique) + 1, 2))
    dx, dy = bx - ax, by - ay
    for k in range(len(unique) + 1):
        if k == 0:
            s = 0.0
        elif k == len(unique):
            s = 1.0
        else:
            s = 0.5 * (unique[k - 1] + unique[k])
        out[k, 0] = ax + s * dx
        out[k, 1] = ay + s * dy
    return out


@njit(cache=True, nogil=True)
def _cost_at(cost, origin_x, origin_y, cell_m, x, y):
    """Cost per metre at a world point; infinite beyond the grid."""
    i = int(np.floor((x - origin_x) / cell_m))
    j = int(np.floor((y - origin_y) / cell_m))
    if i < 0 or j < 0 or i >= cost.shape[0] or j >= cost.shape[1]:
        return np.inf
    return cost[i, j]


@njit(cache=True, nogil=True)
def taut_indices(cost, origin_x, origin_y, cell_m, points):
    """The points of a grid path that string pulling keeps, as indices into ``points``.

    From each kept point the segment reaches on along the path for as long as it crosses
    no cell dearer than the dearest the path itself crosses meanwhile (to 1e-9), and never
    a lethal (infinite) or unknown (NaN) one.
    """
    n = len(points)
    along = np.empty(n)
    for k in range(n):
        along[k] = _cost_at(cost, origin_x, origin_y, cell_m, points[k, 0], points[k, 1])
    kept = [0]
    i = 0
    while i < n - 1:
        best = i + 1
        worst = max(along[i], along[i + 1])
        unknown = np.isnan(along[i]) or np.isnan(along[i + 1])
        for j in range(i + 2, n):
            worst = max(worst, along[j])
            unknown = unknown or np.isnan(along[j])
            line = segment_points(
                origin_x, origin_y, cell_m, points[i, 0], points[i, 1], points[j, 0], points[j, 1]
            )
            passable = not unknown
            for k in range(len(line)):
                c = _cost_at(cost, origin_x, origin_y, cell_m, line[k, 0], line[k, 1])
                if not (np.isfinite(c) and c <= worst + 1e-9):
                    passable = False
                    break
            if not passable:
                break
            best = j
        kept.append(best)
        i = best
    return np.array(kept)
