"""The walking biped on the network: the station's goal walked in MuJoCo, its watchdog, and
the end of a walk with the step under way."""

from __future__ import annotations

import math
import os
import signal
import subprocess
import sys
import time

import mujoco
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from footfall.biped.body import load_biped_spec
from footfall.biped.footsteps import StepLimits, plan_footsteps
from footfall.biped.gait import GaitConfig, gait_pattern, step_at, stop_after_step
from footfall.messages import BipedStatus
from footfall.runtime.zenoh_bus import ZenohBus, ZenohConfig
from footfall.sim.biped_model import biped_mjcf
from footfall.sim.biped_sim import BipedSimulation
from footfall.sim.biped_walk import PatternRunner, stand
from processes import stop
from test_zenoh_bus import free_port

FEET = {"left": (0.0, 0.1, 0.0), "right": (0.0, -0.1, 0.0)}


@settings(max_examples=12, deadline=None)
@given(
    goal=st.tuples(st.floats(0.6, 2.0), st.floats(-1.0, 1.0)),
    when=st.floats(0.0, 1.0),
)
def test_a_walk_ends_with_the_step_under_way_and_the_feet_together(goal, when):
    """Stopped at any time, the walk finishes the step under way on its planned foothold,
    brings the other foot beside it, and the references do not jump: the ZMP is the old one
    until that step ends and the COM continues from where it was, as smoothly as before."""
    footsteps = plan_footsteps(np.array([(0.0, 0.0), goal]), StepLimits())
    config = GaitConfig()
    pattern = gait_pattern(footsteps, FEET, 0.6, config)
    t = when * pattern.duration
    stopped, steps = stop_after_step(pattern, footsteps, t, config)
    n = step_at(t, config)
    kept = min(n, len(footsteps.positions) - 1)
    np.testing.assert_allclose(steps.positions[: kept + 1], footsteps.positions[: kept + 1])
    end = config.hold_time + config.start_time + kept * config.step_time
    k = min(len(stopped.time), len(pattern.time))
    same = pattern.time[:k] <= end
    np.testing.assert_allclose(stopped.zmp[:k][same], pattern.zmp[:k][same])
    i = pattern.index(t)
    np.testing.assert_allclose(stopped.com[:i], pattern.com[:i])
    biggest = np.abs(np.diff(pattern.com, axis=0)).max()
    assert np.abs(np.diff(stopped.com, axis=0)).max() <= 1.5 * biggest + 1e-6
    # Feet side by side at the end, the step width apart, facing the same way.
    left, right = stopped.feet["left"][-1][:2], stopped.feet["right"][-1][:2]
    heading = stopped.foot_yaw["left"][-1]
    across = np.array([-math.sin(heading), math.cos(heading)])
    assert abs((left - right) @ across - 0.2) < 1e-6
    assert abs(stopped.foot_yaw["right"][-1] - heading) < 1e-9
    # It ends no later than the walk would have; one step after the step under way at most.
    assert stopped.duration <= pattern.duration + 1e-9
    assert len(steps.positions) <= n + 2


def test_archie_stops_standing_in_mujoco_when_told_to_mid_step():
    """In the simulator: a walk told to stop during its third step finishes that step,
    closes the feet and stands, without falling."""
    spec = load_biped_spec()
    sim = BipedSimulation(spec, mujoco.MjModel.from_xml_string(biped_mjcf(spec)))
    footsteps = plan_footsteps(np.array([(0.0, 0.0), (2.0, 0.0)]), StepLimits())
    config = GaitConfig(step_time=0.8, step_height=spec.step_height)
    pattern = gait_pattern(footsteps, FEET, stand(sim, FEET), config)
    runner = PatternRunner(sim, pattern)
    while runner.t < config.hold_time + config.start_time + 2.3 * config.step_time:
        assert runner.tick()
    stopped, steps = stop_after_step(pattern, footsteps, runner.t, config)
    runner.switch(stopped)
    while runner.tick():
        pass
    run = runner.result()
    assert not run.fell and run.stopped is None
    assert len(steps.positions) == 5  # the stance, three steps, the closing step
    left, right = sim.sole("left"), sim.sole("right")
    assert abs(left[0] - right[0]) < 0.03 and abs(abs(left[1] - right[1]) - 0.2) < 0.03
    assert left[0] == np.clip(left[0], 0.3, 0.5)  # three steps of 0.15 m, no more


