"""Obstacle detection in point clouds for the biped."""

from __future__ import annotations

import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from conftest import shared_data
from footfall.biped.obstacles import (
    OPTICAL_TO_BASE,
    DetectionConfig,
    camera_to_map,
    describe_cluster,
    detect_obstacles,
)
from footfall.cli import main
from footfall.errors import ConfigError, DatasetError
from footfall.io.clouds import read_points
from footfall.pointcloud.filters import euclidean_clusters, inverted_cone_points
from footfall.pointcloud.ground import CameraOverFloor, find_ground


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
    detection = detect_obstacles(
        _scene(np.random.default_rng(0)), frame="map", config=DetectionConfig(ground="plane")
    )
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
    ground = find_ground(points, (0, 0, 1), np.radians(15), rng=np.random.default_rng(0))
    inliers = np.abs(ground.heights(points)) < 0.02
    assert ground.normal[2] > 0.99 and abs(ground.offset_m) < 0.01
    assert inliers[:4000].mean() > 0.97 and inliers[4000:].mean() < 0.1
    detection = detect_obstacles(points, frame="map", config=DetectionConfig(ground="ransac"))
    assert len(detection.clusters) == 2


def test_inverted_cone_detector_marks_obstacles_not_floor():
    """Manduchi's test (eqs. 71-72) flags points on vertical structure, not the open floor
    (floor points at an obstacle's foot pair with it and count as its base)."""
    points = _scene(np.random.default_rng(2))
    c = DetectionConfig()
    mask = inverted_cone_points(points, c.cone_min_height, c.cone_max_height, c.cone_max_slope)
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


def test_table_scene_keeps_its_table_and_finds_the_mug(tmp_path):
    """PCL's table scene, as `footfall obstacles` takes it with the defaults: the table top is
    the ground (no lower plane holds a tenth of the points), its normal in the camera frame
    is reported, and one obstacle stands on it where the mug is (about 10 cm tall)."""
    cloud = shared_data("pointclouds/pcl_table_scene/table_scene_mug_stereo_textured.pcd")
    code = main(["obstacles", "--cloud", str(cloud), "--out", str(tmp_path)])
    assert code == 0 and (tmp_path / "obstacles.png").exists()
    data = json.loads((tmp_path / "obstacles.json").read_text())
    plane = data["ground_plane"]
    np.testing.assert_allclose(plane["normal_in_camera"], [0.015, -0.838, -0.545], atol=0.03)
    assert plane["offset_in_camera_m"] == pytest.approx(0.53, abs=0.02)
    assert plane["angle_to_up_deg"] == pytest.approx(33.0, abs=3.0)  # from a level camera
    for key in ("voxel_size_m", "points_in", "points_after_voxel", "detect_ms"):
        assert key in data
    assert data["points_in"] > 200_000 > data["points_after_voxel"]
    mugs = [c for c in data["clusters"] if 0.05 < c["box"]["height"] < 0.15]
    assert len(data["clusters"]) == 1 and len(mugs) == 1
    assert 0.06 < mugs[0]["box"]["width"] < 0.2  # the mug and its handle


def test_kinect_frame_looking_down_takes_the_floor():
    """The shared pcl_grabber frame (a Kinect about 45 deg down at a floor with a laptop and
    a box): with --camera-pitch-deg 45 the ground is the floor, within 10 deg of the
    expected up axis, 0.6-0.8 m under the camera, and obstacles stand on it."""
    cloud = shared_data("pointclouds/pcl_grabber/frame_20121214T142255.814212.pcd")
    detection = detect_obstacles(
        read_points(cloud), "camera", camera=CameraOverFloor.from_angles(0.0, np.radians(45))
    )
    assert detection.ground.angle_to_up_deg < 10 and detection.ground.inlier_fraction > 0.5
    assert 0.6 < detection.camera.height_m < 0.8
    standing = [c for c in detection.clusters if c.height > 0.1 and c.centroid[2] < 0.3]
    assert len(standing) >= 2
    assert all(c.centroid[0] > 0.3 for c in detection.clusters)  # in front of the camera


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


def _floor(rng, lo, hi, n):
    return np.column_stack(
        [rng.uniform(lo[0], hi[0], n), rng.uniform(lo[1], hi[1], n), rng.normal(0, 0.003, n)]
    )


def _wall(rng, a, b, thickness=0.1, height=1.0, n=3000):
    a, b = np.asarray(a, float), np.asarray(b, float)
    d = b - a
    normal = np.array([-d[1], d[0]]) / np.linalg.norm(d)
    xy = a + rng.uniform(0, 1, n)[:, None] * d
    xy += normal * rng.uniform(-thickness / 2, thickness / 2, n)[:, None]
    return np.column_stack([xy, rng.uniform(0, height, n)])


