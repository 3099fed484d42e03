"""Walkability on real sensors: a noisy flat floor scores valid, real edges do not.

A Kinect-class noise model (footfall.sensing.noise) sets how far a cell's points may
scatter and how much slope and proximity its noise explains; the real captures in the
shared data must score their open floor valid, and a synthetic 4 cm step under the same
noise must stay invalid.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from conftest import shared_data
from footfall.cli import main
from footfall.mapping.engine import HeightMapConfig
from footfall.mapping.height_map import HeightMap
from footfall.pointcloud.ground import CameraOverFloor
from footfall.scoring.walkability import score_map
from footfall.sensing.camera import PinholeCamera
from footfall.sensing.noise import KINECT
from footfall.sensing.pose import Pose


def _step_depth(camera: PinholeCamera, floor: CameraOverFloor, step_x: float, rise: float):
    """Exact depth of a floor with a step up of ``rise`` at map x = ``step_x``."""
    u, v = np.meshgrid(np.arange(camera.width), np.arange(camera.height))
    rays = np.stack(
        [(u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy, np.ones(u.shape)], -1
    )
    d = floor.rotation_camera_to_map.apply(rays.reshape(-1, 3))
    o = np.array([0.0, 0.0, floor.height_m])
    depth = np.full(len(d), np.nan)
    with np.errstate(divide="ignore", invalid="ignore"):
        t_floor = -o[2] / d[:, 2]
        t_riser = (step_x - o[0]) / d[:, 0]
        t_top = (rise - o[2]) / d[:, 2]
    x_floor = o[0] + t_floor * d[:, 0]
    z_riser = o[2] + t_riser * d[:, 2]
    x_top = o[0] + t_top * d[:, 0]
    on_floor = (t_floor > 0) & (x_floor < step_x)
    on_riser = ~on_floor & (t_riser > 0) & (z_riser >= 0) & (z_riser <= rise)
    on_top = ~on_floor & ~on_riser & (t_top > 0) & (x_top >= step_x)
    for mask, t in ((on_floor, t_floor), (on_riser, t_riser), (on_top, t_top)):
        depth[mask] = t[mask]  # rays have unit optical z: t is the depth
    return depth.reshape(camera.height, camera.width)


def test_a_4cm_step_stays_invalid_while_the_noisy_floor_is_valid():
    """Kinect noise on a floor with a 4 cm step 1.5 m ahead (camera 0.8 m up, 35 deg down),
    five frames fused: the open floor on both sides scores valid, every row of cells along
    the step has its edge invalid."""
    rng = np.random.default_rng(0)
    camera = PinholeCamera(525, 525, 319.5, 239.5, 640, 480, noise=KINECT)
    floor = CameraOverFloor.from_angles(0.8, math.radians(35))
    exact = _step_depth(camera, floor, 1.5, 0.04)
    pose = Pose(np.array([0.0, 0.0, 0.8]), floor.rotation_camera_to_map)
    height_map = HeightMap(HeightMapConfig(size=128, fusion="variance"), centre=(1.4, 0.0))
    for _ in range(5):
        sigma = np.vectorize(KINECT.sigma_m)(np.nan_to_num(exact, nan=1.0))
        noisy = np.where(np.isfinite(exact), exact + rng.normal(0, 1, exact.shape) * sigma, np.nan)
        height_map.integrate_depth(noisy.astype(np.float32), camera, pose)
    snapshot = height_map.snapshot()
    scores = score_map(snapshot)
    x, y = snapshot.centres()
    seen = snapshot.known & (np.abs(y) < 0.4)
    open_floor = seen & ((np.abs(x - 1.5) > 0.12) & (x > 1.0) & (x < 2.0))
    assert scores.valid[open_floor].mean() > 0.95
    rows = np.unique(np.round(y[seen & (np.abs(x - 1.5) < 0.03)], 3))
    assert len(rows) > 20
    for row in rows:
        band = seen & (np.abs(y - row) < 1e-6) & (np.abs(x - 1.5) <= 0.03)
        assert not scores.valid[band].any(), row


def test_tum_frame_scores_its_floor_valid(tmp_path):
    """One real Kinect frame (TUM) from a camera pose over the floor: the open floor scores
    valid, the map leaves as map.npz with its layers in the map frame (row = y)."""
    depth = shared_data("rgbd/tum_frame/TUM_depth.png")
    out = tmp_path / "tum"
    args = ["map", "--tum", str(depth), "--camera-height", "1.8", "--camera-pitch-deg", "29.2"]
    assert main([*args, "--out", str(out)]) == 0
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["floor_valid_fraction"] >= 0.9 and metrics["floor_cells_open"] > 300
    assert abs(metrics["floor_height_median_m"]) < 0.05  # the floor, not the desk
    arrays = np.load(out / "map.npz")
    n = arrays["height"].shape[0]
    for key in ("height", "variance", "score", "valid", "known"):
        assert arrays[key].shape == (n, n), key
    assert arrays["resolution_m"] == pytest.approx(0.02) and arrays["origin_xy_m"].shape == (2,)
    known = arrays["known"]
    assert np.isfinite(arrays["height"][known]).all() and np.isnan(arrays["height"][~known]).all()
    # The camera looks along +x: its cells lie ahead, in columns right of the origin.
    _, cols = np.nonzero(known)
    x = arrays["origin_xy_m"][0] + (cols + 0.5) * 0.02
    assert np.median(x) > 1.0


def test_redwood_sequence_scores_its_floor_valid(tmp_path):
    """The Redwood living room (five frames, Kinect-like noise), converted and mapped:
    the open floor scores valid, the floor spread is that of a flat floor."""
    source = shared_data("rgbd/redwood_livingroom")
    assert main(["convert", "redwood", str(source), str(tmp_path / "tum")]) == 0
    out = tmp_path / "map"
    assert (
        main(["map", "--tum", str(tmp_path / "tum"), "--up", "0", "1", "0", "--out", str(out)]) == 0
    )
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["floor_valid_fraction"] >= 0.9
    assert metrics["floor_height_spread_m"] < 0.02
    assert 0.11 < metrics["floor_height_median_m"] < 0.16


def test_a_single_frame_without_a_pose_is_a_clear_error(tmp_path):
    """A depth PNG with no trajectory and no camera pose: the error names what to give."""
    depth = shared_data("rgbd/tum_frame/TUM_depth.png")
    from footfall.errors import DatasetError
    from footfall.reports.map import MapRequest, run_map

    with pytest.raises(DatasetError, match="--camera-height"):
        run_map(MapRequest(tum=depth))


def test_a_bad_frame_in_a_recording_is_skipped_and_counted(tmp_path):
    """A later frame that is not plausible depth (the lens covered) is skipped and counted;
    the frames around it still map. A first frame in the wrong units is an error."""
    from PIL import Image

    from footfall.datasets.tum import map_tum_sequence
    from footfall.errors import DatasetError

    (tmp_path / "depth").mkdir()
    rng = np.random.default_rng(1)
    good = (7500 + rng.integers(-5, 5, (48, 64))).astype(np.uint16)
    frames = [good, np.zeros((48, 64), np.uint16), good]
    lines, poses = [], []
    for k, image in enumerate(frames):
        Image.fromarray(image).save(tmp_path / "depth" / f"{k}.png")
        lines.append(f"{k / 30:.4f} depth/{k}.png")
        poses.append(f"{k / 30:.4f} 0 0 1 0 0 0 1")
    (tmp_path / "depth.txt").write_text("\n".join(lines) + "\n")
    (tmp_path / "groundtruth.txt").write_text("\n".join(poses) + "\n")
    camera = PinholeCamera(60, 60, 31.5, 23.5, 64, 48, noise=KINECT)
    sequence = map_tum_sequence(tmp_path, camera, (0, 0, 1))
    assert sequence.metrics["frames"] == 2 and sequence.metrics["frames_implausible"] == 1
    with pytest.raises(DatasetError, match="depth-scale"):
        map_tum_sequence(tmp_path, camera, (0, 0, 1), depth_scale=1e-5)
