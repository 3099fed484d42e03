"""What a real robot's IMU and joint encoders get wrong, for the estimator in simulation.

The simulator's gyro, attitude and joint angles are exact; a robot's are not. The defaults
are those of the parts footfall's robots carry:

- **Gyro**: Bosch BMI055 (the RealSense D435i's IMU): rate noise density 0.014 deg/s/sqrt(Hz)
  (2.4e-4 rad/s/sqrt(Hz)), read at the control rate with a bandwidth of half of it; a turn-on
  bias of 0.5 deg/s (1 sigma per axis, within the datasheet's +-1 deg/s zero-rate offset),
  which then wanders as a random walk of 5e-6 rad/s/sqrt(s) (8 deg/h after a minute, a
  consumer MEMS gyro's bias instability).
- **Attitude** (roll and pitch from the accelerometer's gravity): an offset of 0.3 deg per
  axis (a calibrated accelerometer's 5 mg) and 0.1 deg of noise per reading. Its heading is
  the simulator's, but the estimator takes only roll and pitch from it.
- **Joint encoders**: the Dynamixel X series' 4096 counts a turn (0.088 deg), and velocities
  in its 0.229 rev/min units.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from scipy.spatial.transform import Rotation

from footfall.checks import require_non_negative
from footfall.messages import RobotState


@dataclass(frozen=True)
class SensorNoiseConfig:
    """Error magnitudes of the IMU and the encoders (defaults: the module's parts).

    Attributes:
        gyro_noise_density: Rate noise [rad/s/sqrt(Hz)].
        gyro_bias: Turn-on bias, standard deviation per axis [rad/s].
        gyro_bias_walk: Bias random walk [rad/s/sqrt(s)].
        tilt_offset: Roll and pitch offset, standard deviation per axis [rad].
        tilt_noise: Roll and pitch noise per reading [rad].
        encoder_resolution: One encoder count [rad]; 0 for exact angles.
        velocity_resolution: One unit of measured joint rate [rad/s]; 0 for exact rates.
    """

    gyro_noise_density: float = math.radians(0.014)
    gyro_bias: float = math.radians(0.5)
    gyro_bias_walk: float = 5e-6
    tilt_offset: float = math.radians(0.3)
    tilt_noise: float = math.radians(0.1)
    encoder_resolution: float = 2.0 * math.pi / 4096
    velocity_resolution: float = 0.229 * 2.0 * math.pi / 60.0

    def __post_init__(self) -> None:
        require_non_negative("sensor noise", **self.__dict__)


def _quantised(values: npt.NDArray[np.float64], step: float) -> npt.NDArray[np.float64]:
    return values if step == 0.0 else np.round(values / step) * step


class NoisySensors:
    """Turns the simulator's exact readings into a real robot's, reproducibly for ``rng``.

    Args:
        config: Error magnitudes.
        rng: Random generator (seed it for repeatable walks).
    """

    def __init__(self, config: SensorNoiseConfig, rng: np.random.Generator) -> None:
        self.config = config
        self.rng = rng
        self.gyro_bias = rng.normal(0.0, config.gyro_bias, 3)
        self.tilt_offset = Rotation.from_rotvec([*rng.normal(0.0, config.tilt_offset, 2), 0.0])
        self._time: float | None = None

    def read(self, state: RobotState) -> RobotState:
        """``state`` as the robot's own sensors would have read it."""
        c, rng = self.config, self.rng
        dt = 0.0 if self._time is None else max(state.time - self._time, 0.0)
        if dt > 0.0:
            self.gyro_bias += rng.normal(0.0, c.gyro_bias_walk * math.sqrt(dt), 3)
            # White noise read at 1/dt with a bandwidth of half that.
            rate_sigma = c.gyro_noise_density * math.sqrt(0.5 / dt)
        else:
            rate_sigma = 0.0
        self._time = state.time
        gyro = state.angular_velocity_body_in_body + self.gyro_bias + rng.normal(0, rate_sigma, 3)
        tilt_error = Rotation.from_rotvec([*rng.normal(0.0, c.tilt_noise, 2), 0.0])
        return RobotState(
            time=state.time,
            joint_positions=_quantised(state.joint_positions, c.encoder_resolution),
            joint_velocities=_quantised(state.joint_velocities, c.velocity_resolution),
            orientation_body_in_world=state.orientation_body_in_world
            * self.tilt_offset
            * tilt_error,
            angular_velocity_body_in_body=gyro,
            feet_in_contact=state.feet_in_contact,
        )
