"""The body's attitude for a robot whose backend has no IMU: from its pose source or an IMU."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
from scipy.spatial.transform import Rotation

from footfall.messages import ImuReading, PoseEstimate
from footfall.runtime.bus import Bus

GRAVITY = 9.80665  # standard gravity [m/s^2]


class PoseAttitude:
    """The body's attitude from the newest pose estimate, for a robot without an IMU.

    Args:
        bus: Where the (guarded) pose estimates arrive.
    """

    def __init__(self, bus: Bus) -> None:
        self.rotation = Rotation.identity()
        bus.subscribe(PoseEstimate.TOPIC, self._on_pose, last=True)

    def _on_pose(self, estimate: PoseEstimate) -> None:
        self.rotation = estimate.body_in_world.rotation

    def __call__(self) -> tuple[Rotation, npt.NDArray[np.float64]]:
        """The attitude, and no rates (a pose source does not measure them)."""
        return self.rotation, np.zeros(3)


class ImuAttitude:
    """The body's attitude from an IMU on the bus, for a robot whose backend has none.

    A complementary filter: the gyro turns the attitude between readings; the accelerometer
    pulls roll and pitch towards gravity's direction with time constant ``tilt_time_s``
    (only while it reads within 15 % of 1 g, when the body is not being shaken); the heading
    is the pose source's (an IMU without a magnetometer cannot keep one), or the gyro's
    until a pose comes.

    Args:
        bus: Where :class:`~footfall.messages.ImuReading` and the guarded pose estimates
            arrive.
        tilt_time_s: How fast the accelerometer corrects the tilt [s].
    """

    def __init__(self, bus: Bus, tilt_time_s: float = 1.0) -> None:
        self.rotation: Rotation | None = None
        self.rates = np.zeros(3)
        self.readings = 0
        self.tilt_time_s = tilt_time_s
        self._stamp: float | None = None
        self._heading: float | None = None
        bus.subscribe(ImuReading.TOPIC, self._on_imu)
        bus.subscribe(PoseEstimate.TOPIC, self._on_pose, last=True)

    def _on_pose(self, estimate: PoseEstimate) -> None:
        self._heading = float(estimate.body_in_world.rotation.as_euler("ZYX")[0])

    def _on_imu(self, reading: ImuReading) -> None:
        force = np.asarray(reading.specific_force_body_in_body, dtype=np.float64)
        self.rates = np.asarray(reading.angular_velocity_body_in_body, dtype=np.float64)
        up_measured = force / max(float(np.linalg.norm(force)), 1e-9)
        if self.rotation is None:
            # Level the body to gravity, heading zero: the shortest turn of body z to "up".
            self.rotation = Rotation.align_vectors([[0.0, 0.0, 1.0]], [up_measured])[0]
        else:
            dt = max(0.0, reading.stamp - (self._stamp or reading.stamp))
            turned = self.rotation * Rotation.from_rotvec(self.rates * dt)
            up_predicted = turned.inv().apply([0.0, 0.0, 1.0])
            trusted = abs(np.linalg.norm(force) / GRAVITY - 1.0) < 0.15
            gain = min(1.0, dt / self.tilt_time_s) if trusted else 0.0
            correction = gain * np.cross(up_measured, up_predicted)
            self.rotation = turned * Rotation.from_rotvec(correction)
        if self._heading is not None:
            _, pitch, roll = self.rotation.as_euler("ZYX")
            self.rotation = Rotation.from_euler("ZYX", [self._heading, pitch, roll])
        self._stamp = reading.stamp
        self.readings += 1

    def __call__(self) -> tuple[Rotation, npt.NDArray[np.float64]]:
        """The attitude (level until the first reading) and the gyro's rates."""
        return (self.rotation or Rotation.identity()), self.rates
