"""A dry run in two processes: `footfall servo-bus` and `footfall robot --hardware`, driven
over zenoh as a station drives a robot."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

from footfall.messages import (
    GaitState,
    GaitStatus,
    Mode,
    ModeCommand,
    Posture,
    ServoStatus,
    WalkCommand,
)
from footfall.runtime.zenoh_bus import ZenohBus, ZenohConfig
from test_robot_network import wait_for
from test_zenoh_bus import free_port


def footfall(*args: str) -> subprocess.Popen:
    """A footfall command in its own process."""
    env = {**os.environ, "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")}
    return subprocess.Popen(
        [sys.executable, "-m", "footfall.cli", *args],
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
    )


def stopped_saying(*processes: subprocess.Popen | None) -> str:
    """What processes said, once stopped with Ctrl-C (for a failing assertion's message)."""
    said = []
    for process in processes:
        if process is None:
            continue
        if process.poll() is None:
            process.send_signal(signal.SIGINT)
        try:
            said.append(process.communicate(timeout=20)[0].decode(errors="replace")[-4000:])
        except subprocess.TimeoutExpired:
            process.kill()
            said.append(process.communicate(timeout=5)[0].decode(errors="replace")[-4000:])
    return "\n---\n".join(said)


def start_servo_bus(link, *args: str) -> subprocess.Popen:
    """`footfall servo-bus` on flat ground serving its servos at ``link``, once it is there."""
    server = footfall("servo-bus", "--sim", "flat", "--link", str(link), "--seconds", "90", *args)
    end = time.monotonic() + 30
    while not link.is_symlink() and time.monotonic() < end and server.poll() is None:
        time.sleep(0.1)
    if not link.is_symlink():
        server.kill()
        raise AssertionError(server.communicate(timeout=5)[0].decode())
    return server


def test_the_robot_process_walks_on_the_emulated_bus_and_stops_on_the_watchdog(tmp_path):
    """The robot's process opens the emulated servos at the link, stands up when walking
    starts, steps while commands come, stands still on the watchdog when they stop, and
    sits down before it exits on Ctrl-C."""
    link = tmp_path / "ttyDXL"
    sensors = f"tcp/127.0.0.1:{free_port()}"
    robot_endpoint = f"tcp/127.0.0.1:{free_port()}"
    server = start_servo_bus(link, "--listen", sensors)
    robot = None
    try:
        robot = footfall(
            "robot", "--hardware", "default", "--port", str(link),
            "--camera-option", f"connect={sensors}", "--listen", robot_endpoint,
            "--seconds", "80", "--out", str(tmp_path / "out"),
        )  # fmt: skip
        status: list[GaitStatus] = []
        postures: list[Posture] = []
        with ZenohBus(ZenohConfig(connect=(robot_endpoint,))) as station:
            station.subscribe(GaitStatus.TOPIC, status.append)
            station.subscribe(ServoStatus.TOPIC, lambda m: postures.append(m.posture))
            assert wait_for(station, lambda: bool(status), 40), robot.communicate(timeout=5)[0]

            def walking() -> bool:
                now = time.monotonic()
                station.publish(ModeCommand.TOPIC, ModeCommand(Mode.WALKING, now))
                station.publish(WalkCommand.TOPIC, WalkCommand(speed=0.05, stamp=now))
                return status[-1].steps_taken >= 4

            assert wait_for(station, walking, 60), (
                f"last status {status[-1]}; postures {postures[-3:]}\n"
                + stopped_saying(robot, server)
            )
            assert Posture.RISING in postures and postures[-1] is Posture.STANDING
            assert status[-1].mode is Mode.WALKING
            # No more commands: the watchdog stands the robot still.
            assert wait_for(
                station,
                lambda: status[-1].command_age > 0.5 and status[-1].state is not GaitState.STEPPING,
                10,
            )
            still = status[-1]
            wait_for(station, lambda: False, 1.0)
            # Standing: no further step (the pose estimate may still be corrected).
            assert status[-1].steps_taken == still.steps_taken
            assert status[-1].state is not GaitState.STEPPING
            robot.send_signal(signal.SIGINT)
            output = robot.communicate(timeout=20)[0].decode()
            station.spin(0.5)
        assert robot.returncode == 0, output
        assert postures[-2:] == [Posture.SITTING, Posture.LIMP], output
    finally:
        for process in (robot, server):
            if process is not None and process.poll() is None:
                process.send_signal(signal.SIGINT)
                process.communicate(timeout=20)
