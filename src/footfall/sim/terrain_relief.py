"""Terrains a foot can fall into or must climb: stepping stones, gaps, pits, ramps.

- ``stepping_stones``: square stones with ``gap`` between them over a pit ``depth`` deep;
  the robot starts and ends on platforms level with the stones' mean top.
- ``gaps``: platforms of seeded length with trenches ``width`` wide and ``depth`` deep
  between them, across the whole way.
- ``pits``: square pits ``depth`` deep, sides of seeded size in ``size``, sunk into the floor
  (a height field).
- ``ramps``: a ramp up at ``slope_deg``, a landing, a ramp down (a height field).

The stepping stones and the gaps stand on a pit floor at ``-depth`` inside their arena, with
nothing under the arena's edge but the simulator's plane far below. ``height(x, y)`` is the
MuJoCo geometry's surface (to the height field's 1 cm sampling for the pits and ramps).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np
import numpy.typing as npt

from footfall.errors import ConfigError
from footfall.robot.limits import longest_step_m, steepest_slope_rad
from footfall.robot.spec import HexapodSpec
from footfall.sim.terrain import Terrain, TerrainXml, height_field_xml
from footfall.sim.terrain_obstacles import Box, boxes_height, scatter

# Below a sunken terrain's arena lies the simulator's plane, this deep [m].
VOID_Z = -1.0
# Sunken arenas reach this far behind the start and past the goal [m], and this wide.
ARENA_BEHIND = 1.5
ARENA_BEYOND = 1.0
ARENA_HALF_WIDTH = 1.5


def _gap_too_wide(what: str, width: float, spec: HexapodSpec) -> str:
    """Why a gap ``width`` wide cannot be stepped over by the robot ("" if it can)."""
    need = width + 2.0 * spec.foot_radius  # from the near edge to the far one, foot and all
    longest = longest_step_m(spec)
    if need <= longest:
        return ""
    return (
        f"{what} {width:g} m wide need a step of {need:.3f} m from edge to edge; the "
        f"farthest a foot of the {spec.name} robot travels in one swing is {longest:.3f} m "
        "(twice its leg's reach along the way)"
    )


def _sunken_xml(
    prefix: str, tops: tuple[Box, ...], depth: float, x_range: tuple[float, float]
) -> TerrainXml:
    """Boxes rising from a pit floor at ``-depth`` to their tops, on a floor box."""
    x0, x1 = x_range
    parts = [
        f'<geom name="{prefix}_floor" class="terrain" type="box" '
        f'pos="{0.5 * (x0 + x1):.6g} 0 {-depth - 0.025:.6g}" '
        f'size="{0.5 * (x1 - x0):.6g} {ARENA_HALF_WIDTH:.6g} 0.025"/>'
    ]
    for k, (cx, cy, hx, hy, top) in enumerate(tops):
        zc, hz = 0.5 * (top - depth), 0.5 * (top + depth)
        parts.append(
            f'<geom name="{prefix}{k}" class="terrain" type="box" pos="{cx:.6g} {cy:.6g} '
            f'{zc:.6g}" size="{hx:.6g} {hy:.6g} {hz:.6g}"/>'
        )
    return TerrainXml(worldbody="\n    ".join(parts), floor=False)


def _sunken_height(
    tops: tuple[Box, ...],
    depth: float,
    x_range: tuple[float, float],
    x: npt.ArrayLike,
    y: npt.ArrayLike,
) -> npt.NDArray[np.float64]:
    xa, ya = np.broadcast_arrays(np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64))
    inside = (xa >= x_range[0]) & (xa <= x_range[1]) & (np.abs(ya) <= ARENA_HALF_WIDTH)
    on_top = boxes_height(tops, xa, ya)
    covered = np.zeros(xa.shape, dtype=bool)
    for cx, cy, hx, hy, _ in tops:
        covered |= (np.abs(xa - cx) <= hx) & (np.abs(ya - cy) <= hy)
    return np.where(covered, on_top, np.where(inside, -depth, VOID_Z))


class SunkenTerrain(Terrain):
    """Boxes (``tops``) rising from a pit floor at ``-depth``, in an arena round the way."""

    tops: tuple[Box, ...]
    depth: float

    @property
    def _x_range(self) -> tuple[float, float]:
        return (-ARENA_BEHIND, self.goal[0] + ARENA_BEYOND)

    def height(self, x: npt.ArrayLike, y: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """A box top, the pit floor between, the void off the arena [m]."""
        return _sunken_height(self.tops, self.depth, self._x_range, x, y)

    def mjcf(self) -> TerrainXml:
        """A pit floor and one box per top."""
        return _sunken_xml(self.name, self.tops, self.depth, self._x_range)


@dataclass(frozen=True)
class SteppingStones(SunkenTerrain):
    """Stones over a pit, between a start and an end platform.

    Attributes:
        gap: Gap between neighbouring stones [m].
        stone: Stone side [m].
        depth: Pit depth below the platforms [m].
        jitter: Stone tops vary by +- this, and their centres by +- a quarter gap [m].
        seed: Seed of the stones.
        start_x: Where the stones begin [m].
        length: Length of the stone field [m].
        field_width: Width of the stone field [m]; beyond it is pit.
    """

    gap: float = 0.06
    stone: float = 0.2
    depth: float = 0.3
    jitter: float = 0.01
    seed: int = 0
    start_x: float = 0.6
    length: float = 2.0
    field_width: float = 1.8
    name: ClassVar[str] = "stepping_stones"
    difficulty: ClassVar[str | None] = "gap"
    sweep: ClassVar[tuple[float, ...]] = (0.04, 0.08, 0.12)
    tops: tuple[Box, ...] = field(init=False, repr=False, compare=False)

    _end: float = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if not (self.gap >= 0 and self.stone > 0 and self.depth > self.jitter >= 0):
            raise ConfigError("stepping stones need gap >= 0, stone > 0 and depth > jitter >= 0")
        rng = np.random.default_rng(self.seed)
        pitch = self.stone + self.gap
        nx, ny = max(1, round(self.length / pitch)), max(1, round(self.field_width / pitch))
        end = self.start_x + nx * pitch
        # The platforms lie a gap from the first and the last stones.
        near, far = self.start_x - 0.5 * self.gap, end + 0.5 * self.gap
        beyond = end + 0.6 + ARENA_BEYOND
        tops: list[Box] = [
            (0.5 * (near - ARENA_BEHIND), 0.0, 0.5 * (near + ARENA_BEHIND), ARENA_HALF_WIDTH, 0.0),
            (0.5 * (far + beyond), 0.0, 0.5 * (beyond - far), ARENA_HALF_WIDTH, 0.0),
        ]
        y0 = -0.5 * ny * pitch
        for i in range(nx):
            for j in range(ny):
                dx, dy = rng.uniform(-0.25 * self.gap, 0.25 * self.gap, size=2)
                cx = self.start_x + (i + 0.5) * pitch + dx
                cy = y0 + (j + 0.5) * pitch + dy
                top = float(rng.uniform(-self.jitter, self.jitter))
                tops.append((float(cx), float(cy), 0.5 * self.stone, 0.5 * self.stone, top))
        object.__setattr__(self, "tops", tuple(tops))
        object.__setattr__(self, "_end", end)

    @property
    def goal(self) -> tuple[float, float]:  # type: ignore[override]
        """Sixty centimetres past the last stones, on the end platform."""
        return (self._end + 0.6, 0.0)

    def impassable_for(self, spec: HexapodSpec) -> str:
        """Stones farther apart than a foot can step, the stones being the only ground."""
        return _gap_too_wide("stones", self.gap, spec)


@dataclass(frozen=True)
class Gaps(SunkenTerrain):
    """Platforms with trenches between them, across the whole way.

    Attributes:
        width: Trench width [m].
        depth: Trench depth [m].
        platform: Platform lengths are uniform in this range [m].
        seed: Seed of the platform lengths.
        start_x: Where the first trench begins [m].
        length: The trenches lie within this length from ``start_x`` [m].
    """

    width: float = 0.1
    depth: float = 0.3
    platform: tuple[float, float] = (0.4, 0.6)
    seed: int = 0
    start_x: float = 0.6
    length: float = 2.0
    name: ClassVar[str] = "gaps"
    difficulty: ClassVar[str | None] = "width"
    sweep: ClassVar[tuple[float, ...]] = (0.05, 0.1, 0.15)
    tops: tuple[Box, ...] = field(init=False, repr=False, compare=False)
    _goal_x: float = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if not (self.width > 0 and self.depth > 0 and 0 < self.platform[0] <= self.platform[1]):
            raise ConfigError("gaps need a positive width and depth and 0 < platform min <= max")
        rng = np.random.default_rng(self.seed)
        edges = [-ARENA_BEHIND]
        x = self.start_x
        while x < self.start_x + self.length:
            edges += [x, x + self.width]
            x += self.width + float(rng.uniform(*self.platform))
        end = edges[-1]
        object.__setattr__(self, "_goal_x", end + 0.6)
        edges.append(end + 0.6 + ARENA_BEYOND)
        tops = tuple(
            (0.5 * (a + b), 0.0, 0.5 * (b - a), ARENA_HALF_WIDTH, 0.0)
            for a, b in zip(edges[0::2], edges[1::2], strict=True)
        )
        object.__setattr__(self, "tops", tops)

    @property
    def goal(self) -> tuple[float, float]:  # type: ignore[override]
        """Sixty centimetres onto the last platform."""
        return (self._goal_x, 0.0)

    def impassable_for(self, spec: HexapodSpec) -> str:
        """Trenches across the whole way, wider than a foot can step."""
        return _gap_too_wide("trenches", self.width, spec)


@dataclass(frozen=True)
class Pits(Terrain):
    """Square pits sunk into the floor.

    Attributes:
        depth: Pit depth [m].
        size: Pit sides are uniform in this range [m].
        count: Number of pits.
        seed: Seed of the layout.
        start_x: Where the pitted field begins [m].
        length: Field length along x [m].
        width: Field width along y [m].
        sample: Height-field sample spacing [m].
    """

    depth: float = 0.1
    size: tuple[float, float] = (0.2, 0.5)
    count: int = 8
    seed: int = 0
    start_x: float = 0.7
    length: float = 2.2
    width: float = 1.6
    sample: float = 0.01
    name: ClassVar[str] = "pits"
    difficulty: ClassVar[str | None] = "depth"
    sweep: ClassVar[tuple[float, ...]] = (0.05, 0.1, 0.2)
    pits: tuple[Box, ...] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if not (self.depth > 0 and self.count >= 0 and 0 < self.size[0] <= self.size[1]):
            raise ConfigError("pits need a positive depth, a count >= 0 and 0 < size min <= max")
        rng = np.random.default_rng(self.seed)
        pits = []
        span = (self.start_x, self.start_x + self.length)
        for _ in range(self.count):
            pits.append((*scatter(rng, self.size, span, self.width), -self.depth))
        object.__setattr__(self, "pits", tuple(pits))

    @property
    def goal(self) -> tuple[float, float]:  # type: ignore[override]
        """Half a metre past the field."""
        return (self.start_x + self.length + 0.5, 0.0)

    def height(self, x: npt.ArrayLike, y: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Pit floor in a pit, 0 elsewhere on the height field, the void off it [m]."""
        xa, ya = np.broadcast_arrays(
            np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
        )
        in_pit = np.zeros(xa.shape, dtype=bool)
        for cx, cy, hx, hy, _ in self.pits:
            in_pit |= (np.abs(xa - cx) <= hx) & (np.abs(ya - cy) <= hy)
        (x0, x1), (y0, y1) = self._ranges
        on_field = (xa >= x0) & (xa <= x1) & (ya >= y0) & (ya <= y1)
        return np.where(on_field, np.where(in_pit, -self.depth, 0.0), VOID_Z)

    @property
    def _ranges(self) -> tuple[tuple[float, float], tuple[float, float]]:
        return (-1.0, self.goal[0] + 1.0), (-0.5 * self.width - 1.0, 0.5 * self.width + 1.0)

    def mjcf(self) -> TerrainXml:
        """A height field over the field and a margin around it."""
        x_range, y_range = self._ranges
        return height_field_xml("pits", self.height, x_range, y_range, self.sample)


