"""Circles that keep free floor free: split clusters shaped like an L or a U.

The dissertation's circles over a cluster's principal-axes box (eqs. 79-81) hug a person
or a box, but two walls joined at a corner, or a desk against a cupboard, are one
Euclidean cluster whose box spans the free floor between its arms, and a room whose walls
meet at the corners becomes one obstacle that fills the room. A cluster whose circles
cover more than a set share of floor seen free (floor points, no obstacle point above
them) inside its box, away from its points, is split in two by 2-means in the ground
plane (seeded at its two ends along its principal axis), and each part is looked at
again, until the circles cover what is there.
An L splits at its corner into two bars; a U into an L and a bar; a room into its walls.

Floor hidden behind an obstacle is not free: a box seen from its corner is an L of two
faces, but its inside holds no floor point, so it stays one box. A cloud with next to no
floor points off its obstacles (the ground cropped away) has no such evidence, and there
empty area counts.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
import numpy.typing as npt
from scipy.ndimage import distance_transform_edt

# Most cells of the free-floor grid per axis (the cell grows for very large scenes).
_MAX_CELLS = 1500


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

    def coverage(self, cluster, margin_m: float) -> tuple[float, float, float]:
        """How a cluster's circles cover the scene.

        Args:
            cluster: An ``ObstacleCluster`` (its circles and principal-axes box).
            margin_m: Floor nearer than this to an obstacle point is not counted as free
                inside the box [m].

        Returns:
            Shares of the circles' area that hold no obstacle point, that are free floor,
            and that are free floor inside the cluster's box farther than ``margin_m``
            from any obstacle point (what a tighter cover would leave free). Area outside
            the grid counts as unseen: neither empty nor free.
        """
        circles = cluster.circles
        if not circles:
            return 0.0, 0.0, 0.0
        nx, ny = self.occupied.shape
        x = np.array([c.x for c in circles])
        y = np.array([c.y for c in circles])
        r = np.array([c.r for c in circles])
        lo_x, lo_y = np.min(x - r), np.min(y - r)
        count_x = int(np.ceil((np.max(x + r) - lo_x) / self.cell_m)) + 1
        count_y = int(np.ceil((np.max(y + r) - lo_y) / self.cell_m)) + 1
        gx, gy = np.meshgrid(
            lo_x + (np.arange(count_x) + 0.5) * self.cell_m,
            lo_y + (np.arange(count_y) + 0.5) * self.cell_m,
            indexing="ij",
        )
        inside = np.zeros(gx.shape, dtype=bool)
        for k in range(len(circles)):
            inside |= (gx - x[k]) ** 2 + (gy - y[k]) ** 2 <= r[k] ** 2
        total = int(inside.sum())
        if total == 0:
            return 0.0, 0.0, 0.0
        px, py = gx[inside], gy[inside]
        gi = np.floor((px - self.origin_xy_m[0]) / self.cell_m).astype(np.int64)
        gj = np.floor((py - self.origin_xy_m[1]) / self.cell_m).astype(np.int64)
        seen = (gi >= 0) & (gi < nx) & (gj >= 0) & (gj < ny)
        gi, gj, px, py = gi[seen], gj[seen], px[seen], py[seen]
        empty = int(np.count_nonzero(~self.occupied[gi, gj]))
        free = self.free[gi, gj]
        cos, sin = np.cos(cluster.yaw), np.sin(cluster.yaw)
        du, dv = px - cluster.centre[0], py - cluster.centre[1]
        in_box = (np.abs(cos * du + sin * dv) <= 0.5 * cluster.width) & (
            np.abs(-sin * du + cos * dv) <= 0.5 * cluster.depth
        )
        avoidable = free & in_box & (self.clearance_m[gi, gj] > margin_m)
        n_free, n_avoidable = int(np.count_nonzero(free)), int(np.count_nonzero(avoidable))
        return empty / total, n_free / total, n_avoidable / total


def two_means(xy: npt.NDArray[np.float64], iterations: int = 10) -> npt.NDArray[np.bool_]:
    """2-means in the plane, seeded at the two ends along the principal axis.

    Returns:
        Which points belong to the first part, shape (n,).
    """
    centred = xy - xy.mean(axis=0)
    _, vectors = np.linalg.eigh(np.cov(centred.T))
    along = centred @ vectors[:, -1]
    centres = np.array([xy[np.argmin(along)], xy[np.argmax(along)]])
    first = along < 0.5 * (along.min() + along.max())
    for _ in range(iterations):
        d = ((xy[:, None, :] - centres[None]) ** 2).sum(axis=2)
        new = d[:, 0] <= d[:, 1]
        if new.all() or not new.any():
            break
        centres = np.array([xy[new].mean(axis=0), xy[~new].mean(axis=0)])
        if np.array_equal(new, first):
            break
        first = new
    return first


def split_cluster(
    points: npt.NDArray[np.float64],
    grid: FreeFloorGrid,
    describe,
    max_free_fraction: float,
    min_points: int,
    max_depth: int = 6,
):
    """A cluster, or its parts, whose circles cover at most ``max_free_fraction`` free floor.

    Args:
        points: The cluster's points in the map frame, shape (n, 3) [m].
        grid: Obstacle and floor cells of the whole scene.
        describe: ``points -> ObstacleCluster`` (centroid, box, circles).
        max_free_fraction: Largest share of free floor a cluster's circles may cover.
        min_points: Smallest part [points].
        max_depth: Most halvings.

    Returns:
        The parts, each with its ``empty_fraction`` and ``free_floor_fraction``.
    """
    cluster = describe(points)
    # Circles over a box reach past its sides (r = short / sqrt 2 around a square); free
    # floor inside the box, away from the points, is what a tighter cover would leave.
    empty, free, avoidable = grid.coverage(cluster, 2.0 * grid.cell_m)
    cluster = replace(cluster, empty_fraction=empty, free_floor_fraction=free)
    if avoidable <= max_free_fraction or max_depth == 0 or len(points) < 2 * min_points:
        return [cluster]
    first = two_means(points[:, :2])
    if first.sum() < min_points or (~first).sum() < min_points:
        return [cluster]
    return [
        *split_cluster(points[first], grid, describe, max_free_fraction, min_points, max_depth - 1),
        *split_cluster(
            points[~first], grid, describe, max_free_fraction, min_points, max_depth - 1
        ),
    ]
