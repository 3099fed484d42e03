"""Where the body is from its own legs and gyro: leg-kinematic odometry with an IMU.

The model, per control tick of length ``dt``:

- **Attitude.** The gyro turns the body: ``R <- R exp((omega - b) dt)`` with ``b`` the gyro
  bias. Roll and pitch are pulled towards the IMU's own attitude (gravity's direction, which
  an accelerometer measures) with time constant ``tilt_time_s``; the heading is the gyro's
  alone (no magnetometer indoors), so it drifts with what is left of the bias.
- **Gyro bias.** Learned while the robot stands still (every foot down, no joint moving, the
  gyro reading under ``still_rate``) as a running mean with time constant ``bias_time_s``.
  Until ``calibration_s`` of standing has been seen the estimator is *calibrating* and gives
  no pose: a robot that starts walking on an unknown bias turns its map. Calibrating on
  level ground (``level_start``), it also learns the IMU's tilt offset, the turn from the
  IMU's up to the normal of the standing feet's plane: a tilt wrong by a fraction of a degree
  would turn leg odometry's forward motion into climbing, as much as half a centimetre a
  metre, which neither the legs nor a map built on the same poses can see.
- **Position.** A foot that stands does not move in the world, so between two ticks the body
  moved by ``R_prev f_prev - R f`` for every foot ``f`` (forward kinematics of the measured
  joints, in the body frame) that stood at both, plus how far the foot's centre rolled: a
  spherical foot of radius ``r`` whose tibia turned by the rotation vector ``dphi`` (from the
  joints and the body's turn) moves its centre by ``dphi x r up`` without slipping (1.7 %
  of the distance walked on the default robot, were it left out). The feet that stand are
  the gait's supporting feet, and of those the ones whose contact the robot senses, where it
  does. A foot whose motion differs from the median of the others by more than
  ``slip_tolerance_m`` is slipping and left out; the rest are averaged. With no standing
  foot the body coasts at its last velocity for at most ``coast_s``; longer, the estimator
  is *lost*. While the robot is not standing under its controller (limp, rising, sitting:
  ``BodyReading.supported``) its feet slide as the legs fold, so the body keeps its place
  over the ground it started on, at the height its legs hold it.

Uncertainty is propagated in a diagonal covariance of ``x, y, z, roll, pitch, yaw``: each
metre of leg odometry adds ``position_noise_per_m^2`` to the position variances, and the
heading's variance, times the distance walked, to the horizontal ones; the gyro's rate
noise and what may be left of its bias grow the heading's; roll and pitch stay at the IMU's
tilt accuracy. It is an estimate of the error, not of the truth: the walk's metrics report
both.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from scipy.spatial.transform import Rotation

from footfall.checks import require_positive
from footfall.estimation.depth_correction import Correction
from footfall.estimation.rotations import cross, rodrigues, rotation_of, rotation_vectors
from footfall.robot.kinematics import LegKinematics
from footfall.sensing.pose import Pose

UP = np.array([0.0, 0.0, 1.0])
# The path's length is measured between points this far apart [m].
DISTANCE_STEP_M = 0.01


@dataclass(frozen=True)
class EstimatorConfig:
    """How the leg-inertial estimator weighs its sensors.

    Attributes:
        tilt_time_s: How fast roll and pitch follow the IMU's attitude [s].
        bias_time_s: Time constant of the gyro bias learned at standstill [s].
        calibration_s: Standing time before the first pose [s].
        still_joint_rate: Fastest joint rate of a robot standing still [rad/s].
        still_rate: Largest gyro rate of a robot standing still [rad/s].
        slip_tolerance_m: A standing foot whose motion in one tick differs from the other
            standing feet's median by more than this is slipping [m].
        coast_s: Longest time without a standing foot before the estimator is lost [s].
        lost_tilt: A body tilted further than this has fallen: the estimator is lost [rad].
        position_noise_per_m: Position error of leg odometry, a random walk with the
            distance walked [m/sqrt(m)].
        heading_noise: The gyro's rate noise density [rad/s/sqrt(Hz)].
        residual_bias: Gyro bias left after calibration [rad/s].
        tilt_sigma: Accuracy of the IMU's roll and pitch [rad].
        level_start: The robot calibrates standing on level ground: the IMU's tilt offset
            is learned then, against the plane of the feet.
    """

    tilt_time_s: float = 0.5
    bias_time_s: float = 5.0
    calibration_s: float = 3.0
    still_joint_rate: float = 0.05
    still_rate: float = 0.05
    slip_tolerance_m: float = 0.003
    coast_s: float = 0.3
    lost_tilt: float = math.radians(60.0)
    position_noise_per_m: float = 0.005
    heading_noise: float = 2.5e-4
    residual_bias: float = 3e-4
    tilt_sigma: float = math.radians(0.5)
    level_start: bool = True

    def __post_init__(self) -> None:
        require_positive(
            "estimator",
            tilt_time_s=self.tilt_time_s,
            bias_time_s=self.bias_time_s,
            calibration_s=self.calibration_s,
            still_joint_rate=self.still_joint_rate,
            still_rate=self.still_rate,
            slip_tolerance_m=self.slip_tolerance_m,
            coast_s=self.coast_s,
            lost_tilt=self.lost_tilt,
        )


@dataclass(frozen=True)
class BodyReading:
    """What the estimator reads at one tick.

    Attributes:
        stamp: Time [s].
        joint_positions: Measured joint angles, shape (6, 3) [rad].
        joint_velocities: Measured joint rates, shape (6, 3) [rad/s].
        angular_velocity_body_in_body: Gyro rates, shape (3,) [rad/s].
        attitude_body_in_world: The IMU's attitude; only its roll and pitch are used.
        standing: Feet that support the body, shape (6,).
        supported: The robot stands under its controller (the servos' posture is standing);
            False while it is limp, rises or sits, when its feet may slide as the legs fold.
    """

    stamp: float
    joint_positions: npt.NDArray[np.float64]
    joint_velocities: npt.NDArray[np.float64]
    angular_velocity_body_in_body: npt.NDArray[np.float64]
    attitude_body_in_world: Rotation
    standing: npt.NDArray[np.bool_]
    supported: bool = True


class LegInertialEstimator:
    """The body's pose from leg kinematics and a gyro (the model in the module's text).

    Args:
        kinematics: The robot's legs.
        start: The body's pose when the estimator starts (where the world's frame is).
        config: Its weights.

    Attributes:
        pose: The newest estimate of the body in the world.
        covariance: Its diagonal covariance of ``x, y, z, roll, pitch, yaw`` [m^2, rad^2].
        bias: The gyro bias learned so far [rad/s].
        distance_m: Length of the path the estimate travelled [m].
        lost: Why the estimator cannot go on, or None.
        slipped: Standing-foot readings left out as slipping.
    """

    def __init__(
        self,
        kinematics: LegKinematics,
        start: Pose,
        config: EstimatorConfig | None = None,
    ) -> None:
        self.kinematics = kinematics
        self.config = config or EstimatorConfig()
        self.position = np.array(start.position, dtype=np.float64)
        self.rotation_matrix = start.rotation.as_matrix()
        self.covariance = np.zeros(6)
        self.covariance[3:5] = self.config.tilt_sigma**2
        self.bias = np.zeros(3)
        self.distance_m = 0.0
        self.lost: str | None = None
        self.slipped = 0
        self._still_s = 0.0
        self._still_readings = 0
        self._up_sums = np.zeros((2, 3))  # the IMU's and the feet's up, summed while calibrating
        self._tilt_offset: npt.NDArray[np.float64] | None = None
        self._tilt_s = 0.0
        self._ground_z = 0.0  # the ground's height under the start [m]
        self._heading_s = 0.0
        self._unsupported_s = 0.0
        self._velocity = np.zeros(3)
        self._distance_anchor = self.position.copy()
        self._last: BodyReading | None = None
        self._feet_in_body: npt.NDArray[np.float64] | None = None
        self._tibias: npt.NDArray[np.float64] | None = None
        self._mount_yaws = np.asarray(kinematics.spec.mount_yaws, dtype=np.float64)

    @property
    def pose(self) -> Pose:
        """The newest estimate of the body in the world."""
        return Pose(self.position.copy(), rotation_of(self.rotation_matrix))

    @property
    def velocity(self) -> npt.NDArray[np.float64]:
        """The body's velocity over the last tick, in the world [m/s]."""
        return self._velocity.copy()

    @property
    def calibrated(self) -> bool:
        """True once the gyro bias is known well enough to give a pose."""
        return self._still_s >= self.config.calibration_s

    @property
    def ready(self) -> bool:
        """True when the pose may be used: calibrated and not lost."""
        return self.calibrated and self.lost is None

    def update(self, reading: BodyReading) -> None:
        """Take one tick's reading (``position`` and ``rotation_matrix`` follow it)."""
        c = self.config
        angles = np.asarray(reading.joint_positions, dtype=np.float64)
        feet = self.kinematics.forward_in_body(angles)
        last, self._last = self._last, reading
        last_feet, self._feet_in_body = self._feet_in_body, feet
        last_tibias, self._tibias = self._tibias, self._tibias_in_body(angles)
        # The IMU's up in the body frame: the last row of its attitude's matrix.
        up_imu = reading.attitude_body_in_world.as_matrix()[2]
        if last is None:
            self.rotation_matrix = _level(self.rotation_matrix, up_imu)
            self._ground_z = self.position[2] - self._height_over(feet, reading.standing)
            return
        dt = reading.stamp - last.stamp
        if dt <= 0.0 or self.lost is not None:
            return
        gyro = np.asarray(reading.angular_velocity_body_in_body, dtype=np.float64)
        if (
            bool(np.all(reading.standing))
            and float(np.max(np.abs(reading.joint_velocities))) < c.still_joint_rate
            and float(np.linalg.norm(gyro)) < c.still_rate
        ):
            self._stand(gyro, up_imu, feet, dt, reading.supported)
        before = self.rotation_matrix
        turned = before @ rodrigues((gyro - self.bias) * dt)
        up_measured = up_imu if self._tilt_offset is None else self._tilt_offset @ up_imu
        gain = min(1.0, dt / c.tilt_time_s)
        rotation = turned @ rodrigues(gain * cross(up_measured, turned[2]))
        if math.acos(min(1.0, max(-1.0, rotation[2, 2]))) > c.lost_tilt:
            self.lost = "the body has tipped over (tilt beyond its limit)"
        if not reading.supported:
            # Limp, rising or sitting, the feet slide as the legs fold: the body stays where
            # it was over the ground it started on, at the height its legs hold it.
            self.rotation_matrix = rotation
            self._velocity = np.zeros(3)
            height = self._ground_z + self._height_over(feet, reading.standing)
            self.position = np.array([self.position[0], self.position[1], height])
            return
        both = np.asarray(reading.standing, dtype=bool) & np.asarray(last.standing, dtype=bool)
        if both.any():
            assert last_feet is not None and last_tibias is not None
            moved = last_feet[both] @ before.T - feet[both] @ rotation.T
            tibias_before = before @ last_tibias[both]
            turns = (rotation @ self._tibias[both]) @ tibias_before.transpose(0, 2, 1)
            # A turn (x, y, z) of a sphere of radius r rolls its centre by (x, y, z) x (0, 0, r).
            rolled = rotation_vectors(turns) * self.kinematics.spec.foot_radius
            moved[:, 0] += rolled[:, 1]
            moved[:, 1] -= rolled[:, 0]
            median = np.median(moved, axis=0)
            steady = np.linalg.norm(moved - median, axis=1) <= c.slip_tolerance_m
            self.slipped += int(np.count_nonzero(~steady))
            # Feet that all disagree (two, far apart) leave their median.
            step = moved[steady].mean(axis=0) if steady.any() else median
            self._velocity = step / dt
            self._unsupported_s = 0.0
        else:
            step = self._velocity * dt
            self._unsupported_s += dt
            if self._unsupported_s > c.coast_s:
                self.lost = f"no foot has stood for {self._unsupported_s:.2f} s"
        self.rotation_matrix = rotation
        self.position = self.position + step
        self._grow(float(np.linalg.norm(step)), dt)

    def correct(self, correction: Correction) -> None:
        """Take a registration's correction (position, heading, their variances)."""
        if not correction.applied:
            return
        self.position, self.rotation_matrix = correction.apply(self.position, self.rotation_matrix)
        # A correction is not distance walked.
        self._distance_anchor, _ = correction.apply(self._distance_anchor, self.rotation_matrix)
        self.covariance[[0, 1, 2, 5]] *= 1.0 - correction.gains
        # The heading's variance grows with the time since it was last known (see _grow):
        # that time becomes the one at which the model reaches the corrected variance.
        noise, bias = self.config.heading_noise**2, self.config.residual_bias**2
        variance = self.covariance[5]
        if bias > 0.0:
            self._heading_s = (-noise + math.sqrt(noise**2 + 4.0 * bias * variance)) / (2.0 * bias)
        elif noise > 0.0:
            self._heading_s = variance / noise

    def _stand(
        self,
        gyro: npt.NDArray[np.float64],
        up_imu: npt.NDArray[np.float64],
        feet: npt.NDArray[np.float64],
        dt: float,
        supported: bool,
    ) -> None:
        """A reading of a robot standing still: learn the gyro's bias and the IMU's tilt."""
        c = self.config
        # The mean of every standing reading at first, then a running mean.
        self._still_readings += 1
        weight = max(min(1.0, dt / c.bias_time_s), 1.0 / self._still_readings)
        self.bias += weight * (gyro - self.bias)
        self._still_s += dt
        if c.level_start and supported and self._tilt_offset is None:
            # Standing on level ground, the feet's plane is level: the IMU's tilt beyond it
            # is its own offset, taken out once the robot has stood as long as it calibrates.
            self._up_sums += (up_imu, support_normal(feet))
            self._tilt_s += dt
            if self._tilt_s >= c.calibration_s:
                imu, legs = self._up_sums
                self._tilt_offset = Rotation.align_vectors([legs], [imu])[0].as_matrix()

    def _height_over(self, feet: npt.NDArray[np.float64], standing: npt.NDArray[np.bool_]) -> float:
        """How high the body stands over the ground under its standing feet (all, if none) [m]."""
        standing = np.asarray(standing, dtype=bool)
        chosen = feet[standing] if standing.any() else feet
        return -float(np.mean(chosen @ self.rotation_matrix[2])) + self.kinematics.spec.foot_radius

    def _grow(self, travelled: float, dt: float) -> None:
        """The path's length, and the covariance, after a tick that moved ``travelled`` [m]."""
        c = self.config
        # The path's length at a resolution of DISTANCE_STEP_M: the encoders' jitter from
        # one tick to the next is not distance walked.
        leg = float(np.linalg.norm(self.position - self._distance_anchor))
        if leg >= DISTANCE_STEP_M:
            self.distance_m += leg
            self._distance_anchor = self.position.copy()
        # Leg odometry's error grows as a random walk with the distance, and the heading's
        # error turns what is walked sideways.
        self.covariance[:3] += c.position_noise_per_m**2 * travelled
        self.covariance[:2] += (travelled * self.distance_m) * self.covariance[5]
        if self.calibrated:
            # White rate noise grows the heading's variance with time; a bias left over
            # turns it steadily, its error growing with time itself.
            self._heading_s += dt
            self.covariance[5] = (
                c.heading_noise**2 * self._heading_s + (c.residual_bias * self._heading_s) ** 2
            )

    def _tibias_in_body(self, angles: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
        """Each tibia's orientation in the body frame, shape (6, 3, 3).

        Its x axis runs from the knee to the foot: a turn about z by the leg's yaw, then
        about y by minus the femur and tibia angles.
        """
        yaw = self._mount_yaws + angles[:, 0]
        pitch = -(angles[:, 1] + angles[:, 2])
        ca, sa, cb, sb = np.cos(yaw), np.sin(yaw), np.cos(pitch), np.sin(pitch)
        out = np.zeros((len(yaw), 3, 3))
        out[:, 0, 0], out[:, 0, 1], out[:, 0, 2] = ca * cb, -sa, ca * sb
        out[:, 1, 0], out[:, 1, 1], out[:, 1, 2] = sa * cb, ca, sa * sb
        out[:, 2, 0], out[:, 2, 2] = -sb, cb
        return out


def _level(
    rotation: npt.NDArray[np.float64], up: npt.NDArray[np.float64]
) -> npt.NDArray[np.float64]:
    """``rotation``'s heading with the tilt that puts the body's ``up`` (in the body) up."""
    heading = math.atan2(rotation[1, 0], rotation[0, 0])
    tilt = Rotation.align_vectors([UP], [up])[0]  # level: the shortest turn of up to z
    _, pitch, roll = tilt.as_euler("ZYX")
    return Rotation.from_euler("ZYX", [heading, pitch, roll]).as_matrix()


def support_normal(feet_in_body: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    """The upward unit normal of the plane through the feet, in the body frame."""
    feet = np.asarray(feet_in_body, dtype=np.float64)
    design = np.column_stack([feet[:, 0], feet[:, 1], np.ones(len(feet))])
    (a, b, _), *_ = np.linalg.lstsq(design, feet[:, 2], rcond=None)
    normal = np.array([-a, -b, 1.0])
    return normal / np.linalg.norm(normal)
