"""The movement node: command, mode, pose and map in; effector targets and gait status out.

It runs the walking controller (gait, footholds on the map, swing paths, feedback) once per
control tick. Map updates go to the terrain planner, pose estimates re-register the
controller's world. In torque-off it holds still and only reports. A command watchdog
keeps the robot safe when the operator's link drops: with no command for
``command_timeout`` seconds while walking, the body stops at once (within the acceleration
limit), the feet in the air land where they were going and no further step is taken, so the
robot stands still with all feet down; the status says why, and the next command resumes
it. Walking on a map, it stands still the same way while the pose estimate is older than
``POSE_STALE_S`` or the map older than ``MAP_STALE_S`` (a lost SLAM track, a dead camera),
and walks on once both are fresh again.
"""

from __future__ import annotations

import math
from collections.abc import Callable

from footfall.messages import (
    EffectorTargets,
    GaitState,
    GaitStatus,
    MapUpdate,
    Mode,
    ModeCommand,
    PoseEstimate,
    Posture,
    RobotState,
    ServoStatus,
    Touchdown,
    WalkCommand,
)
from footfall.motion.walker import WalkController
from footfall.nodes.mapping import scores_of, snapshot_of
from footfall.runtime.bus import Bus

# No command for this long while walking stops the robot [s].
COMMAND_TIMEOUT_S = 0.5
# Walking on a map, a pose estimate or a map this old stops the robot [s].
POSE_STALE_S = 0.5
MAP_STALE_S = 1.0


