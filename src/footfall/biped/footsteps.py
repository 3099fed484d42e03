"""Footsteps from waypoints (dissertation §6.3.3, eqs. 95-98, Table 9).

The robot starts with its feet side by side, the COM between them; the first step is the
right foot. Along each segment of the path it takes steps of at most ``max_length``, the
last step of a segment taking the remainder; at a waypoint where the heading changes it
turns on the spot, both feet rotating by at most ``max_turn`` a step; at the goal the
feet come side by side again. Steps are walk parameters ``(s_x, s_y, s_theta)``; the
footsteps follow from eq. 96 (the same relation the walking pattern uses).

Erratum: the printed eq. 98 offsets each foot ``s_y`` from the COM line; with ``s_y``
the distance between the feet (Table 9) the offset is ``s_y / 2``, which eq. 96 gives.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from footfall.biped.lipm import WalkParameter
from footfall.errors import ConfigError, PlanningError

# The shortest step limit and the smallest turn a step may be limited to [m], [rad]: below
# them a plan would take millions of steps.
MIN_STEP_LENGTH = 0.005
MIN_TURN = math.radians(0.5)
# The most steps a plan may take.
MAX_STEPS = 100_000


@dataclass(frozen=True)
class StepLimits:
    """Limits of one step.

    Attributes:
        max_length: Longest step along the walk [m].
        width: Distance between the feet, across the walk [m].
        max_turn: Largest heading change of one step [rad].
    """

    max_length: float = 0.15
    width: float = 0.2
    max_turn: float = math.radians(30.0)

    def __post_init__(self) -> None:
        values = (self.max_length, self.width, self.max_turn)
        if not all(math.isfinite(v) for v in values):
            raise ConfigError(f"step limits must be finite numbers, got {values}")
        if not (MIN_STEP_LENGTH <= self.max_length and self.width > 0):
            raise ConfigError(
                f"step max_length must be at least {MIN_STEP_LENGTH} m and width positive, "
                f"got {self.max_length}, {self.width}"
            )
        if not MIN_TURN <= self.max_turn <= math.pi:
            raise ConfigError(
                f"step max_turn must lie in [{math.degrees(MIN_TURN):g}, 180] degrees, "
                f"got {math.degrees(self.max_turn):g}"
            )


def _wrap(angle: float) -> float:
    return math.atan2(math.sin(angle), math.cos(angle))


def walk_parameters(
    waypoints: npt.ArrayLike, limits: StepLimits, initial_heading: float = 0.0
) -> list[WalkParameter]:
    """Walk parameters that carry the COM along the waypoints (the algorithm of §6.3.3).

    Args:
        waypoints: Path from the start (the COM's ground point) to the goal, shape (k, 2) [m].
        limits: Step limits.
        initial_heading: Heading of the feet at the start [rad].

    Returns:
        One parameter per support phase: the first support, the steps, the closing step.
    """
    points = np.asarray(waypoints, dtype=np.float64)
    if not np.all(np.isfinite(points)) or not math.isfinite(initial_heading):
        raise PlanningError("waypoints and the initial heading must be finite numbers")
    length = float(np.sum(np.hypot(*np.diff(points, axis=0).T))) if len(points) > 1 else 0.0
    turns_budget = (len(points) + 1) * math.ceil(math.pi / limits.max_turn)
    if length / limits.max_length + 2 * turns_budget > MAX_STEPS:
        raise PlanningError(
            f"a path of {length:.3g} m with {len(points)} waypoints needs more than "
            f"{MAX_STEPS} steps of at most {limits.max_length} m"
        )
    heading = initial_heading
    params = [WalkParameter(0.0, limits.width, heading)]
    for a, b in itertools.pairwise(points):
        delta = b - a
        distance = float(np.hypot(*delta))
        if distance < 1e-9:
            continue
        target = math.atan2(delta[1], delta[0])
        turn = _wrap(target - heading)
        # Turn on the spot: pairs of steps so both feet end on the new heading.
        turns = math.ceil(abs(turn) / limits.max_turn - 1e-9)
        for k in range(1, turns + 1):
            h = heading + turn * k / turns
            params += [WalkParameter(0.0, limits.width, h), WalkParameter(0.0, limits.width, h)]
        heading = target
        full = math.floor(distance / limits.max_length + 1e-9)
        lengths = [limits.max_length] * full
        remainder = distance - full * limits.max_length
        if remainder > 1e-9:
            lengths.append(remainder)
        params += [WalkParameter(length, limits.width, heading) for length in lengths]
    params.append(WalkParameter(0.0, limits.width, heading))
    return params


@dataclass(frozen=True)
class Footsteps:
    """Footsteps of a walk.

    Attributes:
        positions: Foot centres, shape (m, 2) [m]; the first is the initial support foot.
        headings: Foot headings, shape (m,) [rad].
        sides: ``"left"`` or ``"right"`` per footstep.
        parameters: The walk parameters they come from.
    """

    positions: npt.NDArray[np.float64]
    headings: npt.NDArray[np.float64]
    sides: tuple[str, ...]
    parameters: tuple[WalkParameter, ...]


def footsteps_from_parameters(
    params: list[WalkParameter], start: npt.ArrayLike = (0.0, 0.0), first_step_left: bool = False
) -> Footsteps:
    """Footsteps around the COM path the walk parameters trace (eqs. 97-98).

    The COM advances ``s_x`` along the heading ``s_theta`` each step (eq. 97); each foot
    lies half a step width beside it, alternating sides (eq. 98, with ``s_y / 2``). A turn
    on the spot rotates the feet about the COM. The first support foot stands opposite to
    the first step.
    """
    com = np.asarray(start, dtype=np.float64).copy()
    first = 1.0 if first_step_left else -1.0  # side of step 1: +1 left, -1 right
    positions, headings, sides = [], [], []
    for n, p in enumerate(params):
        com = com + p.length * np.array([math.cos(p.heading), math.sin(p.heading)])
        side = first if n % 2 == 1 else -first
        normal = np.array([-math.sin(p.heading), math.cos(p.heading)])  # to the left
        positions.append(com + side * 0.5 * p.width * normal)
        headings.append(p.heading)
        sides.append("left" if side > 0 else "right")
    return Footsteps(np.array(positions), np.array(headings), tuple(sides), tuple(params))


def plan_footsteps(
    waypoints: npt.ArrayLike, limits: StepLimits, initial_heading: float = 0.0
) -> Footsteps:
    """Footsteps along a path, first step right, turns on the spot (§6.3.3)."""
    points = np.asarray(waypoints, dtype=np.float64)
    params = walk_parameters(points, limits, initial_heading)
    return footsteps_from_parameters(params, points[0], first_step_left=False)
