"""Depth odometry: a camera tracked through a ray-cast room with known poses, a lost track, the
trajectory errors, and ``footfall odometry`` on TUM-layout sequences (synthetic and real)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from PIL import Image
from scipy.spatial.transform import Rotation

from conftest import shared_data
from depth_scenes import CAMERA, looking, render
from footfall.cli import main
from footfall.errors import ConfigError
from footfall.odometry.evaluation import trajectory_errors
from footfall.odometry.registration import DepthOdometry, OdometryConfig, TrackingLostError
from footfall.sensing.pose import Pose

pytest.importorskip("small_gicp")


def _walk(frames: int = 20) -> list[Pose]:
    """A camera drifting forward and left on a bend, turning and tilting, as a hand-held
    one does."""
    return [
        looking(
            [0.03 * k, 0.01 * k + 0.001 * k * k, 1.2 - 0.005 * k], 0.4 + 0.02 * k, 0.3 + 0.005 * k
        )
        for k in range(frames)
    ]


def _noisy(depth: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """A structured-light camera's scatter: 1.5 mm at 1 m, growing with the range squared."""
    return depth + rng.normal(0.0, 0.0015, depth.shape) * depth**2


def _errors(estimate: Pose, truth: Pose) -> tuple[float, float]:
    """Position [m] and angle [deg] between two poses."""
    turn = (estimate.rotation.inv() * truth.rotation).magnitude()
    return float(np.linalg.norm(estimate.position - truth.position)), float(np.degrees(turn))


def test_depth_odometry_follows_a_camera_through_a_room():
    """Twenty noisy frames, 3 cm and a degree apart: every frame registers and the last pose
    is within a centimetre and half a degree of the truth."""
    rng = np.random.default_rng(4)
    truth = _walk()
    odometry = DepthOdometry(CAMERA, start=truth[0])
    for k, pose in enumerate(truth):
        step = odometry.track(_noisy(render(pose), rng), 0.1 * k)
        assert step.registered, step.reason
        assert step.inlier_share > 0.5
    position_m, angle_deg = _errors(odometry.camera_in_world, truth[-1])
    assert position_m < 0.01 and angle_deg < 0.5


def _within(norm: float) -> st.SearchStrategy[np.ndarray]:
    """Vectors of any direction and a length up to ``norm``."""
    unit = st.tuples(*[st.floats(-1.0, 1.0)] * 3).filter(lambda v: np.linalg.norm(v) > 0.1)
    return st.builds(
        lambda v, share: norm * share * np.asarray(v) / np.linalg.norm(v),
        unit,
        st.floats(0.0, 1.0),
    )


@settings(max_examples=12, deadline=None)
@given(_within(0.05), _within(0.05))
def test_one_registered_step_recovers_the_cameras_motion(shift_m, turn_rad):
    """Any motion up to 5 cm and 0.05 rad between two exact frames, from a standing start
    (a fast hand-held camera at 30 Hz: 1.5 m/s, 86 deg/s), far walls in view, is found to a
    millimetre and a tenth of a degree."""
    start = looking([0.5, 0.2, 1.1], 0.5, 0.35)
    moved = Pose(start.position + shift_m, Rotation.from_rotvec(turn_rad) * start.rotation)
    odometry = DepthOdometry(CAMERA, start=start)
    odometry.track(render(start), 0.0)
    step = odometry.track(render(moved), 0.1)
    assert step.registered, step.reason
    position_m, angle_deg = _errors(step.camera_in_world, moved)
    assert position_m < 0.001 and angle_deg < 0.1


def test_a_frame_without_depth_is_skipped_and_the_track_goes_on():
    """A blank frame keeps the last pose and says why; the next frame registers from it."""
    truth = _walk(6)
    odometry = DepthOdometry(CAMERA, start=truth[0])
    for k in range(3):
        odometry.track(render(truth[k]), 0.1 * k)
    blank = odometry.track(np.zeros((CAMERA.height, CAMERA.width)), 0.3)
    assert not blank.registered and "points" in blank.reason
    assert _errors(blank.camera_in_world, truth[2])[0] < 0.002
    for k in (4, 5):
        assert odometry.track(render(truth[k]), 0.1 * k).registered
    assert _errors(odometry.camera_in_world, truth[5])[0] < 0.003