class MovementNode:
    """The walking controller on the bus.

    Args:
        bus: The bus.
        controller: The walking controller (with its terrain planner, if any).
        command_timeout: Watchdog limit [s]; None for no watchdog (a scripted run).
    """

    name = "movement"

    def __init__(
        self,
        bus: Bus,
        controller: WalkController,
        command_timeout: float | None = COMMAND_TIMEOUT_S,
    ) -> None:
        self.bus = bus
        self.controller = controller
        self.command_timeout = command_timeout
        self.mode = Mode.TORQUE_OFF
        self.command: WalkCommand | None = None
        self.state: RobotState | None = None
        self.stop_reason = ""
        self.halted = ""  # why the robot cannot go on (a servo fault), or ""
        self.posture = Posture.STANDING  # the servo node's, once it reports
        self._mode_stamp: float | None = None
        self._time = 0.0
        self._command_time = -math.inf
        self._fresh_command = False
        self._touchdowns_sent = 0
        self._pose_stamp: float | None = None
        self._map_stamp: float | None = None
        self.stops = 0
        self.late_messages = 0
        # Messages the transport dropped as malformed, when the composition tells.
        self.transport_dropped: Callable[[], int] | None = None
        bus.subscribe(ModeCommand.TOPIC, self._on_mode, last=True)
        bus.subscribe(WalkCommand.TOPIC, self._on_command, last=True)
        bus.subscribe(RobotState.TOPIC, self._on_state, last=True)
        bus.subscribe(ServoStatus.TOPIC, self._on_servo, last=True)
        if controller.planner is not None:
            bus.subscribe(MapUpdate.TOPIC, self._on_map, last=True)
            bus.subscribe(PoseEstimate.TOPIC, self._on_pose)
        self.publish_status()

    # Inputs ------------------------------------------------------------------------------
    def _late(self, message: WalkCommand | ModeCommand, last: float | None) -> bool:
        """An older message than one already taken (late, or out of order) is dropped."""
        if last is not None and message.stamp < last:
            self.late_messages += 1
            return True
        return False

    def _on_mode(self, message: ModeCommand) -> None:
        if self._late(message, self._mode_stamp):
            return
        self._mode_stamp = message.stamp
        if message.mode is Mode.WALKING and self.mode is not Mode.WALKING:
            # No time passed for the controller while limp; it stands up from where it lies.
            self.controller.restart_clock(self.state)
        self.mode = message.mode

    def _on_servo(self, message: ServoStatus) -> None:
        if message.posture is Posture.HALTED:
            self.halt(message.fault)
        elif message.posture is Posture.STANDING and self.posture is not Posture.STANDING:
            # No time passed for the controller while the legs rose; it walks from here.
            self.controller.restart_clock(self.state)
        self.posture = message.posture

    def _on_command(self, message: WalkCommand) -> None:
        if self._late(message, self.command.stamp if self.command is not None else None):
            return
        self.command = message
        self._fresh_command = True

    def _on_state(self, message: RobotState) -> None:
        self.state = message

    def _on_map(self, message: MapUpdate) -> None:
        planner = self.controller.planner
        assert planner is not None
        planner.update(snapshot_of(message), scores_of(message))
        self._map_stamp = message.stamp

    def _on_pose(self, message: PoseEstimate) -> None:
        self.controller.correct_pose(message.planar_body, message.aligned_in_world)
        self._pose_stamp = message.stamp
        self.publish_status()

    # The tick ----------------------------------------------------------------------------
    def _stale_sensors(self, t: float) -> str:
        """Why the pose or the map is too old to walk on at ``t`` ("" when neither is)."""
        if self.controller.planner is None:
            return ""
        for what, stamp, limit in (
            ("pose estimate", self._pose_stamp, POSE_STALE_S),
            ("map", self._map_stamp, MAP_STALE_S),
        ):
            if stamp is not None and t - stamp > limit:
                return (
                    f"the {what} is {t - stamp:.2f} s old (limit {limit:.2f} s): "
                    f"standing still until a fresh {what} comes"
                )
        return ""

    def _command_now(self, t: float) -> WalkCommand | None:
        """The command in force at ``t``: the latest, or a standstill once it is stale.

        A stale pose estimate or map stops the robot the same way.
        """
        if self._fresh_command:
            self._command_time = t
            self._fresh_command = False
        if self.command is None:
            return None
        age = t - self._command_time
        reason = self._stale_sensors(t)
        if self.command_timeout is not None and age > self.command_timeout:
            reason = (
                f"no command for {age:.2f} s (limit {self.command_timeout:.2f} s): "
                "standing still until the next command"
            )
        if reason:
            if not self.stop_reason:
                self.stops += 1
            self.stop_reason = reason
            # Stop the body now and land the feet in the air; take no further step.
            self.controller.holding = True
            return WalkCommand(speed=0.0, body_height=self.command.body_height)
        self.stop_reason = ""
        self.controller.holding = False
        return self.command

    def halt(self, reason: str) -> None:
        """Stop for good: the robot cannot go on (a servo fault); the status says why."""
        if not self.halted:
            self.halted = reason
            self.publish_status()

    def tick(self, t: float) -> None:
        """One control tick at controller time ``t`` [s]."""
        self._time = t
        command = self._command_now(t)
        walking = self.mode is Mode.WALKING and self.posture is Posture.STANDING
        if not walking or command is None or self.halted:
            self.publish_status()
            return
        c = self.controller
        feet = c.update(t, command, self.state)
        self.bus.publish(
            EffectorTargets.TOPIC,
            EffectorTargets(
                stamp=t,
                feet_in_body=feet.feet_in_body,
                foot_velocities_in_body=feet.velocities_in_body,
                swinging=c.swinging.copy(),
                feet_in_world=c.feet_commanded_in_world,
            ),
        )
        new = min(c.touchdown_count - self._touchdowns_sent, len(c.touchdowns))
        if new > 0:
            for record in list(c.touchdowns)[-new:]:
                self.bus.publish(Touchdown.TOPIC, record)
        self._touchdowns_sent = c.touchdown_count
        self.publish_status()

    def publish_status(self) -> GaitStatus:
        """Publish the gait status now; returns it."""
        c = self.controller
        frozen = c.state is GaitState.FROZEN or bool(self.halted)
        reason = self.halted or (c.frozen_reason if frozen else self.stop_reason)
        status = GaitStatus(
            stamp=self._time,
            mode=self.mode,
            state=GaitState.FROZEN if frozen else c.state,
            frozen_reason=reason,
            frozen_leg=c.frozen_leg if frozen and not self.halted else "",
            body_pose=c.pose,
            body_z=c.height,
            steps_taken=c.scheduler.steps_taken,
            footholds_adjusted=c.footholds_adjusted,
            command_age=self._time - self._command_time,
            messages_dropped=self.late_messages
            + (self.transport_dropped() if self.transport_dropped is not None else 0),
        )
        self.bus.publish(GaitStatus.TOPIC, status)
        return status
