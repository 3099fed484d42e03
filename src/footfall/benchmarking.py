"""Benchmarks: the mapping speed, and running walks in parallel.

Mapping: depth frame -> points -> map update, and scoring a map. Each figure is measured
against a plain-NumPy baseline in the same run (the :mod:`footfall.mapping.reference` and
:mod:`footfall.scoring.reference` code), so the ratios hold on any machine. The depth frame
is synthetic and deterministic: a 640 x 480 camera 0.3 m above a floor scattered with
boxes, looking ahead and down.

The walking benchmarks are in :mod:`footfall.reliability`.
"""

from __future__ import annotations

import statistics
import time
from collections.abc import Callable

import numpy as np
import numpy.typing as npt
from scipy.spatial.transform import Rotation

from footfall.mapping.engine import HeightMapConfig
from footfall.mapping.height_map import HeightMap
from footfall.mapping.reference import integrate_depth_latest
from footfall.scoring.reference import score_grid_numpy
from footfall.scoring.walkability import ScoreConfig, score_heights
from footfall.sensing.camera import PinholeCamera
from footfall.sensing.pose import Pose


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
