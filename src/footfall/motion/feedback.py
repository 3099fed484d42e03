"""Body attitude and height feedback (the draft's tilt stabilisation, thesis §8.1's fix).

Integral feedback on the IMU's roll and pitch commands the body tilted the other way; on
the body's measured height above its stance feet (from the joint encoders and the IMU) it
raises or lowers the body. Both corrections are bounded.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from footfall.messages import RobotState
from footfall.robot.kinematics import LegKinematics


@dataclass(frozen=True)
class FeedbackConfig:
    """Feedback gains and limits.

    Attributes:
        tilt_gain: Integral gain on IMU roll and pitch [1/s].
        tilt_limit: Largest attitude correction [rad].
        height_gain: Integral gain on the measured height above the stance feet [1/s].
        height_limit: Largest height correction [m].
    """

    tilt_gain: float = 3.0
    tilt_limit: float = math.radians(6.0)
    height_gain: float = 3.0
    height_limit: float = 0.02


class BodyFeedback:
    """The integrated attitude and height corrections.

    Args:
        config: Gains and limits, or None for no feedback (the corrections stay zero).
        kinematics: The legs' kinematics (for the measured height).

    Attributes:
        tilt_correction: Commanded roll and pitch offset, shape (2,) [rad].
        height_correction: Commanded body height offset [m].
    """

    def __init__(self, config: FeedbackConfig | None, kinematics: LegKinematics) -> None:
        self.config = config
        self.kinematics = kinematics
        self.tilt_correction = np.zeros(2)
        self.height_correction = 0.0

    def update(
        self,
        state: RobotState,
        dt: float,
        swinging: npt.NDArray[np.bool_],
        feet_in_world: npt.NDArray[np.float64],
        body_z: float,
        pitch_reference: float = 0.0,
    ) -> None:
        """Integrate one reading over ``dt`` [s].

        Args:
            state: The robot's reading.
            dt: Time since the last update [s].
            swinging: Which legs swing; the others give the measured height.
            feet_in_world: The controller's foot positions, shape (6, 3) [m].
            body_z: The controller's reference body height in the world [m].
            pitch_reference: The pitch the body is commanded to hold [rad] (its incline).
        """
        fb = self.config
        if fb is None:
            return
        roll, pitch = state.roll_pitch
        limit = fb.tilt_limit
        self.tilt_correction = np.clip(
            self.tilt_correction - fb.tilt_gain * np.array([roll, pitch - pitch_reference]) * dt,
            -limit,
            limit,
        )
        stance = ~swinging
        if stance.sum() < 3:
            return
        feet_in_body = self.kinematics.forward_in_body(state.joint_positions)[stance]
        level = state.orientation_body_in_world.apply(feet_in_body)
        measured = -float(level[:, 2].mean())
        reference = body_z - float(feet_in_world[stance, 2].mean())
        self.height_correction = float(
            np.clip(
                self.height_correction + fb.height_gain * (reference - measured) * dt,
                -fb.height_limit,
                fb.height_limit,
            )
        )
