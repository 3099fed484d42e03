"""How far the map may have slid under the feet: the pose corrections over a window."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from footfall.motion.registration import RegistrationDrift
from footfall.motion.walker import WalkController
from footfall.planning.terrain_planner import TerrainPlanner
from footfall.robot.planar import PlanarPose
from footfall.robot.spec import load_spec


def test_jitter_about_a_fixed_pose_stays_small_and_a_drift_shows_over_the_window():
    """Corrections that undo each other (an estimate jittering about the truth) sum to
    little; a steady 1 cm/s drift the controller follows sums to the drift over the
    window, and no more once it stops for longer than the window."""
    rng = np.random.default_rng(3)
    jitter = RegistrationDrift(horizon_s=5.0)
    offset = np.zeros(2)
    for k in range(200):
        new = rng.normal(0.0, 0.002, 2)  # the estimate's error, white
        step = new - offset
        jitter.add(k / 12.0, *step)
        offset = new
    assert jitter.error_m < 0.012

    drift = RegistrationDrift(horizon_s=5.0)
    for k in range(120):
        drift.add(k / 12.0, 0.01 / 12.0, 0.0)
    assert math.isclose(drift.error_m, 0.05, rel_tol=0.05)
    for k in range(120, 200):
        drift.add(k / 12.0, 0.0, 0.0)
    assert drift.error_m < 1e-12


def test_the_first_correction_moves_nothing_against_the_map():
    """The first estimate registers the controller's world: however far it lies from the
    start pose, the map was made in the estimate's world from its first frame."""
    r = RegistrationDrift(horizon_s=5.0)
    r.add(0.0, 3.0, -2.0)
    r.add(0.1, 0.001, 0.0)
    assert math.isclose(r.error_m, 0.001)


@given(
    st.lists(
        st.tuples(st.floats(0.0, 0.5), st.floats(-0.05, 0.05), st.floats(-0.05, 0.05)),
        min_size=2,
        max_size=60,
    ),
    st.floats(0.5, 10.0),
)
@settings(max_examples=100, deadline=None)
def test_the_error_is_the_largest_net_correction_within_the_window(steps, horizon):
    """Brute force: the largest distance between the sum of corrections now and at any
    time from one window ago on (the sum just before the window counts: it is where the
    window starts)."""
    r = RegistrationDrift(horizon_s=horizon)
    t, totals = 0.0, []
    x = y = 0.0
    for k, (dt, dx, dy) in enumerate(steps):
        t += dt
        r.add(t, dx, dy)
        if k:
            x, y = x + dx, y + dy
        totals.append((t, x, y))
    start = max(i for i, (ti, _, _) in enumerate(totals) if ti <= t - horizon or i == 0)
    expected = max(math.hypot(x - hx, y - hy) for _, hx, hy in totals[start:])
    assert math.isclose(r.error_m, expected, abs_tol=1e-12)


def test_a_correction_that_aligns_the_body_with_the_map_is_not_counted_as_the_map_sliding():
    """A pose source that registers its images against its map (footfall's estimator) says
    how far it moved the body to align it: the controller follows the whole correction but
    counts only the rest as the map sliding under the feet."""
    spec = load_spec("default")
    walker = WalkController(spec, planner=TerrainPlanner(spec))
    walker.correct_pose(PlanarPose(0.0, 0.0, 0.0))  # the first estimate registers the world
    for k in range(1, 11):
        walker.correct_pose(PlanarPose(0.003 * k, 0.0, 0.0), aligned_in_world=(0.002, 0.0))
    assert walker.pose.x == 0.03  # followed whole
    assert math.isclose(walker.planner.registration_error_m, 0.01, abs_tol=1e-9)
