"""Terrains of boxes on the floor: random boxes, an obstacle field, a dead end.

- ``boxes``: boxes of random size and height up to ``height`` scattered over the way
  (legged_gym's "discrete obstacles"); low ones are stepped onto, tall ones gone round.
- ``obstacle_field``: blocks no leg can climb (``block_height``), covering ``density`` of
  the field, placed so that at least one route a robot of ``clearance`` half-width fits
  through leads from the start to the goal (checked on a grid; blocks are dropped, last
  first, until one does).
- ``dead_end``: the robot starts in a walled corridor closed at its far end and behind it:
  there is no route to the goal beyond the far wall. The right outcome is to stand still and
  say so.

Each box is axis-aligned; ``height(x, y)`` is the highest box top over the point (0 on the
floor), exact for the MuJoCo geometry.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np
import numpy.typing as npt

from footfall.errors import ConfigError
from footfall.sim.terrain import Terrain, TerrainXml, box_xml

# A box: centre x, centre y, half size x, half size y, top height [m].
Box = tuple[float, float, float, float, float]


def boxes_height(
    boxes: tuple[Box, ...], x: npt.ArrayLike, y: npt.ArrayLike
) -> npt.NDArray[np.float64]:
    """The highest box top over each point, 0 where no box is [m]."""
    xa, ya = np.broadcast_arrays(np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64))
    h = np.full(xa.shape, -np.inf)
    for cx, cy, hx, hy, top in boxes:
        inside = (np.abs(xa - cx) <= hx) & (np.abs(ya - cy) <= hy)
        h = np.where(inside, np.maximum(h, top), h)
    return np.where(np.isfinite(h), h, 0.0)


def boxes_xml(prefix: str, boxes: tuple[Box, ...]) -> TerrainXml:
    """The boxes as MJCF, standing on the floor."""
    return TerrainXml(
        worldbody="\n    ".join(
            box_xml(f"{prefix}{k}", (cx, cy, 0.5 * top), (hx, hy, 0.5 * top))
            for k, (cx, cy, hx, hy, top) in enumerate(boxes)
        )
    )


def route_exists(
    boxes: tuple[Box, ...],
    start: tuple[float, float],
    goal: tuple[float, float],
    clearance: float,
    bounds: tuple[float, float, float, float],
    cell: float = 0.02,
) -> bool:
    """Whether a disc of radius ``clearance`` can move from start to goal between the boxes.

    The free space is the grid over ``bounds`` ``(x0, x1, y0, y1)`` minus every box grown by
    the clearance; the start and goal must lie in one connected piece of it.
    """
    from scipy import ndimage  # with the first layout, not with the list of terrains

    x0, x1, y0, y1 = bounds
    xs = x0 + (np.arange(round((x1 - x0) / cell)) + 0.5) * cell
    ys = y0 + (np.arange(round((y1 - y0) / cell)) + 0.5) * cell
    blocked = np.zeros((len(xs), len(ys)), dtype=bool)
    for cx, cy, hx, hy, _ in boxes:
        dx = np.maximum(np.abs(xs - cx) - hx, 0.0)[:, None]
        dy = np.maximum(np.abs(ys - cy) - hy, 0.0)[None, :]
        blocked |= dx**2 + dy**2 < clearance**2
    labels, _ = ndimage.label(~blocked)

    def label_at(p: tuple[float, float]) -> int:
        i = int(np.clip((p[0] - x0) // cell, 0, len(xs) - 1))
        j = int(np.clip((p[1] - y0) // cell, 0, len(ys) - 1))
        return int(labels[i, j])

    a, b = label_at(start), label_at(goal)
    return a != 0 and a == b


def scatter(
    rng: np.random.Generator, size: tuple[float, float], x_range: tuple[float, float], width: float
) -> tuple[float, float, float, float]:
    """A random box footprint inside ``x_range`` x ``[-width/2, width/2]``: centre, half sizes."""
    sx, sy = rng.uniform(*size, size=2)
    cx = rng.uniform(x_range[0] + 0.5 * sx, x_range[1] - 0.5 * sx)
    cy = rng.uniform(-0.5 * width + 0.5 * sy, 0.5 * width - 0.5 * sy)
    return float(cx), float(cy), 0.5 * float(sx), 0.5 * float(sy)


class BoxTerrain(Terrain):
    """A terrain of boxes standing on the floor: the truth and the MJCF of its ``layout``."""

    @property
    def layout(self) -> tuple[Box, ...]:
        """The boxes."""
        raise NotImplementedError

    def height(self, x: npt.ArrayLike, y: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Highest box top over the point, 0 elsewhere [m]."""
        return boxes_height(self.layout, x, y)

    def mjcf(self) -> TerrainXml:
        """One geom per box."""
        return boxes_xml(self.name, self.layout)