def _robot(endpoint: str, room: int) -> subprocess.Popen:
    command = [sys.executable, "-m", "footfall", "robot", "--biped", "--room", str(room)]
    command += ["--listen", endpoint, "--seconds", "150"]
    return subprocess.Popen(command, env={**os.environ}, stdout=subprocess.PIPE, text=True)


def _station(endpoint: str, goal: tuple[float, float]) -> subprocess.Popen:
    command = [sys.executable, "-m", "footfall", "station", "--biped", "--connect", endpoint]
    command += ["--port", str(free_port()), "--goal", *(str(v) for v in goal)]
    return subprocess.Popen(command, env={**os.environ}, stdout=subprocess.DEVNULL)


def test_the_station_walks_archie_to_its_goal_and_archie_stops_when_it_dies():
    """Two processes, a third watching: the station's goal is planned to and walked in
    MuJoCo; the station killed mid-walk, Archie ends its step, brings its feet together and
    stands; a new station's goal is then walked to the end, no fall, no collision."""
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    goal = (2.6, -0.3)
    robot = _robot(endpoint, 5)
    stations: list[subprocess.Popen] = []
    try:
        with ZenohBus(ZenohConfig(connect=(endpoint,))) as bus:
            seen: list[BipedStatus] = []
            bus.subscribe(BipedStatus.TOPIC, seen.append)

            def wait_for(check, seconds: float) -> BipedStatus:
                end = time.monotonic() + seconds
                while time.monotonic() < end:
                    bus.spin(0.05)
                    if seen and check(seen[-1]):
                        return seen[-1]
                raise AssertionError(f"timed out; last status {seen[-1] if seen else None}")

            wait_for(lambda s: s.state == "standing", 60)
            stations.append(_station(endpoint, goal))
            wait_for(lambda s: s.state == "walking" and s.footsteps >= 4, 60)
            stations[-1].send_signal(signal.SIGKILL)
            stations[-1].wait(timeout=10)
            killed = time.monotonic()
            stopping = wait_for(lambda s: s.state != "walking", 5)
            assert stopping.state in ("stopping", "standing"), stopping
            assert "no mode command" in stopping.text
            stood = wait_for(lambda s: s.state == "standing", 10)
            assert time.monotonic() - killed < 6.0  # a step, the closing step, settling
            assert math.isnan(stood.goal[0]) and "feet together" in stood.text
            left, right = stood.feet
            across = np.array([-math.sin(stood.heading), math.cos(stood.heading)])
            along = np.array([math.cos(stood.heading), math.sin(stood.heading)])
            assert abs((left[:2] - right[:2]) @ along) < 0.04
            assert abs((left[:2] - right[:2]) @ across - 0.2) < 0.04
            still = wait_for(lambda s: s.stamp > stood.stamp + 2.0, 5)
            assert still.footsteps == stood.footsteps and still.state == "standing"
            assert np.linalg.norm(still.com - stood.com) < 0.01
            assert still.com[0] < goal[0] - 0.5  # stopped on the way, not at the goal

            stations.append(_station(endpoint, goal))
            wait_for(lambda s: s.state == "walking", 30)
            done = wait_for(lambda s: s.state != "walking", 120)
            assert done.state == "standing" and "at the goal" in done.text, done
            assert np.hypot(*(done.com - goal)) < 0.25
            assert done.collisions == 0
    finally:
        for station in stations:
            station.kill()
            station.wait(timeout=10)
        stop(robot)
    assert robot.returncode == 0
