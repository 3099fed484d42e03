"""The navigation node: map updates and the robot's status in, walk commands to a goal out.

It keeps the newest :class:`~footfall.messages.MapUpdate`, builds the cost grid from it
(:mod:`footfall.planning.traversability`) and a route to the goal
(:mod:`footfall.planning.navigation`), and turns the route into walk commands for the
movement node. A route is replanned once it is ``replan_period_s`` old and a newer map has
come, and at once when the walker has frozen for want of footholds (the ground ahead is
then kept out for a while: the route was blocked there). A walker frozen because a foot's
place has not been seen (the camera looks ahead, and a route that turns close beside the
edge of what it has seen puts feet where it never looked) first turns on the spot to face
that place, once per place, and walks on when the map has it. When no route reaches the goal
(confirmed over a few replans) it says why and commands standing still; it keeps
replanning, and walks again once a route opens.

With ``background`` the replans run on a worker thread (the search holds no GIL): a command
tick only hands a map over and picks up a finished route, so it never waits for a plan.
Without, each replan runs in the tick that asks for it, which keeps a simulated walk exactly
repeatable.
"""

from __future__ import annotations

import math
import statistics
import threading
import time
from collections import deque
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from footfall.messages import GaitState, GaitStatus, LogLine, MapUpdate, WalkCommand
from footfall.planning.navigation import (
    NavigationConfig,
    NoRoute,
    Route,
    follow_route,
    plan_route,
)
from footfall.planning.traversability import CostGrid, cost_grid, span_radius, wall_faces
from footfall.robot.planar import PlanarPose
from footfall.robot.spec import HexapodSpec
from footfall.runtime.bus import Bus

# Replan times kept for the timing figures.
TIMING_HISTORY = 10_000
# A foot's place counts as unseen when less than this share of the cells around it is known.
UNSEEN_SHARE = 0.5
# A look is done when the body faces the place within this [rad], or after this long [s].
LOOK_DONE_RAD = math.radians(10.0)
LOOK_TIMEOUT_S = 10.0
# A walker that froze and has not moved farther than this since is still stuck there [m].
STUCK_RADIUS_M = 0.1
# A place within this of one already looked at is not looked at again [m].
LOOKED_RADIUS_M = 0.1


@dataclass(frozen=True)
class PlanOutcome:
    """One replan: its result and how long its parts took.

    Attributes:
        result: The route, or why there is none.
        grid: The cost grid it searched.
        map_sequence: Sequence number of the map update it used.
        grid_seconds: Time to build the cost grid [s].
        search_seconds: Time of the route search [s].
    """

    result: Route | NoRoute
    grid: CostGrid
    map_sequence: int
    grid_seconds: float
    search_seconds: float


class WallMemory:
    """Wall tops found on map updates, in world cells, until seen flat.

    Cells are indexed on the world grid of the map's resolution (``floor(x / res)``), so a
    rolling window finds its own cells again. Every map update adds its wall tops (a face
    shows its height only in the frames that see it well: a later, grazing view may leave
    its cell only the face's foot); a replan forgets the cells its grid shows flat. The
    map thread notes while a replan thread reads, hence the lock.
    """

    def __init__(self) -> None:
        self._tops: dict[tuple[int, int], float] = {}
        self._lock = threading.Lock()

    def __len__(self) -> int:
        return len(self._tops)

    @staticmethod
    def _offset(origin: tuple[float, float], resolution: float) -> tuple[int, int]:
        return (round(origin[0] / resolution), round(origin[1] / resolution))

    def window(self, update: MapUpdate) -> npt.NDArray[np.float64]:
        """The remembered tops on the update's cells, NaN where none [m]."""
        n, m = np.shape(update.heights)
        out = np.full((n, m), np.nan)
        i0, j0 = self._offset(update.origin, update.resolution)
        with self._lock:
            tops = list(self._tops.items())
        for (gi, gj), top in tops:
            i, j = gi - i0, gj - j0
            if 0 <= i < n and 0 <= j < m:
                out[i, j] = top
        return out

    def note(self, update: MapUpdate, wall: npt.NDArray[np.bool_]) -> None:
        """Remember the wall tops of a map update (the highest seen per cell)."""
        i0, j0 = self._offset(update.origin, update.resolution)
        heights = np.asarray(update.heights, dtype=np.float64)
        with self._lock:
            for i, j in zip(*np.nonzero(wall), strict=True):
                key = (int(i) + i0, int(j) + j0)
                top = float(heights[i, j])
                if top > self._tops.get(key, -math.inf):
                    self._tops[key] = top

    def forget_flat(self, grid: CostGrid) -> None:
        """Forget the walls on cells the grid shows flat."""
        i0, j0 = self._offset(grid.origin, grid.resolution)
        with self._lock:
            for i, j in zip(*np.nonzero(grid.flat), strict=True):
                self._tops.pop((int(i) + i0, int(j) + j0), None)