def _blocked(detection, xy) -> bool:
    return any((xy[0] - c.x) ** 2 + (xy[1] - c.y) ** 2 < c.r**2 for c in detection.circles)


@pytest.mark.parametrize("with_floor", [True, False])
def test_an_l_shaped_wall_leaves_its_inside_free(with_floor):
    """Two walls joined at a corner are one obstacle, but its circles follow the arms (the
    medial line): the floor inside the L stays free; every wall point stays covered."""
    rng = np.random.default_rng(10)
    walls = np.vstack([_wall(rng, (0, 0), (2, 0)), _wall(rng, (0, 0), (0, 2))])
    cloud = np.vstack([_floor(rng, (-1, -1), (3, 3), 20000), walls]) if with_floor else walls
    detection = detect_obstacles(cloud, "map", DetectionConfig(ground="plane"))
    assert len(detection.clusters) == 1 and len(detection.circles) > 8
    assert max(c.r for c in detection.circles) < 0.2
    for xy in [(0.4, 0.4), (1.0, 1.0), (1.5, 0.5), (0.5, 1.5), (1.8, 1.8)]:
        assert not _blocked(detection, xy), xy
    for xy in [(0.5, 0.0), (1.9, 0.0), (0.0, 1.0), (0.0, 0.0)]:
        assert _blocked(detection, xy), xy


def test_a_room_keeps_its_middle_free():
    """Four walls joined at the corners: the circles follow the walls, the room is free."""
    rng = np.random.default_rng(11)
    corners = [(0, 0), (4, 0), (4, 3), (0, 3)]
    walls = [_wall(rng, corners[k], corners[(k + 1) % 4]) for k in range(4)]
    cloud = np.vstack([_floor(rng, (-0.5, -0.5), (4.5, 3.5), 30000), *walls])
    detection = detect_obstacles(cloud, "map", DetectionConfig(ground="plane"))
    free = [(x, y) for x in np.arange(0.4, 3.7, 0.3) for y in np.arange(0.4, 2.7, 0.3)]
    assert not any(_blocked(detection, xy) for xy in free)
    assert all(_blocked(detection, xy) for xy in [(2, 0), (4, 1.5), (2, 3), (0, 1.5)])


def test_a_box_seen_from_its_corner_stays_one_obstacle():
    """Two faces of a box seen from its corner form an L, but the floor inside is hidden
    (no floor point): the box is not split, its circle covers it."""
    rng = np.random.default_rng(12)
    faces = np.vstack(
        [_wall(rng, (1, 0), (1.5, 0), 0.02, 0.4), _wall(rng, (1, 0), (1, 0.5), 0.02, 0.4)]
    )
    floor = _floor(rng, (0, -1), (3, 1.5), 20000)
    hidden = (floor[:, 0] > 1.0) & (floor[:, 1] > 0.0) & (floor[:, 0] < 3.0)
    cloud = np.vstack([floor[~hidden], faces])
    detection = detect_obstacles(cloud, "map", DetectionConfig(ground="plane"))
    assert len(detection.clusters) == 1
    assert _blocked(detection, (1.25, 0.25))


def test_ransac_takes_the_floor_not_a_larger_wall_or_table():
    """A wall with more points than the floor, and a table top above it: the ground is the
    floor, the lowest plane near the up axis that holds enough of the points."""
    rng = np.random.default_rng(13)
    floor = _floor(rng, (0, -1), (3, 1), 4000)
    wall = np.column_stack(
        [
            np.full(9000, 3.0) + rng.normal(0, 0.003, 9000),
            rng.uniform(-1, 1, 9000),
            rng.uniform(0, 2, 9000),
        ]
    )
    table = _floor(rng, (0.5, -0.8), (2.5, 0.8), 6000) + [0, 0, 0.75]
    ground = find_ground(np.vstack([wall, table, floor]), (0, 0, 1), np.radians(15))
    assert ground.normal[2] > 0.99 and abs(ground.offset_m) < 0.01
    assert ground.candidates >= 2


