"""The robot's link to its station over real zenoh sessions: what it costs, what arrives."""

from __future__ import annotations

import json
import signal
import time
from collections import defaultdict

import numpy as np
import pytest
import zenoh

from footfall.messages import GaitStatus, MapUpdate, Mode, ModeCommand, WalkCommand
from footfall.runtime.link_trial import cut_run, walking_run
from footfall.runtime.radio import PROFILES, EmulatedLink, NamespaceError
from footfall.runtime.zenoh_bus import ZenohBus, ZenohConfig
from test_link import assert_within_quantisation, random_map
from test_robot_network import start_robot, wait_for
from test_zenoh_bus import free_port


def test_the_robot_sends_a_plain_subscriber_under_1_5_mb_s_with_map_and_depth_at_5_hz(
    tmp_path,
):
    """`footfall robot` with default settings, walking the stairs: a plain zenoh
    subscriber to footfall/hexapod/** receives under 1.5 MB/s in all, the map and depth
    each at 5 Hz or more (the unpacked link carried 17 MB/s)."""
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    robot = start_robot(endpoint, "stairs", tmp_path, 90.0)
    arrivals: list[tuple[float, str, int]] = []
    try:
        config = zenoh.Config()
        config.insert_json5("mode", '"peer"')
        config.insert_json5("connect/endpoints", f'["{endpoint}"]')
        config.insert_json5("scouting/multicast/enabled", "false")
        plain = zenoh.open(config)
        plain.declare_subscriber(
            "footfall/hexapod/**",
            lambda s: arrivals.append(
                (time.monotonic(), str(s.key_expr).rsplit("hexapod/", 1)[1], len(s.payload))
            ),
        )
        with ZenohBus(ZenohConfig(connect=(endpoint,))) as bus:
            heard: list[GaitStatus] = []
            bus.subscribe(GaitStatus.TOPIC, heard.append)
            assert wait_for(bus, lambda: bool(heard), 60.0)
            bus.publish(ModeCommand.TOPIC, ModeCommand(Mode.WALKING, time.time()))
            start = time.monotonic()
            while time.monotonic() - start < 14.0:
                bus.publish(WalkCommand.TOPIC, WalkCommand(speed=0.1, stamp=time.time()))
                bus.spin(0.1)
            assert heard[-1].mode is Mode.WALKING and heard[-1].steps_taken > 10
        plain.close()
    finally:
        robot.send_signal(signal.SIGINT)
        output = robot.communicate(timeout=60)[0].decode(errors="replace")
    assert robot.returncode == 0, output
    metrics = json.loads((tmp_path / "metrics.json").read_text())
    # Nobody acknowledged (no footfall station): nothing was held back or dropped.
    assert metrics["link"]["sent"]["map"] > 50 and metrics["link"]["dropped"] == {}
    # Every command reached the joints; on loopback the robot's own ticks are most of it.
    latency = metrics["command_latency_ms"]
    assert latency["count"] > 50 and latency["median"] < 100.0, latency
    window = [a for a in arrivals if start + 4.0 <= a[0] < start + 14.0]  # walking, mapping
    seconds = 10.0
    rate: dict[str, float] = defaultdict(float)
    hz: dict[str, float] = defaultdict(float)
    for _, topic, size in window:
        rate[topic] += size / seconds
        hz[topic] += 1 / seconds
    total = sum(rate.values())
    figures = {t: f"{rate[t] / 1e3:.1f} kB/s at {hz[t]:.1f} Hz" for t in sorted(rate)}
    assert total < 1.5e6, figures
    assert hz["map"] >= 5.0 and hz["depth"] >= 5.0, figures
    print(f"robot -> plain subscriber: {total / 1e3:.0f} kB/s in all; {figures}; {latency}")


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
            assert wait_for(station, lambda: got and got[-1].sequence == 29, 5.0)
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
    the joints in under 100 ms (p95)."""
    result = walking_run(poor_wifi, 12.0)
    assert result["messages_per_second"]["map"] >= 5.0, result
    assert result["age_at_station_ms"]["map"]["p95"] < 300.0, result
    assert result["command_to_joint_targets_ms"]["p95"] < 100.0, result


@pytest.mark.slow
def test_a_cut_radio_stands_the_robot_within_a_second_and_a_whole_map_follows_its_return(
    poor_wifi,
):
    """The radio holds everything for 3 s: the robot stands still within a second of its
    last command (by its own clock), and within 2 s of the link's return the station has a
    whole map the robot made after it."""
    result = cut_run(poor_wifi, 3.0, walk_s=6.0)
    assert result["stopped_after_last_command_s"] <= 1.0, result
    assert result["statuses_while_stopped"] > 10
    assert result["feet_down_from_1_s_after_last_command"], result
    assert result["body_moved_from_1_s_after_last_command_mm"] < 3.0, result
    assert result["whole_map_after_return_s"] is not None
    assert result["whole_map_after_return_s"] < 2.0, result
