"""Obstacle detection in point clouds for the biped."""

from __future__ import annotations

import json

import numpy as np
import pytest

from conftest import shared_data
from footfall.biped.obstacles import (
    OPTICAL_TO_BASE,
    DetectionConfig,
    camera_to_map,
    describe_cluster,
    detect_obstacles,
    euclidean_clusters,
    inverted_cone_points,
    ransac_plane,
)
from footfall.cli import main
from footfall.errors import DatasetError
from footfall.io.clouds import read_points


def _scene(rng: np.random.Generator) -> np.ndarray:
    """A floor with a 0.4 m cube at (2, 0) and a 1.2 x 0.2 m wall at (3, 1), map frame."""
    floor = np.column_stack(
        [rng.uniform(0, 4, 4000), rng.uniform(-2, 2, 4000), rng.normal(0, 0.005, 4000)]
    )
    cube = rng.uniform([1.8, -0.2, 0.0], [2.2, 0.2, 0.4], (800, 3))
    wall = rng.uniform([2.4, 0.9, 0.0], [3.6, 1.1, 0.5], (800, 3))
    return np.vstack([floor, cube, wall])


def test_ground_plane_approach_finds_the_two_obstacles():
    """Above the known ground: two clusters, a box and an elongated wall (a chain of circles)."""
    detection = detect_obstacles(_scene(np.random.default_rng(0)), frame="map")
    assert len(detection.clusters) == 2
    wall, cube = sorted(detection.clusters, key=lambda c: -c.width)
    np.testing.assert_allclose(cube.centre, [2.0, 0.0], atol=0.03)
    assert len(cube.circles) == 1
    np.testing.assert_allclose(wall.centre, [3.0, 1.0], atol=0.03)
    assert wall.width == pytest.approx(1.2, abs=0.05) and wall.depth == pytest.approx(0.2, abs=0.03)
    assert 6 <= len(wall.circles) <= 7  # ceil(1.2 m / measured depth of about 0.2 m)


def test_ransac_removes_the_floor():
    """RANSAC finds the floor plane (normal up) and keeps the obstacles."""
    points = _scene(np.random.default_rng(1))
    normal, d, inliers = ransac_plane(points, 0.02, 100, np.random.default_rng(0))
    assert abs(normal[2]) > 0.99 and abs(d) < 0.01
    assert inliers[:4000].mean() > 0.97 and inliers[4000:].mean() < 0.1
    detection = detect_obstacles(points, frame="map", config=DetectionConfig(ground="ransac"))
    assert len(detection.clusters) == 2


def test_inverted_cone_detector_marks_obstacles_not_floor():
    """Manduchi's test (eqs. 71-72) flags points on vertical structure, not the open floor
    (floor points at an obstacle's foot pair with it and count as its base)."""
    points = _scene(np.random.default_rng(2))
    mask = inverted_cone_points(points, DetectionConfig())
    open_floor = points[:4000, 0] < 1.3  # well away from the cube (x >= 1.8) and the wall
    assert mask[4000:].mean() > 0.8 and not mask[:4000][open_floor].any()


def test_clusters_respect_the_tolerance():
    """Two blobs 0.5 m apart are two clusters at 0.3 m tolerance, one at 0.6 m."""
    rng = np.random.default_rng(3)
    blobs = np.vstack(
        [rng.normal([0, 0, 0], 0.03, (50, 3)), rng.normal([0.5, 0, 0], 0.03, (50, 3))]
    )
    assert len(euclidean_clusters(blobs, 0.3, 5)) == 2
    assert len(euclidean_clusters(blobs, 0.6, 5)) == 1
    assert euclidean_clusters(blobs, 0.3, 60) == []


def test_principal_axes_box_of_a_rotated_wall():
    """PCA aligns the box with a wall however it is turned."""
    rng = np.random.default_rng(4)
    local = rng.uniform([-0.6, -0.1, 0.0], [0.6, 0.1, 0.3], (2000, 3))
    yaw = 0.6
    r = np.array([[np.cos(yaw), -np.sin(yaw), 0], [np.sin(yaw), np.cos(yaw), 0], [0, 0, 1]])
    cluster = describe_cluster(local @ r.T + [1.0, 2.0, 0.0])
    assert cluster.width == pytest.approx(1.2, abs=0.03) and cluster.depth == pytest.approx(
        0.2, abs=0.02
    )
    assert np.cos(cluster.yaw - yaw) ** 2 == pytest.approx(1.0, abs=1e-3)


def test_camera_frame_maps_forward_to_x_and_down_to_minus_z():
    """Optical z (forward) is base x, optical x (right) is base -y, optical y (down) is -z."""
    np.testing.assert_allclose(OPTICAL_TO_BASE @ [0, 0, 1], [1, 0, 0])
    np.testing.assert_allclose(OPTICAL_TO_BASE @ [1, 0, 0], [0, -1, 0])
    np.testing.assert_allclose(OPTICAL_TO_BASE @ [0, 1, 0], [0, 0, -1])
    moved = camera_to_map(
        [[0, 0, 2.0]],
        robot_position=[1, 1, 0],
        robot_rpy=[0, 0, np.pi / 2],
        camera_in_base=[0, 0, 0.5],
    )
    np.testing.assert_allclose(moved, [[1, 3, 0.5]], atol=1e-12)


def test_empty_cloud_is_a_clear_error():
    """An empty cloud, or one the pass-through filter empties, is refused."""
    with pytest.raises(DatasetError, match="empty"):
        detect_obstacles(np.zeros((0, 3)))
    with pytest.raises(DatasetError, match="pass-through"):
        detect_obstacles(np.array([[0.0, 0.0, 9.0]]), frame="camera")


def test_table_scene_floor_and_mug(tmp_path):
    """PCL's table scene: RANSAC takes the table top (about 60 % of the points); a cluster
    remains on it where the mug stands; `footfall obstacles` writes its outputs."""
    cloud = shared_data("pointclouds/pcl_table_scene/table_scene_mug_stereo_textured.pcd")
    points = read_points(cloud)
    detection = detect_obstacles(
        points,
        frame="map",
        config=DetectionConfig(ground="ransac", cluster_tolerance=0.02, min_cluster_size=100),
    )
    assert 0.55 < (~detection.obstacle_mask).mean() < 0.65
    near = [c for c in detection.clusters if np.linalg.norm(c.centroid - [0.06, 0.06, 0.75]) < 0.1]
    assert near and 0.05 < near[0].width < 0.25
    code = main(
        [
            "obstacles",
            "--cloud",
            str(cloud),
            "--ground",
            "ransac",
            "--cluster-tolerance",
            "0.02",
            "--min-cluster-size",
            "100",
            "--out",
            str(tmp_path),
        ]
    )
    assert code == 0
    data = json.loads((tmp_path / "obstacles.json").read_text())
    assert len(data["clusters"]) >= 1 and (tmp_path / "obstacles.png").exists()


def test_plan_on_a_cloud(tmp_path):
    """`footfall plan --cloud` detects obstacles and plans around them."""
    path = tmp_path / "scene.npy"
    np.save(path, _scene(np.random.default_rng(5)))
    assert (
        main(
            [
                "plan",
                "--cloud",
                str(path),
                "--frame",
                "map",
                "--goal",
                "4",
                "0",
                "--out",
                str(tmp_path / "o"),
            ]
        )
        == 0
    )
    plan = json.loads((tmp_path / "o" / "plan.json").read_text())
    assert plan["collisions"] == 0 and plan["path_length_m"] > 4.0
