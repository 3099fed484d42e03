"""The walking controller: command -> gait -> foot targets -> swing paths -> leg targets.

It keeps a *reference* body pose in the world (odometry) frame, integrated from the command;
supporting feet stay fixed in that frame while the body moves, swinging feet follow their
trajectories to targets chosen so that each foot passes under its rest position at
mid-stance (thesis §5.3.4, eqs. 5.17-5.20, implemented for their intent). Foot positions
are foot-sphere centres, one foot radius above the ground when down.

The controller is a thin composition of its parts, each in its own module of
``footfall.motion``: command shaping, the stroke governor, the gait scheduler, a foothold
policy (blind or mapped), body feedback, the leg solver and the safety monitor. Its state
machine is the thesis' (Table 5.1): ``REST`` holds every foot down, ``STEPPING`` walks,
back to ``REST`` once every foot is home; ``FROZEN`` (a target out of reach, no acceptable
foothold) holds the last targets, all feet down, and says why. It is one module: every tick
reads and writes the step under way, the body's reference pose and the state machine
together (a step lengthened for a foot re-targeted as it lands); the policies themselves
live in the parts.
"""

from __future__ import annotations

import math
from collections import deque

import numpy as np
import numpy.typing as npt

from footfall.errors import UnreachableTargetError
from footfall.messages import GaitState, RobotState, Touchdown, WalkCommand
from footfall.motion.command_shaping import CommandShaper
from footfall.motion.feedback import BodyFeedback, FeedbackConfig
from footfall.motion.foothold_policy import (
    BlindFootholds,
    FootholdPolicy,
    MappedFootholds,
    StepContext,
)
from footfall.motion.gait import GaitConfig
from footfall.motion.gait_scheduler import GaitScheduler
from footfall.motion.incline import ground_slope, level_slope_limit, wanted_pitch
from footfall.motion.leg_solver import FootTargets, LegSolver
from footfall.motion.registration import RegistrationDrift
from footfall.motion.safety import SafetyMonitor
from footfall.motion.stroke_governor import StrokeGovernor
from footfall.motion.swing import SwingTrajectory
from footfall.motion.swing_feet import SwingFeet
from footfall.planning.step_plan import NoFoothold
from footfall.planning.terrain_planner import TerrainPlanner
from footfall.robot.kinematics import LegKinematics
from footfall.robot.planar import PlanarPose, level_to_inclined
from footfall.robot.spec import HexapodSpec

# A body this far off its reference height on resuming is re-anchored on the encoders [m].
REANCHOR_HEIGHT = 0.01


