"""Recorded data: the TUM layout, the Redwood converter, PCD files."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image
from scipy.spatial.transform import Rotation

from conftest import shared_data
from footfall.datasets.redwood import convert_redwood, read_trajectory_log
from footfall.datasets.tum import load_depth_png, map_tum_sequence, read_tum_sequence, up_to_z
from footfall.errors import DatasetError, InvalidPoseError
from footfall.io.pcd import lzf_decompress, read_pcd
from footfall.sensing.camera import PinholeCamera

PRIMESENSE = PinholeCamera(525.0, 525.0, 319.5, 239.5, 640, 480)


def test_redwood_floor_maps_flat(tmp_path):
    """The Redwood living room, converted and mapped with y as up, has a flat floor at the
    height its trajectory puts it (y = 0.12-0.14 m)."""
    source = shared_data("rgbd/redwood_livingroom")
    frames = convert_redwood(source, tmp_path / "tum")
    assert frames == 5
    result = map_tum_sequence(tmp_path / "tum", PRIMESENSE, up=(0.0, 1.0, 0.0))
    m = result.metrics
    assert m["frames"] == 5 and m["frames_skipped_no_pose"] == 0
    assert 0.11 < m["floor_height_median_m"] < 0.15
    assert m["floor_height_spread_m"] < 0.02  # 5th to 95th percentile of floor cells
    assert m["floor_cells"] > 1000


def test_redwood_conversion_keeps_depth_and_poses(tmp_path):
    """Converted depth is the millimetre depth times 5; poses round-trip the 4x4 matrices."""
    source = shared_data("rgbd/redwood_livingroom")
    convert_redwood(source, tmp_path)
    original = load_depth_png(source / "depth" / "00002.png").astype(np.int64)
    np.testing.assert_array_equal(load_depth_png(tmp_path / "depth" / "00002.png"), original * 5)
    frames, _ = read_tum_sequence(tmp_path)
    matrices = read_trajectory_log(source / "trajectory.log")
    np.testing.assert_allclose(frames[2].camera_pose.matrix, matrices[2], atol=1e-7)


def _write_sequence(folder, depth_times, pose_rows):
    (folder / "depth").mkdir(parents=True)
    lines = []
    for k, t in enumerate(depth_times):
        Image.fromarray(np.full((480, 640), 5000, dtype=np.uint16)).save(
            folder / "depth" / f"{k}.png"
        )
        lines.append(f"{t} depth/{k}.png")
    (folder / "depth.txt").write_text("# comment\n" + "\n".join(lines) + "\n")
    (folder / "groundtruth.txt").write_text(
        "\n".join(" ".join(map(str, r)) for r in pose_rows) + "\n"
    )


def test_depth_frames_take_the_nearest_pose(tmp_path):
    """Each depth frame pairs with the pose nearest in time; frames without one are skipped."""
    poses = [[t, t, 0, 0, 0, 0, 0, 1] for t in (0.0, 0.1, 0.2, 0.3)]
    _write_sequence(tmp_path, [0.012, 0.19, 0.5], poses)
    frames, skipped = read_tum_sequence(tmp_path, max_time_difference=0.02)
    assert skipped == 1
    assert [f.camera_pose.position[0] for f in frames] == pytest.approx([0.0, 0.2])
    assert frames[0].pose_time_offset == pytest.approx(-0.012)


def test_floor_one_metre_below_a_level_camera(tmp_path):
    """A camera looking down (optical z = world -z) at depth 1 m maps a floor at z = -1."""
    q = Rotation.from_matrix(np.diag([1.0, -1.0, -1.0])).as_quat()
    _write_sequence(tmp_path, [0.0], [[0.0, 0, 0, 0, *q]])
    result = map_tum_sequence(tmp_path, PRIMESENSE, up=(0, 0, 1))
    heights = result.snapshot.heights[result.snapshot.known]
    np.testing.assert_allclose(heights, -1.0, atol=1e-6)


def test_malformed_sequences_are_named(tmp_path):
    """Missing files, short lines and non-unit quaternions give clear errors."""
    with pytest.raises(DatasetError, match=r"missing depth\.txt"):
        read_tum_sequence(tmp_path)
    _write_sequence(tmp_path / "a", [0.0], [[0.0, 0, 0, 0, 0, 0, 0]])
    with pytest.raises(DatasetError, match="line 1: expected 8 fields"):
        read_tum_sequence(tmp_path / "a")
    _write_sequence(tmp_path / "b", [0.0], [[0.0, 0, 0, 0, 0, 0, 0, 3.0]])
    with pytest.raises(InvalidPoseError, match="unit quaternion"):
        read_tum_sequence(tmp_path / "b")


def test_up_axis_alignment():
    """The named up axis becomes +z."""
    for up in ([0, 1, 0], [0, -1, 0], [1, 1, 0], [0, 0, 1]):
        u = np.asarray(up, float) / np.linalg.norm(up)
        np.testing.assert_allclose(up_to_z(up).apply(u), [0, 0, 1], atol=1e-9)
    with pytest.raises(DatasetError):
        up_to_z([0, 0, 0])


def _header(kind: str, n: int) -> str:
    return (
        "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
        f"WIDTH {n}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {n}\nDATA {kind}\n"
    )


def test_pcd_ascii_and_binary(tmp_path):
    """Ascii and binary PCD files give back the points written."""
    points = np.random.default_rng(0).normal(size=(50, 3)).astype(np.float32)
    (tmp_path / "a.pcd").write_text(
        _header("ascii", 50) + "\n".join(" ".join(map(repr, p.tolist())) for p in points)
    )
    (tmp_path / "b.pcd").write_bytes(_header("binary", 50).encode() + points.tobytes())
    for name in ("a.pcd", "b.pcd"):
        np.testing.assert_allclose(read_pcd(tmp_path / name).xyz, points, rtol=1e-6)


def test_pcd_binary_compressed_reads_pcl_data():
    """PCL's own binary_compressed files decode (LZF) to their documented content."""
    cloud = read_pcd(shared_data("pointclouds/pcl_table_scene/table_scene_mug_stereo_textured.pcd"))
    finite = np.isfinite(cloud.xyz).all(axis=1)
    assert 200_000 < finite.sum() < 220_000


def test_corrupt_lzf_is_an_error():
    """A back reference before the start of the output is refused."""
    with pytest.raises(ValueError, match="corrupt"):
        lzf_decompress(np.array([0x20, 0x05], dtype=np.uint8), 10)


def test_ply_clouds_read(tmp_path):
    """PLY files (binary and ascii) give back their vertices."""
    from plyfile import PlyData, PlyElement

    from footfall.io.clouds import read_points

    points = np.random.default_rng(1).normal(size=(20, 3)).astype(np.float32)
    vertex = np.array([tuple(p) for p in points], dtype=[("x", "f4"), ("y", "f4"), ("z", "f4")])
    for text in (False, True):
        path = tmp_path / f"cloud_{text}.ply"
        PlyData([PlyElement.describe(vertex, "vertex")], text=text).write(str(path))
        np.testing.assert_allclose(read_points(path), points, rtol=1e-6)
    (tmp_path / "x.txt").write_text("1 2 3")
    with pytest.raises(DatasetError, match="unknown point cloud format"):
        read_points(tmp_path / "x.txt")
