"""Obstacle avoidance around circles with tangent waypoints (dissertation §6.3.2).

Obstacles are circles, already inflated by half the robot's hip width. When the straight
line from the current point to the goal crosses an obstacle, two avoidance waypoints are
built where the tangents to the circle from the point meet the tangents from the goal,
one on each side (eqs. 82-88, here in vector form: lines as point plus direction, so no
slope is ever infinite). Each waypoint grows a branch of a binary tree; the tree is
searched recursively (the path to a waypoint and from it are planned the same way), a
waypoint that falls inside another obstacle is moved round that obstacle (on the same
side; this walks along a chain of overlapping circles) or pruned, and the shortest complete
branch wins. Where no branch of the bounded tree arrives (a route out of a room and back
round its walls), a grid route round the circles is taken (:mod:`footfall.biped.grid_route`).

The obstacle avoided first is the blocking one met first along the segment (the
dissertation picks by distance to the segment, eqs. 89-92; the first one met is the one
the robot reaches first). The dissertation notes a clearly sub-optimal detour (its
Fig. 93): a waypoint that the path can skip, because the points before and after it see
each other, is dropped ("string pulling"), which removes such detours.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from footfall.errors import PlanningError

# A path may graze an inflated circle by this much [m] (tangent segments touch it).
_GRAZE = 1e-6
# Waypoints are built on circles this much larger, so the path clears by a hair.
_WAYPOINT_MARGIN = 1e-4


@dataclass(frozen=True)
class Circle:
    """A circular obstacle (already inflated), centre ``(x, y)`` and radius ``r`` [m]."""

    x: float
    y: float
    r: float

    @property
    def centre(self) -> npt.NDArray[np.float64]:
        """Shape (2,) [m]."""
        return np.array([self.x, self.y])


def segment_distance(a: npt.ArrayLike, b: npt.ArrayLike, point: npt.ArrayLike) -> float:
    """Distance from a point to the segment ``ab`` [m] (eqs. 89-92)."""
    a, b, p = (np.asarray(v, dtype=np.float64) for v in (a, b, point))
    ab = b - a
    length_sq = float(ab @ ab)
    t = 0.0 if length_sq == 0.0 else float(np.clip((p - a) @ ab / length_sq, 0.0, 1.0))
    return float(np.linalg.norm(a + t * ab - p))


def blocking(a: npt.ArrayLike, b: npt.ArrayLike, obstacles: list[Circle]) -> list[Circle]:
    """Obstacles the segment ``ab`` passes through, in the order the segment meets them."""
    if not obstacles:
        return []
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    centres = np.array([[c.x, c.y] for c in obstacles])
    radii = np.array([c.r for c in obstacles])
    ab = b - a
    length_sq = max(float(ab @ ab), 1e-18)
    t = (centres - a) @ ab / length_sq
    nearest = a + np.clip(t, 0.0, 1.0)[:, None] * ab
    hit = np.hypot(*(nearest - centres).T) < radii - _GRAZE
    order = np.argsort(t[hit], kind="stable")
    indices = np.flatnonzero(hit)[order]
    return [obstacles[i] for i in indices]


def tangent_points(point: npt.ArrayLike, circle: Circle) -> tuple[npt.NDArray, npt.NDArray] | None:
    """The two points where lines from ``point`` touch the circle (eqs. 82-85).

    None when the point is inside the circle.
    """
    p = np.asarray(point, dtype=np.float64)
    d = p - circle.centre
    dist = float(np.hypot(*d))
    if dist <= circle.r:
        return None
    base = math.atan2(d[1], d[0])
    half = math.acos(circle.r / dist)
    return tuple(
        circle.centre + circle.r * np.array([math.cos(base + s * half), math.sin(base + s * half)])
        for s in (1, -1)
    )  # type: ignore[return-value]


def _intersect(
    p: npt.NDArray, u: npt.NDArray, q: npt.NDArray, v: npt.NDArray
) -> npt.NDArray | None:
    """Intersection of lines ``p + s u`` and ``q + t v``; None if (nearly) parallel."""
    det = u[0] * (-v[1]) - u[1] * (-v[0])
    if abs(det) < 1e-12:
        return None
    rhs = q - p
    s = (rhs[0] * (-v[1]) - rhs[1] * (-v[0])) / det
    return p + s * u


def avoidance_waypoints(
    start: npt.ArrayLike, goal: npt.ArrayLike, circle: Circle
) -> dict[int, npt.NDArray]:
    """The avoidance waypoints on either side of a circle between ``start`` and ``goal``.

    Each is where a tangent from the start meets a tangent from the goal (eqs. 86-88).

    Returns:
        The waypoint left (+1) and right (-1) of the line from start to goal, where they
        exist.
    """
    s, g = np.asarray(start, dtype=np.float64), np.asarray(goal, dtype=np.float64)
    grown = Circle(circle.x, circle.y, circle.r + _WAYPOINT_MARGIN)
    from_start, from_goal = tangent_points(s, grown), tangent_points(g, grown)
    if from_start is None or from_goal is None:
        return {}
    direction = g - s

    def side(point: npt.NDArray) -> int:
        return int(np.sign(direction[0] * (point[1] - s[1]) - direction[1] * (point[0] - s[0])))

    points: dict[int, npt.NDArray] = {}
    for ts in from_start:
        for tg in from_goal:
            if side(ts) == side(tg) != 0:
                w = _intersect(s, ts - s, g, tg - g)
                if w is not None:
                    points[side(ts)] = w
    return points


@dataclass(frozen=True)
class AvoidancePath:
    """A planned path.

    Attributes:
        waypoints: From start to goal, shape (k, 2) [m].
        length: Path length [m].
        tree_nodes: Waypoints the search built (its size).
    """

    waypoints: npt.NDArray[np.float64]
    length: float
    tree_nodes: int


def _length(points: list[npt.NDArray]) -> float:
    return float(sum(np.linalg.norm(b - a) for a, b in itertools.pairwise(points)))


def _shortcut(points: list[npt.NDArray], obstacles: list[Circle]) -> list[npt.NDArray]:
    """Drop every waypoint the path can skip (the points around it see each other)."""
    out = [points[0]]
    i = 0
    while i < len(points) - 1:
        j = len(points) - 1
        while j > i + 1 and blocking(points[i], points[j], obstacles):
            j -= 1
        out.append(points[j])
        i = j
    return out


def plan_path(
    start: npt.ArrayLike, goal: npt.ArrayLike, obstacles: list[Circle], max_depth: int = 8
) -> AvoidancePath:
    """The shortest tangent-waypoint path from ``start`` to ``goal`` around the circles.

    Args:
        start: Shape (2,) [m].
        goal: Shape (2,) [m].
        obstacles: Inflated obstacle circles.
        max_depth: Deepest nesting of avoidance waypoints searched.

    Returns:
        The path, shortcut where waypoints see each other.

    Raises:
        PlanningError: The start or goal lies in an obstacle, or no branch reaches the goal.
    """
    s, g = np.asarray(start, dtype=np.float64), np.asarray(goal, dtype=np.float64)
    for name, p in (("start", s), ("goal", g)):
        for c in obstacles:
            if np.hypot(*(p - c.centre)) < c.r - _GRAZE:
                raise PlanningError(
                    f"the {name} ({p[0]:.2f}, {p[1]:.2f}) lies inside the obstacle at "
                    f"({c.x:.2f}, {c.y:.2f}) of radius {c.r:.2f} m (inflated by half the hip width)"
                )
    nodes = 0

    def containing(p: npt.NDArray) -> Circle | None:
        return next((c for c in obstacles if np.hypot(*(p - c.centre)) < c.r - _GRAZE), None)

    def _waypoint_on_side(
        a: npt.NDArray, b: npt.NDArray, circle: Circle, side: int
    ) -> npt.NDArray | None:
        """The waypoint on one side of the first blocking circle.

        When it falls inside another obstacle (circles that overlap, like the chain of an
        elongated obstacle), go round that one instead.
        """
        for _ in range(len(obstacles)):
            w = avoidance_waypoints(a, b, circle).get(side)
            if w is None:
                return None
            other = containing(w)
            if other is None:
                return w
            circle = other
        return None

    # Sub-path searched between two points, with the depth it was searched from: a
    # failure found deeper (with less depth left) does not rule out a shallower search.
    memo: dict[tuple, tuple[list[npt.NDArray] | None, int]] = {}

    def search(a: npt.NDArray, b: npt.NDArray, depth: int) -> list[npt.NDArray] | None:
        key = (round(a[0], 9), round(a[1], 9), round(b[0], 9), round(b[1], 9))
        if key in memo:
            found, searched_at = memo[key]
            if found is not None or searched_at <= depth:
                return found
        found = expand(a, b, depth)
        memo[key] = (found, depth)
        return found

    def expand(a: npt.NDArray, b: npt.NDArray, depth: int) -> list[npt.NDArray] | None:
        nonlocal nodes
        hits = blocking(a, b, obstacles)
        if not hits:
            return [a, b]
        if depth >= max_depth:
            return None
        best: list[npt.NDArray] | None = None
        candidates = []
        for side in (1, -1):
            w = _waypoint_on_side(a, b, hits[0], side)
            nodes += 1
            if w is not None:  # else pruned: no free waypoint on this side
                candidates.append((float(np.linalg.norm(w - a) + np.linalg.norm(b - w)), w))
        for bound, w in sorted(candidates, key=lambda item: item[0]):
            if best is not None and bound >= _length(best):
                continue  # cannot beat the best branch: the straight detour is a lower bound
            first = search(a, w, depth + 1)
            if first is None:
                continue
            second = search(w, b, depth + 1)
            if second is None:
                continue
            candidate = first + second[1:]
            if best is None or _length(candidate) < _length(best):
                best = candidate
        return best

    path = search(s, g, 0)
    if path is None:  # too many nested detours for the tree (the walls of a room)
        from footfall.biped.grid_route import grid_route

        path = grid_route(s, g, obstacles)
    if path is None:
        raise PlanningError(
            f"no path from ({s[0]:.2f}, {s[1]:.2f}) to ({g[0]:.2f}, {g[1]:.2f}): every branch of "
            "the avoidance tree ends in an obstacle"
        )
    path = _shortcut(path, obstacles)
    return AvoidancePath(np.array(path), _length(path), nodes)
