"""A robot and its station across an emulated radio: what the link does to them.

The robot (``footfall robot --sim stairs``) runs in a network namespace of its own behind
an :class:`~footfall.runtime.radio.EmulatedLink`; this process is its station: a footfall
bus that hears every topic (it unpacks and acknowledges the map, depth and colour as
``footfall station`` does) and sends the mode and walk commands five times a second,
stamped with the wall clock.

- :func:`walking_run`: bytes and messages per second per topic at the station; the map's
  and depth's age on arrival (from the robot offering them to the link), median and 95th
  percentile; from a command to the first joint targets computed with it (the robot's
  ``command_latency_ms``); what the robot dropped for newer messages.
- :func:`cut_run`: after some walking the radio holds everything for a while. From the
  robot's own statuses (held, then delivered): how long after the last command before the
  cut the watchdog stopped it, whether its body was still from a second after, when every
  foot was down; and how long after the link returned the station had a whole current map
  (one the robot offered after the return).

``benchmarks/bench_link.py`` runs both over each profile; ``tests/test_radio_link.py``
checks them against what a station needs.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from footfall.messages import (
    GaitState,
    GaitStatus,
    MapUpdate,
    Mode,
    ModeCommand,
    WalkCommand,
)
from footfall.runtime.radio import EmulatedLink
from footfall.runtime.zenoh_bus import ZenohBus, ZenohConfig

HEARTBEAT_S = 0.2
# What a station hears (footfall station draws all of it).
HEARD = (
    "depth",
    "color",
    "pose",
    "state",
    "log",
    "effector_targets",
    "joint_targets",
    "touchdown",
    "servo",
)


def start_robot(link: EmulatedLink, out: str, seconds: float) -> subprocess.Popen:
    """``footfall robot --sim stairs`` inside the link's namespace."""
    command = [sys.executable, "-m", "footfall.cli", "robot", "--sim", "stairs"]
    command += ["--listen", link.robot_endpoint, "--listen-remote"]
    command += ["--seconds", str(seconds), "--out", out]
    env = {**os.environ, "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")}
    return subprocess.Popen(link.inside(command), env=env, stdout=subprocess.DEVNULL)


def stop_robot(robot: subprocess.Popen, out: str) -> dict:
    """End the robot's run; its metrics."""
    robot.send_signal(signal.SIGINT)
    robot.wait(timeout=60)
    return json.loads((Path(out) / "metrics.json").read_text())


class Station:
    """The station's end: every topic heard, commands sent on a heartbeat."""

    def __init__(self, endpoint: str) -> None:
        self.bus = ZenohBus(ZenohConfig(connect=(endpoint,), command_session=True))
        self.statuses: list[GaitStatus] = []
        self.maps: list[tuple[float, float]] = []  # (arrival, offered) [s, wall clock]
        self.bus.subscribe(GaitStatus.TOPIC, self.statuses.append)
        self.bus.subscribe(MapUpdate.TOPIC, self._on_map)
        for topic in HEARD:
            self.bus.subscribe(topic, lambda m: None)  # heard, unpacked, acknowledged
        self._next_beat = 0.0

    def _on_map(self, update: MapUpdate) -> None:
        self.maps.append((time.time(), self.bus.link_receiver.offered_at["map"]))

    def wait_for_robot(self, seconds: float = 90.0) -> None:
        """Spin until the robot's status and a map have come."""
        end = time.monotonic() + seconds
        while not (self.statuses and self.maps) and time.monotonic() < end:
            self.bus.spin(0.05)
        if not (self.statuses and self.maps):
            raise RuntimeError("the robot was not heard over the link")

    def walk(self, seconds: float, send: bool = True) -> None:
        """Spin for ``seconds``, commanding walking on the heartbeat when ``send``."""
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            now = time.monotonic()
            if send and now >= self._next_beat:
                self._next_beat = now + HEARTBEAT_S
                self.bus.publish(ModeCommand.TOPIC, ModeCommand(Mode.WALKING, time.time()))
                self.bus.publish(WalkCommand.TOPIC, WalkCommand(speed=0.1, stamp=time.time()))
            self.bus.spin(0.01)

    def close(self) -> None:
        """Leave the network."""
        self.bus.close()


def percentiles(values_s, scale: float = 1e3) -> dict[str, float]:
    """Median and 95th percentile [ms]."""
    v = np.asarray(list(values_s)) * scale
    if not len(v):
        return {"median": float("nan"), "p95": float("nan")}
    return {"median": round(float(np.median(v)), 1), "p95": round(float(np.percentile(v, 95)), 1)}


