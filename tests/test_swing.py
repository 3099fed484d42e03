"""Swing trajectories: the flow function (thesis Figs. 5.15-5.19) and the polynomial arc."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from footfall.errors import ConfigError
from footfall.motion.flow_swing import (
    FlowConfig,
    FlowSwing,
    cap_height,
    integrate_flow,
    sigmoid_like,
)
from footfall.motion.swing import minimum_jerk
from footfall.motion.swing_polynomial import PolynomialArcSwing, polynomial_arc_coefficients

THESIS = FlowConfig(step_height=2.0, rise=14.0)  # §8.1: Ch = 2.0, q = 14
STRIDE = 0.15


def sampled(swing, t_from: float = 0.0, n: int = 400) -> np.ndarray:
    return np.array([swing.position(t) for t in np.linspace(t_from, swing.duration, n)])


def second_rise(z: np.ndarray, descending: float = 0.002) -> float:
    """How far a height profile climbs again after it has clearly started to come down [m]."""
    peak_so_far = np.maximum.accumulate(z)
    started_down = np.flatnonzero(peak_so_far - z > descending)
    if started_down.size == 0:
        return 0.0
    tail = z[started_down[0] :]
    return float(np.max(tail - np.minimum.accumulate(tail)))


@pytest.mark.parametrize("dz", [0.0, 0.05, -0.05], ids=["level", "above", "below"])
def test_flow_reaches_the_target(dz):
    """Figs. 5.15-5.17: level, raised and lowered targets are reached exactly."""
    target = np.array([STRIDE, 0.02, dz])
    swing = FlowSwing([0.0, 0.02, 0.0], target, 0.6, THESIS)
    np.testing.assert_allclose(swing.position(0.6), target, atol=1e-12)
    np.testing.assert_allclose(swing.position(0.0), [0.0, 0.02, 0.0], atol=1e-12)
    path = sampled(swing)
    assert np.all(np.diff(np.linalg.norm(path[:, :2] - target[:2], axis=1)) <= 1e-9), (
        "never backs away"
    )


def test_flow_rises_vertically_before_a_higher_target():
    """Fig. 5.16: with the target above, the foot climbs to its height before moving on."""
    path = integrate_flow([0.0, 0.0, 0.0], [STRIDE, 0.0, 0.05], THESIS)
    at_target_height = np.flatnonzero(path[:, 2] >= 0.05)[0]
    assert path[at_target_height, 0] < 0.002
    assert path[:, 2].max() > 0.05 + 0.014  # goes on above it before the arc (q = 14 mm)


def test_rise_parameter_lengthens_the_vertical_rise():
    """Fig. 5.16: a larger q keeps the foot rising vertically for longer."""
    heights = []
    for q in (0.0, 14.0, 40.0):
        path = integrate_flow([0.0, 0.0, 0.0], [STRIDE, 0.0, 0.05], FlowConfig(rise=q))
        heights.append(path[np.flatnonzero(path[:, 0] > 0.005)[0], 2])
    assert heights[0] < heights[1] < heights[2]


@given(st.floats(0.5, 3.0), st.floats(0.05, 1.0), st.floats(-0.05, 0.05))
@settings(max_examples=60, deadline=None)
def test_apex_grows_with_step_height_parameter(ch, extra, dz):
    """Fig. 5.15: raising Ch raises the apex."""
    low = integrate_flow([0.0, 0.0, 0.0], [STRIDE, 0.0, dz], FlowConfig(step_height=ch))
    high = integrate_flow([0.0, 0.0, 0.0], [STRIDE, 0.0, dz], FlowConfig(step_height=ch + extra))
    assert high[:, 2].max() > low[:, 2].max()


def test_thesis_parameters_give_an_apex_near_the_stride():
    """§8.1: Ch = 2, q = 14 'equates to a step height roughly equal to the stride'."""
    apex = integrate_flow([0.0, 0.0, 0.0], [STRIDE, 0.0, 0.0], THESIS)[:, 2].max()
    assert apex == pytest.approx(STRIDE, rel=0.15)


def test_lowered_target_gives_a_lower_arc():
    """Fig. 5.17: starting above the target, the arc rises less above the start."""
    level = integrate_flow([0.0, 0.0, 0.0], [STRIDE, 0.0, 0.0], THESIS)
    lowered = integrate_flow([0.0, 0.0, 0.05], [STRIDE, 0.0, 0.0], THESIS)
    assert lowered[:, 2].max() - 0.05 < level[:, 2].max()


@pytest.mark.parametrize("fraction", [0.5, 0.6, 0.7, 0.8])
def test_target_moved_mid_swing_is_reached_without_a_second_rise(fraction):
    """Fig. 5.18: a target moved farther and lower mid-swing is reached without a second rise.

    Once the foot has started down it climbs again only a little; the polynomial arc,
    refitted from the same point, climbs a full step again.
    """
    new_target = np.array([0.20, 0.0, -0.03])
    flow = FlowSwing([0.0, 0.0, 0.0], [STRIDE, 0.0, 0.0], 1.0, THESIS)
    before = sampled(flow, 0.0, 200)[:, 2]
    flow.retarget(new_target, fraction)
    after = sampled(flow, fraction, 200)
    np.testing.assert_allclose(after[-1], new_target, atol=1e-12)
    z = np.concatenate([before[: int(200 * fraction)], after[:, 2]])
    apex = before.max()
    assert second_rise(z) < 0.1 * apex  # at most a small lift to clear the longer way

    poly = PolynomialArcSwing([0.0, 0.0, 0.0], [STRIDE, 0.0, 0.0], 1.0, apex_height=0.1)
    z_here = poly.position(fraction)[2]
    poly.retarget(new_target, fraction)
    assert sampled(poly, fraction, 200)[:, 2].max() - z_here > 0.5 * apex  # a full step again


def test_target_moved_up_and_closer_needs_no_new_vertical_rise():
    """Fig. 5.19: a target moved up and closer is reached with no fresh vertical rise.

    The swing started above its first target, so the foot is already above the new one.
    """
    flow = FlowSwing([0.0, 0.0, 0.05], [STRIDE, 0.0, 0.0], 1.0, THESIS)
    t = 0.45
    here = flow.position(t)
    new_target = np.array([0.10, 0.0, 0.08])
    assert here[2] > new_target[2]
    flow.retarget(new_target, t)
    after = sampled(flow, t, 200)
    np.testing.assert_allclose(after[-1], new_target, atol=1e-12)
    assert second_rise(after[:, 2]) < 0.005
    assert after[:, 2].max() < here[2] + 0.02


def test_retarget_keeps_the_foot_where_it_was():
    """Re-targeting changes the path ahead, not the foot's current position."""
    flow = FlowSwing([0.0, 0.0, 0.0], [STRIDE, 0.0, 0.0], 0.8, THESIS)
    here = flow.position(0.3)
    flow.retarget([0.18, 0.03, 0.02], 0.3)
    np.testing.assert_allclose(flow.position(0.3), here, atol=1e-12)


