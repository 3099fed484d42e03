"""The walking controller without a simulator: gait sequencing, targets and safety."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from footfall.messages import GaitState, WalkCommand
from footfall.motion.gait import GAITS, GaitConfig
from footfall.motion.walker import WalkController

DT = 0.01


def drive(controller: WalkController, command: WalkCommand, seconds: float, t0: float = 0.0):
    """Run the controller alone; yields (t, targets) per tick."""
    for k in range(round(seconds / DT)):
        t = t0 + k * DT
        yield t, controller.update(t, command)


def test_standing_still_is_rest(default_spec):
    """With no motion commanded the robot rests on its rest stance."""
    controller = WalkController(default_spec)
    for _ in drive(controller, WalkCommand(speed=0.0), 1.0):
        assert controller.state is GaitState.REST
    np.testing.assert_allclose(
        controller.feet_in_body()[:, :2], default_spec.rest_feet_in_body()[:, :2]
    )


@pytest.mark.parametrize("kind", GAITS.names())
def test_supporting_feet_stay_fixed_in_the_world(default_spec, kind):
    """Eqs. 5.17-5.18: a foot in stance does not move in the world while the body walks."""
    controller = WalkController(default_spec, GaitConfig(kind=kind))
    previous = controller.feet_in_world.copy()
    was_swinging = controller.swinging.copy()
    for _ in drive(controller, WalkCommand(speed=0.05, yaw_rate=0.1), 6.0):
        stance = ~controller.swinging & ~was_swinging
        np.testing.assert_allclose(controller.feet_in_world[stance], previous[stance], atol=1e-12)
        previous = controller.feet_in_world.copy()
        was_swinging = controller.swinging.copy()


def test_tripod_supports_on_three_feet_and_alternates(default_spec):
    """Tripod: three feet swing at every instant of stepping and the two sets alternate."""
    controller = WalkController(default_spec, GaitConfig(kind="tripod"))
    sets = []
    for t, _ in drive(controller, WalkCommand(speed=0.1), 8.0):
        if t == 0.0:
            continue  # the first tick only sets the clock
        assert controller.state is GaitState.STEPPING
        assert controller.swinging.sum() == 3
        current = tuple(np.flatnonzero(controller.swinging))
        if not sets or sets[-1] != current:
            sets.append(current)
    assert len(sets) > 8
    assert all(a != b for a, b in itertools.pairwise(sets))
    assert set(sets) == {(0, 2, 4), (1, 3, 5)}


@pytest.mark.parametrize("kind", GAITS.names())
def test_feet_touch_down_on_their_targets_and_ground(default_spec, kind):
    """At every touchdown the foot is on the ground, where its swing was aimed."""
    controller = WalkController(default_spec, GaitConfig(kind=kind))
    targets = {}
    touchdowns = 0
    was_swinging = controller.swinging.copy()
    for _ in drive(controller, WalkCommand(speed=0.04), 8.0):
        for leg in np.flatnonzero(was_swinging & ~controller.swinging):
            np.testing.assert_allclose(controller.feet_in_world[leg], targets[leg], atol=1e-9)
            assert controller.feet_in_world[leg, 2] == pytest.approx(default_spec.foot_radius)
            touchdowns += 1
        targets = {int(leg): s.target for leg, s in controller.swings.items()}
        was_swinging = controller.swinging.copy()
    assert touchdowns >= 6


def test_reference_body_moves_at_the_commanded_speed(default_spec):
    """In steady walking the reference body advances at the commanded speed."""
    controller = WalkController(default_spec)
    command = WalkCommand(speed=0.1)
    list(drive(controller, command, 4.0))
    x0 = controller.pose.x
    list(drive(controller, command, 6.0, t0=4.0))
    assert (controller.pose.x - x0) / 6.0 == pytest.approx(0.1, rel=0.02)


def test_stops_and_returns_to_rest(default_spec):
    """When the command goes to zero the robot steps its feet home and rests."""
    controller = WalkController(default_spec)
    list(drive(controller, WalkCommand(speed=0.1), 3.0))
    list(drive(controller, WalkCommand(speed=0.0), 5.0, t0=3.0))
    assert controller.state is GaitState.REST
    rest = default_spec.rest_feet_in_body()[:, :2]
    np.testing.assert_allclose(
        controller.feet_in_body()[:, :2], rest, atol=default_spec.foot_radius
    )


def test_unreachable_command_freezes_with_the_leg_named(default_spec):
    """A body height no leg reaches freezes the robot, holding its last safe foot targets."""
    controller = WalkController(default_spec)
    held = None
    for _t, targets in drive(controller, WalkCommand(speed=0.0, body_height=0.5), 10.0):
        if controller.state is GaitState.FROZEN:
            held = held if held is not None else targets.feet_in_body.copy()
            np.testing.assert_array_equal(targets.feet_in_body, held)
    assert controller.state is GaitState.FROZEN
    assert "out of reach" in controller.frozen_reason
    assert any(name in controller.frozen_reason for name in default_spec.leg_names)
    # The held targets are a pose the legs can actually take.
    controller.kinematics.check_limits(controller.kinematics.inverse_in_body(held))


def test_speed_above_the_gait_maximum_is_capped(default_spec):
    """The controller never walks faster than its gait allows."""
    controller = WalkController(default_spec, GaitConfig(kind="wave"))
    list(drive(controller, WalkCommand(speed=1.0), 5.0))
    assert np.hypot(*controller.body_velocity_in_body) <= controller.config.max_speed + 1e-9


@pytest.mark.parametrize("overshoot_deg", [5.0, 20.0])
def test_a_swing_past_the_coxa_range_is_turned_back(default_spec, overshoot_deg):
    """A swinging foot asked to go beyond its coxa's range (the body lagging behind the
    plan) is brought back to the edge of the range, at the same reach, not refused."""
    from footfall.robot.kinematics import LegKinematics

    controller = WalkController(default_spec)
    controller.swinging[0] = True
    kin = LegKinematics(default_spec)
    rest = default_spec.rest_feet_in_body()
    yaw = kin.upper[0] + np.radians(overshoot_deg)
    in_leg = np.zeros((6, 3))
    in_leg[0] = [0.17 * np.cos(yaw), 0.17 * np.sin(yaw), -0.06]
    feet = rest.copy()
    feet[0] = kin.leg_to_body(in_leg)[0]
    assert not kin.reachable(0, feet[0])
    fixed = controller.solver.within_reach(feet, controller.swinging)
    assert kin.reachable(0, fixed[0])
    back_in_leg = kin.body_to_leg(fixed)[0]
    assert np.degrees(np.arctan2(back_in_leg[1], back_in_leg[0])) == pytest.approx(
        np.degrees(kin.upper[0]), abs=0.1
    )
    np.testing.assert_allclose(fixed[1:], feet[1:])  # other legs untouched


def test_the_body_height_waits_for_a_swinging_foot_to_land_within_reach(default_spec):
    """A swinging foot lands where it is sent (back where it lifted off, when a re-plan
    found no foothold). Asked to rise, the body rises while that landing point stays within
    the leg's reach, and waits once it would leave it, instead of landing the foot on a
    stretched leg that no command could bring back."""
    from footfall.robot.kinematics import LegKinematics

    kin = LegKinematics(default_spec)
    controller = WalkController(default_spec)
    controller.state = GaitState.STEPPING
    back = 2
    controller.swinging[back] = True
    # The landing point: straight out from the hip, reached from the body now but not from
    # a body 3 cm higher.
    start = controller.feet_in_body()
    direction = start[back, :2] - kin.mounts_in_body[back, :2]
    direction /= np.linalg.norm(direction)
    landing = start[back].copy()
    while kin.reachable(back, landing - [0.0, 0.0, 0.03]):
        landing[:2] += 0.002 * direction
    assert kin.reachable(back, landing)
    landing_in_world = controller.pose.points_to_world(landing[None])[0]
    landing_in_world[2] += controller.height
    controller.footholds.plan.targets = controller.feet_in_world.copy()
    controller.footholds.plan.targets[back] = landing_in_world
    command = WalkCommand(speed=0.0, body_height=controller.height + 0.06)
    height = controller.height
    for _ in range(100):
        controller._move_body(command, DT)
        target = controller.pose.points_to_body(landing_in_world[None])[0]
        target[2] -= controller.height
        assert kin.reachable(back, target)
    waited = controller.height
    assert height < waited < command.body_height - 0.005  # it rose, then waited
    near = landing_in_world.copy()
    near[:2] -= 0.03 * direction  # a landing point well within reach
    controller.footholds.plan.targets[back] = near
    controller._move_body(command, DT)
    assert controller.height > waited  # it rises on


def test_a_supporting_foot_near_the_edge_of_its_reach_does_not_hold_the_body_down(default_spec):
    """A supporting foot waits for the body only at the edge of its leg's reach, not at the
    planner's margin inside it: a hind foot left at the foot of a ramp, its leg stretched
    within the margin, lets the body climb on as long as the leg still reaches it."""
    from footfall.planning.terrain_planner import TerrainPlanner
    from footfall.robot.kinematics import LegKinematics

    kin = LegKinematics(default_spec)
    controller = WalkController(default_spec, planner=TerrainPlanner(default_spec))
    controller.state = GaitState.STEPPING
    back = 2
    margin = controller.footholds.reach_margin
    assert margin
    feet = controller.feet_in_body()
    direction = feet[back, :2] - kin.mounts_in_body[back, :2]
    direction /= np.linalg.norm(direction)
    # Out along the leg until a 5 mm rise takes it inside the margin, not out of reach.
    foot = feet[back].copy()
    while kin.reachable(back, foot - [0.0, 0.0, 0.005], margin):
        foot[:2] += 0.001 * direction
    assert kin.reachable(back, foot, margin) and kin.reachable(back, foot - [0.0, 0.0, 0.01])
    foot_in_world = controller.pose.points_to_world(foot[None])[0]
    foot_in_world[2] += controller.height
    controller.feet_in_world[back] = foot_in_world
    controller.footholds.plan.targets = controller.feet_in_world.copy()
    command = WalkCommand(speed=0.0, body_height=controller.height + 0.01)
    height = controller.height
    for _ in range(50):
        controller._move_body(command, DT)
    assert controller.height > height + 0.009
