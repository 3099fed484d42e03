"""Depth odometry: each depth frame registered against a local map of the frames before it.

The camera's path from its depth images alone, where the source systems took it from a SLAM
(the thesis ran ORB-SLAM3 on its RealSense, §4.5). Each frame's points, thinned on a voxel grid
and given covariances from their neighbours, are registered by VGICP (small_gicp; Koide et al.,
"Voxelized GICP", ICRA 2021) against a Gaussian voxel map of the frames before it, from the
pose a constant-velocity model predicts; the registered frame then joins the map, whose voxels
not seen for a while are forgotten. A frame that does not register (too few points, the
optimiser not converging, too few of its points matched, or a motion no hand-held or robot
camera makes between two frames) is skipped and the next one tried from the last good pose;
after ``recover_frames`` skipped frames in a row the track is lost.
"""

from __future__ import annotations

import importlib
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from footfall.checks import require_positive
from footfall.errors import ConfigError, FootfallError
from footfall.sensing.back_projection import BackProjection
from footfall.sensing.camera import PinholeCamera
from footfall.sensing.pose import Pose

# Two registrations are told apart by the share of the frame's points within FIT_REACH
# thinning voxels of the last frame's points; one must fit more by FIT_MARGIN to be taken.
FIT_REACH = 1.0
FIT_MARGIN = 0.02


class TrackingLostError(FootfallError):
    """Depth odometry could not register a run of frames and cannot say where the camera is.

    Attributes:
        stamp: The last frame tried [s].
        last_pose: The camera's last registered pose in the odometry's world.
    """

    def __init__(self, message: str, stamp: float, last_pose: Pose) -> None:
        super().__init__(message)
        self.stamp = stamp
        self.last_pose = last_pose


@dataclass(frozen=True)
class OdometryConfig:
    """Depth odometry settings.

    Attributes:
        stride_px: Every ``stride_px``-th row and column of the image is back-projected.
        min_range_m: Nearer readings are dropped [m].
        max_range_m: Farther readings are dropped (a depth camera's error grows with the
            square of the range) [m].
        downsampling_m: Voxel grid a frame's points are thinned on [m].
        map_voxel_m: Voxel size of the Gaussian map frames register against [m].
        coarse_voxel_m: A second, coarser map, registered against when the fine one misses:
            a VGICP point finds its match in the voxel it falls in, so the coarse map catches
            motions the fine one would miss (fast turns with far walls in view) [m].
        fallback_share: The coarse map is tried when a frame matches fewer of its points
            than this share of the recent frames' matched share.
        neighbours: Points each point's covariance is estimated from.
        max_correspondence_m: Farthest a point and its map voxel may lie apart to match [m].
        max_iterations: Optimiser iterations per frame.
        min_points: A frame with fewer thinned points is skipped.
        min_inlier_share: A registration matching fewer of the frame's points is refused.
        max_step_m: A registration moving the camera farther than this from the predicted
            pose between two frames is refused [m].
        max_turn_deg: Likewise for the turn [deg].
        map_horizon_frames: Map voxels no frame has touched for this many frames are forgotten.
        recover_frames: Skipped frames in a row after which the track is lost.
        threads: Threads small_gicp may use.
    """

    stride_px: int = 2
    min_range_m: float = 0.2
    max_range_m: float = 5.0
    downsampling_m: float = 0.03
    map_voxel_m: float = 0.04
    coarse_voxel_m: float = 0.3
    fallback_share: float = 0.85
    neighbours: int = 10
    max_correspondence_m: float = 0.1
    max_iterations: int = 30
    min_points: int = 200
    min_inlier_share: float = 0.4
    max_step_m: float = 0.25
    max_turn_deg: float = 30.0
    map_horizon_frames: int = 1000
    recover_frames: int = 10
    threads: int = 1

    def __post_init__(self) -> None:
        require_positive(
            "depth odometry",
            min_range_m=self.min_range_m,
            downsampling_m=self.downsampling_m,
            map_voxel_m=self.map_voxel_m,
            coarse_voxel_m=self.coarse_voxel_m,
            max_correspondence_m=self.max_correspondence_m,
            max_step_m=self.max_step_m,
            max_turn_deg=self.max_turn_deg,
        )
        if self.max_range_m <= self.min_range_m:
            raise ConfigError(
                f"max_range_m ({self.max_range_m}) must exceed min_range_m ({self.min_range_m})"
            )
        if min(self.stride_px, self.neighbours, self.max_iterations, self.threads) < 1:
            raise ConfigError("stride_px, neighbours, max_iterations and threads must be >= 1")
        if min(self.min_points, self.map_horizon_frames, self.recover_frames) < 1:
            raise ConfigError("min_points, map_horizon_frames and recover_frames must be >= 1")
        if not 0.0 < self.min_inlier_share <= 1.0:
            raise ConfigError(f"min_inlier_share must be in (0, 1], got {self.min_inlier_share}")
        if not 0.0 <= self.fallback_share <= 1.0:
            raise ConfigError(f"fallback_share must be in [0, 1], got {self.fallback_share}")