def walking_run(link: EmulatedLink, seconds: float) -> dict:
    """Walk the robot behind the link for ``seconds`` (after it is heard and has walked 3 s)."""
    with tempfile.TemporaryDirectory() as out:
        robot = start_robot(link, out, seconds + 120)
        station = Station(link.station_endpoint)
        try:
            station.wait_for_robot()
            station.walk(3.0)  # walking, mapping
            for stats in station.bus.received.values():
                stats.messages = stats.bytes = 0
            for ages in station.bus.link_receiver.latency_s.values():
                ages.clear()
            proxy = link.proxy
            assert proxy is not None
            before = {w: (c.segments, c.lost) for w, c in (("up", proxy.up), ("down", proxy.down))}
            start = time.monotonic()
            station.walk(seconds)
            elapsed = time.monotonic() - start
            segments = {
                w: (c.segments - before[w][0], c.lost - before[w][1])
                for w, c in (("up", proxy.up), ("down", proxy.down))
            }
            received = {t: (s.bytes, s.messages) for t, s in sorted(station.bus.received.items())}
            ages = {t: percentiles(a) for t, a in station.bus.link_receiver.latency_s.items()}
        finally:
            station.close()
            metrics = stop_robot(robot, out)
    return {
        "seconds": round(elapsed, 1),
        "kB_per_second": {t: round(b / elapsed / 1e3, 1) for t, (b, _) in received.items()},
        "messages_per_second": {t: round(n / elapsed, 1) for t, (_, n) in received.items()},
        "kB_per_second_in_all": round(sum(b for b, _ in received.values()) / elapsed / 1e3, 1),
        "age_at_station_ms": ages,
        "command_to_joint_targets_ms": metrics.get("command_latency_ms"),
        "robot_link": metrics.get("link"),
        # Station to robot (up) and back (down): segments a second, and how many were lost.
        "segments_per_second": {w: round(n / elapsed, 1) for w, (n, _) in segments.items()},
        "segments_lost": {w: lost for w, (_, lost) in segments.items()},
    }


def cut_run(link: EmulatedLink, cut_s: float, walk_s: float = 8.0) -> dict:
    """Walk ``walk_s``, cut the link for ``cut_s``, and see what the robot and station did."""
    with tempfile.TemporaryDirectory() as out:
        robot = start_robot(link, out, 120)
        station = Station(link.station_endpoint)
        try:
            station.wait_for_robot()
            station.walk(walk_s)
            assert link.proxy is not None
            link.proxy.cut_link()
            station.walk(cut_s)  # the station keeps commanding; nothing gets through
            link.proxy.restore_link()
            restored = time.time()
            end = time.monotonic() + 10.0
            while time.monotonic() < end and not any(o >= restored for _, o in station.maps):
                station.walk(0.05)
            current = [a for a, o in station.maps if o >= restored]
            station.walk(2.0)
        finally:
            station.close()
            stop_robot(robot, out)
    # When the robot stood, by its controller's clock: the watchdog's statuses say how long
    # since the last command; from a second after it, every foot is down (rest) and the
    # body still.
    stopped = [s for s in station.statuses if "no command" in s.frozen_reason]
    if not stopped:
        raise RuntimeError("the robot never stopped on its watchdog during the cut")
    first = stopped[0]
    last_command = first.stamp - first.command_age
    during = [s for s in stopped if s.stamp >= last_command + 1.0]
    poses = [(s.body_pose.x, s.body_pose.y) for s in during]
    moved = np.ptp(poses, axis=0) if poses else [np.nan]
    # Feet down from the first status after which every one says rest (the feet in the air
    # when the watchdog stopped the body land where they were going).
    resting = [s.state is GaitState.REST for s in stopped]
    down = next((k for k in range(len(stopped)) if all(resting[k:])), None)
    return {
        "cut_seconds": cut_s,
        "stopped_after_last_command_s": round(first.stamp - last_command, 3),
        "body_moved_from_1_s_after_last_command_mm": round(1e3 * float(np.hypot(*moved)), 2),
        "feet_down_after_last_command_s": (
            round(stopped[down].stamp - last_command, 3) if down is not None else None
        ),
        "statuses_while_stopped": len(during),
        "whole_map_after_return_s": round(current[0] - restored, 3) if current else None,
    }
