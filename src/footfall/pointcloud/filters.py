"""Point-cloud filters whose memory grows with the points, never with their neighbour pairs.

- :func:`voxel_downsample`: PCL's voxel grid. Points in one cubic voxel become their
  centroid: a real 640 x 480 frame of 300 k points shrinks to a few ten thousand, with the
  same shapes, and a surface counts by its area rather than by how near the camera was.
- :func:`euclidean_clusters`: Euclidean cluster extraction (dissertation §6.3.1): points
  linked by chains of neighbours at most ``tolerance`` apart form a cluster. Points are
  bucketed in cubic cells of side ``tolerance / sqrt(3)``; every point in a cell is within
  the tolerance of every other, so a cell joins as a whole, and two cells up to two apart
  join at the first pair of points close enough, skipped once they are already one
  cluster (the grid method of exact DBSCAN). The result is the kd-tree's
  ``query_pairs`` graph's connected components, without ever listing the pairs.
- :func:`inverted_cone_points`: Manduchi's obstacle test (dissertation eqs. 71-72) over
  a grid of columns sorted by height, so each point looks only at points a compatible
  height above or below it.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import numpy.typing as npt
from numba import njit

from footfall.errors import ConfigError, DatasetError

# Cells per axis of a packed grid key: 2^20 cells of 1 cm are 10 km, far beyond a sensor.
_AXIS_BITS = 20


def _cell_keys(
    points: npt.NDArray[np.float64], side: float
) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.int64]]:
    """Packed integer keys of the cubic cells points fall in, and the grid's dimensions.

    Raises:
        DatasetError: Points spread over more cells than a key can hold.
    """
    cells = np.floor((points - points.min(axis=0)) / side).astype(np.int64)
    dims = cells.max(axis=0) + 1
    if np.any(dims >= 1 << _AXIS_BITS):
        raise DatasetError(
            f"the cloud spans {np.ptp(points, axis=0).max():.0f} m: too large for "
            f"{side:g} m cells (more than {1 << _AXIS_BITS} per axis)"
        )
    keys = (cells[:, 0] * dims[1] + cells[:, 1]) * dims[2] + cells[:, 2]
    return keys, dims


def voxel_downsample(points: npt.ArrayLike, voxel_size_m: float) -> npt.NDArray[np.float64]:
    """The centroid of the points in each occupied voxel (PCL's ``VoxelGrid``).

    Args:
        points: Shape (n, 3) [m], finite.
        voxel_size_m: Voxel side [m]; 0 keeps the points as they are.

    Returns:
        Shape (m, 3) [m], m <= n, in the order of the voxels' keys.
    """
    p = np.asarray(points, dtype=np.float64)
    if voxel_size_m < 0 or not math.isfinite(voxel_size_m):
        raise ConfigError(f"voxel size must be >= 0, got {voxel_size_m}")
    if voxel_size_m == 0 or len(p) == 0:
        return p.copy()
    keys, _ = _cell_keys(p, voxel_size_m)
    _, inverse, counts = np.unique(keys, return_inverse=True, return_counts=True)
    sums = np.column_stack(
        [np.bincount(inverse, weights=p[:, k], minlength=len(counts)) for k in range(3)]
    )
    return sums / counts[:, None]


@njit(cache=True)
def _find(parent, i):
    while parent[i] != i:
        parent[i] = parent[parent[i]]  # path halving
        i = parent[i]
    return i


@njit(cache=True)
def _union(parent, size, a, b):
    ra, rb = _find(parent, a), _find(parent, b)
    if ra == rb:
        return
    if size[ra] < size[rb]:
        ra, rb = rb, ra
    parent[rb] = ra
    size[ra] += size[rb]


@njit(cache=True)
def _grid_components(points, cell_keys, starts, dims, tolerance, parent):
    """Union-find over a sorted point array whose cells begin at ``starts``."""
    n_cells = cell_keys.shape[0]
    size = np.ones(parent.shape[0], dtype=np.int64)
    tol2 = tolerance * tolerance
    for c in range(n_cells):  # a cell is one cluster: its diagonal is the tolerance
        for i in range(starts[c] + 1, starts[c + 1]):
            _union(parent, size, starts[c], i)
    plane = dims[1] * dims[2]
    for c in range(n_cells):
        key = cell_keys[c]
        cx = key // plane
        cy = (key // dims[2]) % dims[1]
        cz = key % dims[2]
        for dx in range(0, 3):
            for dy in range(-2, 3):
                for dz in range(-2, 3):
                    # Half the neighbourhood: each pair of cells is looked at once.
                    if dx == 0 and (dy < 0 or (dy == 0 and dz <= 0)):
                        continue
                    gap = max(dx - 1, 0) ** 2 + max(abs(dy) - 1, 0) ** 2
                    gap += max(abs(dz) - 1, 0) ** 2
                    if gap > 3:  # cells farther apart than the tolerance everywhere
                        continue
                    nx, ny, nz = cx + dx, cy + dy, cz + dz
                    if nx >= dims[0] or ny < 0 or ny >= dims[1] or nz < 0 or nz >= dims[2]:
                        continue
                    other = np.searchsorted(cell_keys, (nx * dims[1] + ny) * dims[2] + nz)
                    if other >= n_cells or cell_keys[other] != (nx * dims[1] + ny) * dims[2] + nz:
                        continue
                    if _find(parent, starts[c]) == _find(parent, starts[other]):
                        continue
                    joined = False
                    for i in range(starts[c], starts[c + 1]):
                        for j in range(starts[other], starts[other + 1]):
                            d0 = points[i, 0] - points[j, 0]
                            d1 = points[i, 1] - points[j, 1]
                            d2 = points[i, 2] - points[j, 2]
                            if d0 * d0 + d1 * d1 + d2 * d2 <= tol2:
                                _union(parent, size, i, j)
                                joined = True
                                break
                        if joined:
                            break


def cluster_labels(points: npt.ArrayLike, tolerance: float) -> npt.NDArray[np.int64]:
    """The connected component of each point at ``tolerance`` (labels 0, 1, ...).

    Args:
        points: Shape (n, 3) [m], finite.
        tolerance: Largest link between neighbours [m].
    """
    p = np.asarray(points, dtype=np.float64)
    if not tolerance > 0:
        raise ConfigError(f"cluster tolerance must be positive, got {tolerance}")
    if len(p) == 0:
        return np.zeros(0, dtype=np.int64)
    keys, dims = _cell_keys(p, tolerance / math.sqrt(3.0))
    order = np.argsort(keys, kind="stable")
    sorted_keys = keys[order]
    first = np.flatnonzero(np.r_[True, sorted_keys[1:] != sorted_keys[:-1]])
    starts = np.r_[first, len(p)].astype(np.int64)
    parent = np.arange(len(p), dtype=np.int64)
    _grid_components(
        np.ascontiguousarray(p[order]), sorted_keys[first], starts, dims, tolerance, parent
    )
    _, labels_sorted = np.unique(_all_roots(parent), return_inverse=True)
    labels = np.empty(len(p), dtype=np.int64)
    labels[order] = labels_sorted
    return labels


@njit(cache=True)
def _all_roots(parent):
    out = np.empty(parent.shape[0], dtype=np.int64)
    for i in range(parent.shape[0]):
        out[i] = _find(parent, i)
    return out


def euclidean_clusters(
    points: npt.ArrayLike, tolerance: float, min_size: int
) -> list[npt.NDArray[np.int64]]:
    """Euclidean cluster extraction: indices of each cluster, largest first.

    Points linked by chains of neighbours at most ``tolerance`` apart form a cluster;
    clusters smaller than ``min_size`` go. Memory is linear in the number of points.
    """
    labels = cluster_labels(points, tolerance)
    if len(labels) == 0:
        return []
    order = np.argsort(labels, kind="stable")
    bounds = np.flatnonzero(np.r_[True, np.diff(labels[order]) != 0, True])
    clusters = [order[a:b] for a, b in itertools.pairwise(bounds)]
    return sorted((c for c in clusters if len(c) >= min_size), key=len, reverse=True)


@njit(cache=True)
def _cone_marks(points, column_of, starts, columns, dims, reach_cells, h_min, h_max, sin_max):
    n = points.shape[0]
    mark = np.zeros(n, dtype=np.bool_)
    n_columns = columns.shape[0]
    for i in range(n):
        cx = column_of[i] // dims[1]
        cy = column_of[i] % dims[1]
        zi = points[i, 2]
        found = False
        for ring in range(reach_cells + 1):  # nearest columns first
            if found:
                break
            for k in range((2 * ring + 1) * (2 * ring + 1)):
                dx, dy = k // (2 * ring + 1) - ring, k % (2 * ring + 1) - ring
                if max(abs(dx), abs(dy)) != ring:
                    continue
                nx, ny = cx + dx, cy + dy
                if nx < 0 or ny < 0 or nx >= dims[0] or ny >= dims[1]:
                    continue
                key = nx * dims[1] + ny
                c = np.searchsorted(columns, key)
                if c >= n_columns or columns[c] != key:
                    continue
                zs = points[starts[c] : starts[c + 1], 2]
                # Points a compatible height above, then below: z sorted in each column.
                for lo_z, hi_z in ((zi + h_min, zi + h_max), (zi - h_max, zi - h_min)):
                    a = starts[c] + np.searchsorted(zs, lo_z, side="right")
                    b = starts[c] + np.searchsorted(zs, hi_z, side="left")
                    for j in range(a, b):
                        d0 = points[j, 0] - points[i, 0]
                        d1 = points[j, 1] - points[i, 1]
                        dz = abs(points[j, 2] - zi)
                        if dz > sin_max * math.sqrt(d0 * d0 + d1 * d1 + dz * dz):
                            found = True
                            break
                    if found:
                        break
                if found:
                    break
        mark[i] = found
    return mark


def inverted_cone_points(
    points_in_map: npt.ArrayLike, min_height_m: float, max_height_m: float, max_slope_rad: float
) -> npt.NDArray[np.bool_]:
    """Points on an obstacle by Manduchi's test (dissertation eqs. 71-72).

    A point is an obstacle point when another lies in its upward or downward cone:
    ``H_min < |dz| < H_max`` and ``|dz| / |dp| > sin(theta_max)``.

    Args:
        points_in_map: Shape (n, 3) [m], z up.
        min_height_m: ``H_min`` [m].
        max_height_m: ``H_max`` [m].
        max_slope_rad: ``theta_max`` [rad].
    """
    p = np.asarray(points_in_map, dtype=np.float64)
    if len(p) == 0:
        return np.zeros(0, dtype=bool)
    if not (0 <= min_height_m < max_height_m and 0 < max_slope_rad < math.pi / 2):
        raise ConfigError("cones need 0 <= H_min < H_max and 0 < theta_max < 90 degrees")
    # A compatible point lies within |dz| * cot(theta_max) horizontally, |dz| < H_max.
    reach = min(max_height_m, float(np.ptp(p[:, 2]))) / math.tan(max_slope_rad)
    side = max(reach / 4.0, 1e-3)
    xy = np.floor((p[:, :2] - p[:, :2].min(axis=0)) / side).astype(np.int64)
    dims = xy.max(axis=0) + 1
    column = xy[:, 0] * dims[1] + xy[:, 1]
    order = np.lexsort((p[:, 2], column))
    sorted_column = column[order]
    first = np.flatnonzero(np.r_[True, sorted_column[1:] != sorted_column[:-1]])
    starts = np.r_[first, len(p)].astype(np.int64)
    marks = _cone_marks(
        np.ascontiguousarray(p[order]),
        sorted_column,
        starts,
        sorted_column[first],
        dims,
        math.ceil(reach / side),
        min_height_m,
        max_height_m,
        math.sin(max_slope_rad),
    )
    out = np.empty(len(p), dtype=bool)
    out[order] = marks
    return out
