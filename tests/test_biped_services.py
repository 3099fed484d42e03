"""The biped's services over zenoh (dissertation Appendix B3), and the station's biped view."""

from __future__ import annotations

import os
import subprocess
import sys
import time

import numpy as np

from footfall.messages import Ack, BipedPlan, NewMap, Obstacles, PlanningGoal, Trigger
from footfall.runtime.zenoh_bus import ZenohBus, ZenohConfig
from processes import stop
from test_zenoh_bus import free_port


def _served(endpoint: str, *source: str):
    command = [sys.executable, "-m", "footfall.cli", "robot", "--biped", *source]
    command += ["--listen", endpoint, "--seconds", "60"]
    return subprocess.Popen(command, env={**os.environ}, stdout=subprocess.PIPE, text=True)


def _ask(bus: ZenohBus, service: str, request, seconds: float = 20.0) -> Ack:
    end = time.monotonic() + seconds
    while True:  # the server may still be starting
        try:
            return bus.request(service, request, timeout=2.0)
        except Exception:
            if time.monotonic() > end:
                raise
            time.sleep(0.5)


def test_capture_new_map_clear_and_planning_over_the_network():
    """start_capture publishes the map's obstacles; start_planning publishes a plan around
    them (path, footsteps, COM) with no collision; new_map replaces them; clear removes
    them; a goal inside an obstacle is refused with the reason."""
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    robot = _served(endpoint, "--case", "8")
    try:
        with ZenohBus(ZenohConfig(connect=(endpoint,))) as bus:
            obstacles: list[Obstacles] = []
            plans: list[BipedPlan] = []
            bus.subscribe(Obstacles.TOPIC, obstacles.append)
            bus.subscribe(BipedPlan.TOPIC, plans.append)

            def settle() -> None:
                end = time.monotonic() + 2.0
                while time.monotonic() < end:
                    bus.spin(0.05)

            ack = _ask(bus, "start_capture", Trigger())
            assert ack.ok and "11 obstacles" in ack.text
            settle()
            assert len(obstacles[-1].x) == 11
            ack = _ask(bus, "start_planning", PlanningGoal(4.0, 2.0))
            assert ack.ok, ack.text
            settle()
            plan = plans[-1]
            assert plan.collisions == 0 and len(plan.footsteps) > 10
            np.testing.assert_allclose(plan.waypoints[-1], [4.0, 2.0])
            assert len(plan.com) > len(plan.footsteps)
            assert _ask(bus, "stop_capture", Trigger()).ok
            ack = _ask(bus, "new_map", NewMap(np.array([2.0]), np.array([0.0]), 0.3))
            assert ack.ok
            settle()
            assert obstacles[-1].x.tolist() == [2.0] and obstacles[-1].r.tolist() == [0.3]
            refused = _ask(bus, "start_planning", PlanningGoal(2.0, 0.0))
            assert not refused.ok and "obstacle" in refused.text
            assert _ask(bus, "clear", Trigger()).ok
            settle()
            assert len(obstacles[-1].x) == 0
            assert _ask(bus, "start_planning", PlanningGoal(3.0, 0.0)).ok
    finally:
        stop(robot)
    assert robot.returncode == 0


def test_the_biped_station_plans_to_a_clicked_goal_and_draws_the_plan():
    """The station's biped buttons and clicks reach the services; what comes back is drawn."""
    from footfall.station import Station

    endpoint = f"tcp/127.0.0.1:{free_port()}"
    robot = _served(endpoint, "--case", "3")
    try:
        with ZenohBus(ZenohConfig(connect=(endpoint,))) as bus:
            station = Station(bus, port=free_port(), biped=True)
            try:
                _ask(bus, "stop_capture", Trigger())  # the server is up
                assert station.call("start_capture", Trigger()).ok
                station.set_goal((4.0, 0.0))  # what a click on the ground does
                assert "start_planning done" in station.biped_text.content
                end = time.monotonic() + 5.0
                while station.robot.plan is None and time.monotonic() < end:
                    station.step()
                    bus.spin(0.05)
                assert station.robot.obstacles is not None and station.robot.plan is not None
                station.draw(time.monotonic())  # obstacles, path, footsteps, COM
                assert station.robot.plan.collisions == 0
            finally:
                station.close()
    finally:
        stop(robot)
