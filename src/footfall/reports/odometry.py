"""``footfall odometry``: a depth sequence's camera path from its own images.

Reads a TUM-layout sequence (``depth.txt`` and ``depth/*.png``; ``groundtruth.txt`` only to
measure against), runs :class:`~footfall.odometry.registration.DepthOdometry` on every depth
frame and writes the path as ``trajectory.tum`` (``timestamp tx ty tz qx qy qz qw``,
camera-to-world, one line per depth frame, stamped as the frame) with ``metrics.json``. A lost
track writes no trajectory: the error says where it was lost.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import numpy.typing as npt

from footfall.datasets.tum import TUM_DEPTH_SCALE, load_depth_png, stamped_depth_images
from footfall.errors import DatasetError
from footfall.odometry.evaluation import TrajectoryErrors, trajectory_errors
from footfall.odometry.registration import DepthOdometry, OdometryConfig
from footfall.reports import write_json
from footfall.sensing.camera import PinholeCamera
from footfall.sensing.pose import Pose
from footfall.sensing.trajectory import Trajectory


@dataclass(frozen=True)
class OdometryRequest:
    """What to track.

    Attributes:
        sequence: The TUM-layout folder.
        intrinsics: ``(fx, fy, cx, cy)`` of the depth camera [px].
        depth_scale: Metres per depth unit (TUM: 1/5000).
        config: Odometry settings.
        max_frames: Track only the first frames (None: all).
    """

    sequence: Path
    intrinsics: tuple[float, float, float, float]
    depth_scale: float = TUM_DEPTH_SCALE
    config: OdometryConfig = field(default_factory=OdometryConfig)
    max_frames: int | None = None


@dataclass
class OdometryReport:
    """The tracked path and what it cost.

    Attributes:
        rows: TUM rows ``t tx ty tz qx qy qz qw``, one per depth frame, shape (n, 8).
        cpu_ms: CPU time of each frame's tracking (every thread of the process) [ms].
        skipped: Frames that did not register: their time and why.
        errors: Against the sequence's ``groundtruth.txt``, where it has one.
    """

    rows: npt.NDArray[np.float64]
    cpu_ms: list[float]
    skipped: list[tuple[float, str]]
    errors: TrajectoryErrors | None

    def to_json(self) -> dict[str, object]:
        """``metrics.json``."""
        cpu = np.asarray(self.cpu_ms)
        data: dict[str, object] = {
            "frames": len(self.rows),
            "registered": len(self.rows) - len(self.skipped),
            "skipped": [{"t": t, "reason": r} for t, r in self.skipped],
            "cpu_ms_per_frame": float(cpu.mean()),
            "cpu_ms_p95": float(np.percentile(cpu, 95)),
        }
        if self.errors is not None:
            e = self.errors
            data |= {
                "ate_rmse_m": e.ate_rmse_m,
                "rpe_per_m": None if math.isnan(e.rpe_per_m) else e.rpe_per_m,
                "rpe_segment_m": e.rpe_segment_m,
                "reference_length_m": e.reference_length_m,
                "alignment": e.alignment,
            }
        return data

    def write(self, out: Path) -> list[Path]:
        """``trajectory.tum`` and ``metrics.json`` in ``out``."""
        out.mkdir(parents=True, exist_ok=True)
        tum = out / "trajectory.tum"
        lines = ["# timestamp tx ty tz qx qy qz qw (camera-to-world, footfall odometry)"]
        lines += [f"{r[0]:.6f} " + " ".join(f"{v:.9f}" for v in r[1:]) for r in self.rows]
        tum.write_text("\n".join(lines) + "\n")
        return [tum, write_json(out / "metrics.json", self.to_json())]


def run_odometry(request: OdometryRequest) -> OdometryReport:
    """Track the sequence's camera.

    Raises:
        DatasetError: No depth images, or an unreadable one (named).
        TrackingLostError: Frames in a row did not register (the error says when and where).
        ConfigError: small_gicp is not installed.
    """
    frames = stamped_depth_images(request.sequence)
    if request.max_frames is not None:
        frames = frames[: request.max_frames]
    first = load_depth_png(frames[0][1])
    fx, fy, cx, cy = request.intrinsics
    camera = PinholeCamera(fx, fy, cx, cy, first.shape[1], first.shape[0])
    odometry = DepthOdometry(camera, request.config)
    rows, cpu_ms, skipped = [], [], []
    for stamp, path in frames:
        depth = load_depth_png(path)
        if depth.shape != first.shape:
            raise DatasetError(f"{path}: {depth.shape} pixels, the first frame had {first.shape}")
        start = time.process_time()
        step = odometry.track(depth, stamp, request.depth_scale)
        cpu_ms.append(1000.0 * (time.process_time() - start))
        if not step.registered:
            skipped.append((stamp, step.reason))
        pose = step.camera_in_world
        rows.append([stamp, *pose.position, *pose.rotation.as_quat()])
    table = np.asarray(rows, dtype=np.float64)
    truth = request.sequence / "groundtruth.txt"
    errors = trajectory_errors(table, Trajectory.read(truth).table) if truth.is_file() else None
    return OdometryReport(table, cpu_ms, skipped, errors)


# The floor of a sequence tracked without poses: the lowest large plane in its first frame
# within this of the camera's down (a camera held level, or looking down)...
FLOOR_TILT_DEG = 60.0
# ...with the camera this high above it [m].
FLOOR_CAMERA_HEIGHTS_M = (0.05, 3.0)


def first_frame_over_floor(depth: npt.NDArray, camera: PinholeCamera, depth_scale: float) -> Pose:
    """The first camera's pose over the floor it sees: z up, on the floor below it.

    Raises:
        DatasetError: No floor in view (the error says to give the camera's pose).
    """
    import math

    from footfall.pointcloud.ground import CameraOverFloor, find_ground

    points, _ = camera.depth_to_points(depth, depth_scale, stride=4)
    try:
        floor = find_ground(
            points,
            (0.0, -1.0, 0.0),  # up, for a camera held level: against its image's rows
            math.radians(FLOOR_TILT_DEG),
            below_origin=True,
            height_range_m=FLOOR_CAMERA_HEIGHTS_M,
        )
    except DatasetError as exc:
        raise DatasetError(
            f"no floor in the first frame to put the odometry's world on ({exc}): give the "
            "camera's pose over the floor with --camera-height and --camera-pitch-deg"
        ) from exc
    over = CameraOverFloor.from_up(floor.normal, floor.offset_m)
    return Pose(np.array([0.0, 0.0, over.height_m]), over.rotation_camera_to_map)


def odometry_over_floor(
    request: OdometryRequest, first_pose: Pose | None = None
) -> tuple[dict[float, Pose], OdometryReport]:
    """The camera's pose by depth frame time in a z-up world, from depth odometry.

    The odometry's world is its first frame's optical frame; ``first_pose`` puts that frame
    over the floor (else the floor is found in it: :func:`first_frame_over_floor`). Frames
    that did not register are left out: their depth would land at the last good pose.

    Raises:
        DatasetError, TrackingLostError, ConfigError: As :func:`run_odometry`.
    """
    report = run_odometry(request)
    if first_pose is None:
        first = stamped_depth_images(request.sequence)[0][1]
        depth = load_depth_png(first)
        fx, fy, cx, cy = request.intrinsics
        camera = PinholeCamera(fx, fy, cx, cy, depth.shape[1], depth.shape[0])
        first_pose = first_frame_over_floor(depth, camera, request.depth_scale)
    skipped = {t for t, _ in report.skipped}
    poses = {
        float(r[0]): first_pose.compose(Pose.from_quaternion(r[1:4], r[4:8]))
        for r in report.rows
        if float(r[0]) not in skipped
    }
    return poses, report
