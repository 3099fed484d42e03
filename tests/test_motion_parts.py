"""The walking controller's parts, each alone: shaping, governor, scheduler, footholds,
feedback, leg solver, safety."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from footfall.errors import UnreachableTargetError
from footfall.mapping.snapshot import MapSnapshot
from footfall.messages import RobotState, WalkCommand
from footfall.motion.command_shaping import CommandShaper
from footfall.motion.feedback import BodyFeedback, FeedbackConfig
from footfall.motion.foothold_policy import BlindFootholds, MappedFootholds, StepContext
from footfall.motion.gait import GaitConfig
from footfall.motion.gait_scheduler import GaitScheduler
from footfall.motion.leg_solver import LegSolver
from footfall.motion.safety import MAP_FRAMES_BEFORE_RETRY, SafetyMonitor
from footfall.motion.stroke_governor import StrokeGovernor
from footfall.planning.step_plan import NoFoothold
from footfall.planning.terrain_planner import TerrainPlanner
from footfall.robot.kinematics import LegKinematics
from footfall.robot.planar import PlanarPose
from footfall.robot.spec import load_spec
from footfall.scoring.walkability import score_map

TRIPOD = GaitConfig(kind="tripod").for_robot(load_spec("default"))
NO_FEEDBACK = BodyFeedback(None, None)


def _standing(spec, height=None):
    feet = spec.rest_feet_in_body(spec.body_height if height is None else height)
    feet[:, 2] += spec.foot_radius
    return feet


# Command shaping ------------------------------------------------------------------------
@settings(max_examples=50, deadline=None)
@given(vx=st.floats(-1, 1), vy=st.floats(-1, 1), yaw=st.floats(-3, 3), dt=st.floats(1e-3, 0.1))
def test_shaping_never_exceeds_the_rate_limits_or_the_top_speed(vx, vy, yaw, dt):
    """Each update changes the velocity by at most a dt and the yaw rate by alpha dt, and
    the shaped speed converges to the command capped at the gait's top speed."""
    shaper = CommandShaper(TRIPOD, 0.09)
    speed = math.hypot(vx, vy)
    command = WalkCommand((vx, vy) if speed > 1e-6 else (1.0, 0.0), speed, 0.09, yaw)
    for _ in range(int(2.0 / dt) + 2):
        before, yaw_before = np.array(shaper.velocity), shaper.yaw_rate
        shaper.shape(command, dt)
        assert (
            np.hypot(*(np.array(shaper.velocity) - before))
            <= TRIPOD.acceleration_limit * dt + 1e-12
        )
        assert abs(shaper.yaw_rate - yaw_before) <= TRIPOD.yaw_acceleration_limit * dt + 1e-12
    assert math.hypot(*shaper.velocity) == pytest.approx(min(speed, TRIPOD.max_speed), abs=1e-9)
    assert shaper.yaw_rate == pytest.approx(yaw, abs=1e-9)
    shaper.stop()
    assert not shaper.moving


# Stroke governor ------------------------------------------------------------------------
@settings(max_examples=100, deadline=None)
@given(
    offset=st.tuples(st.floats(-0.1, 0.1), st.floats(-0.1, 0.1)),
    u=st.tuples(st.floats(-0.3, 0.3), st.floats(-0.3, 0.3)).filter(lambda v: math.hypot(*v) > 1e-3),
)
def test_stroke_scale_keeps_the_foot_within_its_stroke(default_spec, offset, u):
    """Blind: a foot within its stroke stays within it after drifting by k u."""
    kin = LegKinematics(default_spec)
    governor = StrokeGovernor(TRIPOD, kin, default_spec.rest_feet_in_body(), None)
    reach = 0.5 * TRIPOD.stride * TRIPOD.duty_factor + TRIPOD.stroke_margin
    o, v = np.array(offset), np.array(u)
    k = governor.stroke_scale(o, v)
    assert 0.0 <= k <= 1.0
    if np.hypot(*o) <= reach:
        assert np.hypot(*(o + k * v)) <= reach + 1e-9


