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
from dataclasses import dataclass, field
from enum import StrEnum
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt
from scipy.spatial.transform import Rotation

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
from footfall.planning.terrain_planner import StepPoses
from footfall.robot.spec import HexapodSpec

if TYPE_CHECKING:
    from footfall.backend import RobotState
    from footfall.planning.terrain_planner import TerrainPlanner

# A robot frozen for want of a foothold retries after this many new map frames.
_MAP_FRAMES_BEFORE_RETRY = 5
# Fractions of the commanded speed a step is planned at, fastest first: where footholds
# are scarce the body slows down so the legs can find them.
_STEP_SPEED_SCALES = (1.0, 0.5, 0.25)
# Fraction of a swing after which re-plans keep the target where they can.
_LATE_SWING = 0.5
# Farthest the planned body height looks from the present one [m], and its spacing [m].
_BODY_Z_WINDOW = 0.08
_BODY_Z_STEP = 0.005
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


@dataclass(frozen=True)
class FeedbackConfig:
    """Body attitude and height feedback (the draft's tilt stabilisation, thesis §8.1's fix).

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


@dataclass(frozen=True)
class TouchdownRecord:
    """Where a foot was meant to land and where the planner put it.

    Attributes:
        time: Touchdown time [s].
        leg: Leg index.
        nominal: Nominal foothold (foot centre) in the world, shape (3,) [m].
        chosen: Planned foothold (foot centre) in the world, shape (3,) [m].
    """

    time: float
    leg: int
    nominal: npt.NDArray[np.float64]
    chosen: npt.NDArray[np.float64]


@dataclass
class _StepPlan:
    nominal: npt.NDArray[np.float64] = field(default_factory=lambda: np.zeros((6, 3)))
    targets: npt.NDArray[np.float64] = field(default_factory=lambda: np.zeros((6, 3)))
    version: int = -1
    pending_freeze: str = ""
    body_z: npt.NDArray[np.float64] = field(default_factory=lambda: np.zeros(0))


def _materially_different(a: WalkCommand, b: WalkCommand) -> bool:
    """Whether a new command asks for something else, not just a steering wobble."""
    va, vb = np.array(a.velocity_in_body), np.array(b.velocity_in_body)
    return bool(
        np.hypot(*(va - vb)) > 0.02
        or abs(a.yaw_rate - b.yaw_rate) > 0.1
        or abs(a.body_height - b.body_height) > 0.005
    )


class WalkController:
    """Turns walk commands into joint targets for a hexapod.

    Without a planner the controller walks blind on the plane z = 0 (the thesis'
    baseline). With a :class:`~footfall.planning.terrain_planner.TerrainPlanner` it moves
    every foothold to the nearest acceptable cell of the map, plans the body height with the
    footholds (the commanded height above the floor estimate where every leg reaches its
    foot, else the nearest height where they do), slows a step down where footholds are
    scarce, lifts swing paths over the mapped terrain, and freezes with all feet down when a
    swinging leg has no acceptable foothold; it resumes when the command or the map changes.

    Args:
        spec: The robot.
        config: Gait parameters.
        initial_pose: Body pose in the world frame at start.
        initial_height: Body height at start [m]; the spec's nominal height by default.
        planner: Terrain planner, or None for blind walking.
        feedback: Attitude and height feedback from the measured state, or None for none.
    """

    def __init__(
        self,
        spec: HexapodSpec,
        config: GaitConfig | None = None,
        initial_pose: PlanarPose | None = None,
        initial_height: float | None = None,
        planner: TerrainPlanner | None = None,
        feedback: FeedbackConfig | None = None,
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
        self.planner = planner
        self.feedback = feedback
        self.floor = 0.0  # ground height the body keeps its commanded height above [m]
        self.tilt_correction = np.zeros(2)  # commanded roll, pitch offset [rad]
        self.height_correction = 0.0  # [m]
        self.footholds_adjusted = 0
        self.touchdowns: list[TouchdownRecord] = []
        self._plan = _StepPlan()
        self._frozen_command: WalkCommand | None = None
        self._body_height_command = self.height
        self._start_of_walk = True
        self._step_start_pose = self.pose
        self._stalled_steps = 0
        self._step_speed_scale = 1.0  # the fraction of the command this step plans for
        self._last_command: WalkCommand | None = None
        self._frozen_version = -1
        self._last_targets = self._solve(np.zeros((6, 3)), 0.0, 0.0)

    # Public ------------------------------------------------------------------------------
    @property
    def body_velocity_in_body(self) -> tuple[float, float]:
        """Reference body velocity after rate limits and the stroke governor [m/s]."""
        return (self._velocity[0] * self._velocity_scale, self._velocity[1] * self._velocity_scale)

    def update(
        self, t: float, command: WalkCommand, state: RobotState | None = None
    ) -> JointTargets:
        """Advance the controller to time ``t`` and return the joint targets.

        Args:
            t: Controller time [s]; must not decrease.
            command: The current command.
            state: The latest measured state, for attitude and height feedback.
        """
        dt = 0.0 if self._time is None else max(t - self._time, 0.0)
        self._time = t
        if self.state is GaitState.FROZEN:
            if not self._may_resume(command):
                return self._last_targets
            self.state = GaitState.REST
            self.frozen_reason = ""
            self._velocity, self._yaw_rate = (0.0, 0.0), 0.0  # start again from standstill
        if state is not None and self.feedback is not None:
            self._feedback(state, dt)
        self._shape_command(command, dt)
        self._velocity_scale = self._stroke_governor(t)
        self._move_body(command, dt)
        self._advance_gait(t)
        swing_velocity = self._move_swing_feet(t)
        try:
            targets = self._solve(swing_velocity, *self._twist_scaled())
        except UnreachableTargetError as exc:
            self._freeze(str(exc), command, map_may_help=False)
            return self._last_targets
        self._last_targets = targets
        if self.state is GaitState.FROZEN:
            self._frozen_command = command
        return targets

    def correct_pose(self, estimate: PlanarPose) -> None:
        """Re-register the controller's world on a body pose estimate in the map frame.

        The reference pose, the supporting feet and the swing paths move together by the
        planar transform that takes the reference pose onto the estimate, so the legs hold
        still while footholds planned on the map land where the map says.
        """
        c, s = math.cos(estimate.yaw - self.pose.yaw), math.sin(estimate.yaw - self.pose.yaw)
        rotation = np.array([[c, -s], [s, c]])
        translation = np.array([estimate.x, estimate.y]) - rotation @ np.array(
            [self.pose.x, self.pose.y]
        )

        def move(points: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
            out = points.copy()
            out[..., :2] = points[..., :2] @ rotation.T + translation
            return out

        self.feet_in_world = move(self.feet_in_world)
        self._rolling_in_world[:, :2] = self._rolling_in_world[:, :2] @ rotation.T
        self._plan.nominal = move(self._plan.nominal)
        self._plan.targets = move(self._plan.targets)
        for swing in self.swings.values():
            swing.transform(rotation, translation)
        self.pose = estimate

    def _freeze(
        self, reason: str, command: WalkCommand | None = None, map_may_help: bool = True
    ) -> None:
        self.state = GaitState.FROZEN
        self.frozen_reason = reason
        self._frozen_command = command
        self._frozen_version = (
            self.planner.version if self.planner is not None and map_may_help else -1
        )

    def _may_resume(self, command: WalkCommand) -> bool:
        """Whether a frozen robot should try again.

        It does when the command changes, or, when it froze for want of a foothold, when
        the map has changed.
        """
        if self._frozen_command is not None and _materially_different(
            command, self._frozen_command
        ):
            return True
        # Retry on a fresh map, a few frames on (a third of a second at 15 Hz).
        return (
            self._frozen_version >= 0
            and self.planner is not None
            and self.planner.version >= self._frozen_version + _MAP_FRAMES_BEFORE_RETRY
        )

    def _feedback(self, state: RobotState, dt: float) -> None:
        """Integrate IMU roll and pitch, and the measured body height, into corrections.

        The height is that of the body above its stance feet, from the joint encoders and
        the IMU attitude.
        """
        fb = self.feedback
        assert fb is not None
        roll, pitch = state.roll_pitch
        limit = fb.tilt_limit
        self.tilt_correction = np.clip(
            self.tilt_correction - fb.tilt_gain * np.array([roll, pitch]) * dt, -limit, limit
        )
        stance = ~self.swinging
        if stance.sum() < 3:
            return
        feet_in_body = self.kinematics.forward_in_body(state.joint_positions)[stance]
        level = state.orientation_body_in_world.apply(feet_in_body)
        measured = -float(level[:, 2].mean())
        reference = self.height - float(self.feet_in_world[stance, 2].mean())
        self.height_correction = float(
            np.clip(
                self.height_correction + fb.height_gain * (reference - measured) * dt,
                -fb.height_limit,
                fb.height_limit,
            )
        )

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
        self._last_command = command
        self._body_height_command = command.body_height
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

        Every supporting foot must stay within reach until it lifts off: blind, within its
        nominal stroke (plus a margin), which protects the legs at start-up and on command
        changes; with a planner, whose footholds may sit off their nominal places, within
        the leg's workspace (checked by inverse kinematics at the predicted lift-off).
        """
        if self.state is not GaitState.STEPPING or self._plan.pending_freeze:
            # The body only travels while the legs step, and stops at once when a swinging
            # foot has to go back to where it lifted off.
            return 0.0
        n = len(self.config.groups)
        feet = self.feet_in_body()
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
            if float(u @ u) < 1e-12:
                continue
            if self.planner is None:
                scale = min(
                    scale, self._stroke_scale(feet[leg, :2] - self._rest_in_body[leg, :2], u)
                )
            else:
                scale = min(scale, self._reach_scale(int(leg), feet[leg], u))
        return max(min(scale, self._step_speed_scale), 0.0)

    def _stroke_scale(self, offset: npt.NDArray[np.float64], u: npt.NDArray[np.float64]) -> float:
        """Largest k in [0, 1] with |offset + k u| within the nominal stroke (plus margin)."""
        reach = 0.5 * self.config.stride * self.config.duty_factor + self.config.stroke_margin
        a, b, c = float(u @ u), float(offset @ u), float(offset @ offset) - reach**2
        if c > 0:
            return 1.0 if b < 0 else 0.0
        return min(1.0, (-b + math.sqrt(b * b - a * c)) / a)

    def _reach_scale(
        self, leg: int, foot: npt.NDArray[np.float64], u: npt.NDArray[np.float64]
    ) -> float:
        """Largest k in [0, 1] keeping the foot reachable after drifting by k u (bisection)."""
        # Half the planner's margin: the rest absorbs pose and feedback corrections.
        margin = 0.5 * self.planner.config.reach_margin if self.planner is not None else 0.0

        def ok(k: float) -> bool:
            p = foot.copy()
            p[:2] += k * u
            return self.kinematics.reachable(leg, p, margin)

        if ok(1.0):
            return 1.0
        if not ok(0.0):
            # Already at the edge: allow motion that brings the foot back in.
            return 1.0 if ok(0.05) else 0.0
        low, high = 0.0, 1.0
        for _ in range(6):
            mid = 0.5 * (low + high)
            low, high = (mid, high) if ok(mid) else (low, mid)
        return low

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
        dh = self.floor + command.body_height - self.height
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
                record = TouchdownRecord(t, leg, self._plan.nominal[leg].copy(), swing.target)
                self.touchdowns.append(record)
                self.footholds_adjusted += bool(
                    np.hypot(*(record.chosen - record.nominal)[:2]) > 1e-3
                )
            self.swings = {}
            self.swinging[:] = False
            self.steps_taken += 1
            self.state = GaitState.REST
            if self._stalled():
                return
            if self._plan.pending_freeze:
                self._freeze(self._plan.pending_freeze)
                self._plan.pending_freeze = ""
                return
        if self.state is GaitState.REST:
            if self._moving() or self._feet_off_rest().any():
                self._start_step(t)
            else:
                self._start_of_walk = True  # at rest on the rest stance: the next walk starts anew

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
        walking = math.hypot(*self._velocity) > 1e-6
        if self._start_of_walk and self.config.kind is GaitKind.TRIPOD and walking:
            # Eqs. 5.15-5.16 pick the first tripod from the walk direction; after that the
            # tripods alternate, so a set held back (a refused step) is never starved.
            swing = tripod_swing_set(
                self._last_walk_direction,
                self._rest_in_body,
                self.feet_in_body(),
                self.spec.mount_positions_in_body,
            )
            self._group_index = 0 if swing[0] else 1
            self._start_of_walk = False
            return swing
        if self._start_of_walk and walking:
            # First step of a ripple or wave walk: start with the group of the leg facing the
            # walk direction (the sextant rule of §5.3.3), then follow the cycle.
            xi = active_sextant(self._last_walk_direction, self._rest_in_body)
            self._group_index = next(i for i, g in enumerate(self.config.groups) if xi in g)
            self._start_of_walk = False
        else:
            self._group_index = (self._group_index + 1) % n
        swing[list(self.config.groups[self._group_index])] = True
        return swing

    def _start_step(self, t: float) -> None:
        group_before, start_before = self._group_index, self._start_of_walk
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
        self._step_start_pose = self.pose
        for speed_scale in _STEP_SPEED_SCALES if self.planner is not None else (1.0,):
            self._step_speed_scale = speed_scale
            nominal = self._nominal_targets(n)
            targets = self._plan_footholds(nominal, swing)
            if not isinstance(targets, str):
                break
        if isinstance(targets, str):
            # No step started: every foot is still down. The same group tries again later.
            self._group_index, self._start_of_walk = group_before, start_before
            self._freeze(targets)
            return
        self.swinging = swing
        self.state = GaitState.STEPPING
        self.swings = {}
        terrain = self.planner.terrain_under if self.planner is not None else None
        clearance = (
            self.planner.config.swing_clearance + self.spec.foot_radius
            if self.planner is not None
            else 0.0
        )
        for leg in np.flatnonzero(swing):
            start = self.feet_commanded_in_world[leg].copy()
            self.feet_in_world[leg] = start
            self._rolling_in_world[leg] = 0.0
            if self.config.swing == "flow":
                self.swings[int(leg)] = FlowSwing(
                    start, targets[leg], self.step_duration, self.config.flow, terrain, clearance
                )
            else:
                self.swings[int(leg)] = PolynomialArcSwing(
                    start, targets[leg], self.step_duration, self.config.polynomial_apex
                )
        self._update_floor(targets)

    def _stalled(self) -> bool:
        """Freeze when, asked to move, the body has not advanced for two gait cycles.

        The planner then finds footholds only where the feet already are: the way ahead
        has none the legs can reach. The leg pulled back furthest from its nominal
        foothold is named. Only a new command resumes the walk.
        """
        moved = math.hypot(
            self.pose.x - self._step_start_pose.x, self.pose.y - self._step_start_pose.y
        )
        walking = math.hypot(*self._velocity) > 1e-3
        self._stalled_steps = self._stalled_steps + 1 if walking and moved < 0.005 else 0
        if self.planner is None or self._stalled_steps < 2 * len(self.config.groups):
            return False
        pulled = np.linalg.norm(self._plan.targets[:, :2] - self._plan.nominal[:, :2], axis=1)
        leg = self.spec.leg_names[int(np.argmax(pulled))]
        self._stalled_steps = 0
        self._freeze(
            f"leg {leg}: blocked, no valid foothold it can reach ahead "
            f"(its nominal foothold is {pulled.max():.2f} m from the nearest acceptable cell; "
            f"the body has not advanced for two gait cycles)",
            self._last_command,
            map_may_help=False,
        )
        return True

    def _support_after(self, swing: npt.NDArray[np.bool_]) -> npt.NDArray[np.bool_]:
        """Legs that support during the step after this one (all but the next group)."""
        if self.config.kind is GaitKind.TRIPOD:
            return swing.copy()
        n = len(self.config.groups)
        support = np.ones(6, dtype=bool)
        support[list(self.config.groups[(self._group_index + 1) % n])] = False
        return support

    def _plan_footholds(
        self,
        nominal: npt.NDArray[np.float64],
        swing: npt.NDArray[np.bool_],
        search_from: npt.NDArray[np.float64] | None = None,
    ) -> npt.NDArray[np.float64] | str:
        """Targets for the swinging legs: nominal when blind, else the planner's choice.

        The planner searches from ``search_from`` when given (the present targets, late in
        a swing), else from the nominal targets.
        """
        self._plan.nominal = nominal.copy()
        if self.planner is None:
            self._plan.targets = nominal.copy()
            return nominal
        n = len(self.config.groups)
        remaining = max(self.step_start + self.step_duration - (self._time or 0.0), 0.0)
        # Check footholds against the commanded motion at this step's speed scale (not the
        # governed one, which may be zero while the body waits): the body will travel that
        # far if the legs allow.
        k = self._step_speed_scale
        vx, vy, yaw_rate = self._velocity[0] * k, self._velocity[1] * k, self._yaw_rate * k

        def pose_after(seconds: float) -> PlanarPose:
            return self.pose.moved((vx, vy), yaw_rate, seconds)

        poses = StepPoses(
            now=self.pose,
            touchdown=pose_after(remaining),
            liftoff=pose_after(remaining + (n - 1) * self.step_duration),
            stable=(pose_after(remaining), pose_after(remaining + self.step_duration)),
        )
        # Body heights within reach by touchdown at the height rate limit; the legs see
        # them raised by the height feedback's correction.
        window = float(
            np.clip(self.config.height_rate_limit * remaining, 2 * _BODY_Z_STEP, _BODY_Z_WINDOW)
        )
        body_z = self.height + np.append(np.arange(-window, window - 1e-9, _BODY_Z_STEP), window)
        plan = self.planner.plan(
            nominal if search_from is None else search_from,
            swing,
            self._support_after(swing),
            self.feet_commanded_in_world,
            poses,
            body_z + self.height_correction,
        )
        self._plan.version = self.planner.version
        if isinstance(plan, str):
            return plan
        self._plan.targets = plan.targets.copy()
        self._plan.body_z = plan.body_z - self.height_correction
        return plan.targets

    def _update_floor(self, targets: npt.NDArray[np.float64]) -> None:
        """Thesis §6.4: the floor under the body follows the footholds (blind: z = 0).

        The body height the floor asks for is kept where every leg reaches its foot: of the
        heights the plan allows, the nearest.
        """
        if self.planner is None:
            return
        feet = np.where(self.swinging[:, None], targets, self.feet_in_world)
        wanted = self._body_height_command + self.planner.floor_height(
            feet[:, 2] - self.spec.foot_radius, self.pose, self._body_height_command
        )
        allowed = self._plan.body_z
        body_z = float(allowed[np.argmin(np.abs(allowed - wanted))]) if allowed.size else wanted
        self.floor = body_z - self._body_height_command

    def _nominal_targets(self, n: int) -> npt.NDArray[np.float64]:
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
        targets = self._current_targets(t)
        local_t = t - self.step_start
        for leg, swing in self.swings.items():
            if np.linalg.norm(targets[leg] - swing.target) > self.config.retarget_tolerance:
                swing.retarget(targets[leg], local_t)
            self.feet_in_world[leg] = swing.position(local_t)
            ahead = swing.position(local_t + _VELOCITY_PROBE_DT)
            velocity[leg] = (ahead - self.feet_in_world[leg]) / _VELOCITY_PROBE_DT
        return velocity

    def _current_targets(self, t: float) -> npt.NDArray[np.float64]:
        """Swing targets now: re-planned when the nominal ones moved or the map changed.

        Late in a swing only a new map re-plans, and the search starts from the present
        target rather than the nominal one: a target still acceptable stays, one that is not
        moves to the nearest acceptable cell, so a foot about to land never lurches across a
        step. When a re-plan finds no acceptable foothold, the foot goes back to where it
        lifted off (a known, safe cell) and the robot freezes at the end of the step.
        """
        nominal = self._nominal_targets(len(self.config.groups))
        if self.planner is None:
            self._plan.nominal = nominal
            self._plan.targets = nominal
            return nominal
        moved = np.linalg.norm(
            nominal[self.swinging, :2] - self._plan.nominal[self.swinging, :2], axis=1
        )
        stale = self.planner.version != self._plan.version
        late = t - self.step_start > _LATE_SWING * self.step_duration
        if self._plan.pending_freeze or not (
            stale or (not late and moved.size and moved.max() > 0.02)
        ):
            return self._plan.targets
        replanned = self._plan_footholds(
            nominal, self.swinging, self._plan.targets.copy() if late else None
        )
        if isinstance(replanned, str):
            self._plan.pending_freeze = replanned
            for leg, swing in self.swings.items():
                self._plan.targets[leg] = swing.start
        else:
            self._update_floor(replanned)
        return self._plan.targets

    # Kinematics ---------------------------------------------------------------------------
    def _within_reach(self, feet_in_body: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
        """Bring a swinging foot that left its leg's workspace back in.

        A swing lifted over the terrain can ask for more than a leg reaches near the body;
        the foot then flies as high as the leg allows. A swing whose path sweeps past the
        coxa's range (the body lagging behind the plan) is turned back to the range's edge.
        Supporting feet are never moved: if one is out of reach, inverse kinematics raises
        and the robot freezes.
        """
        out = feet_in_body.copy()
        for leg in np.flatnonzero(self.swinging):
            if self.kinematics.reachable(leg, out[leg]):
                continue
            for candidate in (out[leg], self._within_coxa_range(int(leg), out[leg])):
                drops = np.arange(0.0, 0.1001, 0.005)
                lowered = candidate - np.outer(drops, [0.0, 0.0, 1.0])
                ok = self.kinematics.reachable(int(leg), lowered)
                if ok.any():
                    out[leg] = lowered[int(np.argmax(ok))]
                    break
        return out

    def _within_coxa_range(
        self, leg: int, foot_in_body: npt.NDArray[np.float64]
    ) -> npt.NDArray[np.float64]:
        """The foot turned about the coxa axis to within the coxa's joint range [m]."""
        points = np.zeros((6, 3))
        points[leg] = foot_in_body
        in_leg = self.kinematics.body_to_leg(points)[leg]
        margin = 1e-3
        yaw = np.clip(
            math.atan2(in_leg[1], in_leg[0]),
            self.kinematics.lower[0] + margin,
            self.kinematics.upper[0] - margin,
        )
        radius = math.hypot(in_leg[0], in_leg[1])
        points[leg] = [radius * math.cos(yaw), radius * math.sin(yaw), in_leg[2]]
        return self.kinematics.leg_to_body(points)[leg]

    def _solve(
        self, swing_velocity_in_world: npt.NDArray[np.float64], scale: float, yaw_rate: float
    ) -> JointTargets:
        anchors = self.feet_in_body()
        # Feedback: raise the body by the height correction, and command it tilted by the
        # attitude correction (feet in a body frame rotated by R(roll, pitch)).
        anchors[:, 2] -= self.height_correction
        if np.any(self.tilt_correction):
            anchors = anchors @ Rotation.from_euler("xy", self.tilt_correction).as_matrix()
        anchors = self._within_reach(anchors)
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