def test_a_track_that_loses_the_scene_is_lost_and_says_when_and_where():
    """Frames that match nothing (a camera pressed against a wall it never saw) for
    ``recover_frames`` in a row: lost, with the time and the last good pose."""
    truth = _walk(3)
    config = OdometryConfig(recover_frames=3)
    odometry = DepthOdometry(CAMERA, config, start=truth[0])
    for k, pose in enumerate(truth):
        odometry.track(render(pose), 0.1 * k)
    elsewhere = looking([4.7, 2.2, 2.8], -2.4, -0.6)  # into the far corner, under the ceiling
    with pytest.raises(TrackingLostError, match=r"tracking lost at 0\.500 s") as lost:
        for k in range(3, 10):
            odometry.track(render(elsewhere), 0.1 * k)
    assert lost.value.stamp == pytest.approx(0.5)
    assert _errors(lost.value.last_pose, truth[-1])[0] < 0.002


@settings(max_examples=20, deadline=None)
@given(
    st.tuples(*[st.floats(-5.0, 5.0)] * 3),
    st.tuples(*[st.floats(-3.0, 3.0)] * 3),
)
def test_the_absolute_error_ignores_where_the_estimate_put_its_world(shift_m, turn_rad):
    """An estimate that is the truth in another world frame has no ATE and no drift; one
    whose every position is 2 cm off along one axis has an ATE of at most 2 cm."""
    k = np.arange(40.0)
    positions = np.column_stack([0.1 * k, 0.2 * np.sin(k / 5), 0.01 * k])
    stamps = 100.0 + 0.05 * k
    quats = Rotation.from_rotvec(np.outer(0.05 * k, [0.0, 0.0, 1.0])).as_quat()
    reference = np.column_stack([stamps, positions, quats])
    frame = Pose(np.asarray(shift_m), Rotation.from_rotvec(turn_rad))
    moved = [frame.compose(Pose.from_quaternion(r[1:4], r[4:8])) for r in reference]
    estimate = np.array(
        [[r[0], *p.position, *p.rotation.as_quat()] for r, p in zip(reference, moved, strict=True)]
    )
    errors = trajectory_errors(estimate, reference)
    assert errors.ate_rmse_m < 1e-6 and errors.rpe_per_m < 1e-6 and errors.pairs == 40
    offset = estimate.copy()
    offset[::2, 1:4] += frame.rotation.apply([0.02, 0.0, 0.0])
    assert 0.005 < trajectory_errors(offset, reference).ate_rmse_m <= 0.02
    straight = reference.copy()  # a straight path: no best-fit turn about it exists
    straight[:, 1:4] = np.outer(k, [0.1, 0.0, 0.0])
    estimate[:, 1:4] = [frame.apply(p) for p in straight[:, 1:4]]
    errors = trajectory_errors(estimate, straight)
    assert errors.alignment == "first pose" and errors.ate_rmse_m < 1e-6


def _write_sequence(folder: Path, poses: list[Pose], blank_from: int | None = None) -> Path:
    """A TUM-layout folder of the room seen from ``poses`` (1/5000 m units)."""
    (folder / "depth").mkdir(parents=True)
    lines, truth = [], []
    for k, pose in enumerate(poses):
        stamp = 1000.0 + k / 30.0
        depth = (
            render(pose)
            if blank_from is None or k < blank_from
            else render(looking([4.7, 2.2, 2.8], -2.4, -0.6))
        )
        units = np.clip(np.round(depth * 5000.0), 0, 65535).astype(np.uint16)
        Image.fromarray(units).save(folder / "depth" / f"{k:04d}.png")
        lines.append(f"{stamp:.6f} depth/{k:04d}.png")
        q = pose.rotation.as_quat()
        truth.append(f"{stamp:.6f} " + " ".join(f"{v:.9f}" for v in (*pose.position, *q)))
    (folder / "depth.txt").write_text("# depth\n" + "\n".join(lines) + "\n")
    (folder / "groundtruth.txt").write_text("\n".join(truth) + "\n")
    return folder


INTRINSICS = [str(v) for v in (CAMERA.fx, CAMERA.fy, CAMERA.cx, CAMERA.cy)]


def test_footfall_odometry_writes_the_path_of_every_frame_and_its_errors(tmp_path):
    """One TUM line per depth frame, stamped as the frame; the ATE against groundtruth.txt
    is under 2 mm on exact frames; the CPU time per frame is measured."""
    poses = _walk(12)
    sequence = _write_sequence(tmp_path / "seq", poses)
    out = tmp_path / "out"
    assert main(["odometry", str(sequence), "--intrinsics", *INTRINSICS, "--out", str(out)]) == 0
    rows = np.loadtxt(out / "trajectory.tum")
    assert rows.shape == (12, 8)
    np.testing.assert_allclose(rows[:, 0], 1000.0 + np.arange(12) / 30.0, atol=1e-6)
    np.testing.assert_allclose(
        rows[0, 1:], [0, 0, 0, 0, 0, 0, 1], atol=1e-9
    )  # the first frame's world
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["frames"] == metrics["registered"] == 12
    assert metrics["ate_rmse_m"] < 0.002 and metrics["cpu_ms_per_frame"] > 0