def test_a_camera_frame_cloud_lands_on_its_floor():
    """A synthetic capture from a camera 0.8 m up, pitched 30 deg down and rolled 5 deg: the
    floor found is level in the map frame, the camera's height and pitch come back, and a
    box 2 m ahead stands where it is, whether the pose is given or only guessed (level)."""
    rng = np.random.default_rng(14)
    truth = CameraOverFloor.from_angles(0.8, np.radians(30), np.radians(5))
    scene = np.vstack(
        [
            _floor(rng, (0.5, -1.5), (4, 1.5), 20000),
            rng.uniform([1.8, -0.2, 0], [2.2, 0.2, 0.4], (2000, 3)),
        ]
    )
    to_camera = truth.rotation_camera_to_map.inv()
    in_camera = to_camera.apply(scene - [0, 0, 0.8])
    for pose in (truth, None):
        detection = detect_obstacles(in_camera, "camera", camera=pose)
        assert detection.camera.height_m == pytest.approx(0.8, abs=0.01)
        assert np.degrees(detection.camera.pitch_rad) == pytest.approx(30, abs=1)
        assert np.degrees(detection.camera.roll_rad) == pytest.approx(5, abs=1)
        assert len(detection.clusters) == 1
        np.testing.assert_allclose(detection.clusters[0].centre, [2.0, 0.0], atol=0.05)
    assert detect_obstacles(in_camera, "camera", camera=truth).ground.angle_to_up_deg < 1.0
    plane = detect_obstacles(in_camera, "camera", DetectionConfig(ground="plane"), camera=truth)
    np.testing.assert_allclose(plane.clusters[0].centre, [2.0, 0.0], atol=0.05)
    with pytest.raises(ConfigError, match="camera-height"):
        detect_obstacles(in_camera, "camera", DetectionConfig(ground="plane"))


@given(
    height=st.floats(0.1, 3.0),
    pitch=st.floats(-80, 80),
    roll=st.floats(-80, 80),
)
def test_plane_coefficients_and_angles_agree(height, pitch, roll):
    """The floor plane of a camera pose, given as coefficients, gives back the same pose."""
    pose = CameraOverFloor.from_angles(height, np.radians(pitch), np.radians(roll))
    up = pose.up_in_camera
    again = CameraOverFloor.from_plane([*(2.0 * up), 2.0 * height])
    assert again.height_m == pytest.approx(height)
    assert np.degrees(again.pitch_rad) == pytest.approx(pitch, abs=1e-6)
    assert np.degrees(again.roll_rad) == pytest.approx(roll, abs=1e-6)
    p = np.array([[0.3, -0.2, 2.0]])
    np.testing.assert_allclose(again.to_map(p), pose.to_map(p), atol=1e-9)


