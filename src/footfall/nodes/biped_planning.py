"""The biped's vision and planning node, with its services (dissertation A6, Appendix B3).

It holds the obstacles and plans on request. ``start_capture`` starts taking obstacles from
its source (a map's circles, or the obstacles detected in a point cloud, standing in for the
dissertation's stereo camera and SLAM) and publishing them; ``stop_capture`` stops;
``new_map(ox[], oy[])`` replaces them with circles of one radius; ``clear`` removes them;
``start_planning(gx, gy)`` plans the path around them, the footsteps and the centre-of-mass
pattern from the robot's start to the goal and publishes the plan. Every service answers
with an :class:`~footfall.messages.Ack` that says what it did, or why it could not.

On a robot with a body the source is its head camera (each look updates what is
remembered), the start is where the robot stands now, the plan uses the body's footprint,
and a goal that was planned to is handed on to the walking node.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence

import numpy as np

from footfall.biped.avoidance import Circle
from footfall.biped.maps import PlanMap
from footfall.biped.planner import WalkPlan, plan_walk
from footfall.errors import FootfallError
from footfall.messages import Ack, BipedPlan, NewMap, Obstacles, PlanningGoal, Trigger
from footfall.runtime.bus import Bus

SERVICES = ("start_capture", "stop_capture", "start_planning", "new_map", "clear")


Look = Callable[[tuple[Circle, ...]], Sequence[Circle]]


class BipedPlanningNode:
    """Obstacles, path, footsteps and the COM pattern, as services.

    Args:
        bus: The bus.
        source: The obstacles a capture sees, or a look: what is remembered in, what is
            seen now (remembered or updated) out.
        start: Where the robot stands [m], or a function that says it.
        name: Name of the map (for the plan).
        planner: Plans a map (the footprint of a body may grow its obstacles).
        on_goal: Called with a goal once a plan reaches it; says what the robot does next.
        look_period_s: While capturing, look at most this often [s] (0: every tick).
    """

    name = "biped_planning"

    def __init__(
        self,
        bus: Bus,
        source: Sequence[Circle] | Look,
        start: tuple[float, float] | Callable[[], tuple[float, float]] = (0.0, 0.0),
        name: str = "capture",
        planner: Callable[[PlanMap], WalkPlan] = plan_walk,
        on_goal: Callable[[tuple[float, float]], str] | None = None,
        look_period_s: float = 0.0,
    ) -> None:
        self.bus = bus
        if callable(source):
            self._look = source
        else:
            seen = tuple(source)
            self._look = lambda _known: seen
        self._start = start if callable(start) else (lambda: start)
        self.map_name = name
        self.planner = planner
        self.on_goal = on_goal
        self.look_period_s = look_period_s
        self.obstacles: tuple[Circle, ...] = ()
        self.capturing = False
        self._next_look = 0.0
        for service, handler in zip(
            SERVICES,
            (self._start_capture, self._stop_capture, self._plan, self._new_map, self._clear),
            strict=True,
        ):
            bus.serve(service, handler)

    def _publish_obstacles(self) -> None:
        c = self.obstacles
        self.bus.publish(
            Obstacles.TOPIC,
            Obstacles(
                time.time(),
                np.array([o.x for o in c]),
                np.array([o.y for o in c]),
                np.array([o.r for o in c]),
            ),
        )

    def tick(self) -> None:
        """While capturing, look (when due) and publish what the capture sees."""
        now = time.monotonic()
        if self.capturing and now >= self._next_look:
            self._next_look = now + self.look_period_s
            self.obstacles = tuple(self._look(self.obstacles))
            self._publish_obstacles()

    def _start_capture(self, request: Trigger) -> Ack:
        self.capturing = True
        self._next_look = 0.0
        self.tick()
        return Ack(True, f"capturing: {len(self.obstacles)} obstacles in view")

    def _stop_capture(self, request: Trigger) -> Ack:
        self.capturing = False
        return Ack(True, f"capture stopped with {len(self.obstacles)} obstacles")

    def _new_map(self, request: NewMap) -> Ack:
        self.capturing = False
        self.obstacles = tuple(
            Circle(float(x), float(y), float(request.radius))
            for x, y in zip(request.ox, request.oy, strict=True)
        )
        self._publish_obstacles()
        return Ack(True, f"new map of {len(self.obstacles)} obstacles")

    def _clear(self, request: Trigger) -> Ack:
        self.capturing = False
        self.obstacles = ()
        self._publish_obstacles()
        return Ack(True, "obstacles cleared")

    def plan_to(self, goal: tuple[float, float]) -> WalkPlan:
        """Plan from where the robot stands to ``goal``, and publish the plan.

        While capturing, the capture looks first.

        Raises:
            FootfallError: No plan: the goal in an obstacle, no route round them.
        """
        if self.capturing:
            self._next_look = 0.0
            self.tick()
        start = tuple(float(v) for v in self._start())
        plan = self.planner(PlanMap(self.map_name, start, goal, self.obstacles))
        f = plan.footsteps
        footsteps = np.column_stack([f.positions, f.headings])
        self.bus.publish(
            BipedPlan.TOPIC,
            BipedPlan(
                time.time(),
                plan.path.waypoints,
                footsteps,
                np.array([side == "left" for side in f.sides]),
                plan.pattern.com,
                plan.path.length,
                plan.collisions,
            ),
        )
        return plan

    def _plan(self, request: PlanningGoal) -> Ack:
        goal = (float(request.gx), float(request.gy))
        try:
            plan = self.plan_to(goal)
        except FootfallError as exc:
            return Ack(False, str(exc))
        text = (
            f"planned {plan.path.length:.2f} m, {len(plan.footsteps.positions)} footsteps, "
            f"{plan.collisions} collisions in {plan.plan_ms:.1f} ms"
        )
        if self.on_goal is not None:
            text += f"; {self.on_goal(goal)}"
        return Ack(True, text)