@dataclass(frozen=True)
class Boxes(BoxTerrain):
    """Random boxes on the floor.

    Attributes:
        box_height: Tallest box [m]; heights are uniform in [``box_height`` / 4, ``box_height``].
        count: Number of boxes.
        size: Box sides are uniform in this range [m].
        seed: Seed of the layout.
        start_x: Where the field begins [m].
        length: Field length along x [m].
        width: Field width along y [m].
    """

    box_height: float = 0.08
    count: int = 14
    size: tuple[float, float] = (0.15, 0.4)
    seed: int = 0
    start_x: float = 0.6
    length: float = 2.4
    width: float = 1.6
    name: ClassVar[str] = "boxes"
    difficulty: ClassVar[str | None] = "box_height"
    sweep: ClassVar[tuple[float, ...]] = (0.04, 0.08, 0.12)
    boxes: tuple[Box, ...] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if not (self.box_height > 0 and self.count >= 0 and 0 < self.size[0] <= self.size[1]):
            raise ConfigError("boxes need a positive height, a count >= 0 and 0 < size min <= max")
        rng = np.random.default_rng(self.seed)
        boxes = []
        span = (self.start_x, self.start_x + self.length)
        for _ in range(self.count):
            footprint = scatter(rng, self.size, span, self.width)
            top = rng.uniform(0.25 * self.box_height, self.box_height)
            boxes.append((*footprint, float(top)))
        object.__setattr__(self, "boxes", tuple(boxes))

    @property
    def goal(self) -> tuple[float, float]:  # type: ignore[override]
        """Half a metre past the field."""
        return (self.start_x + self.length + 0.5, 0.0)

    @property
    def layout(self) -> tuple[Box, ...]:
        """The boxes."""
        return self.boxes


@dataclass(frozen=True)
class ObstacleField(BoxTerrain):
    """Blocks no leg climbs, with at least one free route between them.

    Attributes:
        density: Share of the field's area the blocks cover (before any is dropped to open
            a route).
        block_height: Height of every block [m].
        size: Block sides are uniform in this range [m].
        clearance: Half-width of the robot the free route must fit [m] (the default
            hexapod's legs span 0.34 m from its centre; a margin on top).
        seed: Seed of the layout.
        start_x: Where the field begins [m].
        length: Field length along x [m].
        width: Field width along y [m].
    """

    density: float = 0.2
    block_height: float = 0.3
    size: tuple[float, float] = (0.15, 0.4)
    clearance: float = 0.4
    seed: int = 0
    start_x: float = 0.7
    length: float = 2.4
    width: float = 2.4
    name: ClassVar[str] = "obstacle_field"
    difficulty: ClassVar[str | None] = "density"
    difficulty_unit: ClassVar[str] = "share of area"
    sweep: ClassVar[tuple[float, ...]] = (0.1, 0.2, 0.3)
    blocks: tuple[Box, ...] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if not (
            0 <= self.density < 1 and self.block_height > 0 and 0 < self.size[0] <= self.size[1]
        ):
            raise ConfigError(
                "an obstacle field needs 0 <= density < 1, a positive block height and "
                "0 < size min <= max"
            )
        rng = np.random.default_rng(self.seed)
        target = self.density * self.length * self.width
        covered, blocks = 0.0, []
        x0, x1 = self.start_x, self.start_x + self.length
        while covered < target:
            cx, cy, hx, hy = scatter(rng, self.size, (x0, x1), self.width)
            blocks.append((cx, cy, hx, hy, self.block_height))
            covered += 4 * hx * hy
        bounds = (-0.5, x1 + 1.0, -0.5 * self.width - 1.0, 0.5 * self.width + 1.0)
        while blocks and not route_exists(
            tuple(blocks), self.start, self.goal, self.clearance, bounds
        ):
            blocks.pop()
        object.__setattr__(self, "blocks", tuple(blocks))

    @property
    def goal(self) -> tuple[float, float]:  # type: ignore[override]
        """Sixty centimetres past the field."""
        return (self.start_x + self.length + 0.6, 0.0)

    @property
    def layout(self) -> tuple[Box, ...]:
        """The blocks."""
        return self.blocks


@dataclass(frozen=True)
class DeadEnd(BoxTerrain):
    """A walled corridor closed at its far end and behind the start: no route to the goal.

    Attributes:
        length: Corridor length ahead of the start [m].
        corridor_width: Inner width of the corridor [m]; the seed varies it by up to 20 %.
        behind: Room behind the start before the back wall [m].
        wall_height: Wall height [m].
        wall_thickness: Wall thickness [m].
        seed: Seed of the corridor's width and of the goal's side offset.
    """

    length: float = 1.8
    corridor_width: float = 1.4
    behind: float = 0.7
    wall_height: float = 0.3
    wall_thickness: float = 0.1
    seed: int = 0
    name: ClassVar[str] = "dead_end"
    difficulty: ClassVar[str | None] = "length"
    sweep: ClassVar[tuple[float, ...]] = (1.8,)
    has_route: ClassVar[bool] = False
    walls: tuple[Box, ...] = field(init=False, repr=False, compare=False)
    _goal: tuple[float, float] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if min(self.length, self.corridor_width, self.behind, self.wall_height) <= 0:
            raise ConfigError("a dead end needs a positive length, width, room behind and walls")
        rng = np.random.default_rng(self.seed)
        w = 0.5 * self.corridor_width * rng.uniform(0.8, 1.2)
        t = 0.5 * self.wall_thickness
        back, end = -self.behind, self.length
        cx, hx = 0.5 * (back + end), 0.5 * (end - back) + 2 * t
        walls = (
            (cx, w + t, hx, t, self.wall_height),
            (cx, -w - t, hx, t, self.wall_height),
            (end + t, 0.0, t, w + 2 * t, self.wall_height),
            (back - t, 0.0, t, w + 2 * t, self.wall_height),
        )
        object.__setattr__(self, "walls", walls)
        object.__setattr__(self, "_goal", (end + 0.8, float(rng.uniform(-0.3, 0.3))))

    @property
    def goal(self) -> tuple[float, float]:  # type: ignore[override]
        """Beyond the far wall."""
        return self._goal

    @property
    def layout(self) -> tuple[Box, ...]:
        """The walls."""
        return self.walls
