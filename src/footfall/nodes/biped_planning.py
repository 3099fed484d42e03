"""The biped's vision and planning node, with its services (dissertation A6, Appendix B3).

It holds the obstacles and plans on request. ``start_capture`` starts taking obstacles from
its source (a map's circles, or the obstacles detected in a point cloud, standing in for the
dissertation's stereo camera and SLAM) and publishing them; ``stop_capture`` stops;
``new_map(ox[], oy[])`` replaces them with circles of one radius; ``clear`` removes them;
``start_planning(gx, gy)`` plans the path around them, the footsteps and the centre-of-mass
pattern from the robot's start to the goal and publishes the plan. Every service answers
with an :class:`~footfall.messages.Ack` that says what it did, or why it could not.
"""

from __future__ import annotations

import time
from collections.abc import Sequence

import numpy as np

from footfall.biped.avoidance import Circle
from footfall.biped.maps import PlanMap
from footfall.biped.planner import plan_walk
from footfall.errors import FootfallError
from footfall.messages import Ack, BipedPlan, NewMap, Obstacles, PlanningGoal, Trigger
from footfall.runtime.bus import Bus

SERVICES = ("start_capture", "stop_capture", "start_planning", "new_map", "clear")


class BipedPlanningNode:
    """Obstacles, path, footsteps and the COM pattern, as services.

    Args:
        bus: The bus.
        source: The obstacles a capture sees.
        start: Where the robot stands [m].
        name: Name of the map (for the plan).
    """

    name = "biped_planning"

    def __init__(
        self,
        bus: Bus,
        source: Sequence[Circle],
        start: tuple[float, float] = (0.0, 0.0),
        name: str = "capture",
    ) -> None:
        self.bus = bus
        self.source = tuple(source)
        self.start = start
        self.map_name = name
        self.obstacles: tuple[Circle, ...] = ()
        self.capturing = False
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
        """While capturing, publish what the capture sees."""
        if self.capturing:
            self.obstacles = self.source
            self._publish_obstacles()

    def _start_capture(self, request: Trigger) -> Ack:
        self.capturing = True
        self.tick()
        return Ack(True, f"capturing: {len(self.source)} obstacles in view")

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

    def _plan(self, request: PlanningGoal) -> Ack:
        goal = (float(request.gx), float(request.gy))
        try:
            plan = plan_walk(PlanMap(self.map_name, self.start, goal, self.obstacles))
        except FootfallError as exc:
            return Ack(False, str(exc))
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
        return Ack(
            True,
            f"planned {plan.path.length:.2f} m, {len(f.positions)} footsteps, "
            f"{plan.collisions} collisions in {plan.plan_ms:.1f} ms",
        )
