"""A route round the circles on a grid, for where the avoidance tree finds none.

The tangent-waypoint tree (§6.3.2) goes round one obstacle at a time and searches a
bounded depth; among the walls of a room (each a chain of circles along its medial line),
a route that leaves through a door and comes back round a corner needs more nested detours
than it searches. There the route is found on a grid instead: cells whose centre lies
within a circle's radius plus one cell are blocked (so a move between two free
neighbours never touches a circle), Dijkstra finds the shortest 8-connected route, and
the route is pulled taut: from each corner, the farthest cell still in sight is the next.
What comes out is a polyline whose every segment clears every circle.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import numpy.typing as npt

from footfall.biped.avoidance import Circle
from footfall.planning.route_kernels import dijkstra

CELL_M = 0.05  # [m]
MAX_CELLS = 800  # per axis; the cell grows for larger scenes
MARGIN_M = 1.0  # the grid reaches this far past the circles, the start and the goal [m]
_GRAZE = 1e-6


def _clear(a, b, centres: npt.NDArray, radii: npt.NDArray) -> bool:
    """Whether the segment ``ab`` passes through no circle."""
    ab = b - a
    t = np.clip((centres - a) @ ab / max(float(ab @ ab), 1e-18), 0.0, 1.0)
    nearest = a + t[:, None] * ab
    return bool(np.all(np.hypot(*(nearest - centres).T) >= radii - _GRAZE))


def grid_route(
    start: npt.ArrayLike, goal: npt.ArrayLike, obstacles: list[Circle]
) -> list[npt.NDArray[np.float64]] | None:
    """The shortest grid route from ``start`` to ``goal`` round the circles, pulled taut.

    Args:
        start: Shape (2,) [m], outside every circle.
        goal: Shape (2,) [m], outside every circle.
        obstacles: Inflated circles.

    Returns:
        The waypoints from start to goal, or None when the grid holds no route.
    """
    s, g = np.asarray(start, dtype=np.float64), np.asarray(goal, dtype=np.float64)
    centres = np.array([[c.x, c.y] for c in obstacles]).reshape(-1, 2)
    radii = np.array([c.r for c in obstacles])
    ends = np.vstack([s, g])
    lo = np.minimum(ends.min(axis=0), (centres - radii[:, None]).min(axis=0, initial=np.inf))
    hi = np.maximum(ends.max(axis=0), (centres + radii[:, None]).max(axis=0, initial=-np.inf))
    lo, hi = lo - MARGIN_M, hi + MARGIN_M
    cell = max(CELL_M, float(np.max(hi - lo)) / MAX_CELLS)
    shape = tuple(int(n) for n in np.ceil((hi - lo) / cell).astype(np.int64) + 1)
    x = lo[0] + np.arange(shape[0]) * cell
    y = lo[1] + np.arange(shape[1]) * cell
    cost = np.ones(shape)
    for (cx, cy), r in zip(centres, radii, strict=True):
        reach = r + cell
        i0, i1 = np.searchsorted(x, cx - reach), np.searchsorted(x, cx + reach, "right")
        j0, j1 = np.searchsorted(y, cy - reach), np.searchsorted(y, cy + reach, "right")
        near = (x[i0:i1, None] - cx) ** 2 + (y[None, j0:j1] - cy) ** 2 < reach**2
        cost[i0:i1, j0:j1][near] = np.inf
    si, sj = (int(v) for v in np.rint((s - lo) / cell))
    gi, gj = (int(v) for v in np.rint((g - lo) / cell))
    cost[si, sj] = cost[gi, gj] = 1.0  # the ends stand outside the circles themselves
    distance = np.empty(shape)
    parent = np.empty(shape, dtype=np.int64)
    dijkstra(cost, si, sj, cell, distance, parent)
    if not math.isfinite(distance[gi, gj]):
        return None
    cells = [gi * shape[1] + gj]
    while parent.flat[cells[-1]] >= 0:
        cells.append(int(parent.flat[cells[-1]]))
    flat = np.array(cells[::-1])[1:-1]  # the cells between the ends' own
    points = np.vstack([s, np.column_stack([x[flat // shape[1]], y[flat % shape[1]]]), g])
    route = [points[0]]
    anchor, k = 0, 1
    while k < len(points) - 1:  # pull taut: keep the last point in sight of the anchor
        if not _clear(points[anchor], points[k + 1], centres, radii):
            route.append(points[k])
            anchor = k
        k += 1
    route.append(points[-1])
    if not all(_clear(a, b, centres, radii) for a, b in itertools.pairwise(route)):
        return None  # an end too close to a circle for the grid's first move
    return route
