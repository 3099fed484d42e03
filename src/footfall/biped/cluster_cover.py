"""Circles that keep free floor free: circles along an obstacle's medial line.

The dissertation's circles over a cluster's principal-axes box (eqs. 79-81) hug a person
or a box, but an elongated or bent obstacle (a wall, two walls joined at a corner, a
counter and a cupboard, a row of chairs) is one Euclidean cluster whose box spans the free
floor beside it, and a room whose walls meet at the corners becomes one obstacle that
fills the room; the dissertation names the weakness and proposes centres along the
obstacle's medial line (Huang et al., 2013) as future work.

Each cluster's footprint (the ground cells its points stand on, joined across a cell's
gap) is covered by circles along its medial line: the deepest cell of the footprint not
yet covered becomes a centre, its radius the footprint's half thickness there (at least
``min_radius``), until every cell is covered. The cluster keeps the dissertation's circles
where its assumptions hold, a compact obstacle: unless the medial line's circles cover
less floor seen free (floor points, no obstacle point above them) than the box's, by half
of it and at least ``min_gain_m2``. An L keeps the floor inside it, a U the floor between
its arms, a room its middle; every point of the cluster lies inside a circle.

Floor hidden behind an obstacle is not free: a box seen from its corner is an L of two
faces, but its inside holds no floor point, so it keeps its box's circle. A cloud with
next to no floor points off its obstacles (the ground cropped away) has no such evidence,
and there empty area counts.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
import numpy.typing as npt
from scipy.ndimage import binary_closing, distance_transform_edt, label

from footfall.biped.avoidance import Circle
from footfall.biped.maps import box_circles

# Most cells of the free-floor grid per axis (the cell grows for very large scenes).
_MAX_CELLS = 1500
# Most circles along one cluster's medial line: beyond, the smallest radius doubles.
MAX_CIRCLES = 400


@dataclass(frozen=True)
class ObstacleCluster:
    """One detected obstacle.

    Attributes:
        centroid: Mean of its points, shape (3,) [m].
        centre: Centre of its principal-axes box in the ground plane, shape (2,) [m].
        width: Box extent along the first principal axis [m].
        depth: Box extent along the second [m].
        height: Vertical extent [m].
        yaw: Heading of the first principal axis [rad].
        points: How many points it has.
        circles: Its circles (eqs. 79-81), not inflated.
        empty_fraction: Share of its circles' area that holds no obstacle point.
        free_floor_fraction: Share of its circles' area seen to be free floor.
        component: Index of its Euclidean cluster.
    """

    centroid: npt.NDArray[np.float64]
    centre: npt.NDArray[np.float64]
    width: float
    depth: float
    height: float
    yaw: float
    points: int
    circles: tuple[Circle, ...] = field(default=())
    empty_fraction: float = 0.0
    free_floor_fraction: float = 0.0
    component: int = 0


def describe_cluster(points: npt.NDArray[np.float64]) -> ObstacleCluster:
    """Centroid, principal-axes box in the ground plane and circles of one cluster."""
    centroid = points.mean(axis=0)
    xy = points[:, :2] - centroid[:2]
    if len(points) >= 2 and np.ptp(xy, axis=0).max() > 1e-9:
        _, vectors = np.linalg.eigh(np.cov(xy.T))
        axis = vectors[:, -1]  # the principal direction
    else:
        axis = np.array([1.0, 0.0])
    yaw = math.atan2(axis[1], axis[0])
    frame = np.array([axis, [-axis[1], axis[0]]])
    local = xy @ frame.T
    lo, hi = local.min(axis=0), local.max(axis=0)
    width, depth = max(float(hi[0] - lo[0]), 0.01), max(float(hi[1] - lo[1]), 0.01)
    centre = centroid[:2] + 0.5 * (lo + hi) @ frame
    height = float(np.ptp(points[:, 2]))
    circles = tuple(box_circles(centre, width, depth, yaw))
    return ObstacleCluster(centroid, centre, width, depth, height, yaw, len(points), circles)


@dataclass(frozen=True)
class FreeFloorGrid:
    """Which ground-plane cells hold obstacle points, and which show floor.

    Attributes:
        origin_xy_m: Map ``(x, y)`` of the corner of cell ``[0, 0]`` [m].
        cell_m: Cell side [m].
        occupied: Cells with an obstacle point above them, shape (nx, ny).
        free: Cells seen free (floor and no obstacle; without floor points: no obstacle).
        clearance_m: Distance from each cell to the nearest obstacle cell [m].
    """

    origin_xy_m: npt.NDArray[np.float64]
    cell_m: float
    occupied: npt.NDArray[np.bool_]
    free: npt.NDArray[np.bool_]
    clearance_m: npt.NDArray[np.float64]

    @classmethod
    def build(
        cls,
        obstacle_xy: npt.ArrayLike,
        floor_xy: npt.ArrayLike,
        cell_m: float = 0.05,
    ) -> FreeFloorGrid:
        """Rasterise obstacle and floor points (shapes (n, 2) and (m, 2) [m])."""
        obstacles = np.asarray(obstacle_xy, dtype=np.float64).reshape(-1, 2)
        floor = np.asarray(floor_xy, dtype=np.float64).reshape(-1, 2)
        both = np.vstack([obstacles, floor]) if len(floor) else obstacles
        lo = both.min(axis=0) - cell_m if len(both) else np.zeros(2)
        hi = both.max(axis=0) + cell_m if len(both) else np.ones(2)
        cell = max(cell_m, float(np.max(hi - lo)) / _MAX_CELLS)
        shape = tuple(int(v) for v in np.ceil((hi - lo) / cell).astype(int) + 1)

        def mark(xy: npt.NDArray[np.float64]) -> npt.NDArray[np.bool_]:
            grid = np.zeros(shape, dtype=bool)
            ij = np.floor((xy - lo) / cell).astype(np.int64)
            grid[ij[:, 0], ij[:, 1]] = True
            return grid

        occupied = mark(obstacles)
        free = mark(floor) & ~occupied if len(floor) else np.zeros(shape, dtype=bool)
        if free.sum() < 0.1 * occupied.sum():  # next to no floor seen: no evidence either way
            free = ~occupied
        clearance = distance_transform_edt(~occupied) * cell if occupied.any() else None
        if clearance is None:
            clearance = np.full(shape, np.inf)
        return cls(lo, cell, occupied, free, clearance)

    def coverage(self, circles: tuple[Circle, ...]) -> tuple[float, float, float]:
        """How circles cover the scene.

        Returns:
            Shares of the circles' area that hold no obstacle point and that are free
            floor, and the free floor's area [m^2]. Area outside the grid counts as
            unseen: neither empty nor free.
        """
        if not circles:
            return 0.0, 0.0, 0.0
        nx, ny = self.occupied.shape
        x = np.array([c.x for c in circles])
        y = np.array([c.y for c in circles])
        r = np.array([c.r for c in circles])
        lo = np.floor((np.array([np.min(x - r), np.min(y - r)]) - self.origin_xy_m) / self.cell_m)
        hi = np.ceil((np.array([np.max(x + r), np.max(y + r)]) - self.origin_xy_m) / self.cell_m)
        i = np.arange(int(lo[0]), int(hi[0]) + 1)
        j = np.arange(int(lo[1]), int(hi[1]) + 1)
        gx = self.origin_xy_m[0] + (i + 0.5) * self.cell_m
        gy = self.origin_xy_m[1] + (j + 0.5) * self.cell_m
        inside = np.zeros((len(i), len(j)), dtype=bool)
        for k in range(len(circles)):  # each circle marks only the cells of its square
            a = np.searchsorted(gx, x[k] - r[k]), np.searchsorted(gx, x[k] + r[k], "right")
            b = np.searchsorted(gy, y[k] - r[k]), np.searchsorted(gy, y[k] + r[k], "right")
            dx = (gx[a[0] : a[1], None] - x[k]) ** 2
            dy = (gy[None, b[0] : b[1]] - y[k]) ** 2
            inside[a[0] : a[1], b[0] : b[1]] |= dx + dy <= r[k] ** 2
        total = int(inside.sum())
        if total == 0:
            return 0.0, 0.0, 0.0
        ii, jj = np.nonzero(inside)
        gi, gj = i[ii], j[jj]
        seen = (gi >= 0) & (gi < nx) & (gj >= 0) & (gj < ny)
        gi, gj = gi[seen], gj[seen]
        empty = int(np.count_nonzero(~self.occupied[gi, gj]))
        free = int(np.count_nonzero(self.free[gi, gj]))
        return empty / total, free / total, free * self.cell_m**2


def medial_parts(
    points_xy: npt.NDArray[np.float64], grid: FreeFloorGrid, min_radius: float
) -> list[tuple[npt.NDArray[np.bool_], tuple[Circle, ...]]]:
    """Circles along the medial line of a cluster's footprint that cover all of it.

    Args:
        points_xy: The cluster's points in the ground plane, shape (n, 2) [m].
        grid: Obstacle and floor cells of the whole scene.
        min_radius: Smallest circle [m] (a thin wall's circles are this large).

    Returns:
        Per connected part of the footprint (cells joined across a cell's gap): which
        points stand on it, and the circles centred on it. Every point lies inside a
        circle.
    """
    h = grid.cell_m
    ij = np.floor((points_xy - grid.origin_xy_m) / h).astype(np.int64)
    lo = np.maximum(ij.min(axis=0) - 2, 0)
    hi = np.minimum(ij.max(axis=0) + 3, grid.occupied.shape)
    footprint = np.zeros(tuple(hi - lo), dtype=bool)
    footprint[ij[:, 0] - lo[0], ij[:, 1] - lo[1]] = True
    footprint |= binary_closing(footprint, structure=np.ones((3, 3), dtype=bool))
    labels, count = label(footprint, structure=np.ones((3, 3), dtype=bool))
    depth = distance_transform_edt(footprint) * h
    gi, gj = np.meshgrid(*(np.arange(n) for n in footprint.shape), indexing="ij")
    while True:
        cover = _greedy_cover(footprint, depth, gi, gj, min_radius, h)
        if len(cover) <= MAX_CIRCLES:
            break
        min_radius *= 2.0
    origin = grid.origin_xy_m + lo * h + 0.5 * h
    point_labels = labels[ij[:, 0] - lo[0], ij[:, 1] - lo[1]]
    circles: dict[int, list[Circle]] = {k: [] for k in range(1, count + 1)}
    for i, j, r in cover:
        circles[int(labels[i, j])].append(
            Circle(float(origin[0] + i * h), float(origin[1] + j * h), r)
        )
    return [(point_labels == k, tuple(circles[k])) for k in range(1, count + 1)]


def _greedy_cover(footprint, depth, gi, gj, min_radius: float, h: float) -> list:
    """Deepest uncovered cell first, until every footprint cell is inside a circle."""
    uncovered = footprint.copy()
    reach_cells = np.where(uncovered, depth, -1.0)
    circles = []
    corner = h / math.sqrt(2.0)  # a point lies this far from its cell's centre at most
    while uncovered.any():
        k = int(np.argmax(reach_cells))
        i, j = np.unravel_index(k, footprint.shape)
        reach = max(float(depth[i, j]), min_radius)
        n = math.ceil(reach / h)
        box = (slice(max(i - n, 0), i + n + 1), slice(max(j - n, 0), j + n + 1))
        close = (gi[box] - i) ** 2 + (gj[box] - j) ** 2 <= (reach / h) ** 2 + 1e-9
        uncovered[box] &= ~close
        reach_cells[box][close] = -1.0
        circles.append((int(i), int(j), reach + corner))
    return circles


def cover_cluster(
    points: npt.NDArray[np.float64],
    grid: FreeFloorGrid,
    describe,
    min_gain_m2: float,
    min_radius: float,
):
    """A cluster with the dissertation's circles, or its parts along their medial line.

    Args:
        points: The cluster's points in the map frame, shape (n, 3) [m].
        grid: Obstacle and floor cells of the whole scene.
        describe: ``points -> ObstacleCluster`` (centroid, box, circles).
        min_gain_m2: Least free floor [m^2] the medial line's circles must leave free
            beyond the box's (and at least half of what the box's cover) to replace them.
        min_radius: Smallest circle along a medial line [m].

    Returns:
        The cluster with the box's circles, or its parts (the footprint's connected parts)
        with the medial line's; each with the ``empty_fraction`` and
        ``free_floor_fraction`` of its circles.
    """
    cluster = describe(points)
    empty, free, box_m2 = grid.coverage(cluster.circles)
    parts = medial_parts(points[:, :2], grid, min_radius)
    _, _, medial_m2 = grid.coverage(tuple(c for _, circles in parts for c in circles))
    if not box_m2 - medial_m2 > max(min_gain_m2, 0.5 * box_m2):
        return [replace(cluster, empty_fraction=empty, free_floor_fraction=free)]
    out = []
    for mine, circles in parts:
        empty, free, _ = grid.coverage(circles)
        part = replace(describe(points[mine]), circles=circles)
        out.append(replace(part, empty_fraction=empty, free_floor_fraction=free))
    return out
