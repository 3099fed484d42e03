"""What footfall's own nodes cost an on-board computer, per second walked.

Walks the README's main job (stairs) and an obstacle field with navigation, each in its
own process (after a short unmeasured walk of each, so no walk counts the compiling of the
numba kernels), and reads each walk's ``metrics.json``: per node, CPU seconds on its thread
per second walked (share of one core) and the median and 95th percentile latency of an
update; the sum of footfall's own nodes (mapping, navigation, movement, servo, pose guard:
every name that does not start with ``sim``, the simulator's rendering, physics, true pose,
task and record); and the real-time factor. With ``--against REV`` the same walks run on
that revision too (a git worktree, in the same run on the same machine) and the table gives
the ratios; a revision older than the per-node meter reports its real-time factor only.

Run with ``uv run python benchmarks/bench_onboard.py [--against REV]``; it writes
``benchmarks/results/onboard.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
WALKS = {
    "main job (stairs)": ["walk"],
    "obstacle field": ["walk", "--terrain", "obstacle_field"],
}


def walk(source: Path, args: list[str], out: Path) -> dict:
    """One walk run from ``source``'s tree; its metrics."""
    env = {**os.environ, "PYTHONPATH": str(source / "src"), "MUJOCO_GL": "egl"}
    command = [sys.executable, "-m", "footfall", *args, "--out", str(out)]
    subprocess.run(command, cwd=source, env=env, check=True, capture_output=True)
    return json.loads((out / "metrics.json").read_text())


def summary(metrics: dict) -> dict:
    """The figures compared: per-node shares and latencies, the own sum, the RTF."""
    nodes = metrics.get("nodes", {})
    return {
        "reached_goal": metrics["reached_goal"],
        "sim_seconds": metrics["sim_seconds"],
        "realtime_factor": metrics["sim_seconds"] / metrics["wall_seconds"],
        "own_share": metrics.get("cpu_own_share"),
        "nodes": {
            name: {
                "share": n["cpu_share"],
                "median_ms": n["latency_median_ms"],
                "p95_ms": n["latency_p95_ms"],
            }
            for name, n in nodes.items()
        },
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--against", help="a git revision to compare with, in the same run")
    args = parser.parse_args()
    results: dict[str, dict] = {}
    with tempfile.TemporaryDirectory() as tmp:
        trees = {"this tree": ROOT}
        if args.against:
            base = Path(tmp) / "against"
            subprocess.run(
                ["git", "worktree", "add", "--detach", str(base), args.against],
                cwd=ROOT, check=True, capture_output=True,
            )  # fmt: skip
            trees[args.against] = base
        try:
            # A tree's first walk compiles its numba kernels (cached per source tree) and
            # would count that as its nodes' CPU: every tree walks once unmeasured first.
            for source in trees.values():
                for walk_args in WALKS.values():
                    walk(source, [*walk_args, "--seconds", "8"], Path(tmp) / "warm-up")
            for name, walk_args in WALKS.items():
                results[name] = {}
                for tree, source in trees.items():
                    out = Path(tmp) / f"{tree}-{name}".replace(" ", "_")
                    results[name][tree] = summary(walk(source, walk_args, out))
        finally:
            if args.against:
                subprocess.run(
                    ["git", "worktree", "remove", "--force", str(trees[args.against])],
                    cwd=ROOT, check=False, capture_output=True,
                )  # fmt: skip
    for name, runs in results.items():
        print(f"\n{name}")
        mine = runs["this tree"]
        for node, n in mine["nodes"].items():
            line = f"  {node:12s} {100 * n['share']:6.2f} % of a core"
            line += f"  update median {n['median_ms']:7.3f} ms  p95 {n['p95_ms']:7.3f} ms"
            if args.against and node in runs[args.against]["nodes"]:
                old = runs[args.against]["nodes"][node]["share"]
                line += f"  ({n['share'] / old:.2f}x of {args.against})" if old > 0 else ""
            print(line)
        print(
            f"  footfall's own nodes: {100 * mine['own_share']:.2f} % of a core per second walked"
        )
        print(
            f"  real-time factor {mine['realtime_factor']:.2f}, reached goal {mine['reached_goal']}"
        )
        if args.against:
            old = runs[args.against]
            ratio = mine["realtime_factor"] / old["realtime_factor"]
            print(f"  {args.against}: real-time factor {old['realtime_factor']:.2f} ({ratio:.2f}x)")
            if old["own_share"]:
                print(f"  own nodes {mine['own_share'] / old['own_share']:.2f}x of {args.against}")
    out = ROOT / "benchmarks" / "results" / "onboard.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(results, indent=2))
    print(f"\nwrote {out.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