@dataclass(frozen=True)
class OdometryStep:
    """What one frame did.

    Attributes:
        stamp: The frame's time [s].
        camera_in_world: The camera's optical frame in the odometry's world (the first
            frame's, unless another start was given); the last good pose when skipped.
        registered: Whether the frame registered (and joined the map).
        inlier_share: Share of the frame's thinned points matched to the map.
        points: The frame's thinned points.
        reason: Why the frame was skipped ("" when registered).
    """

    stamp: float
    camera_in_world: Pose
    registered: bool
    inlier_share: float
    points: int
    reason: str = ""


def import_small_gicp() -> Any:
    """The small_gicp module.

    Raises:
        ConfigError: It is not installed (it comes with ``footfall[odometry]``).
    """
    try:
        return importlib.import_module("small_gicp")
    except ImportError as exc:
        raise ConfigError(
            "depth odometry needs small_gicp: install footfall[odometry] (pip install small-gicp)"
        ) from exc


def motion_between(a: npt.NDArray[np.float64], b: npt.NDArray[np.float64]) -> tuple[float, float]:
    """Distance [m] and angle [deg] between two 4x4 poses."""
    delta = np.linalg.inv(a) @ b
    cos = (np.trace(delta[:3, :3]) - 1.0) / 2.0
    return float(np.linalg.norm(delta[:3, 3])), math.degrees(math.acos(min(1.0, max(-1.0, cos))))


