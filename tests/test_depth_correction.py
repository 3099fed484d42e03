"""The estimate's drift corrected by registering depth frames against the map of earlier ones."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from depth_scenes import CAMERA, looking, render
from footfall.errors import ConfigError
from footfall.estimation.depth_correction import (
    Correction,
    DepthCorrection,
    DepthCorrectionConfig,
    observed_basis,
)
from footfall.estimation.leg_inertial import LegInertialEstimator
from footfall.robot.kinematics import LegKinematics
from footfall.sensing.pose import Pose

pytest.importorskip("small_gicp")

# Pillars on the floor ahead of a camera 0.4 m up, looking 25 degrees down at them.
PILLARS = tuple(
    (np.array([x - 0.1, y - 0.1, 0.0]), np.array([x + 0.1, y + 0.1, h]))
    for x, y, h in [(1.2, -0.5, 0.3), (1.6, 0.4, 0.5), (2.1, -0.1, 0.4), (2.6, 0.7, 0.6),
                    (2.9, -0.8, 0.3), (1.4, 0.9, 0.4)]
)  # fmt: skip
TRUE = looking([0.5, 0.0, 0.4], 0.0, math.radians(25.0))
LARGE = np.array([1e-2, 1e-2, 1e-2, 1e-2])  # an estimate that knows little [m^2, rad^2]


def drifted(pose: Pose, shift: list[float], yaw_deg: float) -> Pose:
    """``pose`` shifted in the world and turned about the vertical through itself."""
    turn = Rotation.from_euler("z", yaw_deg, degrees=True)
    return Pose(pose.position + np.asarray(shift), turn * pose.rotation)


def heading(rotation: Rotation) -> float:
    """The heading of an optical frame's forward axis [rad]."""
    forward = rotation.apply([0.0, 0.0, 1.0])
    return math.atan2(forward[1], forward[0])


def floor_only(camera_in_world: Pose) -> np.ndarray:
    """Depth of an endless level floor at z = 0."""
    c = CAMERA
    u, v = np.meshgrid(np.arange(c.width), np.arange(c.height))
    rays = np.stack([(u - c.cx) / c.fx, (v - c.cy) / c.fy, np.ones(u.shape)], axis=-1)
    down = camera_in_world.rotation.apply(rays.reshape(-1, 3))[:, 2]
    with np.errstate(divide="ignore"):
        depth = np.where(down < -1e-6, -camera_in_world.position[2] / down, 0.0)
    return np.minimum(depth, 4.0).reshape(c.height, c.width)


def corrected(correction: Correction, prior: Pose) -> Pose:
    position, rotation = correction.apply(prior.position, prior.rotation.as_matrix())
    return Pose(position, Rotation.from_matrix(rotation))


@pytest.mark.parametrize(
    ("shift", "yaw_deg"), [([0.012, -0.008, 0.006], 0.6), ([-0.015, 0.01, -0.004], -0.8)]
)
def test_a_drifted_estimate_is_brought_back_onto_the_map(shift, yaw_deg):
    correction = DepthCorrection()
    first = correction.register(render(TRUE, boxes=PILLARS), CAMERA, None, TRUE.matrix, LARGE)
    assert not first.applied and "first frame" in first.reason
    # The camera moved on 5 cm; the estimate drifted from the truth there.
    now = looking([0.55, 0.0, 0.4], 0.0, math.radians(25.0))
    prior = drifted(now, shift, yaw_deg)
    result = correction.register(render(now, boxes=PILLARS), CAMERA, None, prior.matrix, LARGE)
    assert result.applied, result.reason
    assert result.observed.min() > 0.9  # the pillars' sides fix every direction
    after = corrected(result, prior)
    before_m = np.linalg.norm(prior.position - now.position)
    assert np.linalg.norm(after.position - now.position) < 0.2 * before_m
    assert abs(heading(after.rotation) - heading(now.rotation)) < math.radians(0.1)


def test_a_floor_alone_corrects_the_height_and_nothing_it_cannot_see():
    correction = DepthCorrection()
    start = looking([0.0, 0.0, 0.3], 0.0, math.radians(35.0))
    correction.register(floor_only(start), CAMERA, None, start.matrix, LARGE)
    now = looking([0.05, 0.0, 0.3], 0.0, math.radians(35.0))
    prior = drifted(now, [0.02, -0.02, 0.01], 1.0)
    result = correction.register(floor_only(now), CAMERA, None, prior.matrix, LARGE)
    assert result.applied, result.reason
    assert result.observed[2] > 0.9 and max(result.observed[[0, 1, 3]]) < 0.1
    after = corrected(result, prior)
    assert abs(after.position[2] - now.position[2]) < 0.002  # the height, from the floor
    # Along the floor and about the vertical nothing is seen: the estimate stays.
    assert np.allclose(after.position[:2], prior.position[:2], atol=0.002)
    assert abs(heading(after.rotation) - heading(prior.rotation)) < math.radians(0.1)