def test_footfall_odometry_exits_2_when_lost_and_writes_no_path(tmp_path, capsys):
    """A sequence whose camera loses the scene for good: exit 2, 'lost' and the time said,
    no trajectory written."""
    sequence = _write_sequence(tmp_path / "seq", _walk(16), blank_from=4)
    out = tmp_path / "out"
    assert main(["odometry", str(sequence), "--intrinsics", *INTRINSICS, "--out", str(out)]) == 2
    said = " ".join(capsys.readouterr().out.split())
    # Blank from the fifth frame (1000.133 s): the tenth blank one in a row is the last.
    assert "tracking lost at 1000.433 s" in said and "since 1000.100 s" in said
    assert "last pose" in said
    assert not (out / "trajectory.tum").exists()


def test_footfall_odometry_tracks_a_real_kinect_sequence(tmp_path):
    """TUM freiburg1_xyz, real Kinect depth: within a centimetre of the motion capture."""
    out = tmp_path / "out"
    args = [
        "odometry",
        str(shared_data("rgbd/tum_fr1_xyz")),
        "--intrinsics",
        "517.3",
        "516.5",
        "318.6",
        "255.3",
    ]
    assert main([*args, "--out", str(out)]) == 0
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["registered"] == metrics["frames"] == 37
    assert metrics["ate_rmse_m"] < 0.01


def test_a_sequence_without_poses_maps_by_its_own_odometry(tmp_path):
    """A room seen by a walking camera, mapped once by its recorded poses and once by depth
    odometry with the first frame put over the floor it sees: the floors agree within half
    a centimetre of spread and a centimetre of height, and a frame that did not register is
    not fused."""
    poses = _walk(14)
    sequence = _write_sequence(tmp_path / "seq", poses)
    bare = _write_sequence(tmp_path / "bare", poses)
    (bare / "groundtruth.txt").unlink()
    common = ["--intrinsics", *INTRINSICS, "--sensor", "ideal"]
    assert main(["map", "--tum", str(sequence), *common, "--out", str(tmp_path / "truth")]) == 0
    args = ["map", "--tum", str(bare), *common, "--pose", "odometry"]
    assert main([*args, "--out", str(tmp_path / "odo")]) == 0
    truth = json.loads((tmp_path / "truth" / "metrics.json").read_text())
    odometry = json.loads((tmp_path / "odo" / "metrics.json").read_text())
    assert odometry["odometry"]["registered"] == 14 and odometry["frames"] == 14
    spread = odometry["floor_height_spread_m"] - truth["floor_height_spread_m"]
    assert abs(spread) < 0.005, (odometry, truth)
    assert abs(odometry["floor_height_median_m"] - truth["floor_height_median_m"]) < 0.01


def test_a_recording_replays_by_its_own_odometry(tmp_path):
    """The room as an MCAP recording, replayed by its recorded poses and by depth odometry
    (the recorded poses ignored): the floors agree within half a centimetre of spread."""
    sequence = _write_sequence(tmp_path / "seq", _walk(14))
    recording = tmp_path / "room.mcap"
    convert = ["convert", "tum", str(sequence), str(recording), "--intrinsics", *INTRINSICS]
    assert main([*convert, "--sensor", "ideal"]) == 0
    assert main(["replay", str(recording), "--fast", "--out", str(tmp_path / "truth")]) == 0
    args = ["replay", str(recording), "--fast", "--pose", "odometry"]
    assert main([*args, "--out", str(tmp_path / "odo")]) == 0
    truth = json.loads((tmp_path / "truth" / "metrics.json").read_text())
    odometry = json.loads((tmp_path / "odo" / "metrics.json").read_text())
    assert odometry["pose_source"] == "odometry" and odometry["frames"] == 14
    spread = odometry["floor_height_spread_m"] - truth["floor_height_spread_m"]
    assert abs(spread) < 0.005, (odometry, truth)


@pytest.mark.parametrize(
    ("field", "value"),
    [
        ("fallback_share", 1.5),
        ("fallback_share", -0.1),
        ("min_inlier_share", 0.0),
        ("downsampling_m", 0.0),
        ("max_range_m", 0.1),
    ],
)
def test_settings_out_of_range_are_refused_by_name(field, value):
    """A setting outside its range is refused, and the message names it."""
    with pytest.raises(ConfigError, match=field.split("_")[0]):
        OdometryConfig(**{field: value})
