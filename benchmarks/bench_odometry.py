"""Depth odometry: footfall's against small_gicp used as its examples do, and OpenCV's.

For each TUM-layout sequence given (default: the shared freiburg1_xyz frames, the Redwood
living room, converted, and ``--synthetic`` long sequences rendered in this run by
``rgbd_scenes.py``: a hand-held Kinect in a cluttered room, where drift shows), the camera
is tracked by

- ``footfall``: :class:`footfall.odometry.registration.DepthOdometry` (a fine Gaussian
  voxel map, a coarse one for the frames the fine one misses, constant-velocity prediction,
  refusal of bad frames);
- ``small_gicp f2f``: small_gicp's GICP of each frame against the one before it (the
  library's frame-to-frame example), on the same thinned points;
- ``small_gicp f2m``: small_gicp's VGICP against one incremental voxel map of the past
  frames (its odometry example), from the last pose, on the same points;
- ``opencv depth``: OpenCV's depth odometry (``cv.Odometry``, ICP on the depth image
  pyramid, frame to frame, its defaults), on the whole depth image, where
  ``opencv-contrib-python-headless`` is installed (the dev group has it);
- ``kiss-icp``: KISS-ICP (Vizzo et al., RA-L 2023) on every pixel's point, where
  ``kiss-icp`` is installed (not a footfall dependency: ``pip install kiss-icp``); its
  LiDAR defaults scaled to a room: ranges as footfall's, no deskewing, the adaptive
  threshold starting at 0.1 m and adapting after 1 cm of motion;
- ``open3d rgbd``: Open3D's RGB-D odometry (Steinbruecker et al. and Park et al.'s hybrid
  term, colour and depth, frame to frame), where ``open3d`` is installed and the sequence
  has colour (``rgb.txt``);

all in this run, one thread each (small_gicp's; OpenCV's limited by ``cv.setNumThreads``),
the point-based ones on the same back-projected points (every second pixel).
Reported per method: ATE RMSE after SE(3) alignment [mm] and CPU ms per frame, or "lost"
where footfall's odometry gave up (it says so rather than write a wrong path). Run with
``uv run python benchmarks/bench_odometry.py [SEQUENCE FX FY CX CY ...] [--synthetic SEEDS]
[--frames N]``; it prints the table and writes ``benchmarks/results/odometry.json``.
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import tempfile
import time
from pathlib import Path

import numpy as np
import small_gicp

from footfall.datasets.tum import TUM_DEPTH_SCALE, load_depth_png, stamped_depth_images
from footfall.odometry.evaluation import trajectory_errors
from footfall.odometry.registration import DepthOdometry, OdometryConfig, TrackingLostError
from footfall.sensing.camera import PinholeCamera
from footfall.sensing.pose import Pose
from footfall.sensing.trajectory import Trajectory, read_table

SHARED = Path(__file__).resolve().parents[2] / "shared" / "data" / "rgbd"
CONFIG = OdometryConfig()


def frames_of(sequence: Path, intrinsics: tuple[float, ...]) -> tuple[list, PinholeCamera]:
    """The sequence's (time, camera-frame points) and its camera."""
    stamped = stamped_depth_images(sequence)
    first = load_depth_png(stamped[0][1])
    c = CONFIG
    camera = PinholeCamera(
        *intrinsics, first.shape[1], first.shape[0], c.min_range_m, c.max_range_m
    )
    return [(t, load_depth_png(p)) for t, p in stamped], camera


def row(stamp: float, pose: np.ndarray) -> list[float]:
    """A TUM row from a 4x4 pose."""
    p = Pose.from_matrix(pose)
    return [stamp, *p.position, *p.rotation.as_quat()]


def track_footfall(frames: list, camera: PinholeCamera) -> tuple[list, list[float]]:
    """Track with footfall's odometry: rows and CPU ms per frame."""
    odometry = DepthOdometry(camera, CONFIG)
    rows, cpu = [], []
    for stamp, depth in frames:
        start = time.process_time()
        step = odometry.track(depth, stamp, TUM_DEPTH_SCALE)
        cpu.append(1000.0 * (time.process_time() - start))
        rows.append(row(stamp, step.camera_in_world.matrix))
    return rows, cpu


