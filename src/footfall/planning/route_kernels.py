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
