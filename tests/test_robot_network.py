"""`footfall robot` over a real zenoh session on loopback, driven from another process."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
import time
from collections import defaultdict

import numpy as np
import zenoh

from footfall.messages import (
    DepthFrame,
    EffectorTargets,
    GaitState,
    GaitStatus,
    MapUpdate,
    Mode,
    ModeCommand,
    RobotState,
    WalkCommand,
)
from footfall.runtime.zenoh_bus import ZenohBus, ZenohConfig
from footfall.sim.task import TerrainTask
from footfall.sim.terrains import make_terrain
from processes import read_until
from test_zenoh_bus import free_port


def start_robot(endpoint: str, terrain: str, out, seconds: float, *extra: str):
    """`footfall robot` in its own process, listening on ``endpoint``."""
    env = {**os.environ, "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")}
    command = [sys.executable, "-m", "footfall.cli", "robot", "--sim", terrain]
    command += ["--listen", endpoint, "--seconds", str(seconds), "--out", str(out), *extra]
    return subprocess.Popen(command, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)


class Observer:
    """What a client hears from the robot."""

    def __init__(self, bus: ZenohBus) -> None:
        self.status: list[GaitStatus] = []
        self.states: list[tuple[float, RobotState]] = []
        self.targets: list[EffectorTargets] = []
        self.depth = 0
        self.color = 0
        self.maps = 0
        bus.subscribe(GaitStatus.TOPIC, self.status.append)
        bus.subscribe(RobotState.TOPIC, lambda m: self.states.append((time.monotonic(), m)))
        bus.subscribe(EffectorTargets.TOPIC, self.targets.append)
        bus.subscribe(DepthFrame.TOPIC, lambda m: setattr(self, "depth", self.depth + 1))
        bus.subscribe(MapUpdate.TOPIC, lambda m: setattr(self, "maps", self.maps + 1))
        bus.subscribe("color", lambda m: setattr(self, "color", self.color + 1))


def wait_for(bus: ZenohBus, done, seconds: float) -> bool:
    end = time.monotonic() + seconds
    while not done():
        if time.monotonic() > end:
            return False
        bus.spin(0.02)
    return True


class PlainSubscriber:
    """A plain zenoh subscriber to footfall/hexapod/**: what each topic costs on the wire."""

    def __init__(self, endpoint: str) -> None:
        config = zenoh.Config()
        config.insert_json5("mode", '"peer"')
        config.insert_json5("connect/endpoints", json.dumps([endpoint]))
        config.insert_json5("scouting/multicast/enabled", "false")
        self.session = zenoh.open(config)
        self.arrivals: list[tuple[float, str, int]] = []
        self.session.declare_subscriber("footfall/hexapod/**", self._arrive)

    def _arrive(self, sample: zenoh.Sample) -> None:
        topic = str(sample.key_expr).split("hexapod/", 1)[1]
        self.arrivals.append((time.monotonic(), topic, len(sample.payload)))

    def traffic(self, start: float, seconds: float) -> tuple[dict[str, float], dict[str, float]]:
        """Bytes per second and messages per second per topic over a window."""
        rate: dict[str, float] = defaultdict(float)
        hz: dict[str, float] = defaultdict(float)
        for t, topic, size in self.arrivals:
            if start <= t < start + seconds:
                rate[topic] += size / seconds
                hz[topic] += 1 / seconds
        return rate, hz


def test_a_client_in_another_process_walks_the_robot_across_the_stairs(tmp_path):
    """The robot, in its own process, starts limp; a client that only exchanges messages
    with it receives its depth images, maps and status, switches it to walking and steers
    it: the robot crosses the staircase with no invalid foothold and no fall. A plain zenoh
    subscriber to footfall/hexapod/** receives under 1.5 MB/s in all while it walks, the map
    and depth each at 5 Hz or more (unpacked, the link carried 17 MB/s). Its --record file
    holds what came in from the network (commands, the mode) beside what it sent, and
    replays to a map."""
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    record = tmp_path / "robot.mcap"
    robot = start_robot(
        endpoint, "stairs", tmp_path, 150.0, "--stop-at-goal", "--record", str(record)
    )
    plain = PlainSubscriber(endpoint)
    try:
        with ZenohBus(ZenohConfig(connect=(endpoint,))) as bus:
            seen = Observer(bus)
            task = TerrainTask(bus, make_terrain("stairs", seed=0), WalkCommand(speed=0.1))
            ready = lambda: seen.status and seen.depth and seen.maps and seen.color  # noqa: E731
            assert wait_for(bus, ready, 60.0)
            assert seen.status[-1].mode is Mode.TORQUE_OFF
            bus.publish(ModeCommand.TOPIC, ModeCommand(Mode.WALKING))
            start = time.monotonic()
            while robot.poll() is None and time.monotonic() - start < 120.0:
                bus.spin(0.05)
                task.command(time.monotonic() - start)  # 20 Hz, steered on the status
            assert seen.status[-1].mode is Mode.WALKING
    finally:
        plain.session.close()
        if robot.poll() is None:
            robot.send_signal(signal.SIGINT)
        output = robot.communicate(timeout=60)[0].decode(errors="replace")
    assert robot.returncode == 0, output
    metrics = json.loads((tmp_path / "metrics.json").read_text())
    assert metrics["reached_goal"], metrics
    assert metrics["invalid_footholds"] == 0 and not metrics["fell"]
    assert metrics["bridge_received"]["command"] > 100
    rate, hz = plain.traffic(start + 4.0, 10.0)  # walking and mapping
    figures = {t: f"{rate[t] / 1e3:.1f} kB/s at {hz[t]:.1f} Hz" for t in sorted(rate)}
    assert sum(rate.values()) < 1.5e6, figures
    assert hz["map"] >= 5.0 and hz["depth"] >= 5.0, figures
    # The client acknowledges what it hears, so the sender keeps to a window: on loopback it
    # rarely closes (only while the client, busy steering, falls behind by a few tenths of a
    # second), and then a newer image replaces a waiting one. Nearly everything goes.
    link = metrics["link"]
    assert link["sent"]["map"] > 50 and link["sent"]["depth"] > 50, link
    assert sum(link["dropped"].values()) <= 0.05 * sum(link["sent"].values()), link
    # The client's commands carry its own clock, not the wall's: no latency is claimed.
    assert metrics["command_latency_ms"] is None
    from collections import Counter

    from footfall.recording.reader import Recording

    recording = Recording(record)
    counts = Counter(m.topic for m in recording.messages({"/command", "/footfall/mode"}))
    assert counts["/command"] > 100 and counts["/footfall/mode"] >= 1
    assert "/camera/depth/image_raw" in recording.channels
    from footfall.recording.replay import Replayer
    from footfall.recording.replay_request import ReplayRequest

    assert Replayer(ReplayRequest(record, fast=True)).run().frames > 50


CLIENT = textwrap.dedent(
    """
    import sys, time
    from footfall.messages import Mode, ModeCommand, WalkCommand
    from footfall.runtime.zenoh_bus import ZenohBus, ZenohConfig
    bus = ZenohBus(ZenohConfig(connect=(sys.argv[1],)))
    heard = []
    bus.subscribe("status", heard.append)
    while not heard:  # linked up: the robot is heard
        bus.spin(0.05)
    print("walking", flush=True)
    k = 0
    while True:  # until killed; the mode repeats as a heartbeat
        if k % 20 == 0:
            bus.publish("mode", ModeCommand(Mode.WALKING))
        bus.publish("command", WalkCommand(speed=0.1))
        bus.spin(0.05)
        k += 1
    """
)


def test_killing_the_client_mid_walk_stands_the_robot_still_and_a_new_one_resumes(tmp_path):
    """A client walks the robot and is killed: within a second the robot stands still,
    every foot down, without falling, and says why; a new client walks it on."""
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    robot = start_robot(endpoint, "flat", tmp_path, 60.0)
    client = None
    try:
        with ZenohBus(ZenohConfig(connect=(endpoint,))) as bus:
            seen = Observer(bus)
            assert wait_for(bus, lambda: bool(seen.status), 60.0)
            client = subprocess.Popen(
                [sys.executable, "-c", CLIENT, endpoint], stdout=subprocess.PIPE, text=True
            )
            assert read_until(client, "walking", 60.0).strip() == "walking"
            assert wait_for(bus, lambda: seen.status[-1].steps_taken >= 4, 30.0)
            client.kill()
            client.wait(timeout=10)
            killed = time.monotonic()
            wait_for(bus, lambda: False, 2.5)
            after = [(t, s) for t, s in seen.states if t > killed + 1.0]
            assert len(after) > 10
            moved = np.ptp([s.position_body_in_world[:2] for _, s in after], axis=0)
            assert np.hypot(*moved) < 0.003  # still from 1 s after the kill
            assert not seen.targets[-1].swinging.any()
            assert all(s.tilt < np.radians(10) for _, s in after)
            status = seen.status[-1]
            assert status.state is GaitState.REST and "no command" in status.frozen_reason
            bus.publish_bytes(WalkCommand.TOPIC, b"\x00garbage")  # a malformed command
            assert wait_for(bus, lambda: seen.status[-1].messages_dropped >= 1, 5.0)
            x_stopped = after[-1][1].position_body_in_world[0]
            start = time.monotonic()
            while time.monotonic() - start < 4.0:  # a new client
                bus.publish(WalkCommand.TOPIC, WalkCommand(speed=0.1))
                bus.spin(0.05)
            assert seen.states[-1][1].position_body_in_world[0] > x_stopped + 0.1
            assert seen.status[-1].frozen_reason == ""
    finally:
        if client is not None and client.poll() is None:
            client.kill()
        if robot.poll() is None:
            robot.send_signal(signal.SIGINT)
        output = robot.communicate(timeout=60)[0].decode(errors="replace")
    assert robot.returncode == 0, output
    metrics = json.loads((tmp_path / "metrics.json").read_text())
    assert not metrics["fell"]


def test_by_default_the_robot_listens_on_loopback_only():
    """`footfall robot` without network options listens on 127.0.0.1 only, without
    scouting, and so does the session it opens."""
    from footfall.cli import build_parser
    from footfall.cli.robot import network_config
    from footfall.runtime import DEFAULT_ENDPOINT
    from footfall.runtime.zenoh_bus import is_loopback

    config = network_config(build_parser().parse_args(["robot"]))
    assert config.listen == (DEFAULT_ENDPOINT,) and not config.scouting
    assert not config.allow_remote and config.connect == ()
    port = free_port()  # the same configuration on a port free here
    with ZenohBus(ZenohConfig(listen=(config.listen[0].replace("7447", str(port)),))) as bus:
        locators = bus.listening_locators()
    assert locators and all(is_loopback(loc) for loc in locators)
    station = network_config(build_parser().parse_args(["station"]))
    assert station.listen == () and station.connect == (DEFAULT_ENDPOINT,)