def test_gains_follow_the_estimates_uncertainty():
    correction = DepthCorrection()
    correction.register(render(TRUE, boxes=PILLARS), CAMERA, None, TRUE.matrix, LARGE)
    prior = drifted(TRUE, [0.01, 0.0, 0.0], 0.0)
    sure = np.full(4, DepthCorrectionConfig().sigma_m ** 2)  # as sure as the registration
    result = correction.register(render(TRUE, boxes=PILLARS), CAMERA, None, prior.matrix, sure)
    assert result.applied
    assert result.observed.min() > 0.9
    # As sure as the registration: half the error is taken out, and half the variance.
    assert result.gains[:3] == pytest.approx(0.5, abs=0.05)
    assert result.shift_in_world[0] == pytest.approx(-0.005, abs=0.0015)


def test_a_correction_beyond_what_the_estimate_can_have_drifted_is_refused():
    correction = DepthCorrection()
    correction.register(render(TRUE, boxes=PILLARS), CAMERA, None, TRUE.matrix, LARGE)
    prior = drifted(TRUE, [0.05, 0.0, 0.0], 0.0)  # 5 cm: beyond the 3 cm a frame may correct
    result = correction.register(render(TRUE, boxes=PILLARS), CAMERA, None, prior.matrix, LARGE)
    assert not result.applied and "more than it can have drifted" in result.reason
    assert np.all(result.gains == 0.0) and np.all(result.shift_in_world == 0.0)


def test_a_frame_with_too_few_points_corrects_nothing():
    correction = DepthCorrection()
    result = correction.register(np.zeros((240, 320)), CAMERA, None, TRUE.matrix, LARGE)
    assert not result.applied and "fewer than" in result.reason


def test_bad_settings_are_refused():
    with pytest.raises(ConfigError, match="min_constraint_share"):
        DepthCorrectionConfig(min_constraint_share=1.5)
    with pytest.raises(ConfigError, match="sigma_m"):
        DepthCorrectionConfig(sigma_m=0.0)


@settings(max_examples=60, deadline=None)
@given(
    st.lists(st.floats(0.0, 1e3), min_size=6, max_size=6),
    st.floats(1e-3, 1e3),
    st.integers(0, 2**32 - 1),
)
def test_the_observed_basis_spans_the_well_informed_directions(values, least, seed):
    vectors, _ = np.linalg.qr(np.random.default_rng(seed).normal(size=(6, 6)))
    values = np.array(values)
    information = vectors @ np.diag(values) @ vectors.T
    basis = observed_basis(information, least)
    assert np.allclose(basis.T @ basis, np.eye(basis.shape[1]), atol=1e-9)
    for k in np.flatnonzero(np.abs(values - least) > 1e-6 * max(least, values.max())):
        along = float(np.linalg.norm(basis.T @ vectors[:, k]))
        assert along == pytest.approx(1.0 if values[k] > least else 0.0, abs=1e-6)


def test_the_estimator_takes_a_correction_and_is_surer_after_it(default_spec):
    estimator = LegInertialEstimator(LegKinematics(default_spec), Pose.identity())
    estimator.covariance[:] = [1e-4, 1e-4, 1e-4, 1e-6, 1e-6, 1e-4]
    estimator._heading_s = 30.0
    before = estimator.covariance.copy()
    turn = Correction(
        np.array([0.01, 0.0, -0.002]),
        math.radians(0.5),
        np.array([1.0, 0.0, 0.0]),
        np.array([0.5, 0.5, 0.5, 0.25]),
        np.ones(4),
    )
    estimator.correct(turn)
    # Turned 0.5 degrees about (1, 0, 0), then shifted.
    expected = np.array([1.0 - math.cos(math.radians(0.5)), -math.sin(math.radians(0.5)), 0.0])
    assert estimator.position == pytest.approx(expected + [0.01, 0.0, -0.002], abs=1e-9)
    r = estimator.rotation_matrix
    assert math.atan2(r[1, 0], r[0, 0]) == pytest.approx(math.radians(0.5), abs=1e-9)
    assert estimator.covariance[[0, 1, 2]] == pytest.approx(0.5 * before[[0, 1, 2]])
    assert estimator.covariance[5] == pytest.approx(0.75 * before[5])
    assert estimator.distance_m == 0.0  # a correction is not distance walked
    refused = Correction(reason="too far")
    estimator.correct(refused)
    assert estimator.position == pytest.approx(expected + [0.01, 0.0, -0.002], abs=1e-9)
