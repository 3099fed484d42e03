"""The leg-inertial estimate's drift taken out by registering depth frames against a map.

Leg odometry drifts with the distance walked and the gyro's heading with time; the height
map is built on that pose, so a cell seen from one place and stepped on from another lies
where the drift puts it. Each depth frame is registered by VGICP (small_gicp, Koide et al.,
"Voxelized GICP", ICRA 2021) against a Gaussian voxel map of the frames before it, starting
from the camera pose the estimate gives for the frame's time, and the difference corrects the
estimate:

- **Only what the view constrains.** A floor fixes the height, roll and pitch but not where
  along it the camera stands nor its heading; the optimiser wanders along those directions,
  and what it moves there is noise. Which directions the points fix follows from their
  surfaces' normals: a small turn ``w`` and shift ``v`` of the camera move a point ``p`` on
  a surface of normal ``n`` (both in the camera's frame) off its surface by
  ``(p x n) . w + n . v``. The point-to-plane information ``sum J^T J``, with
  ``J = ((p x n) / L, n)`` over the frame's points thinned on ``normal_voxel_m`` (normals from
  ``normal_neighbours`` points) and turns scaled to metres by the points' RMS range ``L``,
  counts in each direction how many points' surfaces face it. Its eigenvectors whose
  eigenvalues reach ``min_constraint_share`` of the points span the observed subspace, and
  the correction is projected onto it (the "solution remapping" of Zhang, Kaess and Singh,
  "On degeneracy of optimization-based state estimation problems", ICRA 2016). A floor seen
  through the simulated camera's quantised ranges gives its free directions 1.3 % of its
  points with normals from 10 points 3 cm apart, none with 15 points 6 cm apart; a pillar's
  side that fills a few per cent of the view fixes the direction it faces.
- **Weighed against the estimate.** The step along the observed directions is a measurement
  of the estimate's x, y, z and heading (a turn about the vertical through the camera), fused
  with the estimate's variances by a Kalman update with the registration's own error
  ``sigma_m``: a direction that mixes a sideways shift with a turn (far features seen
  across) corrects the two together, as the view constrains them; roll and pitch stay the
  IMU's.
- **Refused when implausible.** A frame with too few points, a registration that matches
  too few of them, or a correction larger than the estimate can have drifted in a frame
  (``max_correction_m``, ``max_correction_deg``) leaves the estimate as it was; the frame
  still joins the map at the estimated pose.

The map is the estimate's own: frames join it at the corrected pose, and voxels no frame has
touched for ``map_horizon_frames`` frames are forgotten, so it spans what the camera has seen
over the last seconds. What it bounds is the drift between seeing ground and stepping on it,
which is what the height map needs.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import Any

import numpy as np
import numpy.typing as npt

from footfall.checks import require_positive
from footfall.errors import ConfigError
from footfall.estimation.rotations import rodrigues, rotation_vectors
from footfall.odometry.registration import import_small_gicp
from footfall.sensing.back_projection import BackProjection
from footfall.sensing.camera import PinholeCamera

UP = np.array([0.0, 0.0, 1.0])


@dataclass(frozen=True)
class DepthCorrectionConfig:
    """How depth frames correct the estimate.

    Attributes:
        stride_px: Every ``stride_px``-th row and column of the image is back-projected.
        downsampling_m: Voxel grid a frame's points are thinned on [m].
        map_voxel_m: Voxel size of the Gaussian map [m].
        neighbours: Points each point's covariance is estimated from.
        max_correspondence_m: Farthest a point and its map voxel may lie apart to match [m].
        max_iterations: Optimiser iterations per frame.
        min_points: A frame with fewer thinned points corrects nothing.
        min_inlier_share: A registration matching fewer of the frame's points is refused.
        max_correction_m: A correction moving the camera farther than this is refused [m].
        max_correction_deg: Likewise for its turn [deg].
        normal_voxel_m: Voxel grid the points are thinned on to find which directions they
            fix [m].
        normal_neighbours: Points each of those points' normal is estimated from.
        min_constraint_share: A direction is observed when the surfaces facing it add up
            to this share of the frame's points (see the module's text).
        sigma_m: The registration's error along each observed direction, a turn counted by
            how far it moves the points at their RMS range [m].
        map_horizon_frames: Map voxels no frame has touched for this many frames are forgotten.
    """

    stride_px: int = 2
    downsampling_m: float = 0.03
    map_voxel_m: float = 0.04
    neighbours: int = 10
    max_correspondence_m: float = 0.06
    max_iterations: int = 10
    min_points: int = 200
    min_inlier_share: float = 0.3
    max_correction_m: float = 0.03
    max_correction_deg: float = 2.0
    normal_voxel_m: float = 0.06
    normal_neighbours: int = 15
    min_constraint_share: float = 0.02
    sigma_m: float = 0.004
    map_horizon_frames: int = 150

    def __post_init__(self) -> None:
        require_positive(
            "depth correction",
            downsampling_m=self.downsampling_m,
            map_voxel_m=self.map_voxel_m,
            normal_voxel_m=self.normal_voxel_m,
            max_correspondence_m=self.max_correspondence_m,
            max_correction_m=self.max_correction_m,
            max_correction_deg=self.max_correction_deg,
            sigma_m=self.sigma_m,
        )
        counts = (self.stride_px, self.neighbours, self.normal_neighbours, self.max_iterations)
        if min(*counts, self.min_points) < 1:
            raise ConfigError(
                "stride_px, neighbours, normal_neighbours, max_iterations and min_points "
                "must be >= 1"
            )
        if self.map_horizon_frames < 1:
            raise ConfigError("map_horizon_frames must be >= 1")
        if not 0.0 < self.min_inlier_share <= 1.0:
            raise ConfigError(f"min_inlier_share must be in (0, 1], got {self.min_inlier_share}")
        if not 0.0 < self.min_constraint_share < 1.0:
            raise ConfigError(
                f"min_constraint_share must be in (0, 1), got {self.min_constraint_share}"
            )


@dataclass(frozen=True)
class Correction:
    """What one frame's registration says of the estimate.

    The estimate is corrected by turning it by ``yaw_rad`` about the vertical through
    ``about_in_world`` (the camera's estimated position), then shifting it by
    ``shift_in_world``, both from a Kalman update of the estimate.

    Attributes:
        shift_in_world: Shift of the camera, gains applied, shape (3,) [m].
        yaw_rad: Turn about the vertical, gain applied [rad].
        about_in_world: The point it turns about, shape (3,) [m].
        gains: Share of the estimate's variance of x, y, z and the heading the correction
            takes out, shape (4,), 0 to 1.
        observed: How much of x, y, z and the heading the view observes, shape (4,), 0 to 1.
        inlier_share: Share of the frame's points matched to the map.
        reason: Why the frame corrects nothing ("" when it does).
    """

    shift_in_world: npt.NDArray[np.float64] = field(default_factory=lambda: np.zeros(3))
    yaw_rad: float = 0.0
    about_in_world: npt.NDArray[np.float64] = field(default_factory=lambda: np.zeros(3))
    gains: npt.NDArray[np.float64] = field(default_factory=lambda: np.zeros(4))
    observed: npt.NDArray[np.float64] = field(default_factory=lambda: np.zeros(4))
    inlier_share: float = 0.0
    reason: str = ""

    @property
    def applied(self) -> bool:
        """Whether the frame corrects the estimate."""
        return not self.reason

    @cached_property
    def turn(self) -> npt.NDArray[np.float64]:
        """The turn about the vertical, a rotation matrix.

        Made once: a correction is applied to every pose the estimator keeps.
        """
        return rodrigues(self.yaw_rad * UP)

    def apply(
        self, position: npt.NDArray[np.float64], rotation: npt.NDArray[np.float64]
    ) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
        """A pose (position, rotation matrix) in the world, corrected."""
        turn = self.turn
        moved = self.about_in_world + turn @ (position - self.about_in_world) + self.shift_in_world
        return moved, turn @ rotation


class DepthCorrection:
    """Registers depth frames against a map of the ones before (see the module's text).

    Args:
        config: Settings.

    Attributes:
        frames: Frames offered.
        applied: Frames that corrected the estimate.

    Raises:
        ConfigError: small_gicp is not installed.
    """

    def __init__(self, config: DepthCorrectionConfig | None = None) -> None:
        self.config = config or DepthCorrectionConfig()
        self._gicp = import_small_gicp()
        self._projection: BackProjection | None = None
        self._map: Any = None
        self.frames = 0
        self.applied = 0

    def register(
        self,
        depth: npt.ArrayLike,
        camera: PinholeCamera,
        depth_scale: float | None,
        camera_in_world: npt.NDArray[np.float64],
        variances: npt.NDArray[np.float64],
    ) -> Correction:
        """Register one frame from the estimate's camera pose; the frame then joins the map.

        Args:
            depth: The depth image (float metres, or integers with ``depth_scale``).
            camera: Its intrinsics.
            depth_scale: Metres per unit of integer depth.
            camera_in_world: The estimate's camera pose at the frame's time, 4x4.
            variances: The estimate's variances of x, y, z and the heading [m^2, rad^2].

        Raises:
            DepthImageError: A malformed image.
        """
        c, gicp = self.config, self._gicp
        self.frames += 1
        if self._projection is None or self._projection.camera != camera:
            self._projection = BackProjection(camera, c.stride_px)
        points = self._projection.points(depth, depth_scale)
        cloud, _ = gicp.preprocess_points(points, c.downsampling_m, c.neighbours, 1)
        n = int(cloud.size())
        if n < c.min_points:
            return Correction(reason=f"{n} points after thinning, fewer than {c.min_points}")
        if self._map is None:
            self._map = gicp.GaussianVoxelMap(c.map_voxel_m)
            self._map.set_lru(c.map_horizon_frames, 10)
            self._map.insert(cloud, camera_in_world)
            return Correction(reason="the first frame makes the map")
        result = gicp.align(
            self._map, cloud, camera_in_world,
            max_correspondence_distance=c.max_correspondence_m,
            num_threads=1, max_iterations=c.max_iterations,
        )  # fmt: skip
        share = result.num_inliers / n
        if share < c.min_inlier_share:
            self._map.insert(cloud, camera_in_world)
            least = c.min_inlier_share
            reason = f"{share:.0%} of its points matched the map, fewer than {least:.0%}"
            return Correction(inlier_share=share, reason=reason)
        # Not converging is no reason to refuse: along the directions the view leaves free
        # the optimiser wanders without end (a floor alone), and those are projected out.
        correction = replace(
            self._correction(camera_in_world, np.asarray(result.T_target_source), cloud, variances),
            inlier_share=share,
        )
        if not correction.applied:
            self._map.insert(cloud, camera_in_world)
            return correction
        position, rotation = correction.apply(camera_in_world[:3, 3], camera_in_world[:3, :3])
        joined = np.eye(4)
        joined[:3, :3], joined[:3, 3] = rotation, position
        self._map.insert(cloud, joined)
        self.applied += 1
        return correction

    def _correction(
        self,
        prior: npt.NDArray[np.float64],
        registered: npt.NDArray[np.float64],
        cloud: Any,
        variances: npt.NDArray[np.float64],
    ) -> Correction:
        """The registered pose's difference from the prior, observed part, gains applied."""
        c = self.config
        # Normals over a wider patch than the registration's covariances: a depth camera's
        # quantised ranges tilt a 10-point patch's normal by degrees, enough to make a floor
        # seem to fix the camera's place along it.
        coarse, _ = self._gicp.preprocess_points(
            np.asarray(cloud.points()), c.normal_voxel_m, c.normal_neighbours, 1
        )
        points = np.asarray(coarse.points())[:, :3]
        normals = np.asarray(coarse.normals())[:, :3]
        length = max(float(np.sqrt(np.mean(np.sum(points**2, axis=1)))), 1e-3)
        scale = np.array([length] * 3 + [1.0] * 3)  # turns in metres at the points' range
        jacobian = np.hstack([np.cross(points, normals) / length, normals])
        basis = observed_basis(jacobian.T @ jacobian, c.min_constraint_share * len(points))
        local = np.linalg.inv(prior) @ registered  # the registration's step, camera frame
        step = np.concatenate([rotation_vectors(local[None, :3, :3])[0], local[:3, 3]]) * scale
        measured = basis.T @ step  # the step along the observed directions [m]
        # How the estimate's x, y, z and heading move the camera in the same (scaled) terms.
        rotation = prior[:3, :3]
        model = np.zeros((6, 4))
        model[3:, :3] = rotation.T  # a shift along world x, y, z, in the camera's frame
        model[:3, 3] = rotation.T @ UP  # a turn about the vertical through the camera
        observed = np.clip(np.sum((basis.T @ model) ** 2, axis=0), 0.0, 1.0)
        model[:3, 3] *= length
        seen = (basis @ measured) / scale
        shift, yaw = rotation @ seen[3:], float(UP @ (rotation @ seen[:3]))
        if float(np.linalg.norm(shift)) > c.max_correction_m or abs(yaw) > math.radians(
            c.max_correction_deg
        ):
            reason = (
                f"the registration moved the camera {1000 * np.linalg.norm(shift):.0f} mm and "
                f"{math.degrees(abs(yaw)):.2f} deg from the estimate, more than it can have drifted"
            )
            return Correction(observed=observed, reason=reason)
        if basis.shape[1] == 0:
            return Correction(reason="the view fixes no direction of the camera's pose")
        # A Kalman update of (x, y, z, heading) by the observed part of the step.
        seen_model = basis.T @ model
        prior_covariance = np.diag(np.asarray(variances, dtype=np.float64))
        innovation = seen_model @ prior_covariance @ seen_model.T
        innovation += c.sigma_m**2 * np.eye(len(measured))
        gain = prior_covariance @ seen_model.T @ np.linalg.inv(innovation)
        change = gain @ measured
        taken = np.clip(np.diag(gain @ seen_model), 0.0, 1.0)
        return Correction(change[:3], float(change[3]), prior[:3, 3].copy(), taken, observed)


def observed_basis(information: npt.NDArray[np.float64], least: float) -> npt.NDArray[np.float64]:
    """An orthonormal basis, shape (6, k), of the directions a registration's points fix.

    The eigenvectors of its information (symmetric 6 x 6) whose eigenvalues reach ``least``.
    """
    values, vectors = np.linalg.eigh(0.5 * (information + information.T))
    return vectors[:, values >= least]
