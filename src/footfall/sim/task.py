"""The task of a simulated walk (dm_control's task): commands towards the goal, and the end.

With a navigator (:mod:`footfall.nodes.navigation`) it walks the routes the navigator plans
on the map, round what cannot be crossed; without, it steers the robot along the straight
line from the terrain's start to its goal, aiming a little ahead on it (the thesis'
behaviour). Either way at the commanded speed, and it stops commanding motion once the goal
is reached. It decides when a run is over: a fall while walking (a limp robot in torque-off
lying down has not fallen), the goal (when asked to stop there), a robot frozen, or left
without a route, for ``FROZEN_TIMEOUT`` seconds.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from footfall.errors import ConfigError
from footfall.messages import GaitState, GaitStatus, Mode, ModeCommand, RobotState, WalkCommand
from footfall.metrics import fallen
from footfall.nodes.navigation import NavigatorNode
from footfall.runtime.bus import Bus
from footfall.sim.terrain import Terrain

# The goal counts as reached when the body is this close to it, or past it [m].
GOAL_TOLERANCE = 0.1
# A robot frozen this long with nothing changing ends the run [s].
FROZEN_TIMEOUT = 3.0
# How far ahead on the route the steering aims [m], and the largest yaw rate [rad/s].
AIM_AHEAD = 0.5
MAX_YAW_RATE = 0.3


class TerrainTask:
    """Walk from the terrain's start to its goal.

    Args:
        bus: The bus.
        terrain: The terrain (start, goal and the true ground for the fall rule).
        command: Speed and body height to walk at.
        stop_at_goal: End the run once the goal is reached.
        frozen_timeout: End the run once the robot has been frozen (or without a route)
            this long [s]; None never (an operator may still change its direction).
        goal: Goal ``(x, y)`` in the world [m]; the terrain's by default.
        navigator: Plans the routes walked; None walks the straight line.
    """

    name = "task"

    def __init__(
        self,
        bus: Bus,
        terrain: Terrain,
        command: WalkCommand,
        stop_at_goal: bool = False,
        frozen_timeout: float | None = FROZEN_TIMEOUT,
        goal: tuple[float, float] | None = None,
        navigator: NavigatorNode | None = None,
    ) -> None:
        self.bus = bus
        self.terrain = terrain
        self.base = command
        self.stop_at_goal = stop_at_goal
        self.frozen_timeout = frozen_timeout
        self.start = np.asarray(terrain.start, dtype=np.float64)
        self.goal = np.asarray(goal if goal is not None else terrain.goal, dtype=np.float64)
        if np.linalg.norm(self.goal - self.start) < GOAL_TOLERANCE:
            raise ConfigError(
                f"the goal {self.goal.tolist()} lies at the start {self.start.tolist()}"
            )
        self.navigator = navigator
        if navigator is not None:
            navigator.set_goal((float(self.goal[0]), float(self.goal[1])))
        self.route = (self.goal - self.start) / np.linalg.norm(self.goal - self.start)
        self.status: GaitStatus | None = None
        self.state: RobotState | None = None
        self._frozen_since: float | None = None
        bus.subscribe(GaitStatus.TOPIC, self._on_status, last=True)
        bus.subscribe(RobotState.TOPIC, self._on_state, last=True)

    def _on_status(self, message: GaitStatus) -> None:
        self.status = message

    def _on_state(self, message: RobotState) -> None:
        self.state = message

    def progress(self, xy: npt.ArrayLike) -> float:
        """Distance travelled along the route from the start [m]."""
        return float((np.asarray(xy) - self.start) @ self.route)

    def at_goal(self, xy: npt.ArrayLike) -> bool:
        """Whether a point is within ``GOAL_TOLERANCE`` of the goal (or past it, on a line)."""
        p = np.asarray(xy, dtype=np.float64)
        if self.navigator is not None:
            return float(np.linalg.norm(p - self.goal)) <= GOAL_TOLERANCE
        return self.progress(p) >= self.progress(self.goal) - GOAL_TOLERANCE

    def begin(self) -> None:
        """Switch the robot to walking."""
        self.bus.publish(ModeCommand.TOPIC, ModeCommand(Mode.WALKING))

    def command(self, t: float) -> WalkCommand:
        """Publish the command for controller time ``t`` [s] and return it."""
        assert self.status is not None, "the movement node publishes a status when it starts"
        pose = self.status.body_pose
        here = np.array([pose.x, pose.y])
        if self.navigator is not None:
            message = self.navigator.command(t, self.status, self.base)
            self.bus.publish(WalkCommand.TOPIC, message)
            return message
        if self.at_goal(here):
            message = WalkCommand(speed=0.0, body_height=self.base.body_height, stamp=t)
        else:
            aim = self.start + self.route * (self.progress(here) + AIM_AHEAD)
            heading = math.atan2(aim[1] - here[1], aim[0] - here[0])
            error = math.atan2(math.sin(heading - pose.yaw), math.cos(heading - pose.yaw))
            message = WalkCommand(
                speed=self.base.speed,
                body_height=self.base.body_height,
                yaw_rate=float(np.clip(error, -MAX_YAW_RATE, MAX_YAW_RATE)),
                stamp=t,
            )
        self.bus.publish(WalkCommand.TOPIC, message)
        return message

    def should_stop(self, t: float) -> bool:
        """Whether the run is over at time ``t`` [s] (after that tick)."""
        state, status = self.state, self.status
        if state is None or status is None or state.position_body_in_world is None:
            return False
        body = state.position_body_in_world
        ground = float(self.terrain.height(body[0], body[1]))
        if status.mode is Mode.WALKING and fallen(
            math.degrees(state.tilt),
            body[2] - ground,
            body[2],
            status.body_z,
            self.base.body_height,
        ):
            return True
        if self.stop_at_goal and self.at_goal(body[:2]):
            return True
        stuck = status.state is GaitState.FROZEN or (
            self.navigator is not None and self.navigator.no_route is not None
        )
        if stuck and self.frozen_timeout is not None:
            if self._frozen_since is None:
                self._frozen_since = t
            return t - self._frozen_since > self.frozen_timeout
        self._frozen_since = None
        return False
