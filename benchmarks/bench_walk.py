"""Time the main job: the simulated hexapod crossing the staircase with the full loop.

Runs ``footfall walk``'s default walk (stairs, seed 0, 320 x 240 camera) in process and
reports its real-time factor and where the wall time goes: the time the in-process bus
itself spends delivering messages (publish minus the subscribers' own work), and a profile
of the heaviest functions. With ``--against REF`` it also runs the same walk from a git
revision of this repository (checked out in a temporary worktree, run in a subprocess) in
the same session, so the figures compare like with like.

    uv run python benchmarks/bench_walk.py [--repeats 2] [--against HEAD~5] [--profile]

Writes ``benchmarks/results/walk.json``.
"""

from __future__ import annotations

import argparse
import cProfile
import json
import os
import pstats
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")

from footfall.messages import Message
from footfall.runtime.bus import InProcessBus
from footfall.sim.walk import simulate_walk
from footfall.sim.walk_request import WalkRequest, prepare_walk

ROOT = Path(__file__).resolve().parents[1]
# Run in a subprocess with an older source tree: the walk's real-time factor.
_OLD_WALK = """
import os, sys
os.environ.setdefault("MUJOCO_GL", "egl")
from footfall.cli import main
sys.exit(main(["walk", "--out", sys.argv[1]]))
"""


class TimingBus(InProcessBus):
    """An in-process bus that measures its own share of the time."""

    def __init__(self) -> None:
        super().__init__()
        self.overhead_s = 0.0
        self.published = 0

    def publish(self, topic: str, message: Message) -> None:
        """Deliver as the in-process bus does, timing delivery apart from the subscribers."""
        start = time.perf_counter()
        inside = 0.0
        self.stats[topic].messages += 1
        self._last[topic] = message
        for callback in tuple(self._subscribers.get(topic, ())):
            t0 = time.perf_counter()
            callback(message)
            inside += time.perf_counter() - t0
        self.overhead_s += time.perf_counter() - start - inside
        self.published += 1


def run_walk(bus: InProcessBus | None = None) -> dict[str, object]:
    """The default walk; its metrics (as ``metrics.json`` holds them)."""
    job = prepare_walk(WalkRequest())
    return simulate_walk(job.spec, job.settings, terrain=job.terrain, bus=bus).metrics.to_json()


def run_revision(ref: str) -> float:
    """Real-time factor of the default walk at a git revision of this repository."""
    with tempfile.TemporaryDirectory() as tmp:
        tree = Path(tmp) / "tree"
        subprocess.run(
            ["git", "-C", str(ROOT), "worktree", "add", "--detach", str(tree), ref],
            check=True,
            capture_output=True,
        )
        try:
            env = {**os.environ, "PYTHONPATH": str(tree / "src")}
            out = Path(tmp) / "out"
            subprocess.run(
                [sys.executable, "-c", _OLD_WALK, str(out)],
                check=True,
                env=env,
                capture_output=True,
            )
            return float(json.loads((out / "metrics.json").read_text())["realtime_factor"])
        finally:
            subprocess.run(
                ["git", "-C", str(ROOT), "worktree", "remove", "--force", str(tree)], check=True
            )


def main() -> dict[str, object]:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=2, help="walks timed")
    parser.add_argument("--against", help="also time this git revision in the same run")
    parser.add_argument("--profile", action="store_true", help="print the heaviest functions")
    args = parser.parse_args()

    run_walk()  # warm-up: compiled kernels, renderer
    factors, shares = [], []
    for _ in range(args.repeats):
        bus = TimingBus()
        metrics = run_walk(bus)
        factors.append(float(metrics["realtime_factor"]))
        shares.append(bus.overhead_s / float(metrics["wall_seconds"]))
    results: dict[str, object] = {
        "realtime_factor_median": statistics.median(factors),
        "realtime_factors": factors,
        "bus_delivery_share_median": statistics.median(shares),
        "messages_per_walk": bus.published,
        "wall_seconds": float(metrics["wall_seconds"]),
        "sim_seconds": float(metrics["sim_seconds"]),
    }
    if args.against:
        old = [run_revision(args.against) for _ in range(args.repeats)]
        results["against"] = args.against
        results["against_realtime_factor_median"] = statistics.median(old)
        results["speedup_over_against"] = statistics.median(factors) / statistics.median(old)
    if args.profile:
        profile = cProfile.Profile()
        profile.runcall(run_walk)
        pstats.Stats(profile).sort_stats("tottime").print_stats(25)
    width = max(len(k) for k in results)
    for key, value in results.items():
        shown = f"{value:10.3f}" if isinstance(value, float) else str(value)
        print(f"{key:<{width}}  {shown}")
    out = Path(__file__).parent / "results"
    out.mkdir(exist_ok=True)
    (out / "walk.json").write_text(json.dumps(results, indent=2) + "\n")
    return results


if __name__ == "__main__":
    main()
