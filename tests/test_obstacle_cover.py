"""Obstacles that keep free floor free, the floor in a cluttered view, routes out of rooms.

Synthetic rooms, corridors, L and U shapes; the shared real clouds; property tests of the
medial-line cover and of the grid route.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from scipy.spatial import cKDTree

from conftest import shared_data
from footfall.biped.avoidance import Circle, blocking, plan_path
from footfall.biped.cluster_cover import FreeFloorGrid, medial_parts
from footfall.biped.grid_route import grid_route
from footfall.biped.maps import PlanMap
from footfall.biped.obstacles import DetectionConfig, detect_obstacles
from footfall.biped.planner import path_collisions, plan_walk
from footfall.errors import DatasetError
from footfall.pointcloud.filters import euclidean_clusters
from footfall.pointcloud.ground import CameraOverFloor

PLANE = DetectionConfig(ground="plane")


def _floor(rng, lo, hi, n):
    xy = rng.uniform(lo, hi, (n, 2))
    return np.column_stack([xy, rng.normal(0, 0.003, n)])


def _wall(rng, a, b, thickness=0.1, height=1.0, n=3000):
    a, b = np.asarray(a, float), np.asarray(b, float)
    normal = np.array([a[1] - b[1], b[0] - a[0]]) / np.linalg.norm(b - a)
    xy = a + rng.uniform(0, 1, n)[:, None] * (b - a)
    xy += normal * rng.uniform(-thickness / 2, thickness / 2, n)[:, None]
    return np.column_stack([xy, rng.uniform(0, height, n)])


def _inside(circles, xy) -> np.ndarray:
    c = np.array([(q.x, q.y) for q in circles])
    r = np.array([q.r for q in circles])
    xy = np.atleast_2d(xy)
    return (((xy[:, None, :] - c[None]) ** 2).sum(axis=2) <= r[None] ** 2 + 1e-12).any(axis=1)


def _open_floor_kept(detection, clearance_m: float = 0.1) -> float:
    """Share of the floor points farther than ``clearance_m`` from every obstacle point
    that no circle covers."""
    p = detection.points_in_map
    obstacle = p[detection.obstacle_mask][:, :2]
    floor = p[np.abs(detection.ground.heights(p)) <= 0.02][:, :2]
    open_floor = floor[cKDTree(obstacle).query(floor)[0] > clearance_m]
    return 1.0 - float(_inside(detection.circles, open_floor).mean())


def test_a_u_keeps_the_floor_between_its_arms_and_a_route_leaves_it():
    """A U of walls (one obstacle): the floor between the arms stays free, the walls are
    covered; from inside it a route leaves through the open side and comes round to a goal
    behind its base, which the avoidance tree alone (one detour at a time) does not find."""
    rng = np.random.default_rng(21)
    walls = [_wall(rng, (0, 0), (3, 0)), _wall(rng, (0, 0), (0, 2)), _wall(rng, (3, 0), (3, 2))]
    cloud = np.vstack([_floor(rng, (-1.5, -1.5), (4.5, 3.5), 30000), *walls])
    detection = detect_obstacles(cloud, "map", PLANE)
    assert len(detection.clusters) == 1
    assert _inside(detection.circles, np.vstack(walls)[:, :2]).all()
    free = [(x, y) for x in np.arange(0.3, 2.8, 0.25) for y in np.arange(0.3, 2.5, 0.25)]
    assert not _inside(detection.circles, free).any()
    plan_map = PlanMap("u", (1.5, 1.0), (1.5, -1.0), tuple(detection.circles))
    plan = plan_walk(plan_map)
    inflated = plan_map.inflated
    assert plan.collisions == 0 and path_collisions(plan.path.waypoints, inflated) == 0
    assert plan.path.waypoints[:, 1].max() > 2.0  # out through the open side
    assert plan.path.length < 9.0


def test_a_corridor_of_two_long_walls_leaves_its_length_free():
    """Two parallel 6 m walls 2 m apart with a person between: the corridor's floor stays
    free but round the person, who is covered by one obstacle of their own."""
    rng = np.random.default_rng(22)
    person = rng.uniform(0, 2 * math.pi, 1500)
    body = np.column_stack(
        [3 + 0.2 * np.cos(person), 0.4 + 0.2 * np.sin(person), rng.uniform(0, 1.7, 1500)]
    )
    walls = [_wall(rng, (0, -1), (6, -1), 0.05), _wall(rng, (0, 1), (6, 1), 0.05)]
    cloud = np.vstack([_floor(rng, (0, -1), (6, 1), 20000), *walls, body])
    detection = detect_obstacles(cloud, "map", PLANE)
    assert _inside(detection.circles, np.vstack([*walls, body])[:, :2]).all()
    free = [(x, y) for x in np.arange(0.2, 5.9, 0.3) for y in (-0.7, -0.4, 0.0)]
    free = [p for p in free if math.hypot(p[0] - 3, p[1] - 0.4) > 0.45]
    assert not _inside(detection.circles, free).any()
    assert _open_floor_kept(detection) > 0.95


def _cluttered_room(rng, height_m: float, pitch_deg: float, floor_points: int):
    """A camera's view of an office: walls, desks, a shelf, chairs and a sofa standing on
    the floor, with the floor only a few per cent of the points."""

    def box(lo, hi, n):  # the faces of a box that a camera can see (not its bottom)
        lo, hi = np.asarray(lo, float), np.asarray(hi, float)
        pts = rng.uniform(lo, hi, (n, 3))
        face = rng.choice([0, 1, 2, 3, 5], n)
        for k in (0, 1, 2, 3, 5):
            pts[face == k, k // 2] = (hi if k % 2 else lo)[k // 2]
        return pts

    scene = [
        _floor(rng, (0.5, -2.0), (5.0, 2.0), floor_points),
        box((5.0, -2.0, 0.0), (5.01, 2.0, 2.6), 13000),
        box((0.5, 2.0, 0.0), (5.0, 2.01, 2.6), 13000),
    ]
    for lo, hi in [
        ((1.5, -2.0, 0.0), (3.5, -1.2, 0.75)),
        ((3.8, -0.5, 0.0), (4.6, 1.5, 0.75)),
        ((2.0, 1.4, 0.0), (4.5, 2.0, 1.9)),
        ((1.2, -0.2, 0.0), (1.7, 0.3, 0.9)),
        ((2.6, 0.3, 0.0), (3.1, 0.8, 0.9)),
        ((0.8, 1.0, 0.0), (1.6, 1.9, 0.45)),
    ]:
        scene.append(box(lo, hi, 5500))
    camera = CameraOverFloor.from_angles(height_m, math.radians(pitch_deg))
    p = camera.rotation_camera_to_map.inv().apply(np.vstack(scene) - [0, 0, height_m])
    seen = (p[:, 2] > 0.3) & (np.abs(p[:, 0]) < 0.6 * p[:, 2]) & (np.abs(p[:, 1]) < 0.45 * p[:, 2])
    return p[seen] + rng.normal(0, 0.003, (seen.sum(), 3))


@pytest.mark.parametrize(("height_m", "pitch_deg"), [(1.2, 20.0), (1.6, 10.0), (0.8, 35.0)])
def test_the_floor_of_a_cluttered_view_is_found_with_no_pose_given(height_m, pitch_deg):
    """No pose given (a level camera guessed) and the floor a few per cent of the points,
    under desk tops and seats that hold more: the ground is the lowest large level plane
    at a plausible camera height, so the camera's height and pitch come back."""
    rng = np.random.default_rng(23)
    cloud = _cluttered_room(rng, height_m, pitch_deg, 250)
    detection = detect_obstacles(cloud, "camera")
    assert detection.camera.height_m == pytest.approx(height_m, abs=0.05)
    assert math.degrees(detection.camera.pitch_rad) == pytest.approx(pitch_deg, abs=2.0)


