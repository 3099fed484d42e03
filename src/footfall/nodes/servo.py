"""The servo node: effector targets in, joint targets to the robot out (the thesis' MCU).

It solves each leg's inverse kinematics for the foot targets and maps the foot rates to
joint rates, and sends both to the backend. It honours the operating mode: torque-off (the
initial mode) switches the servos limp and sends no joint targets; walking switches them on.
It also reads the robot and publishes its state.
"""

from __future__ import annotations

import numpy as np

from footfall.backends import HexapodBackend
from footfall.errors import BackendError, SingularConfigurationError, UnreachableTargetError
from footfall.messages import (
    EffectorTargets,
    JointTargets,
    LogLine,
    Mode,
    ModeCommand,
    RobotState,
)
from footfall.robot.kinematics import LegKinematics
from footfall.robot.spec import HexapodSpec
from footfall.runtime.bus import Bus


class ServoNode:
    """Inverse kinematics and the robot's servos.

    Args:
        bus: The bus.
        spec: The robot.
        backend: The robot's driver (simulated, mocked or real).
    """

    name = "servo"

    def __init__(self, bus: Bus, spec: HexapodSpec, backend: HexapodBackend) -> None:
        self.bus = bus
        self.backend = backend
        self.kinematics = LegKinematics(spec)
        self.mode = Mode.TORQUE_OFF
        self.joint_targets_sent = 0
        self.last_targets: JointTargets | None = None
        self.fault = ""  # why the robot stopped taking targets (a backend fault), or ""
        backend.set_torque(False)
        bus.subscribe(ModeCommand.TOPIC, self._on_mode, last=True)
        bus.subscribe(EffectorTargets.TOPIC, self._on_targets)

    def _on_mode(self, message: ModeCommand) -> None:
        if message.mode is self.mode:
            return
        self.mode = message.mode
        self.backend.set_torque(self.mode is Mode.WALKING)

    def joint_targets(self, targets: EffectorTargets) -> JointTargets:
        """Joint angles and rates for effector targets.

        Raises:
            UnreachableTargetError: If a foot target is out of its leg's reach.
        """
        angles = self.kinematics.inverse_in_body(targets.feet_in_body)
        try:
            rates = self.kinematics.joint_rates(
                angles, self.kinematics.vectors_body_to_leg(targets.foot_velocities_in_body)
            )
        except SingularConfigurationError:
            rates = np.zeros((6, 3))
        return JointTargets(positions=angles, velocities=rates, stamp=targets.stamp)

    def _on_targets(self, targets: EffectorTargets) -> None:
        if self.mode is not Mode.WALKING or self.fault:
            return
        try:
            joints = self.joint_targets(targets)
        except UnreachableTargetError as exc:
            # Hold the last targets: the feet stay where they are.
            self.bus.publish(LogLine.TOPIC, LogLine(targets.stamp, self.name, "error", str(exc)))
            return
        try:
            self.backend.command(joints)
        except BackendError as exc:
            # The servos hold their last goal; nothing more is sent to a failing robot.
            self.fault = str(exc)
            self.bus.publish(LogLine.TOPIC, LogLine(targets.stamp, self.name, "error", self.fault))
            return
        self.last_targets = joints
        self.joint_targets_sent += 1
        self.bus.publish(JointTargets.TOPIC, joints)

    def publish_state(self) -> RobotState:
        """Read the robot and publish its state; returns it."""
        state = self.backend.read()
        self.bus.publish(RobotState.TOPIC, state)
        return state
