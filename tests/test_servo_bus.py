"""The Dynamixel backend on dynamixel-sdk, against servos emulated on a pseudo-terminal."""

from __future__ import annotations

import dataclasses
import math
import os
import time
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from footfall.errors import BackendError, ConfigError
from footfall.hardware.bus import MISSES_ALLOWED
from footfall.hardware.config import hardware_from_dict
from footfall.hardware.dynamixel import DynamixelHexapod
from footfall.hardware.emulated_servos import EmulatedServos
from footfall.hardware.emulator import EmulatedBus
from footfall.hardware.models import servo_model
from footfall.messages import JointTargets
from footfall.robot.spec import load_spec

SPEC = load_spec("default")


class Bench:
    """Emulated servos whose joints follow their set-points (no simulator), on a bus."""

    def __init__(self, protocol: int, table: dict | None = None) -> None:
        config = hardware_from_dict(SPEC, table, protocol=protocol)
        self.servos = EmulatedServos(config)
        self.rest = np.array([(s.lower + s.upper) / 2 for s in config.servos])
        self.servos.start(self.rest, torque=True)
        self.bus = EmulatedBus(self.servos)
        self.config = dataclasses.replace(config, port=self.bus.port)
        self.time = 0.0

    def backend(self) -> DynamixelHexapod:
        """The Dynamixel backend on the bus, on the bench's clock."""
        return DynamixelHexapod(self.config, clock=lambda: self.time)

    def step(self, dt: float = 0.01) -> None:
        """The servos move for ``dt``: joints land on their set-points."""
        setpoints, rates = self.servos.drive(dt)
        held = np.where(self.servos.torque, setpoints, self.servos.position)
        self.servos.sense(held, np.where(self.servos.torque, rates, 0.0), np.zeros(18))
        self.time += dt

    def close(self) -> None:
        """Release the pseudo-terminal."""
        self.bus.close()


@pytest.fixture(params=[1, 2], ids=["protocol1", "protocol2"])
def bench(request):
    b = Bench(request.param)
    yield b
    b.close()


def targets(positions: np.ndarray) -> JointTargets:
    return JointTargets(positions.reshape(6, 3), np.zeros((6, 3)), 0.0)


def test_joints_follow_targets_over_the_bus(bench: Bench) -> None:
    """Targets sent by sync write reach the servos' goals, and reads bring the joints back."""
    robot = bench.backend()
    assert np.allclose(robot.read().joint_positions.ravel(), bench.rest, atol=2e-2)
    robot.set_torque(True)
    goal = bench.rest + 0.2 * np.sin(np.arange(18))
    for _ in range(30):
        robot.command(targets(goal))
        bench.step()
    resolution = 2 * math.pi / 1024  # the coarser servo's step, twice
    assert np.allclose(bench.servos.goal, goal, atol=resolution)
    assert np.allclose(robot.read().joint_positions.ravel(), goal, atol=resolution)
    assert np.all(robot.bus.temperatures > 0) and np.all(robot.bus.voltages > 5)


def test_targets_are_clamped_to_the_joint_limits(bench: Bench) -> None:
    """A target past a joint limit is sent as the limit, and counted."""
    robot = bench.backend()
    robot.set_torque(True)
    goal = bench.rest.copy()
    goal[1] = 10.0
    robot.command(targets(goal))
    assert robot.clamped == 1
    assert bench.servos.goal[1] == pytest.approx(bench.config.servos[1].upper, abs=5e-3)


def test_torque_on_does_not_jump(bench: Bench) -> None:
    """Torque goes on with each goal at its joint's present position."""
    robot = bench.backend()
    robot.set_torque(False)
    moved = bench.rest + 0.3
    bench.servos.sense(moved, np.zeros(18), np.zeros(18))
    robot.set_torque(True)
    assert np.all(bench.servos.torque)
    assert np.allclose(bench.servos.goal, moved, atol=5e-3)


def test_bus_traffic_matches_the_read_schedule(bench: Bench) -> None:
    """Each tick carries exactly the bytes the schedule predicts, under 70 % of 10 ms."""
    robot = bench.backend()
    robot.set_torque(True)
    before = bench.bus.counts.copy()
    ticks = 20
    for _ in range(ticks):
        robot.command(targets(bench.rest))
        bench.step()
    used = bench.bus.counts - before
    schedule = robot.bus.schedule
    assert used.write_bytes == ticks * schedule.write_bytes
    assert used.read_bytes == ticks * schedule.read_bytes
    busy = (used.write_seconds + used.read_seconds) / ticks
    assert busy == pytest.approx(schedule.seconds)
    assert busy < 0.7 * 0.01
    assert used.errors == 0


@pytest.mark.parametrize("fault", ["silent", "overheat", "checksum", "port"])
def test_a_servo_fault_stops_the_backend_naming_the_servo(bench: Bench, fault: str) -> None:
    """Each fault raises BackendError naming the servo and cause within a few ticks."""
    robot = bench.backend()
    robot.set_torque(True)
    robot.command(targets(bench.rest))
    victim = bench.config.servos[4]
    {
        "silent": lambda: bench.bus.silence(victim.servo_id),
        "overheat": lambda: bench.servos.overheat(victim.servo_id),
        "checksum": lambda: bench.bus.corrupt(victim.servo_id),
        "port": bench.bus.close_port,
    }[fault]()
    start = time.perf_counter()
    with pytest.raises(BackendError) as caught:
        for _ in range(MISSES_ALLOWED + 1):
            robot.command(targets(bench.rest))
    assert time.perf_counter() - start < 0.2
    message = str(caught.value)
    expected = {
        "silent": "no status packets",
        "overheat": "overheating",
        "checksum": "corrupted status packets",
        "port": "port",
    }[fault]
    assert expected in message
    if fault != "port":
        assert victim.name in message
    with pytest.raises(BackendError):
        robot.command(targets(bench.rest))  # nothing more is sent to a failed bus