def test_reach_scale_keeps_the_foot_in_the_workspace(default_spec):
    """Mapped: the governor slows the body so a supporting foot stays within reach, and
    leaves the twist alone when nothing is at risk."""
    kin = LegKinematics(default_spec)
    governor = StrokeGovernor(TRIPOD, kin, default_spec.rest_feet_in_body(), 0.01)
    feet = _standing(default_spec)
    u = np.array([-0.4, 0.0])  # far more than the leg reaches
    k = governor.reach_scale(0, feet[0], u)
    assert 0.0 < k < 1.0
    moved = feet[0].copy()
    moved[:2] += k * u
    assert kin.reachable(0, moved, 0.01)
    stance = np.ones(6, dtype=bool)
    assert governor.scale(feet, stance, (0.0, 0.0), 0.0, np.ones(6)) == 1.0


def test_the_governor_counts_the_body_rising_before_a_foot_lifts(default_spec):
    """A supporting hind foot that the body's drift leaves just within reach, with the body
    about to rise to a new floor: the governor lets the body drift fully on a level floor,
    and slows it when the rise is counted, so the foot stays reached once the body has
    risen."""
    kin = LegKinematics(default_spec)
    governor = StrokeGovernor(TRIPOD, kin, default_spec.rest_feet_in_body(), 0.01)
    hind = default_spec.leg_names.index("LB")
    feet = _standing(default_spec)
    drift = np.array([-0.1, 0.0, 0.0])  # 0.1 m/s until lift-off in 1 s
    while kin.reachable(hind, feet[hind] + drift - [0.002, 0.0, 0.0], 0.01):
        feet[hind, 0] -= 0.002
    stance = np.zeros(6, dtype=bool)
    stance[hind] = True
    horizons = np.ones(6)
    rise = np.full(6, 0.03)
    assert governor.scale(feet, stance, (0.1, 0.0), 0.0, horizons) == 1.0
    risen = governor.scale(feet, stance, (0.1, 0.0), 0.0, horizons, rise)
    assert risen < 1.0
    after = feet[hind] + risen * drift - [0.0, 0.0, rise[hind]]
    assert kin.reachable(hind, after, 0.01) or risen == 0.0


def test_a_swinging_foot_beyond_the_stretched_leg_is_drawn_in(default_spec):
    """A foot lifted off a stretched leg as the body rose is out of reach below the hip,
    where lowering it cannot help: the solver draws it in towards the leg until reached,
    and moves it no farther than that."""
    kin = LegKinematics(default_spec)
    solver = LegSolver(kin, default_spec.foot_radius)
    feet = _standing(default_spec)
    back = 2 if default_spec.leg_names[2].endswith("B") else 3
    out_of_reach = feet.copy()
    direction = feet[back, :2] - kin.mounts_in_body[back, :2]
    direction /= np.linalg.norm(direction)
    while kin.reachable(back, out_of_reach[back]):
        out_of_reach[back, :2] += 0.002 * direction
    out_of_reach[back, :2] += 0.002 * direction
    assert not kin.reachable(back, out_of_reach[back] - [0.0, 0.0, 0.1])
    swing = np.zeros(6, dtype=bool)
    swing[back] = True
    out = solver.solve(
        out_of_reach, swing, PlanarPose(), NO_FEEDBACK, ((0.0, 0.0), 0.0), np.zeros((6, 3))
    )
    assert kin.reachable(back, out.feet_in_body[back])
    assert np.linalg.norm(out.feet_in_body[back] - out_of_reach[back]) < 0.01
    with pytest.raises(UnreachableTargetError):
        solver.solve(
            out_of_reach,
            np.zeros(6, dtype=bool),
            PlanarPose(),
            NO_FEEDBACK,
            ((0.0, 0.0), 0.0),
            np.zeros((6, 3)),
        )


