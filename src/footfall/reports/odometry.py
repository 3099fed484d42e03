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
from footfall.odometry.poses import first_frame_over_floor
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


def odometry_over_floor(
    request: OdometryRequest, first_pose: Pose | None = None
) -> tuple[dict[float, Pose], OdometryReport]:
    """The camera's pose by depth frame time in a z-up world, from depth odometry.

    ``first_pose`` puts the first frame over the floor (else the floor is found in it:
    :mod:`footfall.odometry.poses`). Frames that did not register are left out.

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
