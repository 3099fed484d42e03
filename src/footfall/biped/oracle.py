"""Exact shortest path among circular obstacles: a visibility graph of tangents and arcs.

The oracle the tests and the benchmark measure the avoidance planner against. A shortest
path around disjoint or overlapping circles is made of straight segments tangent to the
circles and arcs along them, so the graph has: segments from the start and the goal
tangent to each circle, the common tangents of every pair of circles (two outer, two
inner), and the arcs of each circle between its tangent points. Segments crossing a
circle and arcs running inside another circle are left out; Dijkstra finds the shortest.
"""

from __future__ import annotations

import heapq
import math

import numpy as np
import numpy.typing as npt

from footfall.biped.avoidance import Circle, blocking, tangent_points
from footfall.errors import PlanningError

_ON_CIRCLE = 1e-7


def _common_tangents(a: Circle, b: Circle) -> list[tuple[npt.NDArray, npt.NDArray]]:
    """Tangent segments touching both circles: (point on a, point on b)."""
    d = b.centre - a.centre
    dist = float(np.hypot(*d))
    out = []
    if dist < 1e-12:
        return out
    base = math.atan2(d[1], d[0])
    for sign_r in (1.0, -1.0):  # outer (same side) and inner (crossing) tangents
        r_diff = a.r - sign_r * b.r
        if abs(r_diff) > dist:
            continue
        angle = math.acos(r_diff / dist)
        for side in (1.0, -1.0):
            phi = base + side * angle
            normal = np.array([math.cos(phi), math.sin(phi)])
            out.append((a.centre + a.r * normal, b.centre + sign_r * b.r * normal))
    return out


def shortest_path_length(
    start: npt.ArrayLike, goal: npt.ArrayLike, obstacles: list[Circle]
) -> float:
    """Length of the shortest collision-free path [m] (touching circles allowed).

    Raises:
        PlanningError: When no path exists.
    """
    s, g = np.asarray(start, dtype=np.float64), np.asarray(goal, dtype=np.float64)
    points: list[npt.NDArray] = [s, g]
    on_circle: dict[int, list[tuple[float, int]]] = {i: [] for i in range(len(obstacles))}
    edges: dict[int, list[tuple[int, float]]] = {0: [], 1: []}

    def add_point(p: npt.NDArray, circle: int | None) -> int:
        points.append(p)
        k = len(points) - 1
        edges[k] = []
        if circle is not None:
            c = obstacles[circle]
            on_circle[circle].append((math.atan2(p[1] - c.y, p[0] - c.x), k))
        return k

    def free(a: npt.NDArray, b: npt.NDArray) -> bool:
        return not blocking(a, b, obstacles)

    def link(i: int, j: int) -> None:
        w = float(np.linalg.norm(points[i] - points[j]))
        edges[i].append((j, w))
        edges[j].append((i, w))

    if free(s, g):
        return float(np.linalg.norm(g - s))
    for end in (0, 1):
        for ci, c in enumerate(obstacles):
            touching = tangent_points(points[end], c)
            if touching is None:
                continue
            for t in touching:
                if free(points[end], t):
                    link(end, add_point(t, ci))
    for i, a in enumerate(obstacles):
        for j in range(i + 1, len(obstacles)):
            for pa, pb in _common_tangents(a, obstacles[j]):
                if free(pa, pb):
                    ka, kb = add_point(pa, i), add_point(pb, j)
                    link(ka, kb)
    for ci, c in enumerate(obstacles):
        around = sorted(on_circle[ci])
        for (a0, k0), (a1, k1) in zip(around, around[1:] + around[:1], strict=True):
            sweep = (a1 - a0) % (2 * math.pi)
            if len(around) == 1:
                continue
            samples = a0 + np.linspace(0.0, sweep, 12)[1:-1]
            arc = c.centre + c.r * np.stack([np.cos(samples), np.sin(samples)], axis=1)
            inside_other = any(
                np.any(np.hypot(*(arc - o.centre).T) < o.r - _ON_CIRCLE)
                for oi, o in enumerate(obstacles)
                if oi != ci
            )
            if not inside_other:
                w = c.r * sweep
                edges[k0].append((k1, w))
                edges[k1].append((k0, w))
    best = {0: 0.0}
    queue = [(0.0, 0)]
    while queue:
        d, k = heapq.heappop(queue)
        if k == 1:
            return d
        if d > best.get(k, math.inf):
            continue
        for j, w in edges[k]:
            nd = d + w
            if nd < best.get(j, math.inf):
                best[j] = nd
                heapq.heappush(queue, (nd, j))
    raise PlanningError("no collision-free path exists between start and goal")
