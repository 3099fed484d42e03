"""Mapping benchmark: depth frame -> points -> map update, and scoring a map.

Each figure is measured against a plain-NumPy baseline in the same run (the
:mod:`footfall.mapping.reference` and :mod:`footfall.scoring.reference` code), so the
ratios hold on any machine. The depth frame is synthetic and deterministic: a
640 x 480 camera 0.3 m above a floor scattered with boxes, looking ahead and down.
"""

from __future__ import annotations

import multiprocessing
import statistics
import time
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from typing import TypeVar

import numpy as np
import numpy.typing as npt
from scipy.spatial.transform import Rotation

from footfall.mapping.height_map import HeightMap, HeightMapConfig
from footfall.mapping.reference import integrate_depth_latest
from footfall.scoring.reference import score_grid_numpy
from footfall.scoring.walkability import ScoreConfig, score_heights
from footfall.sensing.camera import PinholeCamera
from footfall.sensing.pose import Pose

T = TypeVar("T")
R = TypeVar("R")


def median_ms(fn: Callable[[], object], repeats: int) -> float:
    """Median wall time of ``fn()`` over ``repeats`` calls, after one warm-up call [ms]."""
    fn()
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return 1e3 * statistics.median(times)


def synthetic_depth_frame(
    rng: np.random.Generator,
) -> tuple[npt.NDArray[np.float32], PinholeCamera, Pose]:
    """A D435i-like 640 x 480 depth frame of a floor with boxes, its intrinsics and pose."""
    camera = PinholeCamera.from_fov(np.radians(87.0), np.radians(58.0), 640, 480, max_range=5.0)
    pitch = np.radians(35.0)
    forward = np.array([np.cos(pitch), 0.0, -np.sin(pitch)])
    right = np.array([0.0, -1.0, 0.0])
    down = np.cross(forward, right)
    pose = Pose(
        np.array([0.0, 0.0, 0.3]), Rotation.from_matrix(np.stack([right, down, forward], axis=1))
    )
    u = np.arange(camera.width) - camera.cx
    v = np.arange(camera.height)[:, None] - camera.cy
    rays = np.stack(
        [u / camera.fx + 0 * v, v / camera.fy + 0 * u, np.ones((camera.height, camera.width))], -1
    )
    rays_world = rays @ pose.rotation.as_matrix().T
    depth = np.where(
        rays_world[..., 2] < 0, -pose.position[2] / np.minimum(rays_world[..., 2], -1e-9), 0.0
    )
    # Boxes: shorten the rays that hit their tops (enough for a realistic binning load).
    for _ in range(12):
        cx, cy, half, top = (
            rng.uniform(0.3, 2.0),
            rng.uniform(-0.8, 0.8),
            rng.uniform(0.05, 0.2),
            rng.uniform(0.02, 0.15),
        )
        t_top = (top - pose.position[2]) / np.minimum(rays_world[..., 2], -1e-9)
        hit = pose.position + t_top[..., None] * rays_world
        inside = (np.abs(hit[..., 0] - cx) < half) & (np.abs(hit[..., 1] - cy) < half) & (t_top > 0)
        depth = np.where(inside & (t_top < depth), t_top, depth)
    depth[depth > camera.max_range] = 0.0
    return depth.astype(np.float32), camera, pose


