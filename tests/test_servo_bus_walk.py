"""Simulated walks whose every joint command and reading crosses an emulated Dynamixel bus."""

from __future__ import annotations

import json

import numpy as np
import pytest

from footfall.cli import main
from footfall.sim.walk import simulate_walk
from footfall.sim.walk_request import WalkRequest, prepare_walk


def walk(tmp_path, *args: str) -> dict:
    assert main(["walk", "--terrain", "stairs", *args, "--out", str(tmp_path)]) == 0
    return json.loads((tmp_path / "metrics.json").read_text())


@pytest.mark.parametrize(("bus", "robot"), [("protocol1", "phantomx"), ("protocol2", "default")])
def test_a_walk_over_the_servo_bus_moves_every_joint_through_it(tmp_path, bus, robot) -> None:
    """The robot walks on the emulated bus; packets and bytes are counted, under 70 % busy."""
    m = walk(tmp_path, "--servo-bus", bus, "--robot", robot, "--seconds", "4")
    sb = m["servo_bus"]
    assert sb["protocol"] == int(bus[-1]) and sb["baud"] == 1_000_000 and sb["servos"] == 18
    assert sb["ticks"] >= 390  # a write every 10 ms tick
    assert sb["packets"] > sb["ticks"] * 2 and sb["errors"] == 0
    assert sb["bytes_per_tick"] == pytest.approx(
        sb["write_bytes_per_tick"] + sb["read_bytes_per_tick"]
    )
    assert 0.3 < sb["utilisation"] < 0.7
    assert not m["fell"] and m["distance_m"] > 0.15 and sb["fault"] == ""


def test_walking_through_the_bus_tracks_as_the_direct_simulation() -> None:
    """The feet follow their commands as closely as when the simulator takes targets directly."""
    errors = {}
    for backend, options in (("sim", {}), ("servo-bus", {"protocol": "2"})):
        job = prepare_walk(
            WalkRequest(terrain="stairs", seconds=4.0, backend=backend, backend_options=options)
        )
        log = simulate_walk(job.spec, job.settings).log
        gap = np.linalg.norm(
            log.array("feet_commanded_in_world") - log.array("feet_in_world"), axis=2
        )
        errors[backend] = np.percentile(gap, 99)
    assert errors["servo-bus"] < errors["sim"] + 0.002


@pytest.mark.parametrize(
    ("fault", "reason"),
    [
        ("silent:5@2", "servo 5 (LM femur): no status packets"),
        ("overheat:5@2", "servo 5 (LM femur): overheating"),
        ("checksum:5@2", "servo 5 (LM femur): corrupted status packets"),
        ("port:0@2", "servo bus port"),
    ],
)
def test_a_bus_fault_stops_the_walk_within_0_2_s(fault, reason) -> None:
    """The walk freezes within 0.2 s of the fault, names the servo and why, and does not fall."""
    job = prepare_walk(
        WalkRequest(
            terrain="stairs",
            seconds=3.0,
            backend="servo-bus",
            backend_options={"protocol": "2", "fault": fault},
        )
    )
    result = simulate_walk(job.spec, job.settings)
    metrics = result.metrics.to_json()
    assert metrics["frozen"] and reason in metrics["frozen_reason"]
    assert not metrics["fell"]
    time = np.array(result.log.time)
    frozen = time[np.array(result.log.state) == "frozen"]
    assert frozen.size and frozen[0] - 2.0 <= 0.2
    assert reason in metrics["servo_bus"]["fault"]


@pytest.mark.slow
@pytest.mark.parametrize("terrain", ["stairs", "cobblestones"])
@pytest.mark.parametrize(("bus", "robot"), [("protocol1", "phantomx"), ("protocol2", "default")])
def test_the_robot_crosses_over_the_servo_bus(tmp_path, terrain, bus, robot) -> None:
    """Stairs and cobblestones crossed on the emulated bus, the PhantomX on its AX-12A's
    Protocol 1.0 and the default robot on Protocol 2.0: goal, no fall, no invalid foothold."""
    m = walk(tmp_path, "--servo-bus", bus, "--robot", robot, "--terrain", terrain, "--seed", "3")
    assert m["reached_goal"] and not m["fell"] and m["invalid_footholds"] == 0
    assert m["servo_bus"]["errors"] == 0 and m["servo_bus"]["utilisation"] < 0.7
