"""Nodes on a thread of their own: fed in order, heard at the next spin, never a backlog."""

from __future__ import annotations

import threading
import time

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from footfall.messages import DepthFrame, LogLine, MapUpdate, Mode, ModeCommand, WalkCommand
from footfall.robot.spec import load_spec
from footfall.runtime.bus import InProcessBus
from footfall.runtime.node_thread import NodeThread, NodeThreadError
from footfall.sim.assembly import WalkingRobot
from footfall.sim.terrains import make_terrain
from footfall.sim.walk_settings import WalkSettings


def wait_for(condition, seconds: float = 5.0) -> None:
    end = time.monotonic() + seconds
    while not condition():
        assert time.monotonic() < end, "the node thread did not get there in time"
        time.sleep(0.002)


class Echo:
    """A node that answers every command with a log line naming it, and its thread."""

    def __init__(self, bus) -> None:
        self.bus = bus
        self.threads: set[str] = set()
        bus.subscribe(WalkCommand.TOPIC, self._on)
        bus.subscribe(LogLine.TOPIC, self._heard)
        self.heard: list[str] = []

    def _on(self, command: WalkCommand) -> None:
        self.threads.add(threading.current_thread().name)
        self.bus.publish(LogLine.TOPIC, LogLine(command.stamp, "echo", "info", f"{command.speed}"))

    def _heard(self, line: LogLine) -> None:
        self.heard.append(line.text)


@settings(max_examples=25, deadline=None)
@given(st.lists(st.floats(0.0, 1.0), min_size=1, max_size=30))
def test_messages_reach_the_thread_in_order_and_its_answers_come_back_at_spin(speeds):
    """What the owner publishes reaches the thread's nodes in order, on that thread; what
    they publish reaches the owner's subscribers only at spin, in order, on the owner's
    thread, and their own subscribers once (not again when it is published outside)."""
    outer = InProcessBus()
    thread = NodeThread(outer, "worker")
    echo = Echo(thread.bus)
    outside: list[tuple[str, str]] = []
    outer.subscribe(
        LogLine.TOPIC, lambda m: outside.append((m.text, threading.current_thread().name))
    )
    thread.start()
    try:
        for k, speed in enumerate(speeds):
            outer.publish(WalkCommand.TOPIC, WalkCommand(speed=speed, stamp=float(k)))
        wait_for(lambda: len(echo.heard) == len(speeds))
        assert outside == []  # nothing before the owner spins
        assert thread.spin() == len(speeds)
    finally:
        thread.close()
    expected = [f"{s}" for s in speeds]
    assert [text for text, _ in outside] == expected
    assert {name for _, name in outside} == {threading.current_thread().name}
    assert echo.threads == {"worker"}
    assert echo.heard == expected  # once each: its own messages do not come back


def test_a_slow_node_takes_the_newest_frames_and_the_replaced_ones_are_counted():
    """While the thread is busy, a topic with a limit keeps only the newest waiting."""
    outer = InProcessBus()
    thread = NodeThread(outer, "mapping", waiting={WalkCommand.TOPIC: 2})
    release = threading.Event()
    seen: list[float] = []

    def slow(command: WalkCommand) -> None:
        release.wait(5.0)
        seen.append(command.stamp)

    thread.bus.subscribe(WalkCommand.TOPIC, slow)
    thread.bus.subscribe(ModeCommand.TOPIC, lambda m: seen.append(-1.0))
    thread.start()
    try:
        outer.publish(WalkCommand.TOPIC, WalkCommand(stamp=0.0))
        time.sleep(0.05)  # the thread holds the first
        for k in range(1, 6):
            outer.publish(WalkCommand.TOPIC, WalkCommand(stamp=float(k)))
        outer.publish(ModeCommand.TOPIC, ModeCommand())  # no limit: never replaced
        release.set()
        wait_for(lambda: len(seen) == 4)
    finally:
        thread.close()
    assert seen == [0.0, 4.0, 5.0, -1.0]
    assert thread.dropped[WalkCommand.TOPIC] == 3