@pytest.mark.parametrize("kind", ["flow", "polynomial"])
def test_a_lengthened_swing_keeps_the_foot_and_lands_on_time(kind):
    """A late re-target with a new duration: the foot stays put at that instant, moves on
    without a jump, and reaches the new target exactly at the new end (not before)."""
    swing = (
        FlowSwing([0.0, 0.0, 0.0], [STRIDE, 0.0, 0.0], 0.8, THESIS)
        if kind == "flow"
        else PolynomialArcSwing([0.0, 0.0, 0.0], [STRIDE, 0.0, 0.0], 0.8, apex_height=0.05)
    )
    t = 0.78  # nearly down
    here = swing.position(t)
    target = np.array([STRIDE + 0.12, 0.04, 0.01])
    swing.retarget(target, t, duration=1.2)
    assert swing.duration == 1.2
    np.testing.assert_allclose(swing.position(t), here, atol=1e-9)
    path = np.array([swing.position(u) for u in np.linspace(t, 1.2, 400)])
    assert np.max(np.linalg.norm(np.diff(path, axis=0), axis=1)) < 0.005  # no jump
    np.testing.assert_allclose(swing.position(1.2), target, atol=1e-9)
    assert np.linalg.norm(swing.position(1.0) - target) > 0.01


def test_height_cap_counts_from_lift_off_not_from_mid_air():
    """A capped swing re-planned in mid-air still stays under lift-off height + cap."""
    config = FlowConfig(max_height=0.06)
    flow = FlowSwing([0.0, 0.0, 0.0], [STRIDE, 0.0, 0.0], 1.0, config)
    for k in range(1, 9):
        flow.retarget([STRIDE + 0.01 * k, 0.0, 0.0], 0.1 * k)
    assert sampled(flow)[:, 2].max() <= 0.06 + 1e-9


