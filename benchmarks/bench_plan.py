"""Time the biped planner and compare its paths with the exact shortest paths.

Over the dissertation's 11 maps and random maps of 5 to 30 obstacles: planning time, and
path length over the optimum computed in the same run by the visibility-graph oracle. A
random map where the oracle finds a path and the planner does not counts as a failure.
Run with ``uv run python benchmarks/bench_plan.py``; writes ``benchmarks/results/plan.json``.
"""

from __future__ import annotations

import json
import statistics
import time
from pathlib import Path

import numpy as np

from footfall.biped.avoidance import Circle, plan_path
from footfall.biped.maps import TEST_CASES, dissertation_map
from footfall.biped.oracle import shortest_path_length
from footfall.errors import PlanningError

RANDOM_MAPS = 200


def main() -> dict[str, object]:
    case_ms, case_ratio = [], []
    for n in TEST_CASES:
        m = dissertation_map(n)
        t0 = time.perf_counter()
        path = plan_path(m.start, m.goal, m.inflated)
        case_ms.append(1e3 * (time.perf_counter() - t0))
        case_ratio.append(path.length / shortest_path_length(m.start, m.goal, m.inflated))
    rng = np.random.default_rng(0)
    random_ms, ratios, failures, unsolvable = [], [], 0, 0
    for _ in range(RANDOM_MAPS):
        count = int(rng.integers(5, 31))
        obstacles = [
            Circle(*rng.uniform([0.5, -2.5], [5.5, 2.5]), float(rng.uniform(0.15, 0.45)))
            for _ in range(count)
        ]
        start, goal = np.array([0.0, 0.0]), np.array([6.0, float(rng.uniform(-2, 2))])
        if any(np.hypot(*(p - c.centre)) < c.r for c in obstacles for p in (start, goal)):
            continue
        try:
            optimum = shortest_path_length(start, goal, obstacles)
        except PlanningError:
            unsolvable += 1
            continue
        t0 = time.perf_counter()
        try:
            path = plan_path(start, goal, obstacles, max_depth=12)
        except PlanningError:
            failures += 1
            continue
        random_ms.append(1e3 * (time.perf_counter() - t0))
        ratios.append(path.length / optimum)
    r = np.array(ratios)
    results = {
        "cases_plan_ms_median": statistics.median(case_ms),
        "cases_plan_ms_max": max(case_ms),
        "cases_length_over_optimum_max": max(case_ratio),
        "random_maps": len(ratios) + failures,
        "random_unsolvable_maps": unsolvable,
        "random_failures": failures,
        "random_plan_ms_median": statistics.median(random_ms),
        "random_plan_ms_p95": float(np.percentile(random_ms, 95)),
        "random_length_over_optimum_median": float(np.median(r)),
        "random_length_over_optimum_p95": float(np.percentile(r, 95)),
        "random_length_over_optimum_max": float(r.max()),
    }
    width = max(len(k) for k in results)
    for key, value in results.items():
        print(
            f"{key:<{width}}  {value:10.4f}"
            if isinstance(value, float)
            else f"{key:<{width}}  {value:10d}"
        )
    out = Path(__file__).parent / "results"
    out.mkdir(exist_ok=True)
    (out / "plan.json").write_text(json.dumps(results, indent=2) + "\n")
    return results


if __name__ == "__main__":
    main()