def run_mapping_benchmark(repeats: int = 30, seed: int = 0) -> dict[str, float]:
    """Time the map update and the scorer against their NumPy baselines.

    Returns:
        ``frame_ms`` (one 640 x 480 frame -> points -> map update, median), ``points_per_s``,
        ``score_ms`` (256 x 256 map, median), ``baseline_frame_ms``, ``baseline_score_ms``,
        and the speed-ups.
    """
    rng = np.random.default_rng(seed)
    depth, camera, pose = synthetic_depth_frame(rng)
    config = HeightMapConfig(size=256, resolution=0.02)
    height_map = HeightMap(config, centre=(1.0, 0.0))
    points = int(np.count_nonzero(depth))
    frame_ms = median_ms(lambda: height_map.integrate_depth(depth, camera, pose), repeats)
    heights = np.zeros((config.size, config.size))
    known = np.zeros((config.size, config.size), dtype=bool)
    origin = (int(height_map.origin[0]), int(height_map.origin[1]))
    baseline_frame_ms = median_ms(
        lambda: integrate_depth_latest(
            heights, known, origin, config.resolution, depth, camera, pose
        ),
        max(3, repeats // 5),
    )
    grid = height_map.snapshot().heights
    filled = np.where(np.isfinite(grid), grid, 0.0) + 0.002 * rng.standard_normal(grid.shape)
    score_config = ScoreConfig()
    score_ms = median_ms(lambda: score_heights(filled, config.resolution, score_config), repeats)
    baseline_score_ms = median_ms(
        lambda: score_grid_numpy(
            filled,
            config.resolution,
            score_config.kernel_1d,
            score_config.slope_weight,
            score_config.proximity_weight,
            score_config.threshold,
        ),
        max(3, repeats // 5),
    )
    return {
        "frame_ms": frame_ms,
        "points_per_frame": points,
        "points_per_s": points / (frame_ms * 1e-3),
        "score_ms": score_ms,
        "baseline_frame_ms": baseline_frame_ms,
        "baseline_points_per_s": points / (baseline_frame_ms * 1e-3),
        "baseline_score_ms": baseline_score_ms,
        "frame_speedup": baseline_frame_ms / frame_ms,
        "score_speedup": baseline_score_ms / score_ms,
        "map_cells": config.size**2,
    }


# The terrain sweep of `footfall bench terrain`: (terrain, swept parameter, values).
TERRAIN_SWEEP: tuple[tuple[str, str, tuple[float, ...]], ...] = (
    ("stairs", "rise", (0.02, 0.04, 0.06, 0.08)),
    ("cobblestones", "groove", (0.01, 0.03, 0.06)),
    ("course", "none", (0.0,)),
)


def _terrain_run(job: tuple[str, str, float, str, int, float]) -> dict[str, object]:
    """One walk of the sweep: ``(terrain, parameter, value, mode, seed, seconds)``."""
    from footfall.robot.spec import load_spec
    from footfall.sim.terrain import make_terrain
    from footfall.sim.walk import WalkSettings, simulate_walk

    name, difficulty, value, mode, seed, seconds = job
    params = {} if difficulty == "none" else {difficulty: value}
    settings = WalkSettings(
        terrain=name, seconds=seconds, blind=mode == "blind", seed=seed, stop_at_goal=True
    )
    terrain = make_terrain(name, seed, **params)
    m = simulate_walk(load_spec("default"), settings, terrain=terrain).metrics
    return {
        "success": bool(m["reached_goal"]) and not m["fell"] and m["invalid_footholds"] == 0,
        "fell": bool(m["fell"]),
        "invalid_footholds": int(m["invalid_footholds"]),
        "frozen": bool(m["frozen"]),
        "tilt_max_deg": float(m["tilt_max_deg"]),
        "wall_seconds": float(m["wall_seconds"]),
    }


def run_parallel(
    function: Callable[[T], R], jobs: Sequence[T], workers: int, on_done: Callable[[T], None]
) -> dict[T, R]:
    """``function`` of every job, in ``workers`` processes (in this one for a single worker).

    ``on_done`` is called with each job as it finishes (in completion order).
    """
    results: dict[T, R] = {}
    if workers <= 1:
        for job in jobs:
            results[job] = function(job)
            on_done(job)
        return results
    # Spawned, not forked: a fork of a process holding rendering contexts and thread pools
    # can deadlock.
    context = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(max_workers=workers, mp_context=context) as pool:
        futures = {pool.submit(function, job): job for job in jobs}
        for future in as_completed(futures):
            results[futures[future]] = future.result()
            on_done(futures[future])
    return results


def run_terrain_benchmark(
    seeds: int,
    seconds: float = 90.0,
    on_run: Callable[[str], None] | None = None,
    jobs: int = 1,
) -> dict[str, object]:
    """Planned and blind walking over the terrain sweep, ``seeds`` runs per configuration.

    Success = reached the goal, no fall, zero invalid footholds.

    Args:
        seeds: Runs per terrain, difficulty and mode.
        seconds: Longest walk [s].
        on_run: Called with a label after each run (progress display).
        jobs: Walks simulated at once, each in its own process.

    Returns:
        Per configuration: runs, successes, falls, invalid footholds, frozen runs, median
        tilt, wall time; overall ``planned_success_rate`` and ``blind_success_rate``.
    """
    configs = [
        (name, difficulty, value, mode)
        for name, difficulty, values in TERRAIN_SWEEP
        for value in values
        for mode in ("planned", "blind")
    ]
    work = [(*config, seed, seconds) for config in configs for seed in range(seeds)]

    def done(job: tuple) -> None:
        if on_run is not None:
            name, difficulty, value, mode, seed, _ = job
            on_run(f"{name} {difficulty}={value:g} {mode} seed {seed}")

    runs = run_parallel(_terrain_run, work, jobs, done)
    rows = []
    for config in configs:
        outcomes = [runs[(*config, seed, seconds)] for seed in range(seeds)]
        name, difficulty, value, mode = config
        rows.append(
            {
                "terrain": name,
                "difficulty": difficulty,
                "value": value,
                "mode": mode,
                "runs": len(outcomes),
                "successes": sum(bool(o["success"]) for o in outcomes),
                "falls": sum(bool(o["fell"]) for o in outcomes),
                "invalid_footholds": sum(int(o["invalid_footholds"]) for o in outcomes),
                "frozen": sum(bool(o["frozen"]) for o in outcomes),
                "median_tilt_max_deg": float(np.median([o["tilt_max_deg"] for o in outcomes])),
                "wall_seconds": float(sum(o["wall_seconds"] for o in outcomes)),
            }
        )

    def rate(mode: str) -> float:
        mine = [r for r in rows if r["mode"] == mode]
        return sum(r["successes"] for r in mine) / max(sum(r["runs"] for r in mine), 1)

    return {
        "seeds": seeds,
        "results": rows,
        "planned_success_rate": rate("planned"),
        "blind_success_rate": rate("blind"),
    }


def terrain_benchmark_runs(seeds: int) -> int:
    """How many walks :func:`run_terrain_benchmark` makes."""
    return 2 * seeds * sum(len(values) for _, _, values in TERRAIN_SWEEP)