class WalkController:
    """Turns walk commands into foot targets: blind, or on a terrain planner's footholds.

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
        self.config = (config or GaitConfig()).for_robot(spec)
        self.kinematics = LegKinematics(spec)
        self.planner = planner
        self.feedback = feedback
        self.pose = initial_pose or PlanarPose()
        self.height = spec.body_height if initial_height is None else initial_height
        self._rest_in_body = spec.rest_feet_in_body(0.0)  # xy of rest feet; z set per use
        self.footholds: FootholdPolicy = (
            BlindFootholds() if planner is None else MappedFootholds(planner, spec.foot_radius)
        )
        self.registration = (
            RegistrationDrift(planner.config.registration_horizon_s) if planner else None
        )
        self.shaper = CommandShaper(self.config, self.height)
        self.scheduler = GaitScheduler(
            self.config, self._rest_in_body, spec.mount_positions_in_body, spec.foot_radius
        )
        self.governor = StrokeGovernor(
            self.config, self.kinematics, self._rest_in_body, self.footholds.reach_margin
        )
        self.body_feedback = BodyFeedback(feedback, self.kinematics)
        self.solver = LegSolver(self.kinematics, spec.foot_radius)
        self.safety = SafetyMonitor()
        self.state = GaitState.REST
        self.feet_in_world = self.scheduler.rest_feet_in_world(self.pose)
        self.swing_feet = SwingFeet()
        self.floor = 0.0  # ground height the body keeps its commanded height above [m]
        self.footholds_adjusted = 0
        # The body's pitch (positive nose down) [rad], where it is heading, and where this
        # step takes it by touchdown (motion.incline).
        self.incline = 0.0
        self.incline_target = 0.0
        self._step_incline = 0.0
        margin = planner.config.reach_margin if planner is not None else 0.0
        self._level_slope = level_slope_limit(
            self.kinematics, spec, self.config.incline_level_share, margin
        )
        self.touchdowns: deque[Touchdown] = deque()  # a long run bounds it (maxlen)
        self.touchdown_count = 0
        self.holding = False  # hold still: finish the step under way, take no new one
        self._time: float | None = None
        self._velocity_scale = 1.0
        self._step_speed_scale = 1.0  # the fraction of the command this step plans for
        self._step_start_pose = self.pose
        self._last_targets = self._solve(np.zeros((6, 3)))

    # Public ------------------------------------------------------------------------------
    @property
    def swinging(self) -> npt.NDArray[np.bool_]:
        """Which legs swing, shape (6,)."""
        return self.swing_feet.swinging

    @property
    def swings(self) -> dict[int, SwingTrajectory]:
        """The swinging legs' paths, by leg index."""
        return self.swing_feet.swings

    @property
    def frozen_reason(self) -> str:
        """Why the robot froze ("" when it has not)."""
        return self.safety.reason

    @property
    def frozen_leg(self) -> str:
        """The leg the freeze concerns ("" when none)."""
        return self.safety.leg

    @property
    def body_velocity_in_body(self) -> tuple[float, float]:
        """Reference body velocity after rate limits and the stroke governor [m/s]."""
        v, k = self.shaper.velocity, self._velocity_scale
        return (v[0] * k, v[1] * k)

    @property
    def feet_commanded_in_world(self) -> npt.NDArray[np.float64]:
        """Commanded foot-sphere centres in the world, shape (6, 3) [m].

        Includes the rolling displacement of stance feet.
        """
        return self.feet_in_world + self.solver.rolling_in_world

    def feet_in_body(self) -> npt.NDArray[np.float64]:
        """Foot positions in the reference body frame, shape (6, 3) [m].

        Stance feet are given by their contact anchors, swing feet by their path position.
        The reference body frame is inclined by :attr:`incline`.
        """
        return self._to_body(self.feet_in_world)

    def _to_body(
        self, points_in_world: npt.NDArray[np.float64], incline: float | None = None
    ) -> npt.NDArray[np.float64]:
        """World points in the reference body frame (inclined by ``incline``, else now's)."""
        points = self.pose.points_to_body(points_in_world)
        points[..., 2] -= self.height
        return level_to_inclined(points, self.incline if incline is None else incline)

    def update(
        self, t: float, command: WalkCommand, state: RobotState | None = None
    ) -> FootTargets:
        """Advance the controller to time ``t`` and return the foot targets.

        Args:
            t: Controller time [s]; must not decrease.
            command: The current command.
            state: The latest measured state, for attitude and height feedback.
        """
        dt = 0.0 if self._time is None else max(t - self._time, 0.0)
        self._time = t
        if self.state is GaitState.FROZEN:
            if not self.safety.may_resume(command, self.footholds.map_version):
                return self._last_targets
            self.state = GaitState.REST
            self.safety.resume()
            self.shaper.stop()  # start again from standstill
        if state is not None:
            self.body_feedback.update(
                state, dt, self.swinging, self.feet_in_world, self.height, self.incline
            )
        self.shaper.shape(command, dt)
        self._velocity_scale = self._govern(t)
        self._move_body(command, dt)
        self._incline_body(dt)
        self._advance_gait(t)
        swing_velocity = self._move_swing_feet(t)
        try:
            targets = self._solve(swing_velocity)
        except UnreachableTargetError as exc:
            self._freeze(str(exc), command, map_may_help=False, leg=exc.leg)
            return self._last_targets
        self._last_targets = targets
        if self.state is GaitState.FROZEN:
            self.safety.frozen_command = command
        return targets

    def restart_clock(self, state: RobotState | None = None) -> None:
        """Start again after a pause (torque-off): the next update advances by nothing.

        A measured body more than ``REANCHOR_HEIGHT`` off the reference (a limp robot sinks)
        re-anchors the feet on the encoders; the body then rises at the height rate limit
        and the feet step back to rest: the robot stands up.
        """
        self._time = None
        if state is None:
            return
        feet = state.orientation_body_in_world.apply(
            self.kinematics.forward_in_body(state.joint_positions)
        )
        height = self.spec.foot_radius - float(feet[:, 2].mean())
        if abs(height - self.height) <= REANCHOR_HEIGHT:
            return
        self.height = height
        self.feet_in_world = self.pose.points_to_world(feet)
        self.feet_in_world[:, 2] += height
        self.swing_feet.clear()
        self.state = GaitState.REST
        self.safety.resume()
        self.shaper.stop()

    def correct_pose(
        self, estimate: PlanarPose, aligned_in_world: tuple[float, float] = (0.0, 0.0)
    ) -> None:
        """Re-register the controller's world on a body pose estimate in the map frame.

        The reference pose, the supporting feet and the swing paths move together by the
        planar transform that takes the reference pose onto the estimate, so the legs hold
        still while footholds planned on the map land where the map says. The part of the
        correction that the pose source made to align the body with the map
        (``aligned_in_world`` [m]) brings the feet's world onto the map rather than away
        from it, and is not counted in how far the map may have slid.
        """
        c, s = math.cos(estimate.yaw - self.pose.yaw), math.sin(estimate.yaw - self.pose.yaw)
        rotation = np.array([[c, -s], [s, c]])
        translation = np.array([estimate.x, estimate.y]) - rotation @ np.array(
            [self.pose.x, self.pose.y]
        )
        if self.registration is not None and self.planner is not None:
            self.registration.add(
                self._time or 0.0,
                estimate.x - self.pose.x - aligned_in_world[0],
                estimate.y - self.pose.y - aligned_in_world[1],
            )
            self.planner.registration_error_m = self.registration.error_m
        feet, self.feet_in_world = self.feet_in_world, self.feet_in_world.copy()
        self.feet_in_world[..., :2] = feet[..., :2] @ rotation.T + translation
        self.solver.rotate(rotation)
        self.footholds.plan.move(rotation, translation)
        self.swing_feet.transform(rotation, translation)
        self.pose = estimate

    # Parts wired together ----------------------------------------------------------------
    def _context(self, swing: npt.NDArray[np.bool_] | None = None) -> StepContext:
        """What the foothold policy sees; ``swing`` is the step's swing set (default: now)."""
        s = self.scheduler
        return StepContext(
            now=self._time or 0.0,
            pose=self.pose,
            body_z=self.height,
            velocity=self.shaper.velocity,
            yaw_rate=self.shaper.yaw_rate,
            step_start=s.step_start,
            step_duration=s.step_duration,
            groups=s.n_groups,
            speed_scale=self._step_speed_scale,
            height_rate_limit=self.config.height_rate_limit,
            height_correction=self.body_feedback.height_correction,
            feet_in_world=self.feet_commanded_in_world,
            support_after=s.support_after(self.swinging if swing is None else swing),
            incline_now=self.incline,
            incline_step=self._step_incline,
        )

    def _freeze(
        self,
        reason: str,
        command: WalkCommand | None = None,
        map_may_help: bool = True,
        leg: str = "",
    ) -> None:
        self.state = GaitState.FROZEN
        version = self.footholds.map_version if map_may_help else None
        self.safety.freeze(reason, command, version, leg)

    def _govern(self, t: float) -> float:
        """The stroke governor's fraction of the twist; 0 unless the legs are stepping."""
        if self.state is not GaitState.STEPPING or self.footholds.plan.pending_freeze:
            # The body only travels while the legs step, and stops at once when a swinging
            # foot has to go back to where it lifted off.
            return 0.0
        horizons = self.scheduler.liftoff_horizons(t)
        command = self.shaper.last_command
        rises = None
        if command is not None:
            # The body keeps rising (or sinking) towards its height over the new floor.
            reach = self.config.height_rate_limit * horizons
            rises = np.clip(self.floor + command.body_height - self.height, -reach, reach)
        scale = self.governor.scale(
            self.feet_in_body(),
            ~self.swinging,
            self.shaper.velocity,
            self.shaper.yaw_rate,
            horizons,
            rises,
        )
        return max(min(scale, self._step_speed_scale), 0.0)

    def _move_body(self, command: WalkCommand, dt: float) -> None:
        k = self._velocity_scale
        v = self.shaper.velocity
        self.pose = self.pose.moved((v[0] * k, v[1] * k), self.shaper.yaw_rate * k, dt)
        dh = self.floor + command.body_height - self.height
        limit = self.config.height_rate_limit * dt
        dh = float(np.clip(dh, -limit, limit))
        if dh != 0.0 and self.state is GaitState.STEPPING:
            # Stepping, the height waits while a foot would leave its leg's reach where it
            # stands or, swinging, where it will land: a supporting foot lifts soon, and the
            # body goes on once it has. (Standing, a height no leg reaches freezes the robot
            # with the reason.) A foot sent back to where it lifted off, the body stopping
            # for want of a foothold, lands where the body has left it room.
            feet = self.feet_in_body()
            landing = self._to_body(self.footholds.plan.targets)
            feet[self.swinging] = landing[self.swinging]
            after = feet.copy()
            after[:, 2] -= dh
            # A landing target also keeps the planner's reach margin, which the feedback's
            # corrections take up once the foot stands.
            reach = self.kinematics.reachable_all
            margin = self.footholds.reach_margin or 0.0
            leaves = reach(feet) & ~reach(after)
            leaves |= self.swinging & reach(feet, margin) & ~reach(after, margin)
            if np.any(leaves):
                dh = 0.0
        self.height += dh

    def _incline_body(self, dt: float) -> None:
        """Turn the body towards its wanted incline at the incline rate.

        The turn waits while a supporting foot, or a swinging foot's landing target, would
        leave its leg's reach, or the margin inside it that the stroke governor keeps.
        """
        limit = self.config.incline_rate * dt
        turn = float(np.clip(self.incline_target - self.incline, -limit, limit))
        if turn == 0.0 or self.state is GaitState.FROZEN:
            return
        feet = self.feet_in_world.copy()
        feet[self.swinging] = self.footholds.plan.targets[self.swinging]
        # The feet keep the stroke governor's margin, which the feedback's corrections take up.
        reach, margin = self.kinematics.reachable_all, self.footholds.reach_margin or 0.0
        before, after = self._to_body(feet), self._to_body(feet, self.incline + turn)
        leaves = reach(before) & ~reach(after)
        leaves |= reach(before, margin) & ~reach(after, margin)
        if not np.any(leaves):
            self.incline += turn

    def _advance_gait(self, t: float) -> None:
        if self.state is GaitState.STEPPING and self.scheduler.step_over(t):
            self._touch_down(t)
            if self.state is GaitState.FROZEN:
                return
        if self.state is GaitState.REST and not self.holding:
            if self.shaper.moving or self.scheduler.off_rest(self.feet_in_world, self.pose).any():
                self._start_step(t)
            else:
                self.scheduler.start_of_walk = True  # at rest: the next walk starts anew

    def _touch_down(self, t: float) -> None:
        """End the step: the swinging feet land; freeze if the step says so."""
        plan = self.footholds.plan
        for leg, swing in self.swings.items():
            self.feet_in_world[leg] = swing.target
            self.solver.touched_down(leg)
            record = Touchdown(t, leg, plan.nominal[leg].copy(), swing.target)
            self.touchdowns.append(record)
            self.touchdown_count += 1
            moved = (record.chosen_in_world - record.nominal_in_world)[:2]
            self.footholds_adjusted += bool(np.hypot(*moved) > 1e-3)
        self.swing_feet.clear()
        self.scheduler.steps_taken += 1
        self.state = GaitState.REST
        moved = math.hypot(
            self.pose.x - self._step_start_pose.x, self.pose.y - self._step_start_pose.y
        )
        stalled = self.safety.stalled(
            moved,
            math.hypot(*self.shaper.velocity),
            self.scheduler.n_groups,
            self.planner is not None,
            plan.nominal,
            plan.targets,
            self.spec.leg_names,
        )
        if stalled is not None:
            # The way ahead has no foothold the legs reach: only a new command resumes.
            command = self.shaper.last_command
            self._freeze(stalled.reason, command, map_may_help=False, leg=stalled.leg)
        elif plan.pending_freeze:
            self._freeze(plan.pending_freeze.reason, leg=plan.pending_freeze.leg)
            plan.pending_freeze = None

    def _start_step(self, t: float) -> None:
        s = self.scheduler
        group_before, start_before = s.group_index, s.start_of_walk
        swing = s.choose_group(
            self.shaper, self.scheduler.off_rest(self.feet_in_world, self.pose), self.feet_in_body
        )
        if not swing.any():
            return
        s.begin_step(t, self.shaper)
        self._step_start_pose = self.pose
        self._aim_incline(swing, self._nominal_targets(), s.step_duration)
        targets = self._plan_step(swing)
        if isinstance(targets, NoFoothold) and self._step_incline != self.incline:
            # The inclined body may not reach footholds the body as it is reaches.
            self.incline_target = self._step_incline = self.incline
            targets = self._plan_step(swing)
        if isinstance(targets, NoFoothold):
            # No step started: every foot is still down. The same group tries again later.
            s.group_index, s.start_of_walk = group_before, start_before
            self._freeze(targets.reason, leg=targets.leg)
            return
        self.state = GaitState.STEPPING
        starts = self.feet_commanded_in_world
        for leg in np.flatnonzero(swing):
            self.feet_in_world[leg] = starts[leg]
            self.solver.lifted(int(leg))
        terrain = self.footholds.terrain_under if self.planner is not None else None
        self.swing_feet.lift(
            swing,
            starts,
            targets,
            s.step_duration,
            self.config,
            terrain,
            self.footholds.swing_clearance,
        )
        self._update_floor(targets)

    def _plan_step(self, swing: npt.NDArray[np.bool_]) -> npt.NDArray[np.float64] | NoFoothold:
        """The step's footholds at the fastest speed scale that has them, or why none."""
        targets: npt.NDArray[np.float64] | NoFoothold = NoFoothold("no step planned")
        for speed_scale in self.footholds.speed_scales:
            self._step_speed_scale = speed_scale
            nominal = self._nominal_targets()
            targets = self.footholds.plan_step(self._context(swing), nominal, swing)
            if not isinstance(targets, NoFoothold):
                break
        return targets

    def _aim_incline(
        self,
        swing: npt.NDArray[np.bool_],
        nominal: npt.NDArray[np.float64],
        step_duration: float,
    ) -> None:
        """Set the incline the body heads for, and the one it will have at touchdown.

        The ground's slope along the heading under the supporting feet and under the
        swinging legs' nominal footholds (steppable mapped cells only: a foothold over a
        gap says nothing of the slope) sets it (:func:`~footfall.motion.incline.wanted_pitch`).
        """
        ground = self.feet_in_world.copy()
        ground[:, 2] -= self.spec.foot_radius
        ground[swing, 2] = self.footholds.steppable_ground(nominal[swing, :2])
        slope = ground_slope(ground, self.pose)
        self.incline_target = wanted_pitch(slope, self._level_slope, self.config.incline_limit)
        turn = self.config.incline_rate * step_duration
        self._step_incline = self.incline + float(
            np.clip(self.incline_target - self.incline, -turn, turn)
        )

    def _update_floor(self, targets: npt.NDArray[np.float64]) -> None:
        floor = self.footholds.floor(
            self._context(), targets, self.swinging, self.feet_in_world, self.shaper.body_height
        )
        if floor is not None:
            self.floor = floor

    def _nominal_targets(self) -> npt.NDArray[np.float64]:
        # With the twist actually applied (after the governor): targets follow the body.
        twist = (self.body_velocity_in_body, self.shaper.yaw_rate * self._velocity_scale)
        return self.scheduler.nominal_targets(self._time or 0.0, self.pose, *twist)

    def _move_swing_feet(self, t: float) -> npt.NDArray[np.float64]:
        """Move swinging feet along their paths; returns their world velocities, shape (6, 3)."""
        if not self.swings:
            return np.zeros((6, 3))
        starts = {leg: swing.start for leg, swing in self.swings.items()}
        targets, replanned = self.footholds.current_targets(
            self._context(), self._nominal_targets(), self.swinging, starts
        )
        if replanned:
            self._update_floor(targets)
        local_t = t - self.scheduler.step_start
        positions, velocity, duration = self.swing_feet.follow(
            targets, local_t, self.scheduler.remaining(t), self.config.retarget_tolerance
        )
        if duration is not None:  # the group lands together, when the farthest foot can
            self.scheduler.step_duration = duration
        for leg, position in positions.items():
            self.feet_in_world[leg] = position
        return velocity

    def _solve(self, swing_velocity_in_world: npt.NDArray[np.float64]) -> FootTargets:
        twist = (self.body_velocity_in_body, self.shaper.yaw_rate * self._velocity_scale)
        feet = self.feet_in_body()
        return self.solver.solve(
            feet,
            self.swinging,
            self.pose,
            self.body_feedback,
            twist,
            swing_velocity_in_world,
            self.incline,
        )
