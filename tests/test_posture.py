"""Standing up from a limp pose and sitting down before the torque goes off."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from footfall.control_loop import WalkingGraph
from footfall.messages import JointTargets, Mode, ModeCommand, Posture, ServoStatus
from footfall.motion.posture import (
    FOOT_SPEED,
    sit_down,
    sitting_height,
    stance_in_body,
    stand_up,
)
from footfall.motion.walker import WalkController
from footfall.robot.kinematics import LegKinematics
from footfall.robot.spec import load_spec
from footfall.runtime.bus import InProcessBus
from footfall.sim.hexapod import MujocoHexapod

DT = 0.01
SPEC = load_spec("default")


@settings(max_examples=30, deadline=None)
@given(st.lists(st.floats(0.05, 0.95), min_size=18, max_size=18))
def test_standing_up_from_any_pose_keeps_rates_and_foot_speeds(fractions) -> None:
    """From any joint angles within the limits, the stand-up reaches the standing stance
    with every joint under the servo rate limit and every foot under the foot speed."""
    lower, upper = np.tile(SPEC.limits.lower, 6), np.tile(SPEC.limits.upper, 6)
    start = (lower + np.array(fractions) * (upper - lower)).reshape(6, 3)
    move = stand_up(SPEC, start, SPEC.body_height)
    assert move is not None
    kinematics = LegKinematics(SPEC)
    joints, feet = start, kinematics.forward_in_body(start)
    for _ in range(3000):
        targets = move.step(DT)
        assert np.abs(targets.positions - joints).max() <= SPEC.servo.max_rate * DT + 1e-9
        moved = kinematics.forward_in_body(targets.positions)
        assert np.linalg.norm(moved - feet, axis=1).max() <= FOOT_SPEED * DT + 1e-9
        joints, feet = targets.positions, moved
        if move.done:
            break
    assert move.done
    np.testing.assert_allclose(feet, stance_in_body(SPEC, SPEC.body_height), atol=1e-9)


def test_a_standing_robot_needs_no_stand_up() -> None:
    """Feet already at the standing stance: no move, the walk starts at once."""
    joints = LegKinematics(SPEC).inverse_in_body(stance_in_body(SPEC, SPEC.body_height))
    assert stand_up(SPEC, joints, SPEC.body_height) is None


def test_sitting_down_keeps_the_feet_in_place() -> None:
    """Sitting lowers the body straight down: the feet keep their x and y in the body."""
    joints = LegKinematics(SPEC).inverse_in_body(stance_in_body(SPEC, SPEC.body_height))
    move = sit_down(SPEC, joints)
    while not move.done:
        targets = move.step(DT)
    feet = LegKinematics(SPEC).forward_in_body(targets.positions)
    standing = stance_in_body(SPEC, SPEC.body_height)
    np.testing.assert_allclose(feet[:, :2], standing[:, :2], atol=1e-9)
    np.testing.assert_allclose(feet[:, 2], -sitting_height(SPEC) + SPEC.foot_radius)


@pytest.fixture(scope="module")
def limp_then_up_then_down():
    """The MuJoCo robot left limp for 2 s, switched to walking, then back to torque-off."""
    backend = MujocoHexapod(SPEC)
    bus = InProcessBus(check_encoding=True)
    graph = WalkingGraph.build(bus, backend, WalkController(SPEC))
    targets: list[tuple[float, JointTargets]] = []
    postures: list[tuple[float, Posture]] = []
    truth: list[tuple[float, np.ndarray, np.ndarray]] = []
    bus.subscribe(JointTargets.TOPIC, lambda m: targets.append((t, m)))
    bus.subscribe(ServoStatus.TOPIC, lambda m: postures.append((t, m.posture)))
    t = 0.0

    def run(seconds: float) -> None:
        nonlocal t
        for _ in range(round(seconds / DT)):
            graph.step(t, DT)
            state = backend.read()
            truth.append((t, state.position_body_in_world.copy(), state.feet_in_world.copy()))
            t += DT

    run(2.0)
    lying = backend.body_height_above()
    bus.publish(ModeCommand.TOPIC, ModeCommand(Mode.WALKING, t))
    run(5.0)
    standing = backend.body_height_above()
    bus.publish(ModeCommand.TOPIC, ModeCommand(Mode.TORQUE_OFF, t))
    run(3.0)
    return targets, postures, truth, lying, standing, backend


def test_the_robot_stands_up_from_limp_and_sits_down(limp_then_up_then_down) -> None:
    """Limp, the body lies low; walking, it rises to its standing height; torque-off, it
    lowers onto its belly and only then goes limp."""
    _, postures, _, lying, standing, backend = limp_then_up_then_down
    assert lying < sitting_height(SPEC) + 0.02
    assert standing == pytest.approx(SPEC.body_height, abs=0.01)
    changes = [p for k, (_, p) in enumerate(postures) if k == 0 or p is not postures[k - 1][1]]
    assert changes == [
        Posture.LIMP,
        Posture.RISING,
        Posture.STANDING,
        Posture.SITTING,
        Posture.LIMP,
    ]
    assert backend.torque is False
    assert backend.body_height_above() < sitting_height(SPEC) + 0.02


def test_standing_up_and_sitting_down_stay_under_the_limits(limp_then_up_then_down) -> None:
    """Joint targets change no faster than the spec's servo rate, and no foot moves faster
    than 0.2 m/s over the ground, while rising and while sitting (measured)."""
    targets, postures, truth, *_ = limp_then_up_then_down
    for posture in (Posture.RISING, Posture.SITTING):
        start = next(s for s, p in postures if p is posture)
        end = next(s for s, p in postures if s > start and p is not posture)
        sent = np.array([m.positions for s, m in targets if start <= s < end])
        assert len(sent) > 20
        rates = np.abs(np.diff(sent, axis=0)) / DT
        assert rates.max() <= SPEC.servo.max_rate + 1e-9
        feet = np.array([f for s, _, f in truth if start <= s < end])
        speeds = np.linalg.norm(np.diff(feet[..., :2], axis=0), axis=2) / DT
        assert speeds.max() < 0.2
