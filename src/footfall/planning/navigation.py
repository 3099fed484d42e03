"""Routes for the hexapod's body over the cost grid, and walk commands that follow them.

The thesis' robot walks the direction it is given and freezes where no foothold is left;
its future work asks for a short-term path planner to go round what cannot be crossed
(§9.2 item 4). This is that planner, local to the rolling map:

- **Search.** Dijkstra over the 8-connected cost grid from the robot's cell
  (:mod:`footfall.planning.route_kernels`). A grid search suits the hexapod: it walks in
  any direction and turns on the spot, so it has no turning radius a lattice or hybrid A*
  would have to respect, and the cost grid already holds its footprint (a disc: any
  heading). The search runs over the whole window rather than towards one cell because the
  goal may lie beyond the map: the target is then the window cell that minimises route
  cost plus the straight distance on to the goal at the cost of unseen ground.
- **No route.** A goal on the window that no route reaches, or a window whose every way out
  towards an off-map goal is closed, gives a :class:`NoRoute` with the reason. A robot on a
  lethal cell (a wall seen late) may leave it through lethal cells near it, at a high cost.
- **Following.** Pure pursuit: the command walks towards the route point ``lookahead_m``
  along from the nearest one, turning to face it (the camera looks where the robot goes);
  it slows as the heading error grows and turns on the spot past ``turn_in_place_rad``.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field, replace

import numpy as np
import numpy.typing as npt
from scipy import ndimage

from footfall.checks import require_non_negative, require_positive
from footfall.errors import ConfigError
from footfall.messages import WalkCommand
from footfall.planning.route_kernels import dijkstra, taut_indices
from footfall.planning.traversability import CostGrid, TraversabilityConfig
from footfall.robot.planar import PlanarPose
from footfall.robot.scale import robot_scale
from footfall.robot.spec import HexapodSpec

# Lengths of the robot's own size on the default robot, scaled to another robot's span [m]:
# the lethal ground a robot standing on it may leave through, and the disc kept out of the
# routes ahead of a robot frozen for want of footholds (its radius, and how far ahead).
ROBOT_LENGTHS_M = {"escape_radius_m": 0.25, "blocked_radius_m": 0.15, "blocked_ahead_m": 0.25}


@dataclass(frozen=True)
class NavigationConfig:
    """Route planning and following settings.

    Attributes:
        traversability: The cost grid's settings.
        goal_tolerance_m: The goal is reached within this distance [m].
        escape_radius_m: A robot on a lethal cell may leave through lethal cells within
            this of it [m]; None takes 0.25 m on the default robot, scaled to the robot's
            span (:meth:`for_robot`, as the two blocked lengths below).
        escape_cost: Cost per metre of such cells.
        replan_period_s: A route is replanned on the newest map once it is this old [s].
        switch_margin: Replanning, the ground along the route being walked costs this share
            less, so that a new route replaces it only when clearly cheaper (or the old one
            is blocked): two near-equal ways round an obstacle must not take turns.
        confirm_no_route: Replans in a row that find no route before the robot stands
            still (one can be a map caught mid-update).
        lookahead_m: Distance along the route the command aims at [m].
        yaw_gain: Yaw rate per radian of heading error [1/s].
        max_yaw_rate: Largest yaw rate commanded [rad/s].
        turn_in_place_rad: Beyond this heading error the robot turns on the spot [rad].
        blocked_after_s: A walker frozen this long for want of footholds has its route
            blocked: the ground ahead of it is kept out of later routes [s].
        blocked_radius_m: Radius of the kept-out disc [m]; None: 0.15 m on the default robot.
        blocked_ahead_m: Its centre lies this far ahead of the body [m]; None: 0.25 m on the
            default robot.
        blocked_for_s: How long a kept-out disc stays [s].
    """

    traversability: TraversabilityConfig = field(default_factory=TraversabilityConfig)
    goal_tolerance_m: float = 0.08
    escape_radius_m: float | None = None
    escape_cost: float = 30.0
    replan_period_s: float = 0.5
    switch_margin: float = 0.4
    confirm_no_route: int = 3
    lookahead_m: float = 0.25
    yaw_gain: float = 1.0
    max_yaw_rate: float = 0.3
    turn_in_place_rad: float = math.radians(50.0)
    blocked_after_s: float = 1.5
    blocked_radius_m: float | None = None
    blocked_ahead_m: float | None = None
    blocked_for_s: float = 30.0

    def __post_init__(self) -> None:
        if not 0 <= self.switch_margin < 1:
            raise ConfigError(f"switch_margin must lie in [0, 1), got {self.switch_margin}")
        require_positive(
            "navigation",
            goal_tolerance_m=self.goal_tolerance_m,
            replan_period_s=self.replan_period_s,
            lookahead_m=self.lookahead_m,
            max_yaw_rate=self.max_yaw_rate,
            turn_in_place_rad=self.turn_in_place_rad,
            blocked_after_s=self.blocked_after_s,
            blocked_for_s=self.blocked_for_s,
        )
        require_non_negative(
            "navigation",
            escape_cost=self.escape_cost,
            yaw_gain=self.yaw_gain,
            **{k: v for k, v in self._robot_lengths().items() if v is not None},
        )
        if self.confirm_no_route < 1:
            raise ConfigError(f"confirm_no_route must be >= 1, got {self.confirm_no_route}")

    def _robot_lengths(self) -> dict[str, float | None]:
        return {name: getattr(self, name) for name in ROBOT_LENGTHS_M}

    def for_robot(self, spec: HexapodSpec) -> NavigationConfig:
        """This config with the lengths that follow the robot's span filled in where unset."""
        span = robot_scale(spec).span
        unset = [name for name, value in self._robot_lengths().items() if value is None]
        return replace(self, **{name: ROBOT_LENGTHS_M[name] * span for name in unset})


