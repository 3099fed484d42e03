"""The biped's plan: path around obstacles -> footsteps -> centre-of-mass pattern."""

from __future__ import annotations

import itertools
import time
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from footfall.biped.avoidance import AvoidancePath, Circle, plan_path, segment_distance
from footfall.biped.footsteps import Footsteps, plan_footsteps
from footfall.biped.lipm import LipmConfig, LipmPattern, lipm_pattern
from footfall.biped.maps import FOOT_LENGTH, PlanMap

# Foot sole width, with the length used to check footsteps against obstacles and draw them [m].
FOOT_WIDTH = 0.06


@dataclass(frozen=True)
class WalkPlan:
    """A planned walk.

    Attributes:
        map: The problem.
        path: Waypoints around the inflated obstacles.
        footsteps: Footsteps along the path.
        pattern: COM pattern over the footsteps.
        plan_ms: Time the path search took [ms].
        collisions: Path samples inside an inflated obstacle plus footsteps touching an
            obstacle (0 for a good plan).
    """

    map: PlanMap
    path: AvoidancePath
    footsteps: Footsteps
    pattern: LipmPattern
    plan_ms: float
    collisions: int

    def to_json(self) -> dict[str, object]:
        """The ``plan.json`` content."""
        f = self.footsteps
        return {
            "map": self.map.name,
            "start": list(self.map.start),
            "goal": list(self.map.goal),
            "waypoints": self.path.waypoints.tolist(),
            "path_length_m": self.path.length,
            "plan_ms": self.plan_ms,
            "collisions": self.collisions,
            "footsteps": [
                {"x": float(p[0]), "y": float(p[1]), "heading_rad": float(h), "side": s}
                for p, h, s in zip(f.positions, f.headings, f.sides, strict=True)
            ],
            "walk_parameters": [
                {"s_x": p.length, "s_y": p.width, "s_theta": p.heading} for p in f.parameters
            ],
            "modified_footsteps": self.pattern.modified_footsteps.tolist(),
            "com": [
                {"t": float(t), "x": float(c[0]), "y": float(c[1])}
                for t, c in zip(self.pattern.time, self.pattern.com, strict=True)
            ],
        }


def path_collisions(
    waypoints: npt.NDArray[np.float64], obstacles: list[Circle], spacing: float = 0.01
) -> int:
    """Samples of the path (every ``spacing`` m) that lie inside an obstacle."""
    count = 0
    for a, b in itertools.pairwise(waypoints):
        n = max(2, int(np.ceil(np.linalg.norm(b - a) / spacing)) + 1)
        samples = a + np.linspace(0.0, 1.0, n)[:, None] * (b - a)
        for c in obstacles:
            count += int(np.sum(np.hypot(*(samples - c.centre).T) < c.r - 1e-6))
    return count


def footstep_collisions(footsteps: Footsteps, obstacles: list[Circle]) -> int:
    """Footsteps whose sole (a rectangle around the foot centre) overlaps an obstacle."""
    count = 0
    for p, h in zip(footsteps.positions, footsteps.headings, strict=True):
        forward = np.array([np.cos(h), np.sin(h)]) * FOOT_LENGTH / 2
        count += any(
            segment_distance(p - forward, p + forward, c.centre) < c.r + FOOT_WIDTH / 2
            for c in obstacles
        )
    return count


def plan_walk(plan_map: PlanMap, lipm: LipmConfig | None = None) -> WalkPlan:
    """Plan the path, the footsteps and the COM pattern for a map.

    Raises:
        PlanningError: When the start or goal is inside an obstacle, or no path exists.
    """
    inflated = plan_map.inflated
    t0 = time.perf_counter()
    path = plan_path(plan_map.start, plan_map.goal, inflated)
    plan_ms = 1e3 * (time.perf_counter() - t0)
    footsteps = plan_footsteps(path.waypoints, plan_map.limits)
    # The walk starts from standing on both feet: the pendulum's first support point is the
    # middle of the stance, under the COM, not the first foot (which would tip it over).
    support = footsteps.positions.copy()
    support[0] = plan_map.start
    pattern = lipm_pattern(
        list(footsteps.parameters),
        lipm,
        initial_com=plan_map.start,
        footsteps=support,
        first_step_left=False,
    )
    collisions = path_collisions(path.waypoints, inflated) + footstep_collisions(
        footsteps, list(plan_map.obstacles)
    )
    return WalkPlan(plan_map, path, footsteps, pattern, plan_ms, collisions)