def test_a_view_with_no_plausible_floor_is_a_clear_error():
    """A camera said to stand at most 1.5 m over its floor sees only a level surface 2.2 m
    below it (a view down into a hall): the detector says it found no floor in that range,
    rather than taking one."""
    rng = np.random.default_rng(24)
    deep = _floor(rng, (0.5, -2), (4, 2), 5000) - [0, 0, 2.2]
    camera = CameraOverFloor.from_angles(0.0, math.radians(30))
    cloud = camera.rotation_camera_to_map.inv().apply(deep)
    config = DetectionConfig(camera_height_range=(0.2, 1.5))
    with pytest.raises(DatasetError, match=r"0\.2 to 1\.5 m below the camera"):
        detect_obstacles(cloud, "camera", config)
    assert detect_obstacles(cloud, "camera").camera.height_m == pytest.approx(2.2, abs=0.02)


@pytest.mark.parametrize(
    "name",
    ["rgbd/tum_frame/TUM_depth.png", "rgbd/redwood_livingroom/depth/00000.png"],
)
def test_real_views_keep_their_open_floor_and_cover_every_obstacle(name):
    """Real depth frames, no pose given: the floor is found, every obstacle point lies in a
    circle, no circle is larger than the furniture it covers, and at least 85 % of
    the open floor (10 cm from any obstacle) stays free (the dissertation's circles kept
    none of the TUM frame's and 44 % of the Redwood frame's)."""
    from PIL import Image

    path = shared_data(name)
    scale = 5000.0 if "tum" in name else 1000.0
    depth = np.asarray(Image.open(path), dtype=np.float64) / scale
    v, u = np.nonzero(depth > 0)
    z = depth[v, u]
    cloud = np.column_stack([(u - 319.5) * z / 525.0, (v - 239.5) * z / 525.0, z])
    config = DetectionConfig()
    detection = detect_obstacles(cloud, "camera", config)
    assert 0.3 < detection.camera.height_m < 2.5
    obstacle = detection.points_in_map[detection.obstacle_mask]
    for members in euclidean_clusters(obstacle, config.cluster_tolerance, config.min_cluster_size):
        assert _inside(detection.circles, obstacle[members, :2]).all()
    assert max(c.r for c in detection.circles) < 0.7
    assert _open_floor_kept(detection) > 0.85