def test_a_swinging_foot_lifted_high_beside_the_hip_is_lowered_into_reach(default_spec):
    """A swing lifted over an obstacle while its foot passes beside the hip can put the
    foot above what the folded leg reaches, further above it than a step height: the
    solver lowers it straight down, as little as the leg needs, instead of freezing."""
    kin = LegKinematics(default_spec)
    solver = LegSolver(kin, default_spec.foot_radius)
    feet = _standing(default_spec)
    back = 2
    high = feet.copy()
    high[back] = kin.mounts_in_body[back] + [-0.04, 0.04, 0.07]  # above and beside the hip
    assert not kin.reachable(back, high[back] - [0.0, 0.0, 0.1])
    swing = np.zeros(6, dtype=bool)
    swing[back] = True
    out = solver.solve(high, swing, PlanarPose(), NO_FEEDBACK, ((0.0, 0.0), 0.0), np.zeros((6, 3)))
    lowered = out.feet_in_body[back]
    assert kin.reachable(back, lowered)
    np.testing.assert_allclose(lowered[:2], high[back, :2])
    assert lowered[2] < high[back, 2] - 0.1
    assert not kin.reachable(back, lowered + [0.0, 0.0, 0.006])  # no lower than needed
    np.testing.assert_allclose(out.feet_in_body[~swing], feet[~swing], atol=1e-12)


# Gait scheduler -------------------------------------------------------------------------
def test_scheduler_alternates_tripods_and_times_steps(default_spec):
    """After the first tripod (from the walk direction), the tripods alternate; each leg's
    next lift-off is within one cycle; the support after a tripod step is its swing set."""
    s = GaitScheduler(
        TRIPOD, default_spec.rest_feet_in_body(), default_spec.mount_positions_in_body
    )
    shaper = CommandShaper(TRIPOD, 0.09)
    shaper.shape(WalkCommand(speed=0.1), 1.0)
    feet = _standing(default_spec)
    sets = [
        tuple(np.flatnonzero(s.choose_group(shaper, np.zeros(6, bool), lambda: feet)))
        for _ in range(4)
    ]
    assert sets[0] != sets[1] and sets[0] == sets[2] and sets[1] == sets[3]
    s.begin_step(2.0, shaper)
    assert s.step_duration == pytest.approx(
        TRIPOD.step_duration(shaper.foot_speed(default_spec.rest_feet_in_body()))
    )
    horizons = s.liftoff_horizons(2.0)
    swinging = np.isin(np.arange(6), sets[-1])
    np.testing.assert_allclose(horizons[~swinging], s.step_duration)
    np.testing.assert_allclose(horizons[swinging], 2 * s.step_duration)
    np.testing.assert_array_equal(s.support_after(swinging), swinging)
    assert s.step_over(2.0 + s.step_duration) and not s.step_over(2.0 + 0.5 * s.step_duration)


def test_a_step_started_while_the_body_accelerates_is_timed_for_the_command(any_spec):
    """A walk starting from rest: the twist is still small when the first step starts, but
    the body will reach the commanded speed before the step ends. The step is timed for
    the command, so the supporting feet travel no more than a stride; timed for the twist
    at its start it would last the longest step and they would trail twice as far."""
    gait = GaitConfig(kind="tripod").for_robot(any_spec)
    rest = any_spec.rest_feet_in_body()
    s = GaitScheduler(gait, rest, any_spec.mount_positions_in_body)
    shaper = CommandShaper(gait, any_spec.body_height)
    command = WalkCommand(speed=0.1, yaw_rate=0.3)
    shaper.shape(command, 0.01)  # one tick into the walk
    s.begin_step(0.0, shaper)
    held = CommandShaper(gait, any_spec.body_height)
    held.velocity, held.yaw_rate = (0.1, 0.0), 0.3
    assert s.step_duration == pytest.approx(gait.step_duration(held.foot_speed(rest)))
    assert held.foot_speed(rest) * s.step_duration <= gait.stride / (len(gait.groups) - 1)
    slowing = CommandShaper(gait, any_spec.body_height)
    slowing.velocity = (0.1, 0.0)
    slowing.shape(WalkCommand(speed=0.0), 0.01)  # asked to stop: timed for the speed it has
    assert slowing.foot_speed(rest) == pytest.approx(0.1, abs=0.006)


def test_scheduler_steps_back_to_rest_only_for_feet_out_of_place(default_spec):
    """Standing still, only a group with a foot off its rest position steps."""
    s = GaitScheduler(
        TRIPOD, default_spec.rest_feet_in_body(), default_spec.mount_positions_in_body
    )
    shaper = CommandShaper(TRIPOD, 0.09)
    off = np.zeros(6, dtype=bool)
    assert not s.choose_group(shaper, off, lambda: None).any()
    off[3] = True
    assert s.choose_group(shaper, off, lambda: None)[3]


