"""Seeded rooms for the biped: boxes and cylinders between a start and a goal.

A room is 6 m long: the robot starts at the origin facing +x and its goal lies 5 m ahead
on the far side. Between them stand four to seven obstacles (boxes of random size and
heading, upright cylinders), at least one of them across the straight line, none closer
than 0.9 m to the start or the goal; a layout is kept only when a route exists for the
robot's body around the obstacles' true footprints, so every room can be crossed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from footfall.biped.avoidance import Circle, plan_path
from footfall.errors import PlanningError
from footfall.sim.biped_model import Obstacle

ROOM_LENGTH = 6.0  # [m]
GOAL_DISTANCE = 5.0  # [m]
HALF_WIDTH = 1.6  # obstacles stand within this distance of the centre line [m]
KEEP_CLEAR = 0.9  # around the start and the goal [m]
ROUTE_CLEARANCE = 0.32  # body reach plus margin the route check inflates obstacles by [m]
MAX_TRIES = 200


@dataclass(frozen=True)
class Room:
    """A room: where the walk starts, where it ends, what stands in the way."""

    name: str
    start: tuple[float, float]
    goal: tuple[float, float]
    obstacles: tuple[Obstacle, ...]

    def circles(self) -> list[Circle]:
        """Each obstacle's covering circle (its true footprint, for checks and plots)."""
        return [Circle(o.x, o.y, o.radius) for o in self.obstacles]


def _draw(rng: np.random.Generator, across: bool) -> Obstacle:
    x = float(rng.uniform(1.2, GOAL_DISTANCE - 1.0))
    y = float(rng.uniform(-0.3, 0.3) if across else rng.uniform(-HALF_WIDTH, HALF_WIDTH))
    height = float(rng.uniform(0.4, 0.9))
    if rng.random() < 0.5:
        d = float(rng.uniform(0.2, 0.45))
        return Obstacle("cylinder", x, y, d, d, height)
    sx, sy = (float(v) for v in rng.uniform(0.2, 0.5, 2))
    return Obstacle("box", x, y, sx, sy, height, float(rng.uniform(0, math.pi)))


def make_room(seed: int) -> Room:
    """The room of a seed (the same seed, the same room)."""
    rng = np.random.default_rng(seed)
    start, goal = np.zeros(2), np.array([GOAL_DISTANCE, 0.0])
    for _ in range(MAX_TRIES):
        count = int(rng.integers(4, 8))
        placed: list[Obstacle] = []
        for _k in range(count * 20):
            if len(placed) == count:
                break
            o = _draw(rng, across=not placed)
            c = np.array([o.x, o.y])
            if min(np.hypot(*(c - start)), np.hypot(*(c - goal))) < KEEP_CLEAR + o.radius:
                continue
            if all(np.hypot(o.x - p.x, o.y - p.y) > o.radius + p.radius + 0.1 for p in placed):
                placed.append(o)
        inflated = [Circle(o.x, o.y, o.radius + ROUTE_CLEARANCE) for o in placed]
        try:
            plan_path(start, goal, inflated)
        except PlanningError:
            continue
        return Room(f"room {seed}", (0.0, 0.0), (GOAL_DISTANCE, 0.0), tuple(placed))
    raise PlanningError(f"no passable room found for seed {seed} in {MAX_TRIES} layouts")