def test_a_missing_servo_is_named_when_the_bus_opens() -> None:
    """A servo that does not answer the ping is named; a wrong model says which it is."""
    b = Bench(1)
    try:
        b.bus.silence(7)
        with pytest.raises(BackendError, match=r"servo 7 \(LB coxa\)"):
            b.backend()
    finally:
        b.close()
    b = Bench(2, {"model": "XL430-W250"})
    try:
        xm430 = servo_model("XM430-W350")
        config = dataclasses.replace(
            b.config, servos=tuple(dataclasses.replace(s, model=xm430) for s in b.config.servos)
        )
        with pytest.raises(BackendError, match="model number 1060, not a XM430-W350"):
            DynamixelHexapod(config)
    finally:
        b.close()


@pytest.mark.parametrize(
    ("table", "message"),
    [
        ({"legs": {"XX": {}}}, "names XX"),
        ({"legs": {"LF": {"ids": [1, 2, 4]}}}, "id 4 is used twice"),
        ({"protocol": 1, "model": "XM430-W350"}, "speaks protocol 2"),
        ({"model": "AX-99"}, "servo model 'AX-99'"),
        ({"legs": {"LF": {"zeros_deg": [0, 0, 0]}}}, "outside what a AX-12A turns to"),
        ({"baud": 12345}, "baud 12345"),
        ({"legs": {"LF": {"directions": [1, 0, 1]}}}, "is not 1 or -1"),
    ],
)
def test_hardware_table_errors_say_what_is_wrong(table: dict, message: str) -> None:
    """A malformed [hardware] table is refused with the entry named."""
    with pytest.raises(ConfigError, match=message):
        hardware_from_dict(SPEC, table, protocol=1)


@pytest.mark.parametrize(
    ("options", "message"),
    [
        ({"fault": "melt:5@2"}, "KIND one of silent, overheat, checksum, port"),
        ({"fault": "overheat:99@2"}, "no such servo"),
        ({"protocol": "3"}, "protocol '3' is not 1 or 2"),
        ({"baud": "57600"}, "no option baud"),
    ],
)
def test_servo_bus_options_are_checked(options: dict, message: str) -> None:
    """The emulated bus's options are refused with what is wrong, before anything opens."""
    from footfall.backends import BackendSetup
    from footfall.hardware.servo_bus import ServoBusHexapod

    with pytest.raises(ConfigError, match=message):
        ServoBusHexapod.open(BackendSetup(SPEC, SPEC.body_height, options=options))


def test_the_dynamixel_backend_needs_a_port() -> None:
    """Without a port in the table or the options, the backend says where to set one."""
    from footfall.backends import BackendSetup

    with pytest.raises(ConfigError, match="no port"):
        DynamixelHexapod.open(BackendSetup(SPEC, SPEC.body_height, options={"protocol": "1"}))


def test_a_servo_fault_needs_the_servo_bus(tmp_path) -> None:
    """--servo-fault without --servo-bus is refused."""
    from footfall.cli import main

    assert main(["walk", "--servo-fault", "silent:1@1", "--out", str(tmp_path)]) == 2


@pytest.mark.parametrize("protocol", [1, 2])
@settings(max_examples=20, deadline=None)
@given(noise=st.binary(min_size=1, max_size=300))
def test_the_emulated_bus_survives_noise_on_the_line(protocol: int, noise: bytes) -> None:
    """Any bytes on the line, malformed packets and false headers included, leave the
    servos answering the next instruction once the line has been quiet."""
    import dynamixel_sdk as sdk

    b = Bench(protocol)
    try:
        line = os.open(b.bus.path, os.O_RDWR | os.O_NOCTTY)
        try:
            os.write(line, noise)
            time.sleep(0.08)  # the line goes quiet: a half packet is dropped
        finally:
            os.close(line)
        port = sdk.PortHandler(b.bus.path)
        assert port.openPort()
        try:
            packets = sdk.PacketHandler(float(protocol))
            number, result, _ = packets.ping(port, 1)
            assert result == sdk.COMM_SUCCESS
            assert number == b.config.servos[0].model.model_number
        finally:
            port.closePort()
    finally:
        b.close()


def test_the_link_never_replaces_a_file(tmp_path) -> None:
    """--link naming an existing file is refused; an old link is replaced."""
    config = hardware_from_dict(SPEC, None, protocol=1)
    taken = tmp_path / "ttyDXL"
    taken.write_text("not a port")
    with pytest.raises(ConfigError, match="is not a link"):
        EmulatedBus(EmulatedServos(config), link=taken)
    assert taken.read_text() == "not a port"
    stale = tmp_path / "old"
    stale.symlink_to(tmp_path / "gone")
    bus = EmulatedBus(EmulatedServos(config), link=stale)
    try:
        assert stale.resolve() == Path(bus.path).resolve()
    finally:
        bus.close()
    assert not stale.is_symlink()
