"""Where swinging feet land: the nominal footholds (blind) or the map's choice (mapped).

Both policies keep the step's plan: the nominal targets, the chosen ones, and a pending
freeze. :class:`BlindFootholds` is the thesis' baseline: every foot lands on its nominal
place on the plane z = 0. :class:`MappedFootholds` asks the terrain planner to move each
nominal foothold to the nearest acceptable cell, plans the body height with the footholds,
slows a step down where footholds are scarce (it is planned again at a fraction of the
speed), lifts swing paths over the mapped terrain and re-plans when the map changes.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol

import numpy as np
import numpy.typing as npt

from footfall.planning.step_plan import NoFoothold, StepPoses
from footfall.planning.terrain_planner import TerrainPlanner
from footfall.robot.planar import PlanarPose, level_to_inclined

# Fractions of the commanded speed a step is planned at, fastest first: where footholds
# are scarce the body slows down so the legs can find them.
STEP_SPEED_SCALES = (1.0, 0.5, 0.25)
# Fraction of a swing after which re-plans keep the target where they can.
LATE_SWING = 0.5
# Farthest the planned body height looks from the present one [m], and its spacing [m].
BODY_Z_WINDOW = 0.08
BODY_Z_STEP = 0.005


@dataclass
class StepPlan:
    """The footholds of the step under way.

    Attributes:
        nominal: Nominal targets (foot centres) in the world, shape (6, 3) [m].
        targets: Chosen targets, shape (6, 3) [m].
        version: Map version the targets were planned on (-1: none).
        pending_freeze: Why the robot must freeze when the step ends ("" if it need not).
        body_z: Body heights in the world at which every leg reaches its foot [m].
    """

    nominal: npt.NDArray[np.float64] = field(default_factory=lambda: np.zeros((6, 3)))
    targets: npt.NDArray[np.float64] = field(default_factory=lambda: np.zeros((6, 3)))
    version: int = -1
    pending_freeze: NoFoothold | None = None
    body_z: npt.NDArray[np.float64] = field(default_factory=lambda: np.zeros(0))

    def move(self, rotation: npt.NDArray[np.float64], translation: npt.NDArray[np.float64]):
        """Apply a planar transform of the world to the targets (pose re-registration)."""
        for name in ("nominal", "targets"):
            points = getattr(self, name).copy()
            points[..., :2] = getattr(self, name)[..., :2] @ rotation.T + translation
            setattr(self, name, points)


@dataclass(frozen=True)
class StepContext:
    """What the controller knows when it plans footholds.

    Attributes:
        now: Controller time [s].
        pose: Reference body pose.
        body_z: Reference body height in the world [m].
        velocity: Rate-limited body velocity in the body frame [m/s].
        yaw_rate: Rate-limited yaw rate [rad/s].
        step_start: Start of the step [s].
        step_duration: Step duration [s].
        groups: Swing groups in the gait cycle.
        speed_scale: Fraction of the command this step is planned for.
        height_rate_limit: Speed of body height changes [m/s].
        height_correction: Height feedback's correction [m].
        feet_in_world: Commanded foot centres now, shape (6, 3) [m].
        support_after: Legs supporting after touchdown, shape (6,).
        incline_now: The body's pitch now [rad] (:mod:`footfall.motion.incline`).
        incline_step: The pitch it will have at touchdown [rad].
    """

    now: float
    pose: PlanarPose
    body_z: float
    velocity: tuple[float, float]
    yaw_rate: float
    step_start: float
    step_duration: float
    groups: int
    speed_scale: float
    height_rate_limit: float
    height_correction: float
    feet_in_world: npt.NDArray[np.float64]
    support_after: npt.NDArray[np.bool_]
    incline_now: float = 0.0
    incline_step: float = 0.0


class FootholdPolicy(Protocol):
    """Where the swinging feet of a step land.

    Attributes:
        plan: The step's footholds.
        speed_scales: Speed fractions a step is tried at, fastest first.
        reach_margin: Workspace margin the stroke governor keeps (None: govern by stroke).
        map_version: Version of the map the policy plans on (None when it uses none).
        swing_clearance: Least gap of a swing path over the terrain [m] (with the foot).
    """

    plan: StepPlan
    speed_scales: tuple[float, ...]
    reach_margin: float | None
    swing_clearance: float

    @property
    def map_version(self) -> int | None:
        """Version of the map planned on; None for a policy without one."""
        ...

    def terrain_under(self, xy: npt.ArrayLike) -> npt.NDArray[np.float64] | None:
        """Highest terrain under points, for swing paths; None for flat ground."""
        ...

    def steppable_ground(self, xy: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Mapped ground height at points on cells a foot may use, NaN elsewhere [m]."""
        ...

    def plan_step(
        self,
        context: StepContext,
        nominal: npt.NDArray[np.float64],
        swing: npt.NDArray[np.bool_],
        search_from: npt.NDArray[np.float64] | None = None,
        previous: npt.NDArray[np.float64] | None = None,
    ) -> npt.NDArray[np.float64] | NoFoothold:
        """Targets for the swinging legs, shape (6, 3) [m], or why there are none.

        ``previous``: the targets planned before in this step (a re-plan), or None.
        """
        ...

    def current_targets(
        self,
        context: StepContext,
        nominal: npt.NDArray[np.float64],
        swinging: npt.NDArray[np.bool_],
        swing_starts: dict[int, npt.NDArray[np.float64]],
    ) -> tuple[npt.NDArray[np.float64], bool]:
        """The swing targets now, and whether they were re-planned (and found)."""
        ...

    def floor(
        self,
        context: StepContext,
        targets: npt.NDArray[np.float64],
        swinging: npt.NDArray[np.bool_],
        feet_in_world: npt.NDArray[np.float64],
        body_height: float,
    ) -> float | None:
        """The ground height the body keeps its height above [m]; None to keep it."""
        ...


