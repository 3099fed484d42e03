"""Archie's leg kinematics (dissertation §4.2, §4.4)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from footfall.biped.archie import (
    ArchieGeometry,
    com_offset,
    leg_forward,
    support_leg_angles,
    swing_leg_angles,
)

G = ArchieGeometry()


@pytest.mark.parametrize("side", ["left", "right"])
def test_zero_pose_matches_the_link_lengths(side):
    """At zero angles the links line up: a1 + a2 + a3 along x, then +a6 (left) or -a6
    (right, Table 4); the offsets d3 and d6 lie across, adding on the left (link 1 turns
    +90 deg about x) and opposing on the right (-90 deg)."""
    t = leg_forward(side, np.zeros(6))
    along = G.a1 + G.a2 + G.a3 + (G.a6 if side == "left" else -G.a6)
    across = G.d3 + G.d6 if side == "left" else G.d6 - G.d3
    np.testing.assert_allclose(t[:3, 3], [along, across, 0.0], atol=1e-12)
    np.testing.assert_allclose(t[:3, :3] @ t[:3, :3].T, np.eye(3), atol=1e-12)


@given(st.floats(-0.3, 0.3), st.floats(-0.5, 0.5))
@settings(max_examples=200, deadline=None)
def test_support_leg_relations_reproduce_the_com(theta0, theta1):
    """Eqs. 41-42 round trip: the angles solved for a COM offset give that offset back."""
    x, y = com_offset(theta0, theta1)
    angles = support_leg_angles(x, y)
    np.testing.assert_allclose(com_offset(angles[0], angles[1]), (x, y), atol=1e-9)
    np.testing.assert_allclose(angles[:2], (theta0, theta1), atol=1e-9)
    assert angles[3] == -angles[1] and angles[4] == -angles[0]  # trunk upright


@given(st.floats(-0.25, 0.25), st.floats(0.3, 0.56))
@settings(max_examples=200, deadline=None)
def test_swing_leg_reaches_the_foot_with_the_foot_level(advance, height):
    """Eqs. 46-52: thigh and shank end at the foot target; the foot stays parallel."""
    if not abs(G.a3 - G.a2) <= math.hypot(advance, height) <= G.a2 + G.a3:
        return
    hip, knee, ankle = swing_leg_angles(advance, height)
    foot = G.a3 * np.array([math.sin(hip), math.cos(hip)]) + G.a2 * np.array(
        [math.sin(hip - knee), math.cos(hip - knee)]
    )
    np.testing.assert_allclose(foot, (advance, height), atol=1e-9)
    assert hip - knee + ankle == pytest.approx(0.0, abs=1e-12)
