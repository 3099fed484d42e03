"""The robot's link to its station over real zenoh sessions: what it costs, what arrives."""

from __future__ import annotations

import time

import numpy as np
import pytest

from footfall.messages import JointTargets, MapUpdate, WalkCommand
from footfall.runtime.bus import InProcessBus
from footfall.runtime.link_trial import cut_run, walking_run
from footfall.runtime.radio import PROFILES, EmulatedLink, NamespaceError
from footfall.runtime.zenoh_bus import ZenohBus, ZenohConfig
from footfall.sim.robot import CommandLatency
from test_link import assert_within_quantisation, random_map
from test_zenoh_bus import free_port


def test_a_commands_latency_counts_to_the_first_joint_targets_computed_with_it():
    """A station's command (stamped with the wall clock) counts from its stamp to the joint
    targets of the tick that delivered it; one to a limp robot (no joint targets that
    tick) and one stamped with another clock are not counted."""
    local = InProcessBus()
    latency = CommandLatency(local)
    targets = JointTargets(np.zeros((6, 3)), np.zeros((6, 3)), 1.0)
    local.publish(WalkCommand.TOPIC, WalkCommand(speed=0.1, stamp=time.time() - 0.05))
    local.publish(JointTargets.TOPIC, targets)
    latency.acted_on()
    local.publish(WalkCommand.TOPIC, WalkCommand(speed=0.1, stamp=time.time() - 0.5))
    latency.acted_on()  # limp: no joint targets
    local.publish(WalkCommand.TOPIC, WalkCommand(speed=0.1, stamp=12.5))  # simulated time
    local.publish(JointTargets.TOPIC, targets)
    latency.acted_on()
    summary = latency.summary()
    assert summary["count"] == 1 and 50.0 <= summary["median"] < 80.0


def test_a_station_joining_late_gets_a_whole_map_first_then_the_robots_map():
    """Over real sessions, a station that joins while the robot streams changes to an
    earlier whole map passes on no map until it has a whole one (it asks for it), then
    every map equals the robot's within the quantisation; its acknowledgements put the
    robot's link under flow control."""
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    rng = np.random.default_rng(11)
    sent: dict[int, MapUpdate] = {}
    with ZenohBus(ZenohConfig(listen=(endpoint,), radio=True)) as robot:
        robot.publish("map", random_map(rng, 96, (0, 0), 1))  # before the station is there
        with ZenohBus(ZenohConfig(connect=(endpoint,))) as station:
            got: list[MapUpdate] = []
            station.subscribe("map", got.append)
            time.sleep(0.5)  # linked up
            update = random_map(rng, 96, (0, 0), 2)
            for k in range(2, 30):
                # The robot walks: the window scrolls a cell, a patch is measured again.
                patch = rng.random(update.known.shape) < 0.05
                fresh = random_map(rng, 96, (k, 0), k)
                shifted = {}
                for name in ("heights", "known", "spread", "score", "valid"):
                    old = np.roll(getattr(update, name), -1, axis=0)
                    shifted[name] = np.where(patch, getattr(fresh, name), old)
                    shifted[name][-1] = getattr(fresh, name)[-1]
                update = MapUpdate(
                    **{**fresh.__dict__, **shifted},
                )
                sent[k] = update
                robot.publish("map", update)
                robot.spin(0.02)
                station.spin(0.05)
            end = time.monotonic() + 5.0  # both ends spin: the robot hears the acknowledgements
            while not (got and got[-1].sequence == 29) and time.monotonic() < end:
                robot.spin(0.01)
                station.spin(0.01)
            assert got and got[-1].sequence == 29
            robot.spin(0.1)
            assert robot.link_sender.flow_controlled
            assert robot.link_sender.counts.wholes >= 2  # the first, and the one asked for
    # Incompressible maps 20 times a second exceed the window: some give way to newer ones.
    assert len(got) >= 10
    for update in got:
        assert_within_quantisation(update, sent[update.sequence])


@pytest.fixture
def poor_wifi():
    """The robot's side of a "poor Wi-Fi" radio, or a skip saying why it cannot be made."""
    link = EmulatedLink(PROFILES["poor-wifi"], seed=5)
    try:
        link.__enter__()
    except NamespaceError as exc:
        pytest.skip(f"the emulated radio needs a network namespace, which cannot be made: {exc}")
    try:
        yield link
    finally:
        link.__exit__(None, None, None)


@pytest.mark.slow
def test_over_poor_wifi_the_map_stays_fresh_and_commands_reach_the_joints(poor_wifi):
    """Over 10 Mbit/s, 40 +- 10 ms and 2 % loss, with the map and images streaming: the
    map arrives under 300 ms old (p95) at 5 Hz or more, and a station's command reaches
    the joints in under 100 ms (p95). Long enough for a hundred commands: each one lost on
    the air (2 %) waits a retransmission, 160 ms."""
    result = walking_run(poor_wifi, 25.0)
    assert result["messages_per_second"]["map"] >= 5.0, result
    assert result["age_at_station_ms"]["map"]["p95"] < 300.0, result
    assert result["command_to_joint_targets_ms"]["p95"] < 100.0, result


@pytest.mark.slow
def test_a_cut_radio_stands_the_robot_within_a_second_and_a_whole_map_follows_its_return(
    poor_wifi,
):
    """The radio holds everything for 3 s: the robot's body stands still within a second of
    its last command (by its own clock), the feet in the air land within 1.5 s, and within
    2 s of the link's return the station has a whole map the robot made after it."""
    result = cut_run(poor_wifi, 3.0, walk_s=6.0)
    assert result["stopped_after_last_command_s"] <= 1.0, result
    assert result["statuses_while_stopped"] > 10
    assert result["feet_down_after_last_command_s"] is not None
    assert result["feet_down_after_last_command_s"] < 1.5, result
    assert result["body_moved_from_1_s_after_last_command_mm"] < 3.0, result
    assert result["whole_map_after_return_s"] is not None
    assert result["whole_map_after_return_s"] < 2.0, result