@dataclass(frozen=True)
class Ramps(Terrain):
    """A ramp up, a landing and a ramp down, across the whole way.

    Attributes:
        slope_deg: Ramp slope [deg].
        rise: Landing height [m].
        landing: Landing length [m].
        start_x: Where the ramp up begins [m].
        half_width: Half the width of the ramps [m]; the height field ends there.
        sample: Height-field sample spacing [m].
    """

    slope_deg: float = 15.0
    rise: float = 0.1
    landing: float = 0.6
    start_x: float = 0.7
    half_width: float = 1.5
    sample: float = 0.01
    name: ClassVar[str] = "ramps"
    difficulty: ClassVar[str | None] = "slope_deg"
    difficulty_unit: ClassVar[str] = "deg"
    sweep: ClassVar[tuple[float, ...]] = (10.0, 20.0, 30.0)

    def __post_init__(self) -> None:
        if not (0 < self.slope_deg < 60 and self.rise > 0 and self.landing > 0):
            raise ConfigError("ramps need 0 < slope_deg < 60, a positive rise and landing")

    @property
    def run(self) -> float:
        """Horizontal length of each ramp [m]."""
        return self.rise / math.tan(math.radians(self.slope_deg))

    @property
    def goal(self) -> tuple[float, float]:  # type: ignore[override]
        """Half a metre past the foot of the ramp down."""
        return (self.start_x + 2 * self.run + self.landing + 0.5, 0.0)

    def impassable_for(self, spec: HexapodSpec) -> str:
        """Ramps across the whole way, steeper than the feet's friction holds."""
        steepest = math.degrees(steepest_slope_rad(spec))
        if self.slope_deg <= steepest:
            return ""
        return (
            f"a {self.slope_deg:g} degree ramp is steeper than the {spec.name} robot's feet "
            f"hold on (friction {spec.foot_friction:g}: {steepest:.1f} degrees)"
        )

    def height(self, x: npt.ArrayLike, y: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """The ramps' surface, 0 before and after, the void off the height field [m]."""
        xa, ya = np.broadcast_arrays(
            np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
        )
        up = (xa - self.start_x) / self.run
        down = (self.start_x + 2 * self.run + self.landing - xa) / self.run
        h = self.rise * np.clip(np.minimum(up, down), 0.0, 1.0)
        x0, x1 = self._x_range
        on_field = (np.abs(ya) <= self.half_width) & (xa >= x0) & (xa <= x1)
        return np.where(on_field, h, VOID_Z)

    @property
    def _x_range(self) -> tuple[float, float]:
        return (-1.0, self.goal[0] + 1.0)

    def mjcf(self) -> TerrainXml:
        """A height field the width of the ramps."""
        return height_field_xml(
            "ramps", self.height, self._x_range, (-self.half_width, self.half_width), self.sample
        )
