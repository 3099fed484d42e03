"""Time leg inverse kinematics and one control tick.

Reports the vectorised IK (6 legs x 1000 targets as one array) against a baseline measured
in the same run: the same IK called one leg pose at a time in a Python loop. Run with
``uv run python benchmarks/bench_kinematics.py``; it prints a table and writes
``benchmarks/results/kinematics.json``.
"""

from __future__ import annotations

import json
import statistics
import time
from pathlib import Path

import numpy as np

from footfall import GaitConfig, LegKinematics, WalkCommand, WalkController, load_spec

TARGETS = 1000
REPEATS = 30


def median_seconds(fn, repeats: int = REPEATS) -> float:
    """Median wall time of ``fn()`` over ``repeats`` calls [s]."""
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def main() -> dict[str, float]:
    spec = load_spec("default")
    kin = LegKinematics(spec)
    rng = np.random.default_rng(0)
    rest = kin.body_to_leg(spec.rest_feet_in_body())
    # 1000 target sets around the rest stance: +-4 cm horizontally, +-3 cm vertically.
    feet = rest[None] + rng.uniform([-0.04, -0.04, -0.03], [0.04, 0.04, 0.03], size=(TARGETS, 6, 3))
    kin.inverse(feet)  # all reachable (raises otherwise)

    vectorised = median_seconds(lambda: kin.inverse(feet))
    per_pose = median_seconds(lambda: [kin.inverse(f) for f in feet], repeats=5)

    controller = WalkController(spec, GaitConfig(kind="tripod"))
    command = WalkCommand(speed=0.1)
    ticks = [k * 0.01 for k in range(1000)]
    for t in ticks[:200]:
        controller.update(t, command)  # into steady walking
    tick_times = []
    for t in ticks[200:]:
        start = time.perf_counter()
        controller.update(t, command)
        tick_times.append(time.perf_counter() - start)

    results = {
        "ik_6x1000_vectorised_ms": 1e3 * vectorised,
        "ik_6x1000_per_pose_loop_ms": 1e3 * per_pose,
        "ik_speedup_over_loop": per_pose / vectorised,
        "ik_us_per_leg_target": 1e6 * vectorised / (6 * TARGETS),
        "control_tick_median_ms": 1e3 * statistics.median(tick_times),
        "control_tick_p99_ms": 1e3 * float(np.percentile(tick_times, 99)),
    }
    width = max(len(k) for k in results)
    for key, value in results.items():
        print(f"{key:<{width}}  {value:10.3f}")
    out = Path(__file__).parent / "results"
    out.mkdir(exist_ok=True)
    (out / "kinematics.json").write_text(json.dumps(results, indent=2) + "\n")
    return results


if __name__ == "__main__":
    main()
