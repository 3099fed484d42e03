"""The body's incline: frames, the ground's slope, the pitch a slope asks for, and a walk."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from footfall.mapping.snapshot import MapSnapshot
from footfall.messages import WalkCommand
from footfall.motion.gait import GaitConfig
from footfall.motion.incline import (
    FULL_RATIO,
    ground_slope,
    level_slope_limit,
    wanted_pitch,
)
from footfall.motion.walker import WalkController
from footfall.planning.terrain_planner import TerrainPlanner
from footfall.robot.kinematics import LegKinematics
from footfall.robot.limits import height_range
from footfall.robot.planar import PlanarPose, inclined_to_level, level_to_inclined
from footfall.robot.spec import load_spec
from footfall.scoring.walkability import score_map

angles = st.floats(-1.2, 1.2, allow_nan=False)
coordinates = st.floats(-1.0, 1.0, allow_nan=False)


@given(angles, st.lists(st.tuples(coordinates, coordinates, coordinates), min_size=1, max_size=6))
def test_the_inclined_frame_turns_about_the_body_y_axis_and_back(pitch, points):
    """A rotation about y: lengths and y kept, the inverse undoes it, and a pitch nose down
    (positive) puts a point ahead of the body below its inclined x axis higher up in it."""
    p = np.array(points)
    inclined = level_to_inclined(p, pitch)
    assert np.allclose(np.linalg.norm(inclined, axis=1), np.linalg.norm(p, axis=1))
    assert np.allclose(inclined[:, 1], p[:, 1])
    assert np.allclose(inclined_to_level(inclined, pitch), p)
    # The body's own x axis, nose down by a positive pitch, points below the horizon.
    nose = inclined_to_level(np.array([1.0, 0.0, 0.0]), pitch)
    assert nose[2] == pytest.approx(-math.sin(pitch))


@given(
    st.floats(-0.6, 0.6),
    st.floats(-math.pi, math.pi),
    st.floats(-0.5, 0.5),
    st.integers(0, 2**31 - 1),
)
def test_the_ground_slope_is_the_plane_s_along_the_heading(slope, yaw, sideways, seed):
    """Points on a plane rising at ``slope`` along the heading (and at any rate across it)
    give back that slope, whatever the heading."""
    rng = np.random.default_rng(seed)
    pose = PlanarPose(rng.uniform(-1, 1), rng.uniform(-1, 1), yaw)
    local = rng.uniform(-0.3, 0.3, size=(6, 2))
    local[0, 0], local[1, 0] = -0.2, 0.2  # spread along the heading
    points = np.zeros((6, 3))
    points[:, :2] = pose.points_to_world(local)
    points[:, 2] = math.tan(slope) * local[:, 0] + sideways * local[:, 1] + 0.3
    assert ground_slope(points, pose) == pytest.approx(slope, abs=1e-9)


def test_too_few_or_bunched_ground_points_give_no_slope():
    pose = PlanarPose()
    assert ground_slope(np.array([[0.0, 0.0, 0.0], [np.nan, 0.1, 0.2]]), pose) is None
    bunched = np.array([[0.0, -0.2, 0.0], [0.01, 0.2, 0.1], [0.02, 0.0, 0.3]])
    assert ground_slope(bunched, pose) is None


@given(st.floats(-1.0, 1.0), st.floats(0.01, 0.4), st.floats(0.05, 0.5))
def test_the_wanted_pitch_levels_shallow_ground_and_follows_steep_ground(slope, level, limit):
    """Level up to the level limit, the whole slope (capped) from FULL_RATIO times it on,
    always against the slope's sign (uphill: nose up, a negative pitch) and never beyond
    the limit or the slope."""
    pitch = wanted_pitch(slope, level, limit)
    assert abs(pitch) <= min(abs(slope), limit) + 1e-12
    if abs(slope) <= level:
        assert pitch == 0.0
    if abs(slope) >= FULL_RATIO * level:
        assert abs(pitch) == pytest.approx(min(abs(slope), limit))
    if pitch != 0.0:
        assert math.copysign(1.0, pitch) == -math.copysign(1.0, slope)


@given(st.floats(0.05, 0.4), st.floats(0.05, 0.5))
def test_the_wanted_pitch_is_continuous_in_the_slope(level, limit):
    """No jump anywhere: a slope estimate near the limit cannot flip the body."""
    slopes = np.linspace(-0.9, 0.9, 3601)
    pitches = np.array([wanted_pitch(s, level, limit) for s in slopes])
    step = slopes[1] - slopes[0]
    assert np.abs(np.diff(pitches)).max() <= (1.0 / (FULL_RATIO - 1.0) + 2.0) * step


def test_a_short_legged_robot_inclines_on_gentler_slopes_than_the_default_one():
    """The level limit comes from the legs: the PhantomX's short femur gives it a far smaller
    height range than the default robot, and its long stance makes it worse."""
    limits = {}
    for name in ("default", "phantomx"):
        spec = load_spec(name)
        kin = LegKinematics(spec)
        assert height_range(kin, spec, 0.02) > 0.0
        limits[name] = level_slope_limit(kin, spec, 0.4, 0.02)
    assert 0.0 < limits["phantomx"] < 0.5 * limits["default"]
    # The PhantomX's 4 cm default stairs (a 9 degree flight) are steeper than its limit.
    assert limits["phantomx"] < math.atan(0.04 / 0.25)


def test_an_inclined_body_s_underside_dips_at_one_end():
    """Nose up by 15 degrees, the body's rear end hangs lower, so the body must stand higher
    over a flat floor to keep its clearance."""
    spec = load_spec("phantomx")
    heights = np.zeros((100, 100))
    snapshot = MapSnapshot(
        heights=heights,
        known=np.ones_like(heights, dtype=bool),
        origin=(-1.0, -1.0),
        resolution=0.02,
        spread=np.zeros_like(heights),
    )
    planner = TerrainPlanner(spec)
    planner.update(snapshot, score_map(snapshot))
    level = planner.lowest_body_z((PlanarPose(),), 0.01)
    inclined = planner.lowest_body_z((PlanarPose(),), 0.01, (math.radians(-15.0),))
    length, _, thickness = spec.body_size
    dip = 0.5 * length * math.sin(math.radians(15.0))
    assert level == pytest.approx(0.01 + 0.5 * thickness)
    assert inclined == pytest.approx(
        0.01 + 0.5 * thickness * math.cos(math.radians(15.0)) + dip, abs=0.002
    )


def _ramp_planner(spec, slope_deg: float) -> TerrainPlanner:
    """A mapped plane rising at ``slope_deg`` along +x from x = 0 (flat before it)."""
    resolution = 0.02
    x = -1.0 + (np.arange(150) + 0.5) * resolution
    heights = np.maximum(x, 0.0)[:, None] * math.tan(math.radians(slope_deg)) * np.ones((1, 100))
    snapshot = MapSnapshot(
        heights=heights,
        known=np.ones_like(heights, dtype=bool),
        origin=(-1.0, -1.0),
        resolution=resolution,
        spread=np.zeros_like(heights),
    )
    planner = TerrainPlanner(spec)
    planner.update(snapshot, score_map(snapshot))
    return planner


def test_the_walker_inclines_up_a_slope_at_its_rate_with_every_foot_in_reach():
    """The PhantomX walking onto a 12 degree plane (steeper than the slope it takes level)
    pitches nose up, never faster than the incline rate, every supporting foot within its
    leg's reach all the way; on a level walk the body stays level."""
    spec = load_spec("phantomx")
    config = GaitConfig()
    kin = LegKinematics(spec)
    for slope_deg, expect_incline in ((12.0, True), (0.0, False)):
        planner = _ramp_planner(spec, slope_deg)
        walker = WalkController(
            spec, config, initial_pose=PlanarPose(-0.3, 0.0, 0.0), planner=planner
        )
        command = WalkCommand(speed=0.05, body_height=spec.body_height)
        dt, pitches = 0.01, []
        for k in range(1200):
            targets = walker.update(k * dt, command)
            stance = ~walker.swinging
            assert kin.reachable_all(targets.feet_in_body)[stance].all()
            pitches.append(walker.incline)
        pitches = np.array(pitches)
        assert np.abs(np.diff(pitches)).max() <= config.incline_rate * dt + 1e-12
        if expect_incline:
            assert walker.pose.x > 0.2, "the walker stalled"
            assert pitches.min() < -math.radians(6.0)
        else:
            assert np.all(pitches == 0.0)