# Foothold policies ----------------------------------------------------------------------
def _context(spec, swing):
    feet = _standing(spec) - [0.0, 0.0, spec.body_height]
    return StepContext(
        now=0.0,
        pose=PlanarPose(),
        body_z=spec.body_height,
        velocity=(0.1, 0.0),
        yaw_rate=0.0,
        step_start=0.0,
        step_duration=0.75,
        groups=2,
        speed_scale=1.0,
        height_rate_limit=0.07,
        height_correction=0.0,
        feet_in_world=feet + [0.0, 0.0, spec.body_height],
        support_after=swing.copy(),
    )


def _flat_planner(spec, hole_x=None):
    n = 100
    heights = np.zeros((n, n))
    if hole_x is not None:
        heights[:, :] = -0.5  # a pit everywhere but under the feet now
        heights[: int((hole_x + 1.0) / 0.02), :] = 0.0
    snapshot = MapSnapshot(heights, np.ones((n, n), bool), (-1.0, -1.0), 0.02, np.zeros((n, n)))
    planner = TerrainPlanner(spec)
    planner.update(snapshot, score_map(snapshot))
    return planner


def test_blind_footholds_are_the_nominal_ones(default_spec):
    """Blind: the targets are the nominal footholds, unchanged."""
    policy = BlindFootholds()
    swing = np.array([True, False, True, False, True, False])
    nominal = _standing(default_spec) + [0.05, 0.0, 0.0]
    out = policy.plan_step(_context(default_spec, swing), nominal, swing)
    np.testing.assert_array_equal(out, nominal)
    assert policy.floor(_context(default_spec, swing), out, swing, nominal, 0.09) is None


def test_mapped_footholds_land_on_valid_cells_and_say_when_none_is_left(default_spec):
    """On flat mapped ground the chosen footholds are the nominal ones; over a pit the
    policy returns a NoFoothold naming the leg, and a re-plan mid-swing that finds none
    sends the foot back to where it lifted off and keeps the freeze pending."""
    spec = default_spec
    swing = np.array([True, False, True, False, True, False])
    feet = _standing(spec) - [0.0, 0.0, spec.body_height]
    nominal = feet.copy()
    nominal[:, 0] += 0.04
    policy = MappedFootholds(_flat_planner(spec), spec.foot_radius)
    targets = policy.plan_step(_context(spec, swing), nominal, swing)
    assert not isinstance(targets, NoFoothold)
    np.testing.assert_allclose(targets[swing, :2], nominal[swing, :2], atol=0.011)
    pit = MappedFootholds(_flat_planner(spec, hole_x=0.0), spec.foot_radius)
    far = nominal.copy()
    far[:, 0] += 0.3
    refused = pit.plan_step(_context(spec, swing), far, swing)
    assert isinstance(refused, NoFoothold) and refused.leg in spec.leg_names
    pit.plan.version = -1  # a new map arrived
    lifted_from = _context(spec, swing).feet_in_world
    starts = {int(leg): lifted_from[leg] for leg in np.flatnonzero(swing)}
    out, replanned = pit.current_targets(_context(spec, swing), far, swing, starts)
    assert not replanned and pit.plan.pending_freeze is not None
    np.testing.assert_array_equal(out[swing], lifted_from[swing])


def test_a_foot_sent_back_never_lands_out_of_reach(default_spec):
    """A re-plan that finds no foothold stops the body; a foot whose lift-off point the
    body has left out of its leg's reach keeps its planned target instead, and every
    swinging foot lands where its leg reaches it."""
    spec = default_spec
    swing = np.array([True, False, True, False, True, False])
    before = _context(spec, swing)
    lifted_from = before.feet_in_world
    policy = MappedFootholds(_flat_planner(spec), spec.foot_radius)
    planned = policy.plan_step(before, lifted_from - [0.06, 0.0, 0.0], swing)  # backwards
    assert not isinstance(planned, NoFoothold)
    planned = planned.copy()
    now = replace(before, pose=PlanarPose(-0.1, 0.0, 0.0))  # the body walked on 10 cm
    kin = LegKinematics(spec)

    def reaches(leg, foot_in_world):
        foot_in_body = now.pose.points_to_body(foot_in_world)
        return kin.reachable(leg, foot_in_body - [0.0, 0.0, now.body_z], policy.reach_margin)

    left_behind = [leg for leg in np.flatnonzero(swing) if not reaches(leg, lifted_from[leg])]
    assert left_behind  # the case under test: a lift-off point out of reach
    policy.planner = _flat_planner(spec, hole_x=-0.5)  # a new map: a pit under every target
    policy.plan.version = -1
    starts = {int(leg): lifted_from[leg] for leg in np.flatnonzero(swing)}
    out, _ = policy.current_targets(now, lifted_from - [0.06, 0.0, 0.0], swing, starts)
    assert policy.plan.pending_freeze is not None
    for leg in np.flatnonzero(swing):
        assert reaches(leg, out[leg])
        expected = planned[leg] if leg in left_behind else lifted_from[leg]
        np.testing.assert_array_equal(out[leg], expected)


