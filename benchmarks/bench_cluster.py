"""What a Ray cluster costs a terrain sweep: walks per minute here and on a 2-CPU cluster.

The same sweep (planned walks on the stairs and the course) runs with ``--jobs 2`` (two
processes on this machine) and on a Ray cluster of two nodes with one CPU each, started on
this machine (:func:`footfall.reliability.cluster.local_cluster`), in the same run. Ray's
overhead per walk is the extra CPU time it takes over the process pool, shared over the
walks; its round trip alone is timed with tasks that do nothing but carry a walk's job and
result. Both sweeps must give the same ``bench.json`` outside wall times.

Run with ``uv run python benchmarks/bench_cluster.py [--seeds N] [--seconds S]``; it prints
the figures and writes ``benchmarks/results/cluster.json``.
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from pathlib import Path

from footfall.reliability.cluster import RayCluster, local_cluster
from footfall.reliability.terrain_bench import run_terrain_benchmark, terrain_benchmark_runs

TERRAINS = ("stairs", "course")
CPUS = 2


def _echo(job: tuple) -> dict[str, object]:
    """A task that does no walking: what Ray costs a walk's job and result alone."""
    return {"success": True, "job": job, "figures": [0.0] * 16}


def _sweep(seeds: int, seconds: float, **where: object) -> tuple[float, dict]:
    start = time.perf_counter()
    bench = run_terrain_benchmark(seeds, seconds, terrains=TERRAINS, modes=("planned",), **where)
    return time.perf_counter() - start, bench


def _without_wall_times(bench: object) -> object:
    if isinstance(bench, dict):
        return {
            k: _without_wall_times(v)
            for k, v in bench.items()
            if "wall" not in k and not k.startswith("replan_ms")
        }
    if isinstance(bench, list):
        return [_without_wall_times(v) for v in bench]
    return bench


def main() -> dict[str, float]:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=2)
    parser.add_argument("--seconds", type=float, default=20.0)
    args = parser.parse_args()
    walks = terrain_benchmark_runs(args.seeds, TERRAINS, ("planned",))
    local_s, local = _sweep(args.seeds, args.seconds, jobs=CPUS)
    start = time.perf_counter()
    with local_cluster(nodes=CPUS, cpus_per_node=1) as address:
        cluster_start_s = time.perf_counter() - start
        cluster_s, on_cluster = _sweep(args.seeds, args.seconds, cluster=address)
        with RayCluster(address) as cluster:
            jobs = [
                ("default", "tripod", "stairs", "rise", 0.04, "planned", k, 20.0)
                for k in range(200)
            ]
            cluster.run(_echo, jobs[:20], lambda job: None)  # the workers start
            one_by_one = []
            for job in jobs[20:60]:
                t = time.perf_counter()
                cluster.run(_echo, [job], lambda job: None)
                one_by_one.append(time.perf_counter() - t)
            t = time.perf_counter()
            cluster.run(_echo, jobs, lambda job: None)
            batch_s = time.perf_counter() - t
    same = json.dumps(_without_wall_times(local), sort_keys=True) == json.dumps(
        _without_wall_times(on_cluster), sort_keys=True
    )
    results = {
        "walks": walks,
        "seeds": args.seeds,
        "seconds": args.seconds,
        "local_jobs2_s": local_s,
        "cluster_2cpu_s": cluster_s,
        "local_walks_per_min": 60.0 * walks / local_s,
        "cluster_walks_per_min": 60.0 * walks / cluster_s,
        "cluster_over_local": cluster_s / local_s,
        "ray_overhead_per_walk_s": CPUS * (cluster_s - local_s) / walks,
        "ray_round_trip_ms": 1e3 * statistics.median(one_by_one),
        "ray_batch_ms_per_task": 1e3 * batch_s / len(jobs),
        "cluster_start_s": cluster_start_s,
        "same_bench_json": same,
    }
    for key, value in results.items():
        print(f"{key:<26} {value:10.3f}" if isinstance(value, float) else f"{key:<26} {value}")
    out = Path(__file__).parent / "results"
    out.mkdir(exist_ok=True)
    (out / "cluster.json").write_text(json.dumps(results, indent=2) + "\n")
    return results


if __name__ == "__main__":
    main()