class DepthOdometry:
    """Track a depth camera from its images (see the module docstring).

    Args:
        camera: The depth camera's intrinsics (its range limits are the config's).
        config: Settings.
        start: The first frame's pose in the world (default: the world is the first frame).

    Raises:
        ConfigError: small_gicp is not installed.
    """

    def __init__(
        self, camera: PinholeCamera, config: OdometryConfig | None = None, start: Pose | None = None
    ) -> None:
        self.config = config or OdometryConfig()
        self._gicp = import_small_gicp()
        c = self.config
        self.camera = PinholeCamera(
            camera.fx, camera.fy, camera.cx, camera.cy, camera.width, camera.height,
            min_range=c.min_range_m, max_range=c.max_range_m,
        )  # fmt: skip
        self._projection = BackProjection(self.camera, c.stride_px)
        self._start = (start or Pose.identity()).matrix
        self._map: Any = None
        self._coarse: Any = None
        self._last_frame: tuple[Any, npt.NDArray[np.float64]] | None = None  # tree, pose
        self._last = self._start.copy()  # the last registered pose, 4x4
        self._velocity = np.eye(4)  # motion over one frame, in the camera's frame
        self._last_stamp: float | None = None
        self._skipped = 0
        self._recent_share = 1.0  # inlier share of the registered frames, smoothed
        self.frames = 0
        self.registered = 0

    @property
    def camera_in_world(self) -> Pose:
        """The camera's last registered pose."""
        return Pose.from_matrix(self._last)

    def track(
        self, depth: npt.ArrayLike, stamp: float, depth_scale: float | None = None
    ) -> OdometryStep:
        """Register one depth image taken at ``stamp`` [s].

        Args:
            depth: Shape (height, width): float metres, or integers with ``depth_scale``.
            stamp: The image's time [s]; frames must come in time order.
            depth_scale: Metres per unit for integer depth.

        Raises:
            TrackingLostError: ``recover_frames`` frames in a row did not register.
            DepthImageError: A malformed image.
        """
        c, gicp = self.config, self._gicp
        self.frames += 1
        points = self._projection.points(depth, depth_scale)
        cloud, tree = gicp.preprocess_points(points, c.downsampling_m, c.neighbours, c.threads)
        n = int(cloud.size())
        if self._map is None:
            if n < c.min_points:
                return self._skip(stamp, n, f"{n} points after thinning, fewer than {c.min_points}")
            self._join(cloud, tree, self._last, stamp)
            return OdometryStep(stamp, self.camera_in_world, True, 1.0, n)
        if n < c.min_points:
            return self._skip(stamp, n, f"{n} points after thinning, fewer than {c.min_points}")
        # Constant velocity over the frames skipped since the last registered one.
        predicted = self._last @ np.linalg.matrix_power(self._velocity, self._skipped + 1)
        pose, share, reason = self._register(self._map, cloud, predicted, c.max_correspondence_m)
        if reason or share < c.fallback_share * self._recent_share:
            # The fine map missed or matched fewer points than frames have lately (a fast
            # turn with far walls in view): try it again from the coarse map's answer, and
            # keep that only where it matches more. Not on every frame: on a view of little
            # but a floor and a wall the coarse map's wide basins slide where the fine one
            # holds.
            coarse, _, _ = self._register(self._coarse, cloud, predicted, c.coarse_voxel_m)
            again = self._register(self._map, cloud, coarse, c.max_correspondence_m)
            if not again[2]:
                again = (again[0], again[1], self._refused(predicted, again[0]))
            if not again[2] and (reason or self._fits_better(cloud, again[0], pose)):
                pose, share, reason = again
        if reason:
            return self._skip(stamp, n, reason, share)
        self._recent_share += 0.2 * (share - self._recent_share)
        frames = self._skipped + 1
        motion = np.linalg.inv(self._last) @ pose
        self._velocity = motion if frames == 1 else _fraction(motion, 1.0 / frames)
        self._join(cloud, tree, pose, stamp)
        return OdometryStep(stamp, self.camera_in_world, True, share, n)

    def _fits_better(
        self, cloud: Any, candidate: npt.NDArray[np.float64], pose: npt.NDArray[np.float64]
    ) -> bool:
        """Whether the frame fits the last frame better at ``candidate`` than at ``pose``.

        Better: more of its points within ``FIT_REACH`` thinning voxels of the last
        registered frame's points, by more than ``FIT_MARGIN``. The voxel map's matched
        share cannot judge two answers: a point matches the voxel it falls in, wherever in
        it, and a 4 cm map matches fewer points at the true pose than at one slid along the
        walls (a camera raised 5 cm: 58 % against 61 %). Points on the last frame's points
        can: at a pose slid along a surface the points still lie on it, at one off the floor
        by 5 cm the floor's do not. Two poses that fit alike (one slid along a floor and a
        wall, where nothing in view tells them apart) keep ``pose``, the one found from the
        prediction.
        """
        assert self._last_frame is not None  # a map exists: a frame has joined it
        tree, last = self._last_frame
        reach = (FIT_REACH * self.config.downsampling_m) ** 2
        points = np.asarray(cloud.points(), dtype=np.float64)[:, :3]
        fits = []
        for guess in (candidate, pose):
            into_last = np.linalg.inv(last) @ guess
            moved = points @ into_last[:3, :3].T + into_last[:3, 3]
            _, squared = tree.batch_nearest_neighbor_search(moved, num_threads=self.config.threads)
            fits.append(float(np.mean(np.asarray(squared) <= reach)))
        return fits[0] > fits[1] + FIT_MARGIN

    def _register(
        self, voxels: Any, cloud: Any, guess: npt.NDArray[np.float64], reach_m: float
    ) -> tuple[npt.NDArray[np.float64], float, str]:
        """Register the frame against a map from ``guess``.

        Returns:
            The pose, the share of the frame's points matched, and why the pose is refused
            ("" when it is not).
        """
        c = self.config
        result = self._gicp.align(
            voxels, cloud, guess,
            max_correspondence_distance=reach_m,
            num_threads=c.threads, max_iterations=c.max_iterations,
        )  # fmt: skip
        pose = np.asarray(result.T_target_source, dtype=np.float64)
        share = result.num_inliers / int(cloud.size())
        if not result.converged:
            return pose, share, f"registration did not converge in {c.max_iterations} iterations"
        if share < c.min_inlier_share:
            return (
                pose,
                share,
                (f"{share:.0%} of its points matched the map, fewer than {c.min_inlier_share:.0%}"),
            )
        return pose, share, self._refused(guess, pose)

    def _refused(self, predicted: npt.NDArray[np.float64], pose: npt.NDArray[np.float64]) -> str:
        """Why a registered pose is too far from the prediction to be believed, or ""."""
        c = self.config
        step_m, turn_deg = motion_between(predicted, pose)
        if step_m > c.max_step_m or turn_deg > c.max_turn_deg:
            return f"registered {step_m:.3f} m and {turn_deg:.1f} deg from the predicted pose"
        return ""

    def _join(self, cloud: Any, tree: Any, pose: npt.NDArray[np.float64], stamp: float) -> None:
        """Add a registered frame to the map; keep it (and its search tree) as the last."""
        self._last_frame = (tree, pose)
        c = self.config
        if self._map is None:
            self._map = self._gicp.GaussianVoxelMap(c.map_voxel_m)
            self._coarse = self._gicp.GaussianVoxelMap(c.coarse_voxel_m)
            for voxels in (self._map, self._coarse):
                voxels.set_lru(c.map_horizon_frames, 10)
        self._map.insert(cloud, pose)
        self._coarse.insert(cloud, pose)
        self._last = pose
        self._last_stamp = stamp
        self._skipped = 0
        self.registered += 1

    def _skip(self, stamp: float, n: int, reason: str, share: float = 0.0) -> OdometryStep:
        """Skip a frame; past ``recover_frames`` in a row, the track is lost."""
        self._skipped += 1
        if self._skipped >= self.config.recover_frames:
            since = "" if self._last_stamp is None else f" since {self._last_stamp:.3f} s"
            x, y, z = self._last[:3, 3]
            raise TrackingLostError(
                f"tracking lost at {stamp:.3f} s: {self._skipped} frames in a row did not "
                f"register{since} (the last: {reason}); last pose ({x:.3f}, {y:.3f}, {z:.3f}) m",
                stamp,
                self.camera_in_world,
            )
        return OdometryStep(stamp, self.camera_in_world, False, share, n, reason)


def _fraction(motion: npt.NDArray[np.float64], share: float) -> npt.NDArray[np.float64]:
    """The motion scaled along its screw by ``share`` (translation and rotation vector)."""
    from scipy.spatial.transform import Rotation

    out = np.eye(4)
    out[:3, :3] = Rotation.from_rotvec(
        Rotation.from_matrix(motion[:3, :3]).as_rotvec() * share
    ).as_matrix()
    out[:3, 3] = motion[:3, 3] * share
    return out
