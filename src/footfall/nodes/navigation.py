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

from footfall.messages import GaitStatus, LogLine, MapUpdate, WalkCommand
from footfall.nodes.stuck import StuckWatch
from footfall.planning.footholds import FootholdConfig
from footfall.planning.navigation import (
    NavigationConfig,
    NoRoute,
    Route,
    follow_route,
    plan_route,
)
from footfall.planning.traversability import (
    CostGrid,
    cost_grid,
    longest_gap,
    span_radius,
    wall_faces,
)
from footfall.robot.planar import PlanarPose
from footfall.robot.spec import HexapodSpec
from footfall.runtime.bus import Bus
from footfall.runtime.cpu_meter import CpuMeter, MeteredBus

# Replan times kept for the timing figures.
TIMING_HISTORY = 10_000


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
        """Forget the walls on cells the grid shows flat.

        Looks up the remembered cells in the grid (a few hundred at most), not the grid's
        flat cells in the memory (most of a 256 x 256 window).
        """
        i0, j0 = self._offset(grid.origin, grid.resolution)
        n, m = grid.flat.shape
        with self._lock:
            if not self._tops:
                return
            keys = np.array(list(self._tops), dtype=np.int64)
            i, j = keys[:, 0] - i0, keys[:, 1] - j0
            inside = (i >= 0) & (i < n) & (j >= 0) & (j < m)
            flat = np.zeros(len(keys), dtype=bool)
            flat[inside] = grid.flat[i[inside], j[inside]]
            for gi, gj in keys[flat]:
                del self._tops[(int(gi), int(gj))]


class NavigatorNode:
    """Walk to a goal in the world along replanned routes.

    Args:
        bus: The bus (map updates in, log lines out).
        spec: The robot (its legs' span and stride).
        goal_in_world: Goal ``(x, y)`` [m]; None until :meth:`set_goal`.
        config: Settings.
        background: Replan on a worker thread (see the module docstring).
        meter: Charged with the node's work, on either thread.
        foothold_search_m: The foothold search's radius [m]: with the stride, the widest
            gap a step crosses (:func:`~footfall.planning.traversability.longest_gap`).
    """

    name = "navigation"

    def __init__(
        self,
        bus: Bus,
        spec: HexapodSpec,
        goal_in_world: tuple[float, float] | None = None,
        config: NavigationConfig | None = None,
        background: bool = False,
        meter: CpuMeter | None = None,
        foothold_search_m: float = FootholdConfig.search_radius,
    ) -> None:
        self.bus = bus
        self.meter = meter if meter is not None else CpuMeter()
        self.config = (config or NavigationConfig()).for_robot(spec)
        self.span_radius_m = span_radius(spec)
        self.max_gap_m = longest_gap(spec, foothold_search_m)
        self.goal: tuple[float, float] | None = None
        self.route: Route | None = None
        self.no_route: NoRoute | None = None
        self.grid: CostGrid | None = None
        self.replans = 0
        self.plan_seconds: deque[float] = deque(maxlen=TIMING_HISTORY)
        self._map: MapUpdate | None = None
        self._planned_sequence = -1
        self._planned_at = -math.inf
        self._force = False
        self._misses = 0
        self._last_command: WalkCommand | None = None
        self.stuck = StuckWatch(
            self.config, spec.leg_names, spec.rest_feet_in_body()[:, :2], self._log
        )
        self._walls = WallMemory()
        self._pool = ThreadPoolExecutor(max_workers=1) if background else None
        self._pending: Future[PlanOutcome] | None = None
        MeteredBus(bus, self.meter, self.name).subscribe(MapUpdate.TOPIC, self._on_map, last=True)
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
            update,
            self.config.traversability,
            self.span_radius_m,
            self._walls.window(update),
            self.max_gap_m,
        )
        self._walls.forget_flat(grid)
        t1 = time.perf_counter()
        blocked = self.stuck.blocked_discs(t)
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
            plan = self.meter.wrap(self.name, self._plan)  # timed on the worker's thread
            self._pending = self._pool.submit(plan, update, pose, goal, t)

    def command(self, t: float, status: GaitStatus, base: WalkCommand) -> WalkCommand:
        """The walk command at time ``t`` [s] for the robot's status, at ``base``'s speed."""
        with self.meter.measure(self.name):
            return self._command(t, status, base)

    def _command(self, t: float, status: GaitStatus, base: WalkCommand) -> WalkCommand:
        pose = status.body_pose
        if self.stuck.watch(t, status, self._last_command, self._map):
            self._force = True
        stop = WalkCommand(speed=0.0, body_height=base.body_height, stamp=t)
        look, looked = self.stuck.looking(t, pose, base)
        if looked:
            self._force = True  # plan on what the look showed
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
            "routes_blocked": self.stuck.blocked_count,
            "looks": self.stuck.looks,
        }

    def close(self) -> None:
        """Stop the worker thread."""
        if self._pool is not None:
            self._pool.shutdown(wait=True, cancel_futures=True)
            self._pool = None