@dataclass(frozen=True)
class Route:
    """A route from the robot towards the goal.

    Attributes:
        points_in_world: Cell centres from the robot's cell on, shape (k, 2) [m]; the
            goal itself last when it lies beyond the map.
        cost: Route cost to the goal, on the grid it was planned on (beyond the map at the
            cost of unseen ground) [cost-weighted m].
        goal_on_map: Whether the grid held the goal.
    """

    points_in_world: npt.NDArray[np.float64]
    cost: float
    goal_on_map: bool


@dataclass(frozen=True)
class NoRoute:
    """Why no route reaches the goal."""

    reason: str


def plan_route(
    grid: CostGrid,
    start_in_world: npt.ArrayLike,
    goal_in_world: npt.ArrayLike,
    config: NavigationConfig,
    blocked: tuple[tuple[float, float, float], ...] = (),
    previous: Route | None = None,
) -> Route | NoRoute:
    """The least-cost route from the robot's position towards the goal.

    Args:
        grid: The cost grid.
        start_in_world: Body centre ``(x, y)`` [m].
        goal_in_world: Goal ``(x, y)`` [m], on the window or beyond it.
        config: Settings.
        blocked: Discs ``(x, y, radius)`` in the world kept out of the route [m].
        previous: The route being walked; the ground along it costs ``switch_margin``
            less.

    Raises:
        ConfigError: If the start lies outside the grid (the map follows the body).
    """
    start = np.asarray(start_in_world, dtype=np.float64)[:2]
    goal = np.asarray(goal_in_world, dtype=np.float64)[:2]
    si, sj = grid.cell_of(start)
    if not grid.contains((si, sj)):
        raise ConfigError(f"the robot at {start.round(3).tolist()} lies outside the cost grid")
    res = grid.resolution
    n, m = grid.shape
    centres_x = grid.origin[0] + (np.arange(n) + 0.5) * res
    centres_y = grid.origin[1] + (np.arange(m) + 0.5) * res
    cost = grid.cost.copy()
    for bx, by, radius in blocked:
        inside = (centres_x[:, None] - bx) ** 2 + (centres_y[None, :] - by) ** 2 <= radius**2
        cost[inside] = np.inf
    if previous is not None and config.switch_margin > 0:
        along = _near_polyline(grid, previous.points_in_world, 2.0 * res)
        cost[along] *= 1.0 - config.switch_margin
    near_start = (centres_x[:, None] - start[0]) ** 2 + (
        centres_y[None, :] - start[1]
    ) ** 2 <= config.escape_radius_m**2
    if not np.isfinite(cost[si, sj]):
        cost[near_start & ~np.isfinite(cost)] = config.escape_cost
    distance = np.empty((n, m))
    parent = np.empty((n, m), dtype=np.int64)
    dijkstra(cost, si, sj, res, distance, parent)

    to_goal = np.hypot(centres_x[:, None] - goal[0], centres_y[None, :] - goal[1])
    goal_cell = grid.cell_of(goal)
    if grid.contains(goal_cell):
        near_goal = to_goal <= max(config.goal_tolerance_m, res)
        if not np.isfinite(cost[near_goal]).any():
            return NoRoute(
                f"the goal ({goal[0]:.2f}, {goal[1]:.2f}) m lies on ground the robot cannot "
                "stand on"
            )
        candidates = np.where(near_goal, distance + to_goal, np.inf)
        if not np.isfinite(candidates).any():
            return NoRoute(
                f"no route to the goal ({goal[0]:.2f}, {goal[1]:.2f}) m: every way there "
                "crosses ground the robot cannot cross"
            )
        goal_on_map = True
    else:
        edge = np.zeros((n, m), dtype=bool)
        edge[0, :] = edge[-1, :] = edge[:, 0] = edge[:, -1] = True
        onward = 1.0 + config.traversability.unknown_cost
        candidates = np.where(edge, distance + onward * to_goal, np.inf)
        if not np.isfinite(candidates).any():
            return NoRoute(
                f"no route towards the goal ({goal[0]:.2f}, {goal[1]:.2f}) m: the mapped "
                "area is closed on every side the robot could leave it by"
            )
        goal_on_map = False
    flat = end_flat = int(np.argmin(candidates))
    cells = []
    while flat >= 0:
        cells.append((flat // m, flat % m))
        flat = int(parent[flat // m, flat % m])
    cells.reverse()
    centres = grid.centres_in_world(np.array(cells))
    centres[0] = start  # pulled straight from where the robot is, not its cell's centre
    points = taut(cost, grid, centres)
    if not goal_on_map:
        points = np.vstack([points, goal[None, :]])
    return Route(points, float(candidates.flat[end_flat]), goal_on_map)


def _samples(
    points: npt.NDArray[np.float64], step_m: float
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """Points every ``step_m`` or less along a polyline, and the length each stands for."""
    out, lengths = [points[:1]], [np.zeros(1)]
    for a, b in itertools.pairwise(points):
        length = float(np.linalg.norm(b - a))
        k = max(1, math.ceil(length / step_m))
        u = (np.arange(k) + 1.0) / k
        out.append(a + u[:, None] * (b - a))
        lengths.append(np.full(k, length / k))
    return np.vstack(out), np.concatenate(lengths)


def _near_polyline(
    grid: CostGrid, points: npt.NDArray[np.float64], radius_m: float
) -> npt.NDArray[np.bool_]:
    """Cells within ``radius_m`` of a polyline."""
    mask = np.zeros(grid.shape, dtype=bool)
    if len(points) < 2:
        return mask
    xy, _ = _samples(points, 0.5 * grid.resolution)
    ij = np.floor((xy - np.asarray(grid.origin)) / grid.resolution).astype(np.int64)
    n, m = grid.shape
    on = (ij[:, 0] >= 0) & (ij[:, 0] < n) & (ij[:, 1] >= 0) & (ij[:, 1] < m)
    mask[ij[on, 0], ij[on, 1]] = True
    return ndimage.binary_dilation(mask, iterations=max(1, round(radius_m / grid.resolution)))


def taut(
    cost: npt.NDArray[np.float64], grid: CostGrid, points: npt.NDArray[np.float64]
) -> npt.NDArray[np.float64]:
    """A grid path pulled straight where that costs no more per metre (string pulling).

    From each kept point the segment reaches on along the path for as long as it crosses
    no cell dearer than the dearest the path itself crosses meanwhile, and never a lethal
    one: the 8-connected zig-zags go, the detours stay (compiled:
    :func:`~footfall.planning.route_kernels.taut_indices`).
    """
    if len(points) <= 2:
        return points.copy()
    ox, oy = (float(v) for v in grid.origin)
    cells = np.ascontiguousarray(cost, dtype=np.float64)
    path = np.ascontiguousarray(points, dtype=np.float64)
    return points[taut_indices(cells, ox, oy, float(grid.resolution), path)].copy()


def _aim(
    points: npt.NDArray[np.float64], here: npt.NDArray[np.float64], lookahead_m: float
) -> npt.NDArray[np.float64]:
    """The point ``lookahead_m`` along the polyline from the point on it nearest ``here``."""
    if len(points) < 2:
        return points[-1]
    a, b = points[:-1], points[1:]
    d = b - a
    length_sq = np.maximum(np.sum(d * d, axis=1), 1e-18)
    u = np.clip(np.sum((here - a) * d, axis=1) / length_sq, 0.0, 1.0)
    foot = a + u[:, None] * d
    k = int(np.argmin(np.linalg.norm(foot - here, axis=1)))
    lengths = np.sqrt(length_sq)
    left = lookahead_m + u[k] * lengths[k]
    while k < len(lengths) - 1 and left > lengths[k]:
        left -= lengths[k]
        k += 1
    return a[k] + min(left / lengths[k], 1.0) * d[k]


def follow_route(
    route: Route, pose: PlanarPose, base: WalkCommand, config: NavigationConfig, stamp: float
) -> WalkCommand:
    """The walk command that follows ``route`` from ``pose`` (pure pursuit).

    Args:
        route: The route.
        pose: Body pose in the world.
        base: Speed and body height to walk at.
        config: Settings.
        stamp: Command time [s].
    """
    points = route.points_in_world
    here = np.array([pose.x, pose.y])
    aim = _aim(points, here, config.lookahead_m)
    dx, dy = float(aim[0] - here[0]), float(aim[1] - here[1])
    if math.hypot(dx, dy) < 1e-6:
        return WalkCommand(speed=0.0, body_height=base.body_height, stamp=stamp)
    heading = math.atan2(dy, dx)
    error = math.atan2(math.sin(heading - pose.yaw), math.cos(heading - pose.yaw))
    yaw_rate = float(np.clip(config.yaw_gain * error, -config.max_yaw_rate, config.max_yaw_rate))
    if abs(error) > config.turn_in_place_rad:
        return WalkCommand(speed=0.0, body_height=base.body_height, yaw_rate=yaw_rate, stamp=stamp)
    c, s = math.cos(pose.yaw), math.sin(pose.yaw)
    direction = (c * dx + s * dy, -s * dx + c * dy)
    speed = base.speed * max(0.0, math.cos(error)) ** 2
    return WalkCommand(direction, speed, base.body_height, yaw_rate, stamp)
