"""The walking controller: command -> gait -> foot targets -> swing paths -> IK -> joints.

It keeps a *reference* body pose in the world (odometry) frame, integrated from the command;
supporting feet stay fixed in that frame while the body moves, swinging feet follow their
trajectories to targets chosen so that each foot passes under its rest position at
mid-stance (thesis §5.3.4, eqs. 5.17-5.20, implemented for their intent). The ground is the
plane ``z = 0`` of that frame (a blind walker); foot positions are foot-sphere centres, one
foot radius above the ground when down.

A round foot rolls as its tibia tilts during stance: holding the sphere's centre still
would make it slide by ``r * dpsi`` (``psi`` the tibia's pitch). So the controller keeps the
*contact point* still instead, moving the commanded centre by the rolling displacement
``-r * (psi - psi_touchdown)`` along the leg's horizontal direction.

The gait state machine is the thesis' (Table 5.1): ``REST`` holds every foot down; it
enters ``STEPPING`` when the command asks for motion or a foot is off its rest position,
and returns to ``REST`` once every foot is back. A target no leg can reach does not throw
the robot over: the controller enters ``FROZEN``, holds its last joint targets (all feet
down) and reports why.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import StrEnum

import numpy as np
import numpy.typing as npt

from footfall.errors import SingularConfigurationError, UnreachableTargetError
from footfall.motion.gait import (
    GaitConfig,
    GaitKind,
    WalkCommand,
    active_sextant,
    tripod_swing_set,
)
from footfall.motion.kinematics import LegKinematics
from footfall.motion.planar import PlanarPose
from footfall.motion.swing import FlowSwing, PolynomialArcSwing, SwingTrajectory
from footfall.robot.spec import HexapodSpec

# Time step of the finite difference that gives the swing foot's velocity [s].
_VELOCITY_PROBE_DT = 1e-3


class GaitState(StrEnum):
    """States of the gait state machine (thesis Table 5.1), plus a safe stop."""

    REST = "rest"
    STEPPING = "stepping"
    FROZEN = "frozen"


@dataclass(frozen=True)
class JointTargets:
    """What the controller asks of the servos at one tick.

    Attributes:
        positions: Joint angles, shape (6, 3) [rad].
        velocities: Joint rates, shape (6, 3) [rad/s].
    """

    positions: npt.NDArray[np.float64]
    velocities: npt.NDArray[np.float64]


class WalkController:
    """Turns walk commands into joint targets for a hexapod.

    Args:
        spec: The robot.
        config: Gait parameters.
        initial_pose: Body pose in the world frame at start.
        initial_height: Body height at start [m]; the spec's nominal height by default.
    """

    def __init__(
        self,
        spec: HexapodSpec,
        config: GaitConfig | None = None,
        initial_pose: PlanarPose | None = None,
        initial_height: float | None = None,
    ) -> None:
        self.spec = spec
        self.config = (config or GaitConfig()).for_robot(spec.stride_length, spec.max_step_height)
        self.kinematics = LegKinematics(spec)
        self.pose = initial_pose or PlanarPose()
        self.height = spec.body_height if initial_height is None else initial_height
        self._rest_in_body = spec.rest_feet_in_body(0.0)  # xy of rest feet; z set per use
        self._foot_z = spec.foot_radius
        self.state = GaitState.REST
        self.frozen_reason = ""
        self.feet_in_world = self._rest_feet_in_world()
        self.swinging = np.zeros(6, dtype=bool)
        self.swings: dict[int, SwingTrajectory] = {}
        self.step_start = 0.0
        self.step_duration = self.config.rest_step_duration
        self.steps_taken = 0
        self._group_index = len(self.config.groups) - 1
        self._time: float | None = None
        self._velocity = (0.0, 0.0)  # rate-limited body velocity [m/s]
        self._yaw_rate = 0.0
        self._velocity_scale = 1.0
        self._last_walk_direction = np.array([1.0, 0.0])
        self._rolling_in_world = np.zeros((6, 3))  # rolling displacement of stance feet [m]
        self._tibia_pitch_at_touchdown = np.full(6, np.nan)  # psi when the foot came down [rad]
        self._last_targets = self._solve(np.zeros((6, 3)), 0.0, 0.0)

    # Public ------------------------------------------------------------------------------
    @property
    def body_velocity_in_body(self) -> tuple[float, float]:
        """Reference body velocity after rate limits and the stroke governor [m/s]."""
        return (self._velocity[0] * self._velocity_scale, self._velocity[1] * self._velocity_scale)

    def update(self, t: float, command: WalkCommand) -> JointTargets:
        """Advance the controller to time ``t`` and return the joint targets.

        Args:
            t: Controller time [s]; must not decrease.
            command: The current command.
        """
        dt = 0.0 if self._time is None else max(t - self._time, 0.0)
        self._time = t
        if self.state is GaitState.FROZEN:
            return self._last_targets
        self._shape_command(command, dt)
        self._velocity_scale = self._stroke_governor(t)
        self._move_body(command, dt)
        self._advance_gait(t)
        swing_velocity = self._move_swing_feet(t)
        try:
            targets = self._solve(swing_velocity, *self._twist_scaled())
        except UnreachableTargetError as exc:
            self.state = GaitState.FROZEN
            self.frozen_reason = str(exc)
            return self._last_targets
        self._last_targets = targets
        return targets

    @property
    def feet_commanded_in_world(self) -> npt.NDArray[np.float64]:
        """Commanded foot-sphere centres in the world, shape (6, 3) [m].

        Includes the rolling displacement of stance feet.
        """
        return self.feet_in_world + self._rolling_in_world

    def feet_in_body(self) -> npt.NDArray[np.float64]:
        """Foot positions in the reference body frame, shape (6, 3) [m].

        Stance feet are given by their contact anchors, swing feet by their path position.
        """
        feet = self.pose.points_to_body(self.feet_in_world)
        feet[:, 2] -= self.height
        return feet

    # Command shaping ---------------------------------------------------------------------
    def _shape_command(self, command: WalkCommand, dt: float) -> None:
        vx, vy = command.velocity_in_body
        speed = math.hypot(vx, vy)
        if speed > self.config.max_speed:
            vx, vy = vx * self.config.max_speed / speed, vy * self.config.max_speed / speed
        if speed > 0:
            self._last_walk_direction = np.array([vx, vy]) / math.hypot(vx, vy)
        dv = np.array([vx - self._velocity[0], vy - self._velocity[1]])
        limit = self.config.acceleration_limit * dt
        norm = float(np.hypot(*dv))
        if norm > limit:
            dv *= limit / norm
        self._velocity = (self._velocity[0] + dv[0], self._velocity[1] + dv[1])
        yaw_limit = self.config.yaw_acceleration_limit * dt
        self._yaw_rate += float(np.clip(command.yaw_rate - self._yaw_rate, -yaw_limit, yaw_limit))

    def _twist_scaled(self) -> tuple[float, float]:
        return (self._velocity_scale, self._yaw_rate * self._velocity_scale)

    def _stroke_governor(self, t: float) -> float:
        """Largest fraction of the commanded twist the supporting feet allow.

        Every supporting foot must stay within its stroke until it lifts off; this protects
        the legs at start-up and on command changes.
        """
        if self.state is not GaitState.STEPPING:
            return 1.0
        n = len(self.config.groups)
        reach = 0.5 * self.config.stride * self.config.duty_factor + self.config.stroke_margin
        feet = self.feet_in_body()[:, :2]
        offset = feet - self._rest_in_body[:, :2]
        vx, vy = self._velocity
        # Body-frame velocity of a world-fixed point: -(v + omega x p).
        drift = np.stack(
            [-vx + self._yaw_rate * feet[:, 1], -vy - self._yaw_rate * feet[:, 0]], axis=1
        )
        remaining = max(self.step_start + self.step_duration - t, 0.0)
        scale = 1.0
        for leg in np.flatnonzero(~self.swinging):
            steps_until = self._steps_until_swing(int(leg), n)
            u = drift[leg] * (remaining + (steps_until - 1) * self.step_duration)
            a, b, c = (
                float(u @ u),
                float(offset[leg] @ u),
                float(offset[leg] @ offset[leg]) - reach**2,
            )
            if a < 1e-12:
                continue
            if c > 0:
                scale = min(scale, 1.0 if b < 0 else 0.0)
            else:
                scale = min(scale, (-b + math.sqrt(b * b - a * c)) / a)
        return max(scale, 0.0)

    def _steps_until_swing(self, leg: int, n: int) -> int:
        groups = self.config.groups
        for k in range(1, n + 1):
            if leg in groups[(self._group_index + k) % n]:
                return k
        return n

    def _move_body(self, command: WalkCommand, dt: float) -> None:
        scale = self._velocity_scale
        self.pose = self.pose.moved(
            (self._velocity[0] * scale, self._velocity[1] * scale), self._yaw_rate * scale, dt
        )
        dh = command.body_height - self.height
        limit = self.config.height_rate_limit * dt
        self.height += float(np.clip(dh, -limit, limit))

    # Gait state machine -----------------------------------------------------------------
    def _rest_feet_in_world(self, pose: PlanarPose | None = None) -> npt.NDArray[np.float64]:
        feet = (pose or self.pose).points_to_world(self._rest_in_body)
        feet[:, 2] = self._foot_z
        return feet

    def _feet_off_rest(self) -> npt.NDArray[np.bool_]:
        offset = self.feet_in_world[:, :2] - self._rest_feet_in_world()[:, :2]
        return np.hypot(offset[:, 0], offset[:, 1]) > self.config.rest_tolerance

    def _moving(self) -> bool:
        return math.hypot(*self._velocity) > 1e-6 or abs(self._yaw_rate) > 1e-6

    def _advance_gait(self, t: float) -> None:
        if self.state is GaitState.STEPPING and t >= self.step_start + self.step_duration - 1e-9:
            for leg, swing in self.swings.items():
                self.feet_in_world[leg] = swing.target
                self._tibia_pitch_at_touchdown[leg] = np.nan
            self.swings = {}
            self.swinging[:] = False
            self.steps_taken += 1
            self.state = GaitState.REST
        if self.state is GaitState.REST and (self._moving() or self._feet_off_rest().any()):
            self._start_step(t)

    def _foot_speed(self) -> float:
        vx, vy = self._velocity
        rest = self._rest_in_body[:, :2]
        speeds = np.hypot(vx - self._yaw_rate * rest[:, 1], vy + self._yaw_rate * rest[:, 0])
        return float(speeds.max())

    def _choose_group(self) -> npt.NDArray[np.bool_]:
        n = len(self.config.groups)
        off = self._feet_off_rest()
        swing = np.zeros(6, dtype=bool)
        if not self._moving():
            # Stepping back to rest: the next group in the cycle that has a foot out of place.
            for k in range(1, n + 1):
                index = (self._group_index + k) % n
                if off[list(self.config.groups[index])].any():
                    self._group_index = index
                    swing[list(self.config.groups[index])] = True
                    return swing
            return swing
        if self.config.kind is GaitKind.TRIPOD and math.hypot(*self._velocity) > 1e-6:
            swing = tripod_swing_set(
                self._last_walk_direction,
                self._rest_in_body,
                self.feet_in_body(),
                self.spec.mount_positions_in_body,
            )
            self._group_index = 0 if swing[0] else 1
            return swing
        if self.steps_taken == 0 and math.hypot(*self._velocity) > 1e-6:
            # First step of a ripple or wave walk: start with the group of the leg facing the
            # walk direction (the sextant rule of §5.3.3), then follow the cycle.
            xi = active_sextant(self._last_walk_direction, self._rest_in_body)
            self._group_index = next(i for i, g in enumerate(self.config.groups) if xi in g)
        else:
            self._group_index = (self._group_index + 1) % n
        swing[list(self.config.groups[self._group_index])] = True
        return swing

    def _start_step(self, t: float) -> None:
        swing = self._choose_group()
        if not swing.any():
            return
        n = len(self.config.groups)
        self.step_duration = (
            self.config.step_duration(self._foot_speed())
            if self._moving()
            else self.config.rest_step_duration
        )
        self.step_start = t
        self.swinging = swing
        self.state = GaitState.STEPPING
        targets = self._swing_targets(n)
        self.swings = {}
        for leg in np.flatnonzero(swing):
            start = self.feet_commanded_in_world[leg].copy()
            self.feet_in_world[leg] = start
            self._rolling_in_world[leg] = 0.0
            if self.config.swing == "flow":
                self.swings[int(leg)] = FlowSwing(
                    start, targets[leg], self.step_duration, self.config.flow
                )
            else:
                self.swings[int(leg)] = PolynomialArcSwing(
                    start, targets[leg], self.step_duration, self.config.polynomial_apex
                )

    def _swing_targets(self, n: int) -> npt.NDArray[np.float64]:
        """Touchdown targets in the world, shape (6, 3) [m].

        Each leg's rest position at the body pose predicted for the middle of its coming
        stance, so that the stance stroke is centred on rest.
        """
        remaining = max(self.step_start + self.step_duration - (self._time or 0.0), 0.0)
        horizon = remaining + 0.5 * (n - 1) * self.step_duration
        # Predict with the reference twist actually applied (after the stroke governor), so
        # targets follow the body; they are re-planned as the twist changes.
        vx, vy = self.body_velocity_in_body
        predicted = self.pose.moved((vx, vy), self._yaw_rate * self._velocity_scale, horizon)
        return self._rest_feet_in_world(predicted)

    def _move_swing_feet(self, t: float) -> npt.NDArray[np.float64]:
        """Move swinging feet along their paths; returns their world velocities, shape (6, 3)."""
        velocity = np.zeros((6, 3))
        if not self.swings:
            return velocity
        targets = self._swing_targets(len(self.config.groups))
        local_t = t - self.step_start
        for leg, swing in self.swings.items():
            if np.linalg.norm(targets[leg] - swing.target) > self.config.retarget_tolerance:
                swing.retarget(targets[leg], local_t)
            self.feet_in_world[leg] = swing.position(local_t)
            ahead = swing.position(local_t + _VELOCITY_PROBE_DT)
            velocity[leg] = (ahead - self.feet_in_world[leg]) / _VELOCITY_PROBE_DT
        return velocity

    # Kinematics ---------------------------------------------------------------------------
    def _solve(
        self, swing_velocity_in_world: npt.NDArray[np.float64], scale: float, yaw_rate: float
    ) -> JointTargets:
        anchors = self.feet_in_body()
        feet = anchors
        angles = self.kinematics.inverse_in_body(feet)
        stance = ~self.swinging
        pitch = angles[:, 1] + angles[:, 2]
        new = stance & np.isnan(self._tibia_pitch_at_touchdown)
        self._tibia_pitch_at_touchdown[new] = pitch[new]
        rolling_in_body = np.zeros((6, 3))
        for _ in range(2):  # fixed point: the rolling moves the foot, which changes psi
            roll = -self.spec.foot_radius * (pitch - self._tibia_pitch_at_touchdown)
            radial = np.stack([np.cos(angles[:, 0]), np.sin(angles[:, 0]), np.zeros(6)], axis=1)
            rolling_in_leg = np.where(stance[:, None], roll[:, None] * radial, 0.0)
            rolling_in_body = (
                self.kinematics.leg_to_body(rolling_in_leg) - self.kinematics.mounts_in_body
            )
            feet = anchors + rolling_in_body
            angles = self.kinematics.inverse_in_body(feet)
            pitch = angles[:, 1] + angles[:, 2]
        self._rolling_in_world = self.pose.vectors_to_world(rolling_in_body)
        vx, vy = self._velocity[0] * scale, self._velocity[1] * scale
        # Velocity of each foot in the body frame: its own world velocity, minus the body's
        # motion (translation and rotation about z).
        velocity = self.pose.vectors_to_body(swing_velocity_in_world)
        velocity[:, 0] += -vx + yaw_rate * feet[:, 1]
        velocity[:, 1] += -vy - yaw_rate * feet[:, 0]
        try:
            rates = self.kinematics.joint_rates(
                angles, self.kinematics.vectors_body_to_leg(velocity)
            )
        except SingularConfigurationError:
            rates = np.zeros((6, 3))
        return JointTargets(positions=angles, velocities=rates)