@st.composite
def _strokes(draw):
    """Points along a few random strokes (walls, bars, bends) on a 4 m square."""
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    pieces = []
    for _ in range(draw(st.integers(1, 4))):
        a = rng.uniform(0, 4, 2)
        b = a + rng.uniform(-2, 2, 2)
        width = draw(st.floats(0.0, 0.6))
        pieces.append(_wall(rng, a, b, width, 1.0, 400)[:, :2])
    return np.vstack(pieces)


@settings(max_examples=40, deadline=None)
@given(points=_strokes(), min_radius=st.floats(0.05, 0.3))
def test_the_medial_cover_covers_every_point_from_centres_on_the_footprint(points, min_radius):
    """Whatever the shape, every point lies inside a circle; every circle is centred on the
    footprint (within one cell's diagonal of a point, as the gap-closing joins cells), and
    no circle is larger than the shape's half thickness allows plus a cell."""
    grid = FreeFloorGrid.build(points, np.empty((0, 2)), 0.05)
    parts = medial_parts(points, grid, min_radius)
    circles = [c for _, part in parts for c in part]
    assert _inside(circles, points).all()
    assert np.all(np.sum([mine for mine, _ in parts], axis=0) == 1)  # each point one part
    centres = np.array([(c.x, c.y) for c in circles])
    assert cKDTree(points).query(centres)[0].max() <= 2 * 0.05 * math.sqrt(2) + 1e-9
    longest = float(np.ptp(points, axis=0).max())
    assert max(c.r for c in circles) <= max(min_radius, 0.5 * longest) + 0.1


@st.composite
def _circle_fields(draw):
    count = draw(st.integers(1, 25))
    return [
        Circle(draw(st.floats(-3, 3)), draw(st.floats(-3, 3)), draw(st.floats(0.1, 0.8)))
        for _ in range(count)
    ]


@settings(max_examples=60, deadline=None)
@given(
    circles=_circle_fields(),
    start=st.tuples(st.floats(-4, 4), st.floats(-4, 4)),
    goal=st.tuples(st.floats(-4, 4), st.floats(-4, 4)),
)
def test_a_grid_route_never_enters_a_circle(circles, start, goal):
    """A grid route, when there is one, runs from start to goal in segments that clear
    every circle; plan_path's routes (tree or grid) do too."""
    for p in (start, goal):
        assume(all(math.hypot(p[0] - c.x, p[1] - c.y) > c.r + 1e-3 for c in circles))
    route = grid_route(start, goal, circles)
    if route is not None:
        np.testing.assert_allclose(route[0], start)
        np.testing.assert_allclose(route[-1], goal)
        for a, b in itertools.pairwise(route):
            assert not blocking(a, b, circles)
    try:
        path = plan_path(start, goal, circles)
    except Exception:
        return
    for a, b in itertools.pairwise(path.waypoints):
        assert not blocking(a, b, circles)