# Feedback -------------------------------------------------------------------------------
def test_feedback_opposes_tilt_and_stays_bounded(default_spec):
    """A body rolled right is commanded to roll left, never beyond the limit; without a
    configuration nothing is corrected."""
    kin = LegKinematics(default_spec)
    feet = _standing(default_spec) - [0.0, 0.0, 0.0]
    angles = kin.inverse_in_body(_standing(default_spec) - [0, 0, 0])
    state = RobotState(0.0, angles, np.zeros((6, 3)), Rotation.from_euler("x", 0.1), np.zeros(3))
    fb = BodyFeedback(FeedbackConfig(), kin)
    for _ in range(1000):
        fb.update(state, 0.01, np.zeros(6, bool), feet, default_spec.body_height)
    assert fb.tilt_correction[0] == pytest.approx(-FeedbackConfig().tilt_limit)
    assert abs(fb.height_correction) <= FeedbackConfig().height_limit
    none = BodyFeedback(None, kin)
    none.update(state, 0.01, np.zeros(6, bool), feet, 0.09)
    assert not none.tilt_correction.any() and none.height_correction == 0.0


# Leg solver -----------------------------------------------------------------------------
def test_solver_targets_are_reachable_and_an_unreachable_stance_foot_raises(default_spec):
    """Standing, the solver's targets are the feet (no rolling yet) and reachable; a swing
    foot out of reach is brought in; a supporting foot out of reach raises."""
    kin = LegKinematics(default_spec)
    solver = LegSolver(kin, default_spec.foot_radius)
    feet = _standing(default_spec)
    none = np.zeros(6, dtype=bool)
    out = solver.solve(feet, none, PlanarPose(), NO_FEEDBACK, ((0.0, 0.0), 0.0), np.zeros((6, 3)))
    np.testing.assert_allclose(out.feet_in_body, feet, atol=1e-12)
    np.testing.assert_allclose(out.velocities_in_body, 0.0)
    high = feet.copy()
    while kin.reachable(0, high[0]):
        high[0, 2] += 0.005  # a swing path lifted just beyond what the leg reaches
    swing = none.copy()
    swing[0] = True
    out = solver.solve(high, swing, PlanarPose(), NO_FEEDBACK, ((0.0, 0.0), 0.0), np.zeros((6, 3)))
    assert kin.reachable(0, out.feet_in_body[0])
    far = feet.copy()
    far[0, :2] *= 3.0  # half a metre out: beyond the leg
    with pytest.raises(UnreachableTargetError, match="leg LF"):
        solver.solve(far, none, PlanarPose(), NO_FEEDBACK, ((0.0, 0.0), 0.0), np.zeros((6, 3)))


