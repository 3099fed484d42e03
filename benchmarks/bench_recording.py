"""What recording costs a walk, and how fast a recording replays.

The same seeded stairs walk (planned, 640 x 480 depth) runs without recording, with
``--record`` (MCAP) and with ``--rerun``; the recording then replays with ``--fast``. Wall
times and ratios against the plain walk measured in the same run, file sizes in MB.

Run with ``uv run python benchmarks/bench_recording.py``; it prints the figures and writes
``benchmarks/results/recording.json``.
"""

from __future__ import annotations

import json
import tempfile
import time
from pathlib import Path

from footfall.recording.replay import Replayer
from footfall.recording.replay_request import ReplayRequest
from footfall.reports.walk import run_walk
from footfall.sim.walk_request import WalkRequest, prepare_walk

SECONDS = 6.0


def _walk(**recording: Path) -> float:
    job = prepare_walk(WalkRequest(terrain="stairs", seconds=SECONDS, seed=1, **recording))
    start = time.perf_counter()
    run_walk(job)
    return time.perf_counter() - start


def main() -> dict[str, float]:
    results: dict[str, float] = {}
    with tempfile.TemporaryDirectory() as folder:
        mcap, rrd = Path(folder) / "walk.mcap", Path(folder) / "walk.rrd"
        _walk()  # compile and warm up
        results["walk_s"] = _walk()
        results["walk_record_s"] = _walk(record=mcap)
        results["walk_rerun_s"] = _walk(rerun=rrd)
        results["record_ratio"] = results["walk_record_s"] / results["walk_s"]
        results["rerun_ratio"] = results["walk_rerun_s"] / results["walk_s"]
        results["mcap_mb"] = mcap.stat().st_size / 1e6
        results["rrd_mb"] = rrd.stat().st_size / 1e6
        start = time.perf_counter()
        frames = Replayer(ReplayRequest(mcap, fast=True)).run().frames
        results["replay_s"] = time.perf_counter() - start
        results["replay_frames_per_s"] = frames / results["replay_s"]
        results["sim_seconds"] = SECONDS
    for key, value in results.items():
        print(f"{key:<22} {value:10.3f}")
    out = Path(__file__).parent / "results"
    out.mkdir(exist_ok=True)
    (out / "recording.json").write_text(json.dumps(results, indent=2) + "\n")
    return results


if __name__ == "__main__":
    main()