class NavigatorNode:
    """Walk to a goal in the world along replanned routes.

    Args:
        bus: The bus (map updates in, log lines out).
        spec: The robot (its legs' span).
        goal_in_world: Goal ``(x, y)`` [m]; None until :meth:`set_goal`.
        config: Settings.
        background: Replan on a worker thread (see the module docstring).
    """

    name = "navigation"

    def __init__(
        self,
        bus: Bus,
        spec: HexapodSpec,
        goal_in_world: tuple[float, float] | None = None,
        config: NavigationConfig | None = None,
        background: bool = False,
    ) -> None:
        self.bus = bus
        self.config = config or NavigationConfig()
        self.span_radius_m = span_radius(spec)
        self.leg_names = spec.leg_names
        self.rest_feet_in_body = spec.rest_feet_in_body()[:, :2]
        self.goal: tuple[float, float] | None = None
        self.route: Route | None = None
        self.no_route: NoRoute | None = None
        self.grid: CostGrid | None = None
        self.replans = 0
        self.blocked_count = 0
        self.looks = 0
        self.plan_seconds: deque[float] = deque(maxlen=TIMING_HISTORY)
        self._map: MapUpdate | None = None
        self._planned_sequence = -1
        self._planned_at = -math.inf
        self._force = False
        self._misses = 0
        self._blocked: list[tuple[float, float, float, float]] = []
        self._frozen_since: float | None = None
        self._frozen_at: tuple[float, float] | None = None
        self._blocked_this_freeze = False
        self._last_command: WalkCommand | None = None
        self._look: tuple[float, float] | None = None  # (yaw to face [rad], until [s])
        self._looked: list[tuple[float, float]] = []
        self._walls = WallMemory()
        self._pool = ThreadPoolExecutor(max_workers=1) if background else None
        self._pending: Future[PlanOutcome] | None = None
        bus.subscribe(MapUpdate.TOPIC, self._on_map, last=True)
        if goal_in_world is not None:
            self.set_goal(goal_in_world)

    def _on_map(self, message: MapUpdate) -> None:
        self._map = message
        self._walls.note(message, wall_faces(message, self.config.traversability))

    def set_goal(self, goal_in_world: tuple[float, float] | None) -> None:
        """Walk to a new goal (None: stop navigating); the route is planned afresh."""
        self.goal = (
            None if goal_in_world is None else (float(goal_in_world[0]), float(goal_in_world[1]))
        )
        self.route = None
        self.no_route = None
        self._misses = 0
        self._force = True

    def at_goal(self, pose: PlanarPose) -> bool:
        """Whether the body is within the goal tolerance."""
        if self.goal is None:
            return False
        return (
            math.hypot(pose.x - self.goal[0], pose.y - self.goal[1]) <= self.config.goal_tolerance_m
        )

    def _plan(
        self, update: MapUpdate, pose: PlanarPose, goal: tuple[float, float], t: float
    ) -> PlanOutcome:
        t0 = time.perf_counter()
        grid = cost_grid(
            update, self.config.traversability, self.span_radius_m, self._walls.window(update)
        )
        self._walls.forget_flat(grid)
        t1 = time.perf_counter()
        blocked = tuple((x, y, r) for x, y, r, until in self._blocked if until > t)
        result = plan_route(grid, (pose.x, pose.y), goal, self.config, blocked, self.route)
        t2 = time.perf_counter()
        return PlanOutcome(result, grid, update.sequence, t1 - t0, t2 - t1)

    def _take(self, outcome: PlanOutcome, t: float) -> None:
        self.replans += 1
        self.grid = outcome.grid
        self.plan_seconds.append(outcome.grid_seconds + outcome.search_seconds)
        if isinstance(outcome.result, Route):
            if self.no_route is not None:
                self._log(t, "info", "a route to the goal is open again")
            self.route, self.no_route, self._misses = outcome.result, None, 0
            return
        self._misses += 1
        if self._misses >= self.config.confirm_no_route and self.no_route is None:
            self.no_route = outcome.result
            self.route = None
            self._log(t, "warning", f"standing still: {outcome.result.reason}")

    def _log(self, t: float, level: str, text: str) -> None:
        self.bus.publish(LogLine.TOPIC, LogLine(t, self.name, level, text))

    def _watch_freeze(self, t: float, status: GaitStatus) -> None:
        """Keep the ground ahead of a walker frozen for want of footholds out of routes."""
        pose = status.body_pose
        if self._frozen_at is not None and (
            math.hypot(pose.x - self._frozen_at[0], pose.y - self._frozen_at[1]) > STUCK_RADIUS_M
        ):
            # Walked on from where it froze: the next freeze starts the count afresh.
            self._frozen_since, self._frozen_at, self._blocked_this_freeze = None, None, False
        if status.state is not GaitState.FROZEN:
            return
        if self._frozen_since is None:
            # Counted from the first freeze here: a walker that retries on each fresh map
            # and freezes again at once is as stuck as one that stays frozen.
            self._frozen_since, self._frozen_at = t, (pose.x, pose.y)
        if self._blocked_this_freeze or t - self._frozen_since < self.config.blocked_after_s:
            return
        place = self._unseen_place(status)
        if place is not None:
            self._looked.append(place)
            yaw = math.atan2(place[1] - pose.y, place[0] - pose.x)
            self._look = (yaw, t + LOOK_TIMEOUT_S)
            self._blocked_this_freeze = True
            self.looks += 1
            self._log(
                t,
                "info",
                f"leg {status.frozen_leg} has not seen where it steps ({place[0]:.2f}, "
                f"{place[1]:.2f}) m; turning to look",
            )
            return
        heading = pose.yaw
        command = self._last_command
        if command is not None and command.speed > 0:
            heading += math.atan2(command.direction[1], command.direction[0])
        ahead = self.config.blocked_ahead_m
        x, y = pose.x + ahead * math.cos(heading), pose.y + ahead * math.sin(heading)
        self._blocked.append((x, y, self.config.blocked_radius_m, t + self.config.blocked_for_s))
        self._blocked = [b for b in self._blocked if b[3] > t]
        self._blocked_this_freeze = True
        self.blocked_count += 1
        self._force = True
        self._log(
            t, "info", f"route blocked at ({x:.2f}, {y:.2f}) m ({status.frozen_reason}); replanning"
        )

    def _unseen_place(self, status: GaitStatus) -> tuple[float, float] | None:
        """Where the frozen leg steps at rest, if the map has not seen it and no look has."""
        update = self._map
        if update is None or status.frozen_leg not in self.leg_names:
            return None
        foot = self.rest_feet_in_body[self.leg_names.index(status.frozen_leg)]
        x, y = (float(v) for v in status.body_pose.points_to_world(foot))
        if any(math.hypot(x - a, y - b) < LOOKED_RADIUS_M for a, b in self._looked):
            return None
        known = np.asarray(update.known, dtype=bool)
        res = update.resolution
        half = max(1, round(self.config.traversability.support_radius_m / res))
        i = math.floor((x - update.origin[0]) / res)
        j = math.floor((y - update.origin[1]) / res)
        n = known.shape[0]
        around = known[
            max(i - half, 0) : min(i + half + 1, n), max(j - half, 0) : min(j + half + 1, n)
        ]
        seen = float(around.mean()) if around.size else 0.0
        return (x, y) if seen < UNSEEN_SHARE else None

    def _looking(self, t: float, pose: PlanarPose, base: WalkCommand) -> WalkCommand | None:
        """The turn on the spot of a look under way, or None once it is done."""
        if self._look is None:
            return None
        yaw, until = self._look
        error = math.atan2(math.sin(yaw - pose.yaw), math.cos(yaw - pose.yaw))
        if abs(error) < LOOK_DONE_RAD or t > until:
            self._look = None
            self._force = True  # plan on what the look showed
            # Stuck here again after the look: the count starts afresh, and ends in a block.
            self._frozen_since, self._frozen_at, self._blocked_this_freeze = None, None, False
            return None
        rate = self.config.max_yaw_rate
        yaw_rate = float(np.clip(self.config.yaw_gain * error, -rate, rate))
        return WalkCommand(speed=0.0, body_height=base.body_height, yaw_rate=yaw_rate, stamp=t)

    def _replan(self, t: float, pose: PlanarPose) -> None:
        if self._pending is not None and self._pending.done():
            outcome = self._pending.result()
            self._pending = None
            self._take(outcome, t)
        update, goal = self._map, self.goal
        if update is None or goal is None or self._pending is not None:
            return
        due = self._force or t - self._planned_at >= self.config.replan_period_s
        # Without a route the same map is planned on again (the robot may have moved), so an
        # unchanged map that has no route confirms it and the robot says why it stands.
        same_map = update.sequence == self._planned_sequence and self.route is not None
        if not due or (same_map and not self._force):
            return
        self._force = False
        self._planned_at, self._planned_sequence = t, update.sequence
        if self._pool is None:
            self._take(self._plan(update, pose, goal, t), t)
        else:
            self._pending = self._pool.submit(self._plan, update, pose, goal, t)

    def command(self, t: float, status: GaitStatus, base: WalkCommand) -> WalkCommand:
        """The walk command at time ``t`` [s] for the robot's status, at ``base``'s speed."""
        pose = status.body_pose
        self._watch_freeze(t, status)
        stop = WalkCommand(speed=0.0, body_height=base.body_height, stamp=t)
        look = self._looking(t, pose, base)
        if self.goal is None or self.at_goal(pose):
            command = stop
        elif look is not None:
            command = look
        else:
            self._replan(t, pose)
            if self.route is None:
                command = stop
            else:
                command = follow_route(self.route, pose, base, self.config, t)
        self._last_command = command
        return command

    def timing(self) -> dict[str, float]:
        """Replan count and times (cost grid plus search): median and 95th percentile [ms]."""
        times = sorted(self.plan_seconds)
        if not times:
            return {"replans": 0}
        p95 = times[min(len(times) - 1, math.ceil(0.95 * len(times)) - 1)]
        return {
            "replans": self.replans,
            "replan_ms_median": 1e3 * statistics.median(times),
            "replan_ms_p95": 1e3 * p95,
            "routes_blocked": self.blocked_count,
            "looks": self.looks,
        }

    def close(self) -> None:
        """Stop the worker thread."""
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None