def track_small_gicp(frames: list, camera: PinholeCamera, to_map: bool) -> tuple[list, list[float]]:
    """small_gicp as its examples use it: frame to frame (GICP) or frame to map (VGICP)."""
    c = CONFIG
    pose, rows, cpu = np.eye(4), [], []
    previous = voxels = None
    for stamp, depth in frames:
        start = time.process_time()
        points, _ = camera.depth_to_points(depth, TUM_DEPTH_SCALE, c.stride_px)
        cloud, tree = small_gicp.preprocess_points(points, c.downsampling_m, c.neighbours, 1)
        if to_map:
            if voxels is None:
                voxels = small_gicp.GaussianVoxelMap(c.map_voxel_m)
            else:
                pose = small_gicp.align(voxels, cloud, pose, num_threads=1).T_target_source
            voxels.insert(cloud, pose)
        else:
            if previous is not None:
                result = small_gicp.align(
                    previous[0], cloud, previous[1], max_correspondence_distance=0.1
                )
                pose = pose @ result.T_target_source
            previous = (cloud, tree)
        cpu.append(1000.0 * (time.process_time() - start))
        rows.append(row(stamp, np.asarray(pose)))
    return rows, cpu


def track_opencv(frames: list, camera: PinholeCamera) -> tuple[list, list[float]]:
    """OpenCV's depth odometry, frame to frame, on whole images in metres."""
    import cv2

    cv2.setNumThreads(1)
    settings = cv2.OdometrySettings()
    settings.setCameraMatrix(camera.matrix.astype(np.float32))
    odometry = cv2.Odometry(cv2.OdometryType_DEPTH, settings, cv2.OdometryAlgoType_COMMON)
    pose, rows, cpu, previous = np.eye(4), [], [], None
    for stamp, depth in frames:
        start = time.process_time()
        metres = (depth * TUM_DEPTH_SCALE).astype(np.float32)
        if previous is not None:
            found, motion = odometry.compute(previous, metres)  # motion @ previous = this
            if found:
                pose = pose @ np.linalg.inv(motion)
        previous = metres
        cpu.append(1000.0 * (time.process_time() - start))
        rows.append(row(stamp, pose))
    return rows, cpu


def track_kiss_icp(frames: list, camera: PinholeCamera) -> tuple[list, list[float]]:
    """KISS-ICP on every pixel's point, its defaults scaled to a room."""
    from kiss_icp.config import KISSConfig
    from kiss_icp.kiss_icp import KissICP

    c = CONFIG
    config = KISSConfig()
    config.data.min_range, config.data.max_range = c.min_range_m, c.max_range_m
    config.data.deskew = False
    config.mapping.voxel_size = c.max_range_m / 100.0  # its own rule, as load_config has it
    config.adaptive_threshold.initial_threshold = 0.1
    config.adaptive_threshold.min_motion_th = 0.01
    config.registration.max_num_threads = 1
    odometry = KissICP(config)
    rows, cpu = [], []
    for stamp, depth in frames:
        start = time.process_time()
        points, _ = camera.depth_to_points(depth, TUM_DEPTH_SCALE, 1)
        odometry.register_frame(points, np.zeros(len(points)))
        cpu.append(1000.0 * (time.process_time() - start))
        rows.append(row(stamp, odometry.last_pose))
    return rows, cpu


def colour_of(sequence: Path, frames: list) -> list[Path] | None:
    """Each depth frame's colour image (the nearest in time, within 20 ms), or None."""
    if not (sequence / "rgb.txt").is_file():
        return None
    stamped = sorted((float(r[0]), sequence / r[1]) for r in read_table(sequence / "rgb.txt", 2))
    times = np.array([t for t, _ in stamped])
    chosen = []
    for stamp, _ in frames:
        k = int(np.argmin(np.abs(times - stamp)))
        if abs(times[k] - stamp) > 0.02:
            return None
        chosen.append(stamped[k][1])
    return chosen


def track_open3d(frames: list, camera: PinholeCamera, colour: list[Path]) -> tuple[list, list]:
    """Open3D's RGB-D odometry (hybrid colour and depth term), frame to frame."""
    import open3d as o3d

    intrinsic = o3d.camera.PinholeCameraIntrinsic(
        camera.width, camera.height, camera.fx, camera.fy, camera.cx, camera.cy
    )
    option = o3d.pipelines.odometry.OdometryOption()
    option.depth_max = CONFIG.max_range_m
    jacobian = o3d.pipelines.odometry.RGBDOdometryJacobianFromHybridTerm()
    pose, rows, cpu, previous = np.eye(4), [], [], None
    for (stamp, depth), image in zip(frames, colour, strict=True):
        start = time.process_time()
        rgbd = o3d.geometry.RGBDImage.create_from_color_and_depth(
            o3d.io.read_image(str(image)),
            o3d.geometry.Image(depth.astype(np.uint16)),
            depth_scale=1.0 / TUM_DEPTH_SCALE,
            depth_trunc=CONFIG.max_range_m,
        )
        if previous is not None:
            found, motion, _ = o3d.pipelines.odometry.compute_rgbd_odometry(
                rgbd, previous, intrinsic, np.eye(4), jacobian, option
            )
            if found:  # motion takes this frame's points into the previous frame's
                pose = pose @ motion
        previous = rgbd
        cpu.append(1000.0 * (time.process_time() - start))
        rows.append(row(stamp, pose))
    return rows, cpu


