"""A mock hexapod (upkie's mock backend): no physics, joints that follow their targets.

Each joint moves toward its commanded angle as a first-order servo with time constant
``servo_time_constant``; the body stays level on flat ground, so the IMU reads no tilt and
the feet nearest the ground count as in contact. It lets the control loop, the feedback and
the freeze paths run without MuJoCo, and records what it was sent.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt
from scipy.spatial.transform import Rotation

from footfall.backends import BackendSetup
from footfall.errors import ConfigError
from footfall.messages import JointTargets, RobotState
from footfall.robot.kinematics import LegKinematics
from footfall.robot.spec import HexapodSpec

# Feet within this of the lowest one count as touching the flat ground [m].
CONTACT_BAND = 0.003


class MockHexapod:
    """A hexapod whose joints track their targets; standing on its rest stance at start.

    Args:
        spec: The robot.
        servo_time_constant: First-order lag of each joint [s]; 0 tracks exactly.
        body_height: Initial body height [m]; the spec's by default.
    """

    realtime = False

    def __init__(
        self,
        spec: HexapodSpec,
        servo_time_constant: float = 0.01,
        body_height: float | None = None,
    ) -> None:
        self.spec = spec
        self.kinematics = LegKinematics(spec)
        self.servo_time_constant = servo_time_constant
        height = spec.body_height if body_height is None else body_height
        feet = spec.rest_feet_in_body(height)
        feet[:, 2] += spec.foot_radius
        self.joint_positions = self.kinematics.inverse_in_body(feet)
        self.joint_velocities = np.zeros((6, 3))
        self.targets: JointTargets | None = None
        self.torque = True
        self.time = 0.0
        self.commands_received = 0
        self.commands_while_limp = 0

    @classmethod
    def open(cls, setup: BackendSetup) -> MockHexapod:
        """The mock standing at ``setup.body_height``.

        ``setup.options`` may set ``servo_time_constant`` [s].
        """
        tau = setup.options.get("servo_time_constant", "0.01")
        try:
            servo_time_constant = float(tau)
        except ValueError as exc:
            raise ConfigError(f"servo_time_constant {tau!r} is not a number of seconds") from exc
        return cls(setup.spec, servo_time_constant, body_height=setup.body_height)

    def read(self) -> RobotState:
        """Encoders, a level IMU, and contacts of the feet nearest the ground."""
        feet = self.kinematics.forward_in_body(self.joint_positions)
        contact = feet[:, 2] <= feet[:, 2].min() + CONTACT_BAND
        return RobotState(
            time=self.time,
            joint_positions=self.joint_positions.copy(),
            joint_velocities=self.joint_velocities.copy(),
            orientation_body_in_world=Rotation.identity(),
            angular_velocity_body_in_body=np.zeros(3),
            feet_in_contact=contact,
        )

    def command(self, targets: JointTargets) -> None:
        """Take joint targets; ignored (and counted) while the torque is off."""
        self.commands_received += 1
        if not self.torque:
            self.commands_while_limp += 1
            return
        self.targets = targets

    def set_torque(self, enabled: bool) -> None:
        """Servos on or off; off, the joints stay where they are and targets are dropped."""
        self.torque = bool(enabled)
        if not self.torque:
            self.targets = None

    def advance(self, duration: float) -> None:
        """Move the joints toward their targets for ``duration`` seconds."""
        self.time += duration
        if self.targets is None:
            self.joint_velocities = np.zeros((6, 3))
            return
        goal: npt.NDArray[np.float64] = np.asarray(self.targets.positions, dtype=np.float64)
        tau = self.servo_time_constant
        blend = 1.0 if tau <= 0 else 1.0 - math.exp(-duration / tau)
        moved = (goal - self.joint_positions) * blend
        self.joint_velocities = moved / duration if duration > 0 else np.zeros((6, 3))
        self.joint_positions = self.joint_positions + moved