@given(
    cloud=st.lists(
        st.tuples(*[st.floats(-2.0, 2.0, allow_nan=False)] * 3), min_size=1, max_size=150
    ),
    tolerance=st.floats(0.05, 1.0),
)
@settings(deadline=None)  # the first call compiles the kernels; speed is for benchmarks
def test_grid_clusters_equal_the_neighbour_pair_graph(cloud, tolerance):
    """The grid union-find gives exactly the connected components of the kd-tree's pairs
    within the tolerance (the method it replaces), in linear memory."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components
    from scipy.spatial import cKDTree

    points = np.array(cloud)
    pairs = cKDTree(points).query_pairs(tolerance, output_type="ndarray")
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(len(points),) * 2)
    _, labels = connected_components(graph, directed=False)
    expected = sorted(sorted(np.flatnonzero(labels == k).tolist()) for k in np.unique(labels))
    got = sorted(sorted(c.tolist()) for c in euclidean_clusters(points, tolerance, 1))
    assert got == expected


@given(
    cloud=st.lists(
        st.tuples(*[st.floats(-3.0, 3.0, allow_nan=False)] * 3), min_size=1, max_size=200
    ),
    voxel=st.floats(0.01, 1.0),
)
def test_voxel_grid_keeps_one_centroid_per_voxel(cloud, voxel):
    """Each output point is the centroid of the input points of one voxel, and no two
    outputs share a voxel; the total mass is kept."""
    from footfall.pointcloud.filters import voxel_downsample

    points = np.array(cloud)
    out = voxel_downsample(points, voxel)
    keys = np.floor((points - points.min(axis=0)) / voxel).astype(int)
    voxels = {tuple(k) for k in keys}
    assert len(out) == len(voxels)
    sums = {}
    for k, p in zip(map(tuple, keys), points, strict=True):
        sums.setdefault(k, []).append(p)
    centroids = np.array(sorted(tuple(np.mean(v, axis=0)) for v in sums.values()))
    np.testing.assert_allclose(np.array(sorted(map(tuple, out))), centroids, atol=1e-9)


def test_a_level_camera_under_a_ceiling_takes_the_floor():
    """A corridor seen by a level camera 1 m up: the ceiling (more points than the floor)
    and the walls are not the ground; the floor is, and the person standing on it is found."""
    rng = np.random.default_rng(15)
    floor = _floor(rng, (0.5, -1), (6, 1), 3000)
    ceiling = _floor(rng, (0.5, -1), (6, 1), 6000) + [0, 0, 2.5]
    walls = np.vstack(
        [
            np.column_stack(
                [rng.uniform(0.5, 6, 4000), np.full(4000, side), rng.uniform(0, 2.5, 4000)]
            )
            for side in (-1.0, 1.0)
        ]
    )
    person = rng.uniform([2.9, -0.2, 0.0], [3.1, 0.2, 1.7], (1500, 3))
    scene = np.vstack([floor, ceiling, walls, person])
    level = CameraOverFloor.from_angles(1.0)
    in_camera = level.rotation_camera_to_map.inv().apply(scene - [0, 0, 1.0])
    detection = detect_obstacles(in_camera, "camera")
    assert detection.camera.height_m == pytest.approx(1.0, abs=0.02)
    assert detection.ground.angle_to_up_deg < 2
    people = [
        c for c in detection.clusters if abs(c.centre[0] - 3.0) < 0.2 and abs(c.centre[1]) < 0.2
    ]
    assert len(people) == 1 and people[0].height > 1.5


def test_obstacles_cli_takes_the_pose_options(tmp_path):
    """`footfall obstacles` with --camera-height/--camera-pitch-deg and each ground method."""
    rng = np.random.default_rng(16)
    truth = CameraOverFloor.from_angles(0.7, np.radians(40))
    scene = np.vstack(
        [
            _floor(rng, (0.3, -1), (2.5, 1), 8000),
            rng.uniform([1.2, -0.2, 0], [1.5, 0.2, 0.5], (1500, 3)),
        ]
    )
    path = tmp_path / "capture.npy"
    np.save(path, truth.rotation_camera_to_map.inv().apply(scene - [0, 0, 0.7]))
    base = ["obstacles", "--cloud", str(path), "--camera-height", "0.7", "--camera-pitch-deg", "40"]
    for ground in ("ransac", "plane", "cones"):
        out = tmp_path / ground
        assert main([*base, "--ground", ground, "--out", str(out)]) == 0
        data = json.loads((out / "obstacles.json").read_text())
        assert data["ground_plane"]["angle_to_up_deg"] < 2, ground
        boxes = [c for c in data["clusters"] if abs(c["box"]["x"] - 1.35) < 0.15]
        assert boxes, ground
    a, b, c = truth.up_in_camera
    plane = ["--ground-plane", str(a), str(b), str(c), "0.7", "--ground", "plane"]
    out = tmp_path / "coefficients"
    assert main(["obstacles", "--cloud", str(path), *plane, "--out", str(out)]) == 0
    data = json.loads((out / "obstacles.json").read_text())
    assert data["camera"]["pitch_deg"] == pytest.approx(40, abs=1e-6)
    assert [c for c in data["clusters"] if abs(c["box"]["x"] - 1.35) < 0.15]


def test_a_corridor_with_a_ceiling_and_people_leaves_its_middle_free():
    """A level camera 1.2 m up in a corridor with a ceiling: the ceiling is overhead (not
    an obstacle joining the walls into one that fills the corridor), each person standing in
    it is one obstacle, and the floor between them stays free."""
    rng = np.random.default_rng(17)

    def box(n, lo, hi):
        return rng.uniform(lo, hi, (n, 3))

    floor = _floor(rng, (0.5, -1.2), (6, 1.2), 15000)
    walls = np.vstack(
        [box(8000, (0.5, -1.2, 0), (6, -1.19, 2.5)), box(8000, (0.5, 1.19, 0), (6, 1.2, 2.5))]
    )
    ceiling = box(10000, (0.5, -1.2, 2.5), (6, 1.2, 2.51))
    people = []
    for x, y in [(2.5, 0.3), (3.5, -0.5), (4.5, 0.6)]:
        a = rng.uniform(np.pi / 2, 3 * np.pi / 2, 2000)
        people.append(
            np.column_stack([x + 0.2 * np.cos(a), y + 0.2 * np.sin(a), rng.uniform(0, 1.75, 2000)])
        )
    camera = CameraOverFloor.from_angles(1.2, np.radians(10))
    scene = np.vstack([floor, walls, ceiling, *people])
    in_camera = camera.rotation_camera_to_map.inv().apply(scene - [0, 0, 1.2])
    detection = detect_obstacles(in_camera + rng.normal(0, 0.003, in_camera.shape), "camera")
    found = [c for c in detection.clusters if 1.5 < c.height < 1.9 and c.width < 0.6]
    assert len(found) == 3
    for xy in [(1.5, 0.0), (3.0, 0.5), (4.0, -0.4), (5.5, 0.0)]:
        assert not _blocked(detection, xy), xy
