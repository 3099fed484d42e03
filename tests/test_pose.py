"""Poses and the SLAM-like pose-estimate noise."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from footfall.errors import InvalidPoseError
from footfall.sensing.pose import Pose, SlamNoise, SlamNoiseConfig

vectors = st.lists(st.floats(-10, 10), min_size=3, max_size=3).map(np.array)
quaternions = (
    st.lists(st.floats(-1, 1), min_size=4, max_size=4)
    .map(np.array)
    .filter(lambda q: np.linalg.norm(q) > 0.1)
)


@given(vectors, quaternions, vectors, quaternions, st.lists(vectors, min_size=1, max_size=5))
@settings(max_examples=100, deadline=None)
def test_compose_and_inverse(p1, q1, p2, q2, points):
    """(A * B) applied equals A applied to B applied; A^-1 * A is the identity."""
    a = Pose(p1, Rotation.from_quat(q1))
    b = Pose(p2, Rotation.from_quat(q2))
    pts = np.stack(points)
    np.testing.assert_allclose(a.compose(b).apply(pts), a.apply(b.apply(pts)), atol=1e-9)
    np.testing.assert_allclose(a.inverse().apply(a.apply(pts)), pts, atol=1e-9)
    np.testing.assert_allclose(Pose.from_matrix(a.matrix).apply(pts), a.apply(pts), atol=1e-9)


def test_non_unit_quaternion_is_refused():
    """A quaternion far from unit norm is an error; a rounded one is normalised."""
    with pytest.raises(InvalidPoseError, match=r"norm 2\.0"):
        Pose.from_quaternion([0, 0, 0], [0, 0, 0, 2.0])
    with pytest.raises(InvalidPoseError, match="finite"):
        Pose.from_quaternion([0, 0, 0], [0, 0, np.nan, 1.0])
    pose = Pose.from_quaternion([1, 2, 3], [0, 0, 0, 1.0004])
    np.testing.assert_allclose(pose.rotation.as_quat(), [0, 0, 0, 1])


def test_non_rigid_matrix_is_refused():
    """A 4x4 with a scaled rotation block is not a pose."""
    m = np.eye(4)
    m[0, 0] = 2.0
    with pytest.raises(InvalidPoseError, match="not a rotation"):
        Pose.from_matrix(m)


def test_slam_noise_is_seeded_and_drifts():
    """Same seed, same estimates; the error grows with time like a random walk."""
    truth = Pose(np.zeros(3), Rotation.identity())

    def errors(seed: int) -> np.ndarray:
        noise = SlamNoise(
            SlamNoiseConfig(position_jitter=0.0, angle_jitter=0.0), np.random.default_rng(seed)
        )
        return np.array(
            [np.linalg.norm(noise.estimate(truth, t).position) for t in np.arange(0, 400, 1.0)]
        )

    np.testing.assert_array_equal(errors(3), errors(3))
    runs = np.array([errors(s) for s in range(40)])
    rms = np.sqrt(np.mean(runs**2, axis=0))
    assert rms[-1] > 3 * rms[10]  # sqrt(400 / 10) ~ 6


def test_zero_noise_is_the_truth():
    """A noise model with all magnitudes zero returns the true pose."""
    zero = SlamNoiseConfig(0.0, 0.0, 0.0, 0.0, 0.0)
    truth = Pose(np.array([1.0, 2.0, 0.5]), Rotation.from_euler("z", 0.3))
    estimate = SlamNoise(zero, np.random.default_rng(0)).estimate(truth, 1.0)
    np.testing.assert_allclose(estimate.matrix, truth.matrix, atol=1e-15)


def test_poses_decoded_from_bytes_compose() -> None:
    """A pose that came over the network (read-only arrays) maps points and composes."""
    from footfall.messages import PoseEstimate

    pose = Pose(np.array([1.0, 2.0, 3.0]), Rotation.from_euler("z", 0.3))
    estimate = PoseEstimate.decode(PoseEstimate(1.0, pose, pose).encode())
    assert not estimate.body_in_world.position.flags.writeable
    composed = estimate.body_in_world.compose(estimate.camera_in_world)
    np.testing.assert_allclose(composed.position, pose.compose(pose).position)