class BlindFootholds:
    """The thesis' baseline: nominal footholds on the plane z = 0."""

    speed_scales = (1.0,)
    reach_margin = None
    swing_clearance = 0.0
    map_version = None

    def __init__(self) -> None:
        self.plan = StepPlan()

    def terrain_under(self, xy: npt.ArrayLike) -> None:
        """Flat ground: nothing to clear."""
        return None

    def steppable_ground(self, xy: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """No map: nothing is known."""
        return np.full(np.shape(xy)[:-1], np.nan)

    def plan_step(self, context, nominal, swing, search_from=None, previous=None):  # noqa: D102
        self.plan.nominal = nominal.copy()
        self.plan.targets = nominal.copy()
        return nominal

    def current_targets(self, context, nominal, swinging, swing_starts):  # noqa: D102
        self.plan.nominal = nominal
        self.plan.targets = nominal
        return nominal, False

    def floor(self, context, targets, swinging, feet_in_world, body_height):  # noqa: D102
        return None


class MappedFootholds:
    """Footholds chosen on the map by a terrain planner.

    Args:
        planner: The terrain planner fed with the map.
        foot_radius: Radius of the feet [m].
    """

    speed_scales = STEP_SPEED_SCALES

    def __init__(self, planner: TerrainPlanner, foot_radius: float) -> None:
        self.planner = planner
        self.plan = StepPlan()
        self.foot_radius = foot_radius
        self.reach_margin = 0.5 * planner.config.reach_margin  # the rest absorbs corrections
        self.swing_clearance = planner.config.swing_clearance + foot_radius

    @property
    def map_version(self) -> int:
        """Version of the planner's map."""
        return self.planner.version

    def terrain_under(self, xy: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Highest mapped height within a foot radius of each point [m]."""
        return self.planner.terrain_under(xy)

    def steppable_ground(self, xy: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Mapped ground height at points on valid cells, NaN elsewhere [m]."""
        return self.planner.steppable_ground(xy)

    def plan_step(
        self,
        context: StepContext,
        nominal: npt.NDArray[np.float64],
        swing: npt.NDArray[np.bool_],
        search_from: npt.NDArray[np.float64] | None = None,
        previous: npt.NDArray[np.float64] | None = None,
    ) -> npt.NDArray[np.float64] | NoFoothold:
        """The planner's footholds, checked against the motion at the step's speed scale.

        The planner searches from ``search_from`` when given (the present targets, late in
        a swing), else from the nominal targets; a re-plan passes the targets planned
        before as ``previous``, whose steppable regions the footholds keep where they can.
        """
        c = context
        self.plan.nominal = nominal.copy()
        remaining = max(c.step_start + c.step_duration - c.now, 0.0)
        # Check footholds against the commanded motion at this step's speed scale (not the
        # governed one, which may be zero while the body waits): the body will travel that
        # far if the legs allow.
        k = c.speed_scale
        vx, vy, yaw_rate = c.velocity[0] * k, c.velocity[1] * k, c.yaw_rate * k

        def pose_after(seconds: float) -> PlanarPose:
            return c.pose.moved((vx, vy), yaw_rate, seconds)

        poses = StepPoses(
            now=c.pose,
            touchdown=pose_after(remaining),
            liftoff=pose_after(remaining + (c.groups - 1) * c.step_duration),
            stable=(pose_after(remaining), pose_after(remaining + c.step_duration)),
            incline_now=c.incline_now,
            incline_step=c.incline_step,
        )
        # Body heights within reach by touchdown at the height rate limit; the legs see
        # them raised by the height feedback's correction.
        window = float(np.clip(c.height_rate_limit * remaining, 2 * BODY_Z_STEP, BODY_Z_WINDOW))
        body_z = c.body_z + np.append(np.arange(-window, window - 1e-9, BODY_Z_STEP), window)
        plan = self.planner.plan(
            nominal if search_from is None else search_from,
            swing,
            c.support_after,
            c.feet_in_world,
            poses,
            body_z + c.height_correction,
            previous,
        )
        self.plan.version = self.planner.version
        if isinstance(plan, NoFoothold):
            return plan
        self.plan.targets = plan.targets.copy()
        self.plan.body_z = plan.body_z - c.height_correction
        return plan.targets

    def current_targets(
        self,
        context: StepContext,
        nominal: npt.NDArray[np.float64],
        swinging: npt.NDArray[np.bool_],
        swing_starts: dict[int, npt.NDArray[np.float64]],
    ) -> tuple[npt.NDArray[np.float64], bool]:
        """Swing targets now: re-planned when the nominal ones moved or the map changed.

        Late in a swing only a new map re-plans, and the search starts from the present
        target rather than the nominal one: a target still acceptable stays, one that is
        not moves to the nearest acceptable cell, so a foot about to land never lurches
        across a step. When a re-plan finds no acceptable foothold, the body stops, each
        swinging foot goes back to where it lifted off (a known, safe cell) and the robot
        freezes at the end of the step. A lift-off point the stopped body has left behind
        out of the leg's reach is no place to land: that foot keeps its planned target if
        the leg reaches it (planned on the map before), so no supporting foot ends up out
        of reach, which no new command could undo.
        """
        plan = self.plan
        moved = np.linalg.norm(nominal[swinging, :2] - plan.nominal[swinging, :2], axis=1)
        stale = self.planner.version != plan.version
        late = context.now - context.step_start > LATE_SWING * context.step_duration
        if plan.pending_freeze or not (stale or (not late and moved.size and moved.max() > 0.02)):
            return plan.targets, False
        before = plan.targets.copy()
        replanned = self.plan_step(context, nominal, swinging, before if late else None, before)
        if isinstance(replanned, NoFoothold):
            plan.pending_freeze = replanned
            for leg, start in swing_starts.items():
                if self._reaches(context, leg, start) or not self._reaches(
                    context, leg, plan.targets[leg]
                ):
                    plan.targets[leg] = start
            return plan.targets, False
        return plan.targets, True

    def _reaches(
        self, context: StepContext, leg: int, foot_in_world: npt.NDArray[np.float64]
    ) -> bool:
        """Whether a leg of the body as it stands now reaches a foot position."""
        foot_in_body = context.pose.points_to_body(foot_in_world)
        foot_in_body[2] -= context.body_z + context.height_correction
        foot_in_body = level_to_inclined(foot_in_body, context.incline_now)
        return bool(self.planner.kinematics.reachable(leg, foot_in_body, self.reach_margin))

    def floor(
        self,
        context: StepContext,
        targets: npt.NDArray[np.float64],
        swinging: npt.NDArray[np.bool_],
        feet_in_world: npt.NDArray[np.float64],
        body_height: float,
    ) -> float:
        """Thesis §6.4: the floor under the body follows the footholds.

        The body height the floor asks for is kept where every leg reaches its foot: of
        the heights the plan allows, the nearest.
        """
        feet = np.where(swinging[:, None], targets, feet_in_world)
        ground = feet[:, 2] - self.foot_radius
        wanted = body_height + self.planner.floor_height(
            ground, context.pose, body_height, context.incline_step
        )
        allowed = self.plan.body_z
        body_z = float(allowed[np.argmin(np.abs(allowed - wanted))]) if allowed.size else wanted
        return body_z - body_height
