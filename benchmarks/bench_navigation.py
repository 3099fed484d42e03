"""Time one replan of the hexapod's route planner on a 256 x 256 map.

A replan is the cost grid from a map update plus the route search and string pulling
(:mod:`footfall.planning.traversability`, :mod:`footfall.planning.navigation`). The map is a
seeded obstacle field (blocks 30 cm tall covering a fifth of a 2.4 m square, the rest
flat, a strip not yet seen), scored by the real scorer. The search is set against a
baseline measured in the same run: SciPy's Dijkstra over the same 8-connected graph
(``scipy.sparse.csgraph``, the graph built outside the timing). Run with
``uv run python benchmarks/bench_navigation.py``; it prints the figures and writes
``benchmarks/results/navigation.json``.
"""

from __future__ import annotations

import json
import statistics
import time
from pathlib import Path

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra as scipy_dijkstra

from footfall import load_spec
from footfall.messages import MapUpdate
from footfall.planning.navigation import NavigationConfig, plan_route
from footfall.planning.route_kernels import dijkstra
from footfall.planning.traversability import TraversabilityConfig, cost_grid, span_radius
from footfall.scoring.walkability import score_heights

SIZE = 256
RES = 0.02
REPEATS = 40


def obstacle_map(seed: int = 0) -> MapUpdate:
    """A 256 x 256 map update of a seeded obstacle field in front of the robot."""
    rng = np.random.default_rng(seed)
    origin = (-SIZE * RES / 2, -SIZE * RES / 2)
    xs = origin[0] + (np.arange(SIZE) + 0.5) * RES
    x, y = np.meshgrid(xs, xs, indexing="ij")
    h = np.zeros((SIZE, SIZE))
    covered = 0.0
    while covered < 0.2 * 2.4 * 2.4:
        sx, sy = rng.uniform(0.15, 0.4, 2)
        cx, cy = rng.uniform(0.6, 2.2), rng.uniform(-1.2, 1.2)
        h[(np.abs(x - cx) <= sx / 2) & (np.abs(y - cy) <= sy / 2)] = 0.3
        covered += sx * sy
    h[x > 2.4] = np.nan  # not yet seen
    slope, proximity, score, valid = score_heights(h, RES)
    return MapUpdate(0.0, 1, h, np.isfinite(h), None, slope, proximity, score, valid, origin, RES)


def percentile(values: list[float], q: float) -> float:
    """The ``q`` percentile of ``values``."""
    return float(np.percentile(values, q))


def scipy_graph(cost: np.ndarray):
    """The 8-connected move graph of a cost grid, as SciPy's Dijkstra takes it."""
    n, m = cost.shape
    index = np.arange(n * m).reshape(n, m)
    rows, cols, weights = [], [], []
    for di, dj in ((1, 0), (0, 1), (1, 1), (1, -1)):
        j0, j1 = max(0, -dj), m - max(0, dj)
        a = index[0 : n - di, j0:j1].ravel()
        b = index[di:n, j0 + dj : j1 + dj].ravel()
        w = np.hypot(di, dj) * RES * 0.5 * (cost.flat[a] + cost.flat[b])
        ok = np.isfinite(w)
        for p, q in ((a[ok], b[ok]), (b[ok], a[ok])):
            rows.append(p)
            cols.append(q)
            weights.append(w[ok])
    return coo_matrix(
        (np.concatenate(weights), (np.concatenate(rows), np.concatenate(cols))), (n * m, n * m)
    ).tocsr()


def main() -> dict[str, float]:
    """Time the replan and its parts; the search against SciPy's."""
    spec = load_spec("default")
    span = span_radius(spec)
    update = obstacle_map()
    config = NavigationConfig().for_robot(spec)
    start, goal = (0.0, 0.0), (4.0, 0.3)
    grid = cost_grid(update, TraversabilityConfig(), span)
    plan_route(grid, start, goal, config)  # compile
    grid_s, plan_s, search_s, baseline_s = [], [], [], []
    distance = np.empty(grid.shape)
    parent = np.empty(grid.shape, dtype=np.int64)
    si, sj = grid.cell_of(start)
    graph = scipy_graph(grid.cost)
    for _ in range(REPEATS):
        t0 = time.perf_counter()
        grid = cost_grid(update, TraversabilityConfig(), span)
        t1 = time.perf_counter()
        plan_route(grid, start, goal, config)
        t2 = time.perf_counter()
        dijkstra(grid.cost, si, sj, RES, distance, parent)
        t3 = time.perf_counter()
        expected = scipy_dijkstra(graph, indices=si * SIZE + sj)
        t4 = time.perf_counter()
        grid_s.append(t1 - t0)
        plan_s.append(t2 - t1)
        search_s.append(t3 - t2)
        baseline_s.append(t4 - t3)
    np.testing.assert_allclose(distance.ravel(), expected, rtol=1e-9)
    replan = [a + b for a, b in zip(grid_s, plan_s, strict=True)]
    figures = {
        "map_cells": SIZE * SIZE,
        "replan_ms_median": 1e3 * statistics.median(replan),
        "replan_ms_p95": 1e3 * percentile(replan, 95),
        "cost_grid_ms_median": 1e3 * statistics.median(grid_s),
        "route_ms_median": 1e3 * statistics.median(plan_s),
        "search_ms_median": 1e3 * statistics.median(search_s),
        "scipy_search_ms_median": 1e3 * statistics.median(baseline_s),
        "search_speedup_vs_scipy": statistics.median(baseline_s) / statistics.median(search_s),
    }
    out = Path(__file__).parent / "results" / "navigation.json"
    out.parent.mkdir(exist_ok=True)
    out.write_text(json.dumps(figures, indent=2))
    for key, value in figures.items():
        print(f"{key:28s} {value:10.3f}")
    return figures


if __name__ == "__main__":
    main()
