"""Planning maps: start, goal, obstacles and the robot's step limits (the "load map" service).

A map file is JSON::

    {
      "name": "my room",
      "start": [0.0, 0.0],
      "goal": [4.0, 0.0],
      "hip_width": 0.2,                       # [m]; obstacles are inflated by half of it
      "step": {"max_length": 0.15, "width": 0.2, "max_turn_deg": 30},   # optional
      "obstacles": [
        {"x": 1.0, "y": 1.0, "r": 0.2},                                   # a circle [m]
        {"box": {"x": 2.0, "y": 0.0, "width": 1.2, "depth": 0.3, "yaw_deg": 90}}
      ]
    }

Boxes become circles as obstacles from a point cloud do (eqs. 79-81, :func:`box_circles`).
The dissertation's 11 test maps (§6.3.2) ship as :func:`dissertation_map`; their obstacles are
circles of radius 0.2 m (the text gives only the centres).
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import numpy.typing as npt

from footfall.biped.avoidance import Circle
from footfall.biped.footsteps import StepLimits
from footfall.errors import ConfigError

TEST_CASE_RADIUS = 0.2  # [m]
FOOT_LENGTH = 0.12  # sole length [m]
DEFAULT_HIP_WIDTH = 0.2  # [m]
# The largest coordinate or radius a map may hold [m].
MAX_COORDINATE = 1e5
# A box longer than this many times its width is refused (as many circles would cover it).
MAX_BOX_CIRCLES = 1000


def box_circles(
    centre: npt.ArrayLike, width: float, depth: float, yaw: float = 0.0
) -> list[Circle]:
    """Circles covering a box (eqs. 79-81).

    When width and depth agree within 10 %, one circle through the corners; otherwise a
    chain of ``n = ceil(long / short)`` circles along the long axis, each of radius
    ``short * cos(45 deg)`` so that together they cover the box (eq. 80 as intended).

    Args:
        centre: Box centre, shape (2,) [m].
        width: Extent along the box's own x axis [m].
        depth: Extent along its y axis [m].
        yaw: Heading of the box's x axis [rad].
    """
    if not all(math.isfinite(v) for v in (width, depth, yaw)) or not (width > 0 and depth > 0):
        raise ConfigError(
            f"a box needs finite positive width and depth and a finite yaw, got "
            f"{width}, {depth}, {yaw}"
        )
    c = np.asarray(centre, dtype=np.float64)
    if c.shape != (2,) or not np.all(np.isfinite(c)):
        raise ConfigError(f"a box centre must be two finite numbers, got {centre!r}")
    if max(width, depth) / min(width, depth) > MAX_BOX_CIRCLES:
        raise ConfigError(
            f"a {width} m x {depth} m box would take more than {MAX_BOX_CIRCLES} circles"
        )
    long_side, short_side = max(width, depth), min(width, depth)
    axis_angle = yaw if width >= depth else yaw + math.pi / 2
    axis = np.array([math.cos(axis_angle), math.sin(axis_angle)])
    if long_side <= 1.1 * short_side:
        return [Circle(float(c[0]), float(c[1]), 0.5 * math.hypot(width, depth))]
    n = math.ceil(long_side / short_side)
    r = short_side * math.cos(math.pi / 4)
    spacing = long_side / n
    offsets = (np.arange(n) + 0.5) * spacing - 0.5 * long_side
    return [Circle(float(p[0]), float(p[1]), r) for p in c + offsets[:, None] * axis]


@dataclass(frozen=True)
class PlanMap:
    """A planning problem.

    Attributes:
        name: Label.
        start: Start of the COM's ground point, shape (2,) [m].
        goal: Goal, shape (2,) [m].
        obstacles: Obstacle circles, not inflated.
        hip_width: The robot's hip width [m].
        limits: Step limits.
    """

    name: str
    start: tuple[float, float]
    goal: tuple[float, float]
    obstacles: tuple[Circle, ...]
    hip_width: float = DEFAULT_HIP_WIDTH
    limits: StepLimits = field(default_factory=StepLimits)

    def __post_init__(self) -> None:
        if not (math.isfinite(self.hip_width) and self.hip_width > 0):
            raise ConfigError(f"hip_width must be a positive number, got {self.hip_width}")
        for what, point in (("start", self.start), ("goal", self.goal)):
            if not all(math.isfinite(v) and abs(v) <= MAX_COORDINATE for v in point):
                raise ConfigError(
                    f"map {what} must be finite coordinates within {MAX_COORDINATE:g} m, "
                    f"got {point}"
                )
        for c in self.obstacles:
            if not all(math.isfinite(v) and abs(v) <= MAX_COORDINATE for v in (c.x, c.y, c.r)):
                raise ConfigError(
                    f"obstacle ({c.x}, {c.y}, r={c.r}) must hold finite numbers within "
                    f"{MAX_COORDINATE:g} m"
                )
            if not c.r > 0:
                raise ConfigError(f"obstacle at ({c.x}, {c.y}) has a non-positive radius {c.r}")

    @property
    def inflation(self) -> float:
        """How much obstacles grow for planning [m].

        Half the hip width (the outer circles of Fig. 80), plus half a foot: a foot centred
        half the hip width off the path still reaches half its length further (a turn on
        the spot points it anywhere).
        """
        return 0.5 * self.hip_width + 0.5 * FOOT_LENGTH

    @property
    def inflated(self) -> list[Circle]:
        """Obstacles grown by :attr:`inflation`."""
        return [Circle(c.x, c.y, c.r + self.inflation) for c in self.obstacles]

    def with_endpoints(
        self, start: npt.ArrayLike | None = None, goal: npt.ArrayLike | None = None
    ) -> PlanMap:
        """The same map with another start and/or goal."""
        from dataclasses import replace

        s = self.start if start is None else (float(start[0]), float(start[1]))
        g = self.goal if goal is None else (float(goal[0]), float(goal[1]))
        return replace(self, start=s, goal=g)


def map_from_dict(data: dict, name: str = "map") -> PlanMap:
    """Build a :class:`PlanMap` from the parsed JSON layout.

    Raises:
        ConfigError: On a missing key or a malformed entry (named).
    """
    if not isinstance(data, dict):
        raise ConfigError(f"a map is a JSON object, got {type(data).__name__}")
    try:
        obstacles: list[Circle] = []
        for k, entry in enumerate(data.get("obstacles", [])):
            if "box" in entry:
                b = entry["box"]
                obstacles += box_circles(
                    (b["x"], b["y"]),
                    float(b["width"]),
                    float(b["depth"]),
                    math.radians(float(b.get("yaw_deg", 0.0))),
                )
            elif {"x", "y", "r"} <= entry.keys():
                obstacles.append(Circle(float(entry["x"]), float(entry["y"]), float(entry["r"])))
            else:
                raise ConfigError(
                    f"obstacle {k} is neither a circle {{x, y, r}} nor a box: {entry}"
                )
        step = data.get("step", {})
        limits = StepLimits(
            max_length=float(step.get("max_length", StepLimits.max_length)),
            width=float(step.get("width", StepLimits.width)),
            max_turn=math.radians(
                float(step.get("max_turn_deg", math.degrees(StepLimits.max_turn)))
            ),
        )
        start, goal = data["start"], data["goal"]
        return PlanMap(
            name=str(data.get("name", name)),
            start=(float(start[0]), float(start[1])),
            goal=(float(goal[0]), float(goal[1])),
            obstacles=tuple(obstacles),
            hip_width=float(data.get("hip_width", DEFAULT_HIP_WIDTH)),
            limits=limits,
        )
    except KeyError as exc:
        raise ConfigError(f"map is missing the key {exc}") from exc
    except (TypeError, ValueError, IndexError, AttributeError, OverflowError) as exc:
        if isinstance(exc, ConfigError):
            raise
        raise ConfigError(f"map has a malformed entry: {exc}") from exc


def load_map(path: str | Path) -> PlanMap:
    """Read a JSON map file.

    Raises:
        ConfigError: When the file is missing, not JSON, or malformed.
    """
    p = Path(path)
    if not p.is_file():
        raise ConfigError(f"map file {p} does not exist")
    try:
        data = json.loads(p.read_text(encoding="utf-8"))
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise ConfigError(f"map file {p} is not JSON: {exc}") from exc
    except RecursionError as exc:
        raise ConfigError(f"map file {p} nests too deeply") from exc
    return map_from_dict(data, name=p.stem)


_ROW = [(1.0, 1.0), (1.5, 1.0), (2.0, 1.0)]
_SEVENTH = [
    *_ROW,
    (2.0, 2.0),
    (3.0, 2.0),
    (2.0, 4.0),
    (3.0, 0.0),
    (0.5, -1.0),
    (1.0, -1.0),
    (1.5, -1.0),
]
# The dissertation's test maps (§6.3.2, Figs. 86-95): obstacle centres and goals, start (0, 0).
# Maps 1 and 2 (Fig. 86) show an elongated obstacle as a chain of circles; the text gives no
# numbers, so they are a 1.2 m x 0.3 m wall across the way and one along it.
_CASES: dict[int, tuple[list, tuple[float, float]]] = {
    1: ([{"box": {"x": 1.5, "y": 0.0, "width": 1.2, "depth": 0.3, "yaw_deg": 90.0}}], (3.0, 0.0)),
    2: ([{"box": {"x": 1.5, "y": 0.35, "width": 1.6, "depth": 0.3, "yaw_deg": 0.0}}], (3.0, 0.6)),
    3: ([*_ROW, (0.0, 3.0), (3.0, 0.0)], (4.0, 0.0)),
    4: ([*_ROW, (0.0, 3.0)], (2.0, 3.0)),
    5: (
        [(1.0, 1.0), (1.0, 1.5), (1.0, 2.0), (0.0, 3.0), (2.0, 2.0), (2.0, 3.0), (4.0, 2.0)],
        (4.0, 4.0),
    ),
    6: ([(1.0, 1.0), (1.5, 1.0), (3.0, 1.0), (3.0, 2.0), (2.0, 2.5), (-0.5, 1.5)], (4.0, 3.0)),
    7: (_SEVENTH, (5.0, 2.0)),
    8: ([*_SEVENTH, (0.0, -2.0)], (4.0, 2.0)),
    9: ([*_SEVENTH, (0.0, -2.0)], (1.0, -3.0)),
    10: ([*_SEVENTH, (0.0, -2.0)], (5.0, 1.0)),
    11: ([*_SEVENTH, (0.0, -2.0)], (3.0, 5.0)),
}
TEST_CASES = tuple(sorted(_CASES))


def dissertation_map(number: int) -> PlanMap:
    """The dissertation's test map ``number`` (1 to 11).

    Raises:
        ConfigError: For a number outside 1..11.
    """
    if number not in _CASES:
        raise ConfigError(f"test case {number} does not exist; choose 1 to {len(_CASES)}")
    entries, goal = _CASES[number]
    obstacles = [
        e if isinstance(e, dict) else {"x": e[0], "y": e[1], "r": TEST_CASE_RADIUS} for e in entries
    ]
    return map_from_dict(
        {"start": [0.0, 0.0], "goal": list(goal), "obstacles": obstacles}, name=f"case {number}"
    )