@settings(max_examples=60, deadline=None)
@given(
    leg=st.integers(0, 5),
    distance=st.floats(0.0005, 0.03),
    bearing_deg=st.floats(-180.0, 180.0),
)
@example(leg=0, distance=0.0005, bearing_deg=60.0)
def test_a_supporting_foot_under_its_hip_is_turned_into_the_coxa_range(
    default_spec, leg, distance, bearing_deg
):
    """A supporting foot a few millimetres from its coxa axis, on a bearing beyond the
    coxa's range (the body's feedback swings such a coxa by tens of degrees per millimetre):
    when turning it about the axis into the range moves it by at most NEAR_AXIS_SLIP_M, the
    solver does so and the leg reaches it; otherwise it raises, as for any foot the leg
    cannot reach."""
    from footfall.motion.leg_solver import NEAR_AXIS_SLIP_M

    kin = LegKinematics(default_spec)
    solver = LegSolver(kin, default_spec.foot_radius)
    feet = _standing(default_spec)
    points = np.zeros((6, 3))
    bearing = math.radians(bearing_deg)
    points[leg] = [distance * math.cos(bearing), distance * math.sin(bearing), 0.0]
    asked = feet.copy()
    asked[leg, :2] = kin.leg_to_body(points)[leg, :2]
    low, high = kin.lower[0], kin.upper[0]
    beyond = not low <= bearing <= high
    turn = max(low - bearing, bearing - high, 0.0)
    slip = 2.0 * distance * math.sin(0.5 * min(turn, math.pi))
    none = np.zeros(6, dtype=bool)

    def solve():
        return solver.solve(
            asked, none, PlanarPose(), NO_FEEDBACK, ((0.0, 0.0), 0.0), np.zeros((6, 3))
        )

    if beyond and slip > NEAR_AXIS_SLIP_M + 1e-4:
        with pytest.raises(UnreachableTargetError, match="coxa"):
            solve()
        return
    if slip > NEAR_AXIS_SLIP_M - 1e-4 and beyond:
        return  # on the rule's edge: either answer is right
    out = solve().feet_in_body
    assert np.linalg.norm(out[leg] - asked[leg]) <= NEAR_AXIS_SLIP_M + 1e-9
    angles = kin.inverse_in_body(out)
    assert low - 1e-9 <= angles[leg, 0] <= high + 1e-9
    others = np.arange(6) != leg
    np.testing.assert_allclose(out[others], asked[others], atol=1e-12)
    # A bearing on the range's limit itself may come back from the body frame a rounding
    # error beyond it, and is then turned inside like any foot beyond the range.
    on_limit = min(abs(bearing - low), abs(bearing - high)) < 1e-9
    if not beyond and not on_limit:
        np.testing.assert_allclose(out[leg], asked[leg], atol=1e-12)


def test_solver_rates_are_the_feet_moving_against_the_body(default_spec):
    """With the body moving at v, a planted foot moves at -v in the body frame."""
    solver = LegSolver(LegKinematics(default_spec), default_spec.foot_radius)
    out = solver.solve(
        _standing(default_spec),
        np.zeros(6, bool),
        PlanarPose(),
        NO_FEEDBACK,
        ((0.1, 0.02), 0.0),
        np.zeros((6, 3)),
    )
    np.testing.assert_allclose(out.velocities_in_body[:, :2], [[-0.1, -0.02]] * 6)


# Safety ---------------------------------------------------------------------------------
def test_safety_resumes_on_a_new_command_or_a_fresh_map():
    """Frozen for want of a foothold: a steering wobble does not resume, a changed command
    or MAP_FRAMES_BEFORE_RETRY new maps do; a freeze no map can help waits for a command."""
    walk = WalkCommand(speed=0.1)
    safety = SafetyMonitor()
    safety.freeze("leg LF: no foothold", walk, map_version=10)
    assert not safety.may_resume(WalkCommand(speed=0.1, yaw_rate=0.05), 11)
    assert safety.may_resume(WalkCommand(speed=0.1), 10 + MAP_FRAMES_BEFORE_RETRY)
    assert safety.may_resume(WalkCommand(speed=0.0), 10)
    safety.freeze("leg LF: out of reach", walk, map_version=None)
    assert not safety.may_resume(walk, 1000)


def test_a_stall_of_two_cycles_freezes_naming_the_leg_pulled_back_most():
    """Steps that make no progress while walking freeze after two gait cycles, and the
    reason names the leg whose foothold was pulled back furthest."""
    safety = SafetyMonitor()
    nominal = np.zeros((6, 3))
    targets = nominal.copy()
    targets[4, 0] = -0.12
    names = ("LF", "LM", "LB", "RB", "RM", "RF")
    reasons = [safety.stalled(0.0, 0.1, 2, True, nominal, targets, names) for _ in range(4)]
    assert reasons[:3] == [None, None, None]
    assert reasons[3].reason.startswith("leg RM: blocked") and reasons[3].leg == "RM"
    assert safety.stalled(0.0, 0.1, 2, False, nominal, targets, names) is None