def measure(sequence: Path, intrinsics: tuple[float, ...]) -> dict[str, dict[str, float]]:
    """Every method on one sequence: ATE [mm] and CPU ms per frame."""
    frames, camera = frames_of(sequence, intrinsics)
    truth = Trajectory.read(sequence / "groundtruth.txt").table
    methods = {
        "footfall": lambda: track_footfall(frames, camera),
        "small_gicp f2f": lambda: track_small_gicp(frames, camera, to_map=False),
        "small_gicp f2m": lambda: track_small_gicp(frames, camera, to_map=True),
    }
    if importlib.util.find_spec("cv2") is not None:
        methods["opencv depth"] = lambda: track_opencv(frames, camera)
    if importlib.util.find_spec("kiss_icp") is not None:
        methods["kiss-icp"] = lambda: track_kiss_icp(frames, camera)
    colour = colour_of(sequence, frames)
    if importlib.util.find_spec("open3d") is not None and colour is not None:
        methods["open3d rgbd"] = lambda: track_open3d(frames, camera, colour)
    out = {}
    for name, track in methods.items():
        try:
            rows, cpu = track()
        except TrackingLostError as lost:
            out[name] = {"lost": str(lost), "frames": len(frames)}
            continue
        errors = trajectory_errors(np.array(rows), truth)
        out[name] = {
            "ate_mm": 1000.0 * errors.ate_rmse_m,
            "cpu_ms_per_frame": float(np.mean(cpu[1:])),
            "frames": len(rows),
            "path_m": errors.reference_length_m,
        }
    return out


def sequences(args: argparse.Namespace, scratch: Path) -> list[tuple[str, Path, tuple]]:
    """The sequences asked for, or the shared ones; then the synthetic ones."""
    given = args.sequences
    if given:
        chosen = [
            (Path(given[k]).name, Path(given[k]), tuple(float(v) for v in given[k + 1 : k + 5]))
            for k in range(0, len(given), 5)
        ]
    else:
        from footfall.datasets.redwood import convert_redwood

        redwood = scratch / "redwood"
        convert_redwood(SHARED / "redwood_livingroom", redwood)
        chosen = [
            ("tum_fr1_xyz", SHARED / "tum_fr1_xyz", (517.3, 516.5, 318.6, 255.3)),
            ("redwood_livingroom", redwood, (525.0, 525.0, 319.5, 239.5)),
        ]
    if args.synthetic:
        from rgbd_scenes import INTRINSICS, write_sequence

        for seed in (int(v) for v in args.synthetic.split(",")):
            folder = scratch / f"room_{seed}"
            write_sequence(folder, seed, args.frames)
            chosen.append((f"synthetic room {seed}", folder, INTRINSICS))
    return chosen


def main() -> None:
    """Measure and write the results."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("sequences", nargs="*", help="SEQUENCE FX FY CX CY, repeated")
    parser.add_argument("--synthetic", default="", help="seeds of rendered rooms, e.g. 0,1,2")
    parser.add_argument("--frames", type=int, default=900, help="frames per rendered room")
    args = parser.parse_args()
    if len(args.sequences) % 5:
        parser.error("each sequence is given as SEQUENCE FX FY CX CY")
    results = {}
    with tempfile.TemporaryDirectory() as scratch:
        for name, folder, intrinsics in sequences(args, Path(scratch)):
            results[name] = measure(folder, intrinsics)
            for method, r in results[name].items():
                if "lost" in r:
                    print(f"{name:20s} {method:16s} lost: {r['lost']}")
                    continue
                print(
                    f"{name:20s} {method:16s} ATE {r['ate_mm']:6.1f} mm  "
                    f"{r['cpu_ms_per_frame']:6.1f} ms/frame  ({r['frames']} frames, "
                    f"{r['path_m']:.2f} m)"
                )
    out = Path(__file__).parent / "results" / "odometry.json"
    out.parent.mkdir(exist_ok=True)
    out.write_text(json.dumps(results, indent=2) + "\n")
    print(f"Wrote {out}")


if __name__ == "__main__":
    main()
