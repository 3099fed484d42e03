"""How the biped's obstacle circles keep free floor free on the shared real clouds.

For each cloud (no camera pose given, as a robot without one would see it), the detection
runs twice in the same process: with the dissertation's circles for every cluster (its
principal-axes box, eqs. 79-81; ``medial_min_gain_m2`` infinite) and with the default,
circles along the medial line where a box's would cover free floor. Reported per run: the
camera's height found, how many circles and the largest, the share of obstacle points of
every cluster inside a circle, the share of the open floor (floor points farther than
10 cm from any obstacle point) that no circle covers, the detection time and its peak
traced memory.

Run with ``uv run python benchmarks/bench_obstacle_cover.py``; it prints a table and
writes ``benchmarks/results/obstacle_cover.json``. The shared data is read from
``../shared/data`` (or ``FOOTFALL_SHARED_DATA``); clouds that are absent are skipped.
"""

from __future__ import annotations

import json
import math
import os
import time
import tracemalloc
from pathlib import Path

import numpy as np
from PIL import Image
from scipy.spatial import cKDTree

from footfall.biped.obstacles import DetectionConfig, detect_obstacles
from footfall.io.clouds import read_points
from footfall.pointcloud.filters import euclidean_clusters

ROOT = Path(__file__).resolve().parents[1]
SHARED = Path(os.environ.get("FOOTFALL_SHARED_DATA", ROOT.parent / "shared" / "data"))
# Depth frames: path, depth units per metre, fx, fy, cx, cy.
DEPTH = {
    "tum_frame": ("rgbd/tum_frame/TUM_depth.png", 5000.0, 525.0, 525.0, 319.5, 239.5),
    "tum_fr1_xyz_0": (
        "rgbd/tum_fr1_xyz/depth/1305031102.160407.png",
        5000.0,
        517.3,
        516.5,
        318.6,
        255.3,
    ),
    "redwood_0": ("rgbd/redwood_livingroom/depth/00000.png", 1000.0, 525.0, 525.0, 319.5, 239.5),
    "redwood_4": ("rgbd/redwood_livingroom/depth/00004.png", 1000.0, 525.0, 525.0, 319.5, 239.5),
}
CLOUDS = {
    "pcl_grabber": "pointclouds/pcl_grabber/frame_20121214T142255.814212.pcd",
    "pcl_table_scene": "pointclouds/pcl_table_scene/table_scene_mug_stereo_textured.pcd",
}
OPEN_FLOOR_M = 0.1


def depth_cloud(relative: str, scale: float, fx: float, fy: float, cx: float, cy: float):
    """A depth image's points in the optical camera frame [m]."""
    depth = np.asarray(Image.open(SHARED / relative), dtype=np.float64) / scale
    v, u = np.nonzero(depth > 0)
    z = depth[v, u]
    return np.column_stack([(u - cx) * z / fx, (v - cy) * z / fy, z])


def inside(circles, xy) -> np.ndarray:
    """Which points lie in a circle."""
    if not circles or len(xy) == 0:
        return np.zeros(len(xy), dtype=bool)
    c = np.array([(q.x, q.y) for q in circles])
    r = np.array([q.r for q in circles])
    hit = np.zeros(len(xy), dtype=bool)
    for k in range(0, len(c), 64):
        d = ((xy[:, None, :] - c[None, k : k + 64]) ** 2).sum(axis=2)
        hit |= (d <= r[None, k : k + 64] ** 2 + 1e-12).any(axis=1)
    return hit


def measure(points, config: DetectionConfig) -> dict[str, object]:
    """One detection and what its circles cover."""
    tracemalloc.start()
    started = time.perf_counter()
    detection = detect_obstacles(points, "camera", config)
    ms = 1000.0 * (time.perf_counter() - started)
    peak_mb = tracemalloc.get_traced_memory()[1] / 1e6
    tracemalloc.stop()
    p = detection.points_in_map
    obstacle = p[detection.obstacle_mask]
    members = euclidean_clusters(obstacle, config.cluster_tolerance, config.min_cluster_size)
    clustered = obstacle[np.concatenate(members)][:, :2] if members else np.empty((0, 2))
    floor = p[np.abs(detection.ground.heights(p)) <= 0.02][:, :2]
    if len(obstacle) and len(floor):
        open_floor = floor[cKDTree(obstacle[:, :2]).query(floor)[0] > OPEN_FLOOR_M]
    else:
        open_floor = floor
    circles = detection.circles
    return {
        "camera_height_m": detection.camera.height_m,
        "ground_fraction": detection.ground.inlier_fraction,
        "obstacles": len(detection.clusters),
        "circles": len(circles),
        "largest_circle_m": max((c.r for c in circles), default=0.0),
        "obstacle_points_covered": float(inside(circles, clustered).mean())
        if len(clustered)
        else 1.0,
        "open_floor_kept_free": (
            1.0 - float(inside(circles, open_floor).mean()) if len(open_floor) else math.nan
        ),
        "detect_ms": ms,
        "peak_traced_mb": peak_mb,
    }


def main() -> None:
    sources = {name: lambda a=args: depth_cloud(*a) for name, args in DEPTH.items()}
    sources |= {name: lambda r=rel: read_points(SHARED / r) for name, rel in CLOUDS.items()}
    detect_obstacles(np.random.default_rng(0).uniform(0.5, 3, (2000, 3)) * [1, 0.3, 1], "map")
    results = {}
    header = f"{'cloud':16s} {'cover':10s} {'height':>7s} {'circles':>7s} {'largest':>8s}"
    header += f" {'covered':>8s} {'floor kept':>10s} {'ms':>6s} {'MB':>5s}"
    print(header)
    for name, load in sources.items():
        relative = DEPTH[name][0] if name in DEPTH else CLOUDS[name]
        if not (SHARED / relative).exists():
            print(f"{name:16s} skipped: {relative} is absent")
            continue
        points = load()
        runs = {
            "dissertation": measure(points, DetectionConfig(medial_min_gain_m2=math.inf)),
            "medial": measure(points, DetectionConfig()),
        }
        results[name] = runs
        for cover, r in runs.items():
            print(
                f"{name:16s} {cover:10s} {r['camera_height_m']:6.2f}m {r['circles']:7d} "
                f"{r['largest_circle_m']:7.2f}m {r['obstacle_points_covered']:8.1%} "
                f"{r['open_floor_kept_free']:10.1%} {r['detect_ms']:6.0f} "
                f"{r['peak_traced_mb']:5.0f}"
            )
    out = ROOT / "benchmarks" / "results" / "obstacle_cover.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(results, indent=2))
    print(f"wrote {out.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
