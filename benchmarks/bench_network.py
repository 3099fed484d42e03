"""Latency and bandwidth of the robot on the network: two processes over zenoh on loopback.

Starts ``footfall robot --sim stairs`` in its own process (every topic sent at full rate:
depth and map updates at 15 Hz, 320 x 240 depth; unpacked unless ``--radio``) and acts
as the station in this one: switches it to walking, commands it forward at 10 Hz, and
measures

- the latency from a depth frame's capture to the map update that includes it arriving
  here (stamps are the robot's controller time; the wall time it counts from is estimated
  as the least difference between a status message's arrival and its stamp);
- the latency from a command to the first joint target that reflects it: the robot is
  switched to walking every 4 s (limp in between, when no joint target goes out), and the
  first joint target after each switch is timed against the switch;
- the bytes per second of each topic received here.

    uv run python benchmarks/bench_network.py [--seconds 20]

Writes ``benchmarks/results/network.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import socket
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from footfall.messages import (
    DepthFrame,
    GaitStatus,
    JointTargets,
    MapUpdate,
    Mode,
    ModeCommand,
    WalkCommand,
)
from footfall.runtime.zenoh_bus import ZenohBus, ZenohConfig


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def main() -> dict[str, object]:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=20.0, help="walking time measured")
    parser.add_argument(
        "--radio", action="store_true", help="the robot's packed radio link (default: unpacked)"
    )
    args = parser.parse_args()
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    full = ("map", "state", "status", "joint_targets", "effector_targets")
    rates = [f"--rate={t}=all" for t in full] + ([] if args.radio else ["--full-precision"])
    with tempfile.TemporaryDirectory() as out:
        robot = subprocess.Popen(
            [sys.executable, "-m", "footfall.cli", "robot", "--sim", "stairs", "--listen"]
            + [endpoint, "--seconds", str(args.seconds + 60), "--out", out, *rates],
            env={**os.environ, "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")},
            stdout=subprocess.DEVNULL,
        )
        try:
            results = measure(endpoint, args.seconds)
        finally:
            robot.send_signal(signal.SIGINT)
            robot.wait(timeout=60)
    width = max(len(k) for k in results)
    for key, value in results.items():
        print(f"{key:<{width}}  {value}")
    path = Path(__file__).parent / "results"
    path.mkdir(exist_ok=True)
    (path / "network.json").write_text(json.dumps(results, indent=2) + "\n")
    return results


def measure(endpoint: str, seconds: float) -> dict[str, object]:
    with ZenohBus(ZenohConfig(connect=(endpoint,))) as bus:
        epoch: list[float] = []  # least (arrival - stamp) of the status messages so far
        depth_arrival: dict[float, float] = {}
        maps: list[tuple[float, float]] = []  # (arrival, stamp)
        joints: list[tuple[float, JointTargets]] = []

        def on_status(status: GaitStatus) -> None:
            offset = time.time() - status.stamp
            if status.stamp > 0 and (not epoch or offset < epoch[0]):
                epoch[:] = [offset]

        bus.subscribe(GaitStatus.TOPIC, on_status)
        bus.subscribe(MapUpdate.TOPIC, lambda m: maps.append((time.time(), m.stamp)))
        bus.subscribe(DepthFrame.TOPIC, lambda f: depth_arrival.setdefault(f.stamp, time.time()))
        bus.subscribe(JointTargets.TOPIC, lambda j: joints.append((time.time(), j)))
        for topic in ("pose", "state", "effector_targets", "touchdown", "log"):
            bus.subscribe(topic, lambda m: None)  # counted for the bandwidth
        end = time.monotonic() + 90.0
        while not (epoch and depth_arrival) and time.monotonic() < end:
            bus.spin(0.05)
        for stats in bus.received.values():
            stats.messages = stats.bytes = 0
        start = time.monotonic()
        switched_on: list[tuple[float, int]] = []  # (send time, joint targets before it)
        while time.monotonic() - start < seconds:
            # Walking for 3.5 s, then limp for 0.5 s: each switch to walking is a command
            # whose first joint target can be told apart (none go out while limp).
            switched_on.append((time.time(), len(joints)))
            bus.publish(ModeCommand.TOPIC, ModeCommand(Mode.WALKING, time.time()))
            phase = time.monotonic()
            while time.monotonic() - phase < 3.5:
                bus.publish(WalkCommand.TOPIC, WalkCommand(speed=0.1, stamp=time.time()))
                bus.spin(0.1)
            bus.publish(ModeCommand.TOPIC, ModeCommand(Mode.TORQUE_OFF, time.time()))
            phase = time.monotonic()
            while time.monotonic() - phase < 0.5:
                bus.spin(0.1)
        elapsed = time.monotonic() - start
        bus.spin(0.5)
        map_latency = [arrival - (epoch[0] + stamp) for arrival, stamp in maps]
        command_latency = [
            epoch[0] + joints[count][1].stamp - sent
            for sent, count in switched_on
            if count < len(joints)
        ]
        bandwidth = {
            topic: round(stats.bytes / elapsed) for topic, stats in sorted(bus.received.items())
        }
        rates = {
            topic: round(stats.messages / elapsed, 1)
            for topic, stats in sorted(bus.received.items())
        }
    if not (map_latency and command_latency):
        raise RuntimeError(
            f"no measurement: {len(map_latency)} maps, {len(command_latency)} switches timed; "
            f"heard {dict(bus.received)}, epoch {epoch}"
        )
    return {
        "seconds": round(elapsed, 1),
        "depth_to_map_at_station_ms_median": 1e3 * statistics.median(map_latency),
        "depth_to_map_at_station_ms_p95": 1e3 * float(np.percentile(map_latency, 95)),
        "command_to_joint_target_ms_median": 1e3 * statistics.median(command_latency)
        if command_latency
        else float("nan"),
        "bytes_per_second": bandwidth,
        "messages_per_second": rates,
    }


if __name__ == "__main__":
    main()
