"""Euclidean clustering and obstacle detection on real and large clouds: time and peak memory.

Compares the grid union-find clustering against the kd-tree neighbour-pair graph it
replaced (``cKDTree.query_pairs`` + connected components) on the same points, where the
old method fits in memory, and times the whole detection on the shared real clouds and on
a 2 M point synthetic scene. Each case runs in a fresh process, so its peak resident
memory is its own.

Run with ``uv run python benchmarks/bench_obstacles.py``; it prints a table and writes
``benchmarks/results/obstacles.json``. The shared clouds are read from ``../shared/data``
(or ``FOOTFALL_SHARED_DATA``) and skipped when absent.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SHARED = Path(os.environ.get("FOOTFALL_SHARED_DATA", ROOT.parent / "shared" / "data"))
CLOUDS = {
    "pcl_grabber": SHARED / "pointclouds/pcl_grabber/frame_20121214T142255.814212.pcd",
    "table_scene": SHARED / "pointclouds/pcl_table_scene/table_scene_mug_stereo_textured.pcd",
}

_CASE = r"""
import json, math, resource, sys, time
import numpy as np
source, method, limit, voxel = sys.argv[1], sys.argv[2], int(sys.argv[3]), float(sys.argv[4])
if source == "synthetic":
    rng = np.random.default_rng(0)
    n = limit
    floor = np.column_stack([rng.uniform(0, 8, n), rng.uniform(-4, 4, n), rng.normal(0, 0.005, n)])
    boxes = rng.uniform([0, -4, 0], [8, 4, 0.5], (n // 10, 3))
    points = np.vstack([floor[: n - n // 10], boxes])
    frame = "map"
else:
    from footfall.io.clouds import read_points
    points = read_points(source)
    frame = "camera"
    if limit and limit < len(points):
        points = points[np.random.default_rng(0).choice(len(points), limit, replace=False)]
from footfall.biped.obstacles import DetectionConfig, detect_obstacles
from footfall.pointcloud.filters import euclidean_clusters, voxel_downsample
if method != "detect" and voxel > 0:
    points = voxel_downsample(points, voxel)
if method == "detect":
    detect_obstacles(points[:1000], frame, DetectionConfig(voxel_size=voxel))  # compile
else:
    euclidean_clusters(points[:100], 0.3, 5)
before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
start = time.perf_counter()
if method == "detect":
    d = detect_obstacles(points, frame, DetectionConfig(voxel_size=voxel))
    clusters = [c.points for c in d.clusters]
elif method == "grid":
    clusters = [len(c) for c in euclidean_clusters(points, 0.3, 5)]
else:
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree
    pairs = cKDTree(points).query_pairs(0.3, output_type="ndarray")
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(len(points),) * 2)
    _, labels = connected_components(graph, directed=False)
    sizes = np.bincount(labels)
    clusters = sorted((int(s) for s in sizes if s >= 5), reverse=True)
seconds = time.perf_counter() - start
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
print(json.dumps({"points": len(points), "seconds": seconds, "peak_mb": peak / 1024,
                  "extra_mb": (peak - before) / 1024, "clusters": clusters[:20]}))
"""


def run_case(source: str, method: str, limit: int = 0, voxel: float = 0.02) -> dict:
    """One measurement in a fresh process (limited to 8 GB of address space)."""
    cmd = [sys.executable, "-c", _CASE, source, method, str(limit), str(voxel)]
    done = subprocess.run(
        ["prlimit", f"--as={8 << 30}", *cmd] if _has_prlimit() else cmd,
        capture_output=True,
        text=True,
        timeout=900,
    )
    if done.returncode != 0:
        return {"failed": done.stderr.strip().splitlines()[-1] if done.stderr else "killed"}
    return json.loads(done.stdout.strip().splitlines()[-1])


def _has_prlimit() -> bool:
    return subprocess.run(["which", "prlimit"], capture_output=True).returncode == 0


def main() -> dict:
    results: dict[str, dict] = {}
    for name, path in CLOUDS.items():
        if not path.exists():
            print(f"skipping {name}: {path} is absent")
            continue
        for limit in (20000, 60000):  # sizes where the pair graph still fits
            for method in ("kdtree_pairs", "grid"):
                results[f"{name}/{limit}/{method}"] = run_case(str(path), method, limit, 0.0)
        for method in ("kdtree_pairs", "grid"):  # the whole cloud after the voxel grid
            results[f"{name}/voxel_0.02/{method}"] = run_case(str(path), method, 0, 0.02)
        results[f"{name}/all/grid"] = run_case(str(path), "grid", 0, 0.0)
        results[f"{name}/all/detect"] = run_case(str(path), "detect")
    results["synthetic/2000000/grid"] = run_case("synthetic", "grid", 2_000_000, 0.0)
    results["synthetic/2000000/detect"] = run_case("synthetic", "detect", 2_000_000)
    results["synthetic/2000000/detect_no_voxel"] = run_case("synthetic", "detect", 2_000_000, 0.0)
    print(f"{'case':<36} {'points':>9} {'seconds':>9} {'peak MB':>9} {'extra MB':>9}  clusters")
    for key, r in results.items():
        if "failed" in r:
            print(f"{key:<36} failed: {r['failed']}")
            continue
        print(
            f"{key:<36} {r['points']:>9} {r['seconds']:>9.3f} {r['peak_mb']:>9.0f} "
            f"{r['extra_mb']:>9.0f}  {r['clusters'][:5]}"
        )
    out = ROOT / "benchmarks" / "results"
    out.mkdir(exist_ok=True)
    (out / "obstacles.json").write_text(json.dumps(results, indent=2) + "\n")
    return results


if __name__ == "__main__":
    main()
