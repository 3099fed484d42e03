"""Linear Inverted Pendulum walking pattern (dissertation §4.1)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from footfall.biped.lipm import (
    LipmConfig,
    WalkParameter,
    lipm_pattern,
    pendulum_state,
    walk_primitive,
)

KAJITA = [WalkParameter(sx, 0.2) for sx in (0.0, 0.3, 0.3, 0.3, 0.0)]


@given(
    st.floats(0.0, 0.5),
    st.floats(0.05, 0.4),
    st.floats(0.3, 1.2),
    st.floats(0.3, 1.5),
    st.integers(0, 5),
)
@settings(max_examples=100, deadline=None)
def test_walk_primitive_velocity_is_the_closed_form(sx, sy, zc, tsup, n):
    """Eq. 11: a pendulum leaving (-x_bar, v_bar) over its foot arrives at (x_bar, v_bar),
    and in y leaving (y_bar, -v_bar) it arrives at (y_bar, v_bar): the primitive is symmetric."""
    config = LipmConfig(com_height=zc, support_time=tsup)
    bar, v_bar = walk_primitive(WalkParameter(sx, sy), n, config)
    (x_end,), (v_end,) = pendulum_state(
        [-bar[0], bar[1]], [v_bar[0], -v_bar[1]], [0.0, 0.0], [tsup], config.time_constant
    )
    np.testing.assert_allclose(x_end, bar, atol=1e-9)
    np.testing.assert_allclose(v_end, v_bar, atol=1e-9)


def test_com_trajectory_is_continuous():
    """Position and velocity of the COM are continuous across every step change."""
    pattern = lipm_pattern(KAJITA)
    dt = LipmConfig().dt
    accel_bound = 9.81 / 0.8 * 1.0  # |x - p| stays under 1 m
    assert np.max(np.linalg.norm(np.diff(pattern.com, axis=0), axis=1)) < 1.0 * dt + 1e-3
    assert np.max(np.linalg.norm(np.diff(pattern.com_velocity, axis=0), axis=1)) < accel_bound * dt


def test_modified_foot_placement_minimises_the_cost():
    """Eq. 24: moving a modified footstep either way raises a (x_d - x_f)^2 + b (v_d - v_f)^2."""
    config = LipmConfig()
    pattern = lipm_pattern(KAJITA, config)
    tsup, tc = config.support_time, config.time_constant
    k = round(tsup / config.dt)
    for n in (1, 2, 3):
        x_i, v_i = pattern.com[n * k], pattern.com_velocity[n * k]
        following = KAJITA[n + 1] if n + 1 < len(KAJITA) else WalkParameter(0.0, 0.0)
        bar, v_bar = walk_primitive(following, n, config)
        x_d, v_d = pattern.footsteps[n] + bar, v_bar

        def cost(p, x_i=x_i, v_i=v_i, x_d=x_d, v_d=v_d):
            (x_f,), (v_f,) = pendulum_state(x_i, v_i, p, [tsup], tc)
            return (
                config.position_weight * (x_d - x_f) ** 2
                + config.velocity_weight * (v_d - v_f) ** 2
            )

        best = cost(pattern.modified_footsteps[n])
        for delta in ([0.01, 0.0], [-0.01, 0.0], [0.0, 0.01], [0.0, -0.01]):
            assert np.all(cost(pattern.modified_footsteps[n] + delta) >= best - 1e-12)


def test_textbook_example_walks_forward_and_ends_still():
    """Kajita's example (z_c 0.8 m, T_sup 0.8 s, a 10, b 1): the COM ends between the last
    feet, about 0.9 m ahead, slowing down; the feet alternate left and right."""
    pattern = lipm_pattern(KAJITA)
    np.testing.assert_allclose(pattern.footsteps[:, 0], [0.0, 0.3, 0.6, 0.9, 0.9])
    np.testing.assert_allclose(pattern.footsteps[:, 1], [0.0, 0.2, 0.0, 0.2, 0.0])
    assert pattern.com[-1, 0] == pytest.approx(0.9, abs=0.05)
    assert 0.0 < pattern.com[-1, 1] < 0.2
    assert abs(pattern.com_velocity[-1, 0]) < 0.1
    assert pattern.time[-1] == pytest.approx(4 * 0.8)


def test_turning_rotates_the_primitive():
    """Eqs. 25-26: a heading rotates the walk primitive and its velocity."""
    config = LipmConfig()
    straight, v_straight = walk_primitive(WalkParameter(0.3, 0.2, 0.0), 1, config)
    turned, v_turned = walk_primitive(WalkParameter(0.3, 0.2, np.pi / 2), 1, config)
    np.testing.assert_allclose(turned, [-straight[1], straight[0]], atol=1e-12)
    np.testing.assert_allclose(v_turned, [-v_straight[1], v_straight[0]], atol=1e-12)
