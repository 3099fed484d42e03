"""The servo node: effector targets in, joint targets to the robot out (the thesis' MCU).

It solves each leg's inverse kinematics for the foot targets and maps the foot rates to
joint rates, and sends both to the backend. It honours the operating mode: torque-off (the
initial mode) leaves the servos limp and sends no joint targets. Switched to walking, it
turns the torque on where the joints are and stands the robot up from there
(:mod:`footfall.motion.posture`) before the walking controller's targets go through;
switched back to torque-off, it sits the robot down and then lets go. A backend fault stops
every target for good (:data:`Posture.HALTED`). It also reads the robot and publishes its
state, and its posture and servo health as :class:`~footfall.messages.ServoStatus`.
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
    Posture,
    RobotState,
    ServoStatus,
)
from footfall.motion.posture import PostureMove, sit_down, stand_up
from footfall.robot.kinematics import LegKinematics
from footfall.robot.spec import HexapodSpec
from footfall.runtime.bus import Bus

STATUS_PERIOD = 0.5  # the servo status goes out at least this often [s]
MAX_POSTURE_STEP = 0.1  # the longest a standing-up or sitting-down step covers [s]


class ServoNode:
    """Inverse kinematics, standing up and sitting down, and the robot's servos.

    Args:
        bus: The bus.
        spec: The robot.
        backend: The robot's driver (simulated, mocked or real).
        stand_height: Body height it stands up to [m]; the spec's by default.
    """

    name = "servo"

    def __init__(
        self,
        bus: Bus,
        spec: HexapodSpec,
        backend: HexapodBackend,
        stand_height: float | None = None,
    ) -> None:
        self.bus = bus
        self.spec = spec
        self.backend = backend
        self.kinematics = LegKinematics(spec)
        self.stand_height = spec.body_height if stand_height is None else stand_height
        self.mode = Mode.TORQUE_OFF
        self.posture = Posture.LIMP
        self.move: PostureMove | None = None
        self.joint_targets_sent = 0
        self.last_targets: JointTargets | None = None
        self.fault = ""  # why the robot stopped taking targets (a backend fault), or ""
        self._time = 0.0
        self._next_status = 0.0
        backend.set_torque(False)
        bus.subscribe(ModeCommand.TOPIC, self._on_mode, last=True)
        bus.subscribe(EffectorTargets.TOPIC, self._on_targets)

    def _on_mode(self, message: ModeCommand) -> None:
        if message.mode is self.mode:
            return
        self.mode = message.mode
        if self.posture is Posture.HALTED:
            return
        if self.mode is Mode.WALKING:
            self._send_torque(True)
            joints = self.backend.read().joint_positions
            self.move = stand_up(self.spec, joints, self.stand_height)
            self._set_posture(Posture.STANDING if self.move is None else Posture.RISING)
        elif self.posture is Posture.LIMP:
            pass
        else:
            start = (
                self.last_targets.positions
                if self.last_targets is not None
                else self.backend.read().joint_positions
            )
            self.move = sit_down(self.spec, start)
            self._set_posture(Posture.SITTING)

    def tick(self, t: float, dt: float) -> None:
        """Move the legs one step while standing up or sitting down, at time ``t`` [s].

        A step covers the time since the last tick (ticks a late wall clock skipped
        included, up to ``MAX_POSTURE_STEP``): the legs keep their rates in real time.
        """
        step = min(max(dt, t - self._time), MAX_POSTURE_STEP)
        self._time = t
        if t >= self._next_status:
            self._next_status = t + STATUS_PERIOD
            self.publish_status()
        if self.move is None or self.posture not in (Posture.RISING, Posture.SITTING):
            return
        if self._send(self.move.step(step, t)) and self.move.done:
            self.move = None
            if self.posture is Posture.RISING:
                self._set_posture(Posture.STANDING)
            else:
                self._send_torque(False)
                if self.posture is not Posture.HALTED:
                    self._set_posture(Posture.LIMP)

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
        if self.mode is not Mode.WALKING or self.posture is not Posture.STANDING:
            return
        try:
            joints = self.joint_targets(targets)
        except UnreachableTargetError as exc:
            # Hold the last targets: the feet stay where they are.
            self.bus.publish(LogLine.TOPIC, LogLine(targets.stamp, self.name, "error", str(exc)))
            return
        self._send(joints)

    def _send(self, joints: JointTargets) -> bool:
        """Joint targets to the backend; False (and halted) when it fails."""
        try:
            self.backend.command(joints)
        except BackendError as exc:
            self._halt(str(exc), joints.stamp)
            return False
        self.last_targets = joints
        self.joint_targets_sent += 1
        self.bus.publish(JointTargets.TOPIC, joints)
        return True

    def _send_torque(self, enabled: bool) -> None:
        try:
            self.backend.set_torque(enabled)
        except BackendError as exc:
            self._halt(str(exc), self._time)

    def _halt(self, reason: str, stamp: float) -> None:
        """The servos hold their last goal; nothing more is sent to a failing robot."""
        self.fault = reason
        self.move = None
        self.bus.publish(LogLine.TOPIC, LogLine(stamp, self.name, "error", reason))
        self._set_posture(Posture.HALTED)

    def _set_posture(self, posture: Posture) -> None:
        if posture is not self.posture:
            self.posture = posture
            self.publish_status()

    def publish_state(self) -> RobotState:
        """Read the robot and publish its state; returns it."""
        state = self.backend.read()
        self.bus.publish(RobotState.TOPIC, state)
        return state

    def publish_status(self) -> ServoStatus:
        """Publish the posture and, from a backend that reads them, the servos' health."""
        health = getattr(self.backend, "health", None)
        temperatures, voltages, loads = health() if callable(health) else (None, None, None)
        status = ServoStatus(self._time, self.posture, self.fault, temperatures, voltages, loads)
        self.bus.publish(ServoStatus.TOPIC, status)
        return status
