"""Benchmarks: the mapping speed, and walking over the terrain sweep.

Mapping: depth frame -> points -> map update, and scoring a map. Each figure is measured
against a plain-NumPy baseline in the same run (the :mod:`footfall.mapping.reference` and
:mod:`footfall.scoring.reference` code), so the ratios hold on any machine. The depth frame
is synthetic and deterministic: a 640 x 480 camera 0.3 m above a floor scattered with
boxes, looking ahead and down.

Terrain sweep: every terrain over its difficulty range, walked planned (with route
planning), straight (the same loop on the straight line, the thesis' behaviour) and blind.
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

from footfall.errors import ConfigError
from footfall.mapping.engine import HeightMapConfig
from footfall.mapping.height_map import HeightMap
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


# The modes: the full loop with route planning, the same on the straight line (the
# thesis' behaviour), and the blind baseline.
TERRAIN_MODES = ("planned", "straight", "blind")


def terrain_sweep(
    terrains: Sequence[str] | None = None,
) -> tuple[tuple[str, str, tuple[float, ...]], ...]:
    """What ``footfall bench terrain`` walks: ``(terrain, swept parameter, values)``.

    Every registered terrain that is benchmarked (or the named ones), in registration
    order; a terrain without a difficulty parameter is walked once, as ``("none", (0.0,))``.

    Raises:
        ConfigError: On a name the sweep does not hold.
    """
    from footfall.sim.terrains import TERRAINS

    sweep = []
    for name in TERRAINS:
        kind = TERRAINS.get(name)
        if kind.benchmarked:
            if kind.difficulty is not None and kind.sweep:
                sweep.append((name, kind.difficulty, tuple(kind.sweep)))
            else:
                sweep.append((name, "none", (0.0,)))
    if terrains is None:
        return tuple(sweep)
    known = {name for name, _, _ in sweep}
    unknown = [t for t in terrains if t not in known]
    if unknown:
        raise ConfigError(
            f"no terrain {', '.join(map(repr, unknown))} in the sweep; choose from "
            f"{', '.join(name for name, _, _ in sweep)}"
        )
    return tuple(entry for entry in sweep if entry[0] in terrains)


def terrain_modes(modes: Sequence[str] | None = None) -> tuple[str, ...]:
    """The named modes (all by default), in ``TERRAIN_MODES``' order.

    Raises:
        ConfigError: On a mode that is not one of them.
    """
    if modes is None:
        return TERRAIN_MODES
    unknown = [m for m in modes if m not in TERRAIN_MODES]
    if unknown or not modes:
        raise ConfigError(
            f"no mode {', '.join(map(repr, unknown)) or 'given'}; choose from "
            f"{', '.join(TERRAIN_MODES)}"
        )
    return tuple(m for m in TERRAIN_MODES if m in modes)


def _terrain_run(job: tuple[str, str, float, str, int, float]) -> dict[str, object]:
    """One walk of the sweep: ``(terrain, parameter, value, mode, seed, seconds)``."""
    from footfall.robot.spec import load_spec
    from footfall.sim.terrains import TERRAINS, make_terrain
    from footfall.sim.walk import simulate_walk
    from footfall.sim.walk_metrics import WalkMetrics
    from footfall.sim.walk_settings import WalkSettings

    name, difficulty, value, mode, seed, seconds = job
    params = {} if difficulty == "none" else {difficulty: value}
    settings = WalkSettings(
        terrain=name,
        seconds=seconds,
        blind=mode == "blind",
        straight=mode == "straight",
        seed=seed,
        stop_at_goal=True,
    )
    terrain = make_terrain(name, seed, **params)
    m = simulate_walk(load_spec("default"), settings, terrain=terrain).metrics
    assert isinstance(m, WalkMetrics)  # a simulated walk always walks
    invalid = m.footholds.invalid_footholds or 0
    safe = not m.fell and invalid == 0
    navigation = m.navigation
    no_route = navigation is not None and navigation.no_route
    if not TERRAINS.get(name).has_route:
        # Standing still with the reason: the navigator's "no route", or a freeze that
        # says why (the thesis' robot at a wall).
        success = safe and not m.reached_goal and (no_route or m.outcome.frozen)
    else:
        success = safe and m.reached_goal
    reason = (navigation.no_route_reason if navigation is not None else "") or (
        m.outcome.frozen_reason
    )

    def replan_ms(value: float | None) -> float:
        return float("nan") if value is None else float(value)

    return {
        "success": success,
        "fell": m.fell,
        "invalid_footholds": invalid,
        "frozen": m.outcome.frozen,
        "no_route": no_route,
        "reason": reason,
        "tilt_max_deg": m.gait.tilt_max_deg,
        "sim_seconds": m.gait.sim_seconds,
        "wall_seconds": m.gait.wall_seconds,
        "replan_ms_median": replan_ms(navigation and navigation.replan_ms_median),
        "replan_ms_p95": replan_ms(navigation and navigation.replan_ms_p95),
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
    seconds: float = 150.0,
    on_run: Callable[[str], None] | None = None,
    jobs: int = 1,
    terrains: Sequence[str] | None = None,
    first_seed: int = 0,
    modes: Sequence[str] | None = None,
) -> dict[str, object]:
    """The terrain sweep in every mode (or ``modes``), ``seeds`` runs per configuration.

    Success = reached the goal, no fall, zero invalid footholds; on a terrain without a
    route (``Terrain.has_route`` False): stood still and said why, no fall, zero invalid.

    Args:
        seeds: Runs per terrain, difficulty and mode.
        seconds: Longest walk [s].
        on_run: Called with a label after each run (progress display).
        jobs: Walks simulated at once, each in its own process.
        terrains: Terrains of the sweep to walk (all by default).
        first_seed: The seeds run from this one up.
        modes: Modes to walk (all of ``TERRAIN_MODES`` by default); a mode not walked has
            no success rate.

    Returns:
        Per configuration (``results``): runs, successes, falls, invalid footholds, frozen
        runs, runs without a route, median tilt, the reasons given, wall time; overall
        ``planned_success_rate``, ``straight_success_rate`` and ``blind_success_rate``;
        and the route planner's replan times over the planned runs.
    """
    sweep = terrain_sweep(terrains)
    chosen = terrain_modes(modes)
    configs = [
        (name, difficulty, value, mode)
        for name, difficulty, values in sweep
        for value in values
        for mode in chosen
    ]
    seed_range = range(first_seed, first_seed + seeds)
    work = [(*config, seed, seconds) for config in configs for seed in seed_range]

    def done(job: tuple) -> None:
        if on_run is not None:
            name, difficulty, value, mode, seed, _ = job
            on_run(f"{name} {difficulty}={value:g} {mode} seed {seed}")

    runs = run_parallel(_terrain_run, work, jobs, done)
    rows = []
    for config in configs:
        outcomes = [runs[(*config, seed, seconds)] for seed in seed_range]
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
                "no_route": sum(bool(o["no_route"]) for o in outcomes),
                "median_tilt_max_deg": float(np.median([o["tilt_max_deg"] for o in outcomes]))
                if outcomes
                else float("nan"),
                "reasons": sorted({str(o["reason"]) for o in outcomes if o["reason"]}),
                "wall_seconds": float(sum(o["wall_seconds"] for o in outcomes)),
            }
        )

    def rate(mode: str) -> float:
        mine = [r for r in rows if r["mode"] == mode]
        runs_of_mode = sum(r["runs"] for r in mine)
        if not runs_of_mode:
            return float("nan")
        return sum(r["successes"] for r in mine) / runs_of_mode

    planned = [runs[job] for job in work if job[3] == "planned"]
    medians = [o["replan_ms_median"] for o in planned if np.isfinite(o["replan_ms_median"])]
    p95s = [o["replan_ms_p95"] for o in planned if np.isfinite(o["replan_ms_p95"])]
    return {
        "seeds": seeds,
        "first_seed": first_seed,
        "terrains": [name for name, _, _ in sweep],
        "modes": list(chosen),
        "results": rows,
        "planned_success_rate": rate("planned"),
        "straight_success_rate": rate("straight"),
        "blind_success_rate": rate("blind"),
        "replan_ms_median": float(np.median(medians)) if medians else float("nan"),
        "replan_ms_p95_max": float(np.max(p95s)) if p95s else float("nan"),
    }


def terrain_benchmark_runs(
    seeds: int, terrains: Sequence[str] | None = None, modes: Sequence[str] | None = None
) -> int:
    """How many walks :func:`run_terrain_benchmark` makes."""
    sweep = terrain_sweep(terrains)
    return len(terrain_modes(modes)) * seeds * sum(len(values) for _, _, values in sweep)
