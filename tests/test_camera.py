"""Pinhole camera: depth -> points, validation, and the PCL reference frame."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from conftest import shared_data
from footfall.errors import ConfigError, DepthImageError
from footfall.io.pcd import read_pcd
from footfall.sensing.camera import PinholeCamera

CAMERA = PinholeCamera(525.0, 525.0, 320.0, 240.0, 640, 480, max_range=8.0)


def test_depth_to_points_reproduces_pcl_grabber():
    """Back-projecting PCL's raw depth gives PCL's organised cloud: same points to 1e-6 m,
    NaN exactly where the depth is 0."""
    folder = shared_data("pointclouds/pcl_grabber")
    depth = np.load(folder / "pclzf_decoded_frame_20121214T142255.814212_depth_uint16_mm.npy")
    cloud = read_pcd(folder / "frame_20121214T142255.814212.pcd")
    expected = cloud.xyz.reshape(cloud.height, cloud.width, 3)
    points = CAMERA.organized_points(depth, depth_scale=0.001)
    np.testing.assert_array_equal(np.isnan(points[..., 2]), depth == 0)
    np.testing.assert_array_equal(np.isnan(expected[..., 2]), depth == 0)
    valid = depth > 0
    assert np.max(np.abs(points[valid] - expected[valid])) < 1e-6
    flat, stats = CAMERA.depth_to_points(depth, depth_scale=0.001)
    assert stats.valid == int(valid.sum()) and stats.zero == int((~valid).sum())
    np.testing.assert_allclose(flat, expected[valid], atol=1e-6)


def test_invalid_pixels_are_dropped_and_counted():
    """Zero, NaN, infinite, negative and out-of-range pixels give no point; each is counted."""
    depth = np.full((480, 640), 1.0, dtype=np.float32)
    depth[0, :10] = 0.0
    depth[1, :5] = np.nan
    depth[2, :3] = np.inf
    depth[2, 3:5] = -np.inf
    depth[3, :7] = -0.5
    depth[4, :2] = 9.0  # beyond max_range
    points, stats = CAMERA.depth_to_points(depth)
    assert (stats.zero, stats.non_finite, stats.negative, stats.out_of_range) == (10, 10, 7, 2)
    assert stats.valid == 640 * 480 - 29 == len(points)
    assert np.all(np.isfinite(points))


@pytest.mark.parametrize(
    ("depth", "scale", "message"),
    [
        (np.ones((480, 641), np.float32), None, "shape"),
        (np.ones((480, 640), np.uint16), None, "depth_scale"),
        (np.ones((480, 640), np.int16), 0.001, "dtype"),
        (np.ones((480, 640), np.float32), 0.001, "metres already"),
    ],
)
def test_malformed_depth_is_a_clear_error(depth, scale, message):
    """Wrong shape, signed integers, integer depth without a scale: DepthImageError."""
    with pytest.raises(DepthImageError, match=message):
        CAMERA.depth_to_points(depth, depth_scale=scale)


@given(
    st.integers(0, 639),
    st.integers(0, 479),
    st.floats(0.2, 7.9),
    st.floats(300, 700),
    st.floats(300, 700),
    st.floats(300, 340),
    st.floats(220, 260),
)
@settings(max_examples=100, deadline=None)
def test_points_project_back_to_their_pixels(u, v, z, fx, fy, cx, cy):
    """Eq. 4.5: projecting a back-projected point lands on its pixel at its depth."""
    camera = PinholeCamera(fx, fy, cx, cy, 640, 480, max_range=8.0)
    depth = np.zeros((480, 640), dtype=np.float64)
    depth[v, u] = z
    (point,), _ = camera.depth_to_points(depth)
    assert point[2] == pytest.approx(z)
    assert fx * point[0] / point[2] + cx == pytest.approx(u, abs=1e-9)
    assert fy * point[1] / point[2] + cy == pytest.approx(v, abs=1e-9)


def test_stride_downsamples():
    """stride=k keeps every k-th row and column."""
    depth = np.random.default_rng(0).uniform(0.5, 3.0, (480, 640))
    full = CAMERA.organized_points(depth)[::4, ::4].reshape(-1, 3)
    points, stats = CAMERA.depth_to_points(depth, stride=4)
    assert stats.valid == 120 * 160
    np.testing.assert_allclose(points, full)


def test_intrinsic_matrix_round_trip():
    """A camera built from its K has the same intrinsics; a skewed K is refused."""
    assert PinholeCamera.from_matrix(CAMERA.matrix, 640, 480, max_range=8.0) == CAMERA
    skewed = CAMERA.matrix.copy()
    skewed[0, 1] = 0.5
    with pytest.raises(ConfigError, match="fx, 0, cx"):
        PinholeCamera.from_matrix(skewed, 640, 480)


@settings(max_examples=60, deadline=None)
@given(
    st.integers(1, 4),
    st.booleans(),
    st.integers(0, 2**32 - 1),
    st.floats(0.0, 0.5),
)
def test_the_reused_buffers_back_project_exactly_as_depth_to_points(stride, integer, seed, bad):
    """Frame after frame, with holes, NaN, infinities, negatives and readings out of range,
    in units or in metres, the buffered back-projection gives depth_to_points' points to
    the bit."""
    from footfall.sensing.back_projection import BackProjection

    camera = PinholeCamera(80.0, 75.0, 31.5, 23.7, 64, 48, min_range=0.3, max_range=4.0)
    projection = BackProjection(camera, stride)
    rng = np.random.default_rng(seed)
    for _ in range(3):
        metres = rng.uniform(-0.5, 6.0, (48, 64))
        holes = rng.random((48, 64)) < bad
        if integer:
            depth = np.where(holes, 0, np.clip(metres, 0, None) * 5000).astype(np.uint16)
            scale = 1.0 / 5000.0
        else:
            depth = np.where(holes, rng.choice([0.0, np.nan, np.inf, -1.0]), metres)
            scale = None
        expected, _ = camera.depth_to_points(depth, scale, stride)
        assert np.array_equal(projection.points(depth, scale), expected)


def test_the_reused_buffers_refuse_what_depth_to_points_refuses():
    """A wrong shape, integer depth without a scale and a stride below 1 are refused."""
    from footfall.sensing.back_projection import BackProjection

    camera = PinholeCamera(80.0, 75.0, 31.5, 23.7, 64, 48)
    projection = BackProjection(camera, 2)
    with pytest.raises(DepthImageError, match="shape"):
        projection.points(np.ones((48, 63)))
    with pytest.raises(DepthImageError, match="depth_scale"):
        projection.points(np.ones((48, 64), dtype=np.uint16))
    with pytest.raises(DepthImageError, match="stride"):
        BackProjection(camera, 0)