@given(st.floats(0.01, 0.2), st.floats(-0.1, 0.1), st.floats(0.0, 0.3))
@settings(max_examples=60, deadline=None)
def test_cap_height_keeps_ends_and_ceiling(cap, dz, distance):
    """Capping keeps both ends and never leaves the path above the ceiling."""
    path = integrate_flow([0.0, 0.0, 0.0], [distance, 0.0, dz], THESIS)
    ceiling = max(0.0, dz) + cap
    capped = cap_height(path, ceiling)
    np.testing.assert_allclose(capped[[0, -1]], path[[0, -1]])
    assert capped[:, 2].max() <= ceiling + 1e-9


def test_sigmoid_range_matches_the_errata():
    """S(y) runs from about -1.02 far below q to about +0.01 far above it, -0.505 at q."""
    assert sigmoid_like(-1e6, 14.0) == pytest.approx(-1.02, abs=1e-4)
    assert sigmoid_like(1e6, 14.0) == pytest.approx(0.01, abs=1e-4)
    assert sigmoid_like(14.0, 14.0) == pytest.approx(-0.505)


def test_polynomial_arc_passes_through_its_three_points():
    """Eq. 5.22: the arc is at q_i at 0, q_m at t_f/2 and q_f at t_f, starting at rest."""
    qi, qm, qf = (
        np.array([0.0, 0.0, 0.0]),
        np.array([0.07, 0.01, 0.12]),
        np.array([0.15, 0.02, 0.03]),
    )
    tf = 0.7
    a = polynomial_arc_coefficients(qi, qm, qf, tf)
    at = lambda t: (t ** np.arange(7)) @ a  # noqa: E731
    np.testing.assert_allclose(at(0.0), qi, atol=1e-12)
    np.testing.assert_allclose(at(tf / 2), qm, atol=1e-12)
    np.testing.assert_allclose(at(tf), qf, atol=1e-12)
    np.testing.assert_allclose(a[1], 0.0)
    np.testing.assert_allclose(a[2], 0.0)


def test_polynomial_swing_apex_is_above_the_higher_end():
    """The baseline swing's mid point sits apex_height above the higher end."""
    swing = PolynomialArcSwing([0.0, 0.0, 0.0], [STRIDE, 0.0, 0.04], 0.5, apex_height=0.08)
    np.testing.assert_allclose(swing.position(0.25), [STRIDE / 2, 0.0, 0.12], atol=1e-12)
    np.testing.assert_allclose(swing.position(0.5), [STRIDE, 0.0, 0.04], atol=1e-12)


def test_minimum_jerk_profile():
    """Progress starts and ends at rest and is symmetric."""
    assert minimum_jerk(0.0) == 0.0 and minimum_jerk(1.0) == 1.0
    assert minimum_jerk(0.5) == pytest.approx(0.5)
    eps = 1e-4
    assert minimum_jerk(eps) / eps < 1e-6
    assert minimum_jerk(0.3) + minimum_jerk(0.7) == pytest.approx(1.0)


def test_bad_parameters_are_rejected():
    """Negative Ch, a zero unit or a non-positive duration raise ConfigError."""
    with pytest.raises(ConfigError):
        FlowConfig(step_height=-1.0)
    with pytest.raises(ConfigError):
        FlowConfig(length_unit=0.0)
    with pytest.raises(ConfigError):
        FlowSwing([0, 0, 0], [0.1, 0, 0], 0.0, THESIS)
