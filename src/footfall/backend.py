"""The interface between the walking controller and a robot: simulated or real.

A backend reads the robot's state (joint encoders, IMU attitude) and takes joint targets.
The MuJoCo simulation (:mod:`footfall.sim.hexapod`) is one implementation; a driver for a
real robot's servo bus implements the same three methods.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np
import numpy.typing as npt
from scipy.spatial.transform import Rotation

from footfall.motion.walker import JointTargets


@dataclass(frozen=True)
class RobotState:
    """One reading of the robot.

    Attributes:
        time: Backend clock [s].
        joint_positions: Shape (6, 3) [rad].
        joint_velocities: Shape (6, 3) [rad/s].
        orientation_body_in_world: IMU attitude: rotates body-frame vectors into the world.
        angular_velocity_body_in_body: Gyro reading, shape (3,) [rad/s].
        position_body_in_world: Body position, shape (3,) [m], when the backend knows it
            (a simulator's ground truth, a motion-capture system); else None.
        feet_in_world: Foot centres, shape (6, 3) [m], when known; else None.
        feet_in_contact: Which feet touch the ground, shape (6,), when known; else None.
        foot_orientations_in_world: Rotation matrices of the feet (tibia frames), shape
            (6, 3, 3), when known; else None. With them, rolling can be told from sliding.
    """

    time: float
    joint_positions: npt.NDArray[np.float64]
    joint_velocities: npt.NDArray[np.float64]
    orientation_body_in_world: Rotation
    angular_velocity_body_in_body: npt.NDArray[np.float64]
    position_body_in_world: npt.NDArray[np.float64] | None = None
    feet_in_world: npt.NDArray[np.float64] | None = None
    feet_in_contact: npt.NDArray[np.bool_] | None = None
    foot_orientations_in_world: npt.NDArray[np.float64] | None = None

    @property
    def roll_pitch(self) -> tuple[float, float]:
        """Body roll and pitch [rad] (intrinsic z-y-x Euler angles of the attitude)."""
        _, pitch, roll = self.orientation_body_in_world.as_euler("ZYX")
        return float(roll), float(pitch)

    @property
    def tilt(self) -> float:
        """Angle between the body z axis and the world z axis [rad]."""
        z_axis = self.orientation_body_in_world.apply([0.0, 0.0, 1.0])
        return float(np.arccos(np.clip(z_axis[2], -1.0, 1.0)))


class HexapodBackend(Protocol):
    """What the control loop needs from a robot."""

    def read(self) -> RobotState:
        """The latest state."""
        ...

    def command(self, targets: JointTargets) -> None:
        """Send joint position and rate targets to the servos."""
        ...

    def advance(self, duration: float) -> None:
        """Let ``duration`` seconds pass (a simulator steps; a real robot waits)."""
        ...
