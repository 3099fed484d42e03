"""Mapping in simulation: the depth camera, the map's accuracy and the course's scores."""

from __future__ import annotations

import numpy as np
import pytest

from footfall.mapping.height_map import HeightMap
from footfall.robot.spec import load_spec
from footfall.scoring.walkability import ScoreConfig, score_map
from footfall.sim.camera import SimDepthCamera
from footfall.sim.hexapod import MujocoHexapod
from footfall.sim.model import CameraMount
from footfall.sim.survey import MappingSettings, simulate_mapping, vertical_edge_cells
from footfall.sim.terrains import make_terrain
from footfall.sim.truth import TrueScores

SPEC = load_spec("default")
SMALL_CAMERA = CameraMount(width=320, height=240)


def test_simulated_depth_matches_ray_geometry():
    """Over flat ground every pixel's depth is the ray-plane distance along the optical axis,
    with the principal point at the image centre (MuJoCo samples pixel centres)."""
    sim = MujocoHexapod(SPEC, make_terrain("flat"), SMALL_CAMERA)
    camera = SimDepthCamera(sim.model, SMALL_CAMERA)
    depth, pose = camera.capture(sim.data)
    k = camera.intrinsics
    v, u = np.mgrid[0:240, 0:320]
    rays = np.stack([(u - k.cx) / k.fx, (v - k.cy) / k.fy, np.ones_like(u, dtype=float)], -1)
    world = rays @ pose.rotation.as_matrix().T
    expected = -pose.position[2] / world[..., 2]
    hits = depth > 0
    assert hits.mean() > 0.95
    np.testing.assert_allclose(depth[hits], expected[hits], rtol=1e-4)
    camera.close()


def test_map_of_a_single_frame_is_flat_ground():
    """One frame of flat ground maps to height 0 to within a millimetre."""
    sim = MujocoHexapod(SPEC, make_terrain("flat"), SMALL_CAMERA)
    camera = SimDepthCamera(sim.model, SMALL_CAMERA)
    m = HeightMap()
    depth, pose = camera.capture(sim.data)
    m.integrate_depth(depth, camera.intrinsics, pose)
    snapshot = m.snapshot()
    assert snapshot.known.sum() > 1000
    assert np.nanmax(np.abs(snapshot.heights)) < 0.001
    camera.close()


@pytest.fixture(scope="module")
def course_map():
    settings = MappingSettings(terrain="course", seconds=20.0, camera=SMALL_CAMERA)
    return simulate_mapping(SPEC, settings)


def test_course_map_is_accurate(course_map):
    """Noise-free camera over the course: height RMSE <= 5 mm over known cells, wall cells
    excluded and counted; the lane along the path is mapped."""
    m = course_map.metrics
    assert m["height_rmse_m"] <= 0.005
    assert m["edge_cells_excluded"] > 0
    assert m["cells_scored"] > 3000
    assert m["coverage"] > 0.8
    assert m["frames"] == pytest.approx(20 * 15, abs=2)
    assert m["mujoco_warnings"] == {}


def _cells(result, x, y, radius):
    xs, ys = result.snapshot.centres()
    return np.hypot(xs - x, ys - y) <= radius


def test_course_scores_follow_the_true_geometry(course_map):
    """On the mapped course: cells on the ramp and box tops are valid where seen, cells at box
    edges and the hole rim are invalid (classified by the true geometry)."""
    snapshot, scores, terrain = course_map.snapshot, course_map.scores, course_map.terrain
    xs, ys = snapshot.centres()
    known = snapshot.known
    edges = vertical_edge_cells(terrain, snapshot)
    # A box-top cell is judged when its whole window was seen and lies on the top, clear of
    # the cells that straddle the box's walls.
    truth = terrain.height(xs, ys)
    seen = np.ones_like(known)
    on_top = np.ones_like(known)
    half = ScoreConfig().kernel_size // 2
    for di in range(-half, half + 1):
        for dj in range(-half, half + 1):
            seen &= np.roll(known, (di, dj), axis=(0, 1))
            on_top &= (np.roll(truth, (di, dj), axis=(0, 1)) == 0.06) & ~np.roll(
                edges, (di, dj), axis=(0, 1)
            )
    ramp = (xs > 1.42) & (xs < 1.75) & (ys > 0.38) & (ys < 0.58) & seen
    box_top = on_top & seen
    # The rim: the top of the hole's sloped wall, the band from 0.5 to 4 cm inside its lip
    # (r = 0.19 m); a cell centred right at the lip is floor as much as wall.
    r_hole = np.hypot(xs - 0.9, ys + 0.5)
    rim = (r_hole > 0.15) & (r_hole < 0.185) & known
    assert ramp.sum() > 20 and scores.valid[ramp].all()
    assert box_top.sum() > 0 and scores.valid[box_top].all()
    walls = vertical_edge_cells(terrain, snapshot, margin_cells=0)  # cells the walls cross
    box_walls = walls & known & (np.abs(xs - 0.9) < 0.16) & (np.abs(ys - 0.46) < 0.16)
    assert box_walls.sum() > 10 and not scores.valid[box_walls].any()
    assert rim.sum() > 10 and not scores.valid[rim].any()


def test_one_centimetre_grooves_hidden_at_grazing_angles_score_invalid():
    """Cobblestones with 1 cm grooves, mapped walking over them: along the path no cell the
    true terrain rules out scores valid, though without the shadow rule some do (the
    grooves hide behind their near edges from the camera)."""
    terrain = make_terrain("cobblestones", 1, groove=0.01)
    settings = MappingSettings(terrain="cobblestones", seconds=12.0, camera=SMALL_CAMERA)
    result = simulate_mapping(SPEC, settings, terrain=terrain)
    snapshot = result.snapshot
    x0, y0 = snapshot.origin
    side = snapshot.size * snapshot.resolution
    truth = TrueScores(terrain, snapshot.resolution, settings.score, (x0, x0 + side, y0, y0 + side))
    xs, ys = snapshot.centres()
    path = (np.abs(ys) < 0.3) & (xs > 0.6) & (xs < result.path_xy[-1, 0] + 0.1)
    assert (truth.valid & path).sum() > 500
    assert not (result.scores.valid & path & ~truth.valid).any()
    assert (result.scores.valid & path).sum() > 0.6 * (truth.valid & path).sum()
    unshadowed = score_map(snapshot, ScoreConfig(shadow_points=10**9)).valid
    assert (unshadowed & path & ~truth.valid).any()


def test_slam_noise_degrades_but_does_not_break_the_map():
    """With SLAM-like pose noise the map still forms; its error grows but stays bounded."""
    settings = MappingSettings(
        terrain="flat", seconds=4.0, noise="slam", seed=1, camera=CameraMount(width=160, height=120)
    )
    m = simulate_mapping(SPEC, settings).metrics
    assert m["cells_known"] > 1000
    assert 0.0005 < m["height_rmse_m"] < 0.03
