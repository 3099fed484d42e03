"""The interface between footfall and a robot: simulated, mocked or real.

A backend reads the robot's state (joint encoders, IMU attitude) and takes joint targets.
The MuJoCo simulation (:mod:`footfall.sim.hexapod`) is one implementation, the mock of
:mod:`footfall.backends.mock` another; a driver for a real robot's servo bus implements
the same methods.
"""

from __future__ import annotations

from typing import Protocol

from footfall.messages import JointTargets, RobotState


class HexapodBackend(Protocol):
    """What the servo node and the control loop need from a robot.

    Attributes:
        realtime: True when ``advance`` is a real wait (hardware: time passes by itself);
            False when it computes the next state (a simulator or a mock), which a
            wall-clock scheduler then paces.
    """

    realtime: bool

    def read(self) -> RobotState:
        """The latest state."""
        ...

    def command(self, targets: JointTargets) -> None:
        """Send joint position and rate targets to the servos."""
        ...

    def set_torque(self, enabled: bool) -> None:
        """Switch the servos' torque on (they hold their targets) or off (limp)."""
        ...

    def advance(self, duration: float) -> None:
        """Let ``duration`` seconds pass (a simulator steps; a real robot waits)."""
        ...