def test_a_node_that_fails_on_the_thread_fails_the_owner_at_its_next_spin():
    """The error is not lost on the thread: the owner's spin raises it, named."""
    outer = InProcessBus()
    thread = NodeThread(outer, "mapping")

    def broken(command: WalkCommand) -> None:
        raise ValueError("bad frame")

    thread.bus.subscribe(WalkCommand.TOPIC, broken)
    thread.start()
    try:
        outer.publish(WalkCommand.TOPIC, WalkCommand())
        with pytest.raises(NodeThreadError, match="mapping: bad frame"):
            wait_for(lambda: thread.spin() < 0, 2.0)
    finally:
        thread.close()


def test_a_threaded_robot_renders_and_maps_what_the_robot_in_one_loop_does():
    """The same ticks with the camera's render, the pose and the mapping on the perception
    thread give the same depth images and the same map, a tick or two later."""
    spec = load_spec("default")
    walk = WalkSettings(terrain="stairs", seed=0, blind=False)
    terrain = make_terrain(walk.terrain, seed=0)
    runs = {}
    for threaded in (False, True):
        bus = InProcessBus()
        robot = WalkingRobot.build(spec, walk, terrain, bus, perception_thread=threaded)
        thread = robot.perception_thread
        frames: list[DepthFrame] = []
        maps: list[MapUpdate] = []
        bus.subscribe(DepthFrame.TOPIC, frames.append)
        bus.subscribe(MapUpdate.TOPIC, maps.append)
        bus.publish(ModeCommand.TOPIC, ModeCommand(Mode.WALKING))
        try:
            for k in range(30):
                bus.publish(WalkCommand.TOPIC, WalkCommand(speed=0.0, stamp=k * 0.01))  # stand
                robot.step(k * 0.01, 0.01)
                if thread is not None:
                    wait_for(lambda thread=thread: thread.idle)
            while thread is not None and thread.spin():  # what the last ticks began
                wait_for(lambda thread=thread: thread.idle)
        finally:
            robot.close()
        runs[threaded] = (frames, maps)
    (frames, maps), (frames_t, maps_t) = runs[False], runs[True]
    # The first frame, taken as the robot is built, comes out at the first tick's spin
    # (the loop without a thread published it and its map while the robot was built).
    assert frames_t[0].stamp == 0.0
    frames_t = frames_t[1:]
    assert len(frames) == len(frames_t) >= 4
    # The loop renders the kinematics of the physics step's start; the thread those of the
    # joint state the step ended with: the same view within a millimetre or two.
    for a, b in zip(frames, frames_t, strict=True):
        assert a.stamp == b.stamp
        off = np.abs(a.depth - b.depth)
        assert np.median(off) < 2e-3 and np.mean(off > 0.02) < 0.01
    assert maps_t[0].stamp == 0.0  # the first map too
    assert len(maps) == len(maps_t) - 1 >= 4
    a, b = world_cells(maps[-1]), world_cells(maps_t[-1])
    both = a.keys() & b.keys()
    assert len(both) > 0.995 * max(len(a), len(b)) > 1000
    off = np.array([abs(a[c][0] - b[c][0]) for c in both])
    assert np.mean(off > 2e-3) < 0.005
    assert np.mean([a[c][1] != b[c][1] for c in both]) < 0.005


def world_cells(update: MapUpdate) -> dict[tuple[int, int], tuple[float, bool]]:
    """Height and validity of each known cell, by its index on the world grid (the rolling
    window's origin may differ by a cell between two maps of the same ground)."""
    i0, j0 = (round(o / update.resolution) for o in update.origin)
    return {
        (int(i) + i0, int(j) + j0): (float(update.heights[i, j]), bool(update.valid[i, j]))
        for i, j in zip(*np.nonzero(update.known), strict=True)
    }
