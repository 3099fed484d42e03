"""Terrains for the simulator, each with an exact ground-truth height function.

Every terrain gives MJCF for MuJoCo (boxes, or a height field for shapes boxes cannot
make) and ``height(x, y)``, the true ground height for tests and metrics. A walk on a
terrain starts at ``start`` facing +x and has its goal at ``goal``.

- ``flat``: the floor.
- ``stairs``: steps up, a landing, steps down (boxes).
- ``cobblestones``: square stones of jittered height separated by grooves down to the
  floor (boxes; seeded).
- ``course``: the scoring course of thesis Fig. 6.5 beside a clear lane: boxes, a ramp,
  a sloped pillar, a sloped hole and a round pedestal (a height field).
- The harder suite, as locomotion benchmarks generate (legged_gym, Isaac Lab), each seeded
  and with one difficulty parameter: ``stepping_stones``, ``gaps``, ``ramps`` and ``pits``
  (:mod:`footfall.sim.terrain_relief`); ``boxes``, ``obstacle_field`` and ``dead_end``
  (:mod:`footfall.sim.terrain_obstacles`).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Callable
from dataclasses import dataclass, field, fields
from typing import TYPE_CHECKING, ClassVar

import numpy as np
import numpy.typing as npt

from footfall.errors import ConfigError

if TYPE_CHECKING:
    from footfall.robot.spec import HexapodSpec


@dataclass(frozen=True)
class HeightField:
    """A MuJoCo height field to fill after the model is compiled.

    Attributes:
        name: Asset name.
        elevation: Normalised elevations in [0, 1], shape (nrow, ncol); rows along y.
    """

    name: str
    elevation: npt.NDArray[np.float64]


@dataclass(frozen=True)
class TerrainXml:
    """MJCF pieces of a terrain.

    Attributes:
        assets: Elements for ``<asset>``.
        worldbody: Elements for ``<worldbody>``.
        height_fields: Height-field data to copy into the compiled model.
        floor: Whether the infinite floor plane at z = 0 is part of the terrain.
    """

    assets: str = ""
    worldbody: str = ""
    height_fields: tuple[HeightField, ...] = ()
    floor: bool = True


class Terrain(ABC):
    """A terrain: ground truth plus MJCF, and how the benchmarks use it.

    A new terrain is a subclass (a frozen dataclass whose fields are its parameters, with a
    ``seed`` field if it is random) registered with one line in :mod:`footfall.sim.terrains`
    (or ``register_terrain(MyTerrain)`` in your own code).

    Attributes:
        name: The name ``--terrain`` takes.
        difficulty: The parameter that sets its difficulty (``footfall walk
            --difficulty``, the one ``footfall bench terrain`` sweeps), or None.
        difficulty_unit: Its unit, for help texts and axis labels.
        sweep: The values of ``difficulty`` the terrain benchmark walks.
        benchmarked: Whether ``footfall bench terrain`` walks it (once, at its defaults,
            when it has no difficulty parameter).
        has_route: Whether a route to the goal exists; where none does, a walk succeeds by
            standing still and saying why.
        start: Where a walk starts, facing +x [m].
        goal: Where a walk ends [m].
    """

    name: ClassVar[str]
    difficulty: ClassVar[str | None] = None
    difficulty_unit: ClassVar[str] = "m"
    sweep: ClassVar[tuple[float, ...]] = ()
    benchmarked: ClassVar[bool] = True
    has_route: ClassVar[bool] = True
    start: tuple[float, float] = (0.0, 0.0)
    goal: tuple[float, float] = (4.0, 0.0)

    @classmethod
    def seeded(cls, seed: int = 0, **params: float) -> Terrain:
        """The terrain laid out by ``seed`` (when it is random), with ``params`` set.

        Raises:
            ConfigError: On a parameter it does not have, or a value it refuses.
        """
        try:
            if "seed" in {f.name for f in fields(cls)}:  # type: ignore[arg-type]
                return cls(seed=seed, **params)  # type: ignore[call-arg]
            return cls(**params)  # type: ignore[call-arg]
        except TypeError as exc:
            raise ConfigError(f"terrain {cls.name!r}: {exc}") from exc

    def impassable_for(self, spec: HexapodSpec) -> str:
        """Why no gait of the robot can cross this terrain ("" where one may).

        Decided from the terrain's own parameters against bounds from the robot's geometry
        (:mod:`footfall.robot.limits`), never from margins a planner adds: ``footfall bench
        terrain`` reports such a row as ``impassable`` and leaves it out of its success
        rates. A terrain with no such rule can always be crossed.
        """
        return ""

    @abstractmethod
    def height(self, x: npt.ArrayLike, y: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """True ground height at world ``(x, y)`` [m], vectorised."""

    @abstractmethod
    def mjcf(self) -> TerrainXml:
        """The terrain as MJCF pieces."""


def box_xml(name: str, centre: tuple[float, float, float], half: tuple[float, float, float]) -> str:
    """An MJCF box geom of the terrain class, from its centre and half sizes [m]."""
    c = " ".join(f"{v:.6g}" for v in centre)
    h = " ".join(f"{v:.6g}" for v in half)
    return f'<geom name="{name}" class="terrain" type="box" pos="{c}" size="{h}"/>'


@dataclass(frozen=True)
class Flat(Terrain):
    """The floor, nothing else."""

    name: ClassVar[str] = "flat"
    benchmarked: ClassVar[bool] = False

    def height(self, x: npt.ArrayLike, y: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Zero everywhere [m]."""
        return np.zeros(np.broadcast(np.asarray(x), np.asarray(y)).shape)

    def mjcf(self) -> TerrainXml:
        """Just the floor."""
        return TerrainXml()


@dataclass(frozen=True)
class Stairs(Terrain):
    """Steps up to a landing and down again, across the walking direction.

    Attributes:
        rise: Step height [m].
        tread: Step depth along x [m].
        steps: Steps up (and as many down).
        landing: Length of the top landing [m].
        start_x: Where the first step begins [m].
        width: Width of the staircase along y [m].
    """

    rise: float = 0.04
    tread: float = 0.25
    steps: int = 4
    landing: float = 0.5
    start_x: float = 0.6
    width: float = 1.5
    name: ClassVar[str] = "stairs"
    difficulty: ClassVar[str | None] = "rise"
    sweep: ClassVar[tuple[float, ...]] = (0.02, 0.04, 0.06, 0.08)

    def __post_init__(self) -> None:
        if not (self.rise > 0 and self.tread > 0 and self.steps >= 1 and self.landing > 0):
            raise ConfigError("stairs need positive rise, tread and landing, and at least one step")

    @property
    def end_x(self) -> float:
        """Where the last step down ends [m]."""
        return self.start_x + 2 * (self.steps - 1) * self.tread + self.landing

    @property
    def goal(self) -> tuple[float, float]:  # type: ignore[override]
        """Half a metre past the last step."""
        return (self.end_x + 0.5, 0.0)

    @classmethod
    def seeded(cls, seed: int = 0, **params: float) -> Terrain:
        """The staircase, its first step shifted by up to 10 cm by ``seed``.

        Unless ``start_x`` is given: so footholds fall differently on every seed.
        """
        if "start_x" not in params:
            shift = float(np.random.default_rng(seed).uniform(-0.1, 0.1))
            params = {**params, "start_x": cls.start_x + shift}
        return super().seeded(seed, **params)

    def _spans(self) -> list[tuple[float, float]]:
        return [
            (self.start_x + k * self.tread, self.end_x - k * self.tread) for k in range(self.steps)
        ]

    def height(self, x: npt.ArrayLike, y: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """``rise`` times the number of stacked step boxes under the point [m]."""
        xa, ya = np.broadcast_arrays(
            np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
        )
        inside = np.abs(ya) <= 0.5 * self.width
        count = np.zeros(xa.shape)
        for a, b in self._spans():
            count += (xa >= a) & (xa <= b)
        return np.where(inside, count * self.rise, 0.0)

    def mjcf(self) -> TerrainXml:
        """One box per step level, stacked."""
        boxes = [
            box_xml(
                f"step{k}",
                (0.5 * (a + b), 0.0, (k + 0.5) * self.rise),
                (0.5 * (b - a), 0.5 * self.width, 0.5 * self.rise),
            )
            for k, (a, b) in enumerate(self._spans())
        ]
        return TerrainXml(worldbody="\n    ".join(boxes))


@dataclass(frozen=True)
class Cobblestones(Terrain):
    """A field of square stones with grooves between them down to the floor.

    Attributes:
        stone: Stone pitch (stone plus groove) [m].
        groove: Groove width [m].
        height_mean: Mean stone height [m].
        jitter: Stone heights vary uniformly by +- this [m].
        seed: Seed of the stone heights.
        start_x: Where the field begins [m].
        length: Field length along x [m].
        width: Field width along y [m].
    """

    stone: float = 0.16
    groove: float = 0.03
    height_mean: float = 0.03
    jitter: float = 0.01
    seed: int = 0
    start_x: float = 0.6
    length: float = 2.4
    width: float = 1.2
    name: ClassVar[str] = "cobblestones"
    difficulty: ClassVar[str | None] = "groove"
    sweep: ClassVar[tuple[float, ...]] = (0.01, 0.03, 0.06)
    _tops: npt.NDArray[np.float64] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if not (0 <= self.groove < self.stone and self.height_mean - self.jitter > 0):
            raise ConfigError("cobblestones need 0 <= groove < stone and stones above the floor")
        rng = np.random.default_rng(self.seed)
        shape = (round(self.length / self.stone), round(self.width / self.stone))
        object.__setattr__(
            self, "_tops", self.height_mean + rng.uniform(-self.jitter, self.jitter, shape)
        )

    @property
    def goal(self) -> tuple[float, float]:  # type: ignore[override]
        """Half a metre past the field."""
        return (self.start_x + self.length + 0.5, 0.0)

    def _y0(self) -> float:
        return -0.5 * self._tops.shape[1] * self.stone

    def height(self, x: npt.ArrayLike, y: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Stone top on a stone, the floor (0) in a groove or off the field [m]."""
        xa, ya = np.broadcast_arrays(
            np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
        )
        u = (xa - self.start_x) / self.stone
        v = (ya - self._y0()) / self.stone
        i, j = np.floor(u).astype(np.int64), np.floor(v).astype(np.int64)
        on_field = (i >= 0) & (i < self._tops.shape[0]) & (j >= 0) & (j < self._tops.shape[1])
        half_groove = 0.5 * self.groove / self.stone
        on_stone = (np.abs(u - i - 0.5) <= 0.5 - half_groove) & (
            np.abs(v - j - 0.5) <= 0.5 - half_groove
        )
        top = self._tops[
            np.clip(i, 0, self._tops.shape[0] - 1), np.clip(j, 0, self._tops.shape[1] - 1)
        ]
        return np.where(on_field & on_stone, top, 0.0)

    def mjcf(self) -> TerrainXml:
        """One box per stone."""
        half = 0.5 * (self.stone - self.groove)
        boxes = []
        for i in range(self._tops.shape[0]):
            for j in range(self._tops.shape[1]):
                cx = self.start_x + (i + 0.5) * self.stone
                cy = self._y0() + (j + 0.5) * self.stone
                top = float(self._tops[i, j])
                boxes.append(box_xml(f"stone{i}_{j}", (cx, cy, 0.5 * top), (half, half, 0.5 * top)))
        return TerrainXml(worldbody="\n    ".join(boxes))


@dataclass(frozen=True)
class Course(Terrain):
    """The scoring course of thesis Fig. 6.5, laid out on both sides of a clear lane.

    Left of the lane (y > 0): a box, a ramp, a sloped pillar; right: a sloped hole, a round
    pedestal and a taller box, all between x = 0.75 and 2.5 m. The lane ``|y| < 0.3`` stays
    flat so a blind robot can walk it while its camera maps the features.

    Attributes:
        sample: Height-field sample spacing [m].
    """

    sample: float = 0.01
    name: ClassVar[str] = "course"
    x_range: tuple[float, float] = (-0.7, 3.5)
    y_range: tuple[float, float] = (-1.0, 1.0)

    @property
    def goal(self) -> tuple[float, float]:  # type: ignore[override]
        """The far end of the lane."""
        return (3.0, 0.0)

    def height(self, x: npt.ArrayLike, y: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """The course's analytic surface [m]."""
        xa, ya = np.broadcast_arrays(
            np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
        )
        h = np.zeros(xa.shape)
        # Left: a box 0.26 x 0.26, 6 cm.
        h = np.maximum(
            h, np.where((np.abs(xa - 0.9) <= 0.13) & (np.abs(ya - 0.46) <= 0.13), 0.06, 0.0)
        )
        # Left: a ramp rising along x from 0 to 7 cm over 0.5 m (8 deg), 0.3 m wide.
        on_ramp = (xa >= 1.35) & (xa <= 1.85) & (ya >= 0.33) & (ya <= 0.63)
        h = np.maximum(h, np.where(on_ramp, 0.07 * (xa - 1.35) / 0.5, 0.0))
        # Left: a sloped pillar, flat top r 0.08 at 10 cm, sides reaching the floor at r 0.19.
        r = np.hypot(xa - 2.35, ya - 0.52)
        h = np.maximum(h, np.clip(0.10 * (0.19 - r) / 0.11, 0.0, 0.10))
        # Right: a round pedestal, flat top r 0.10 at 7 cm with a rounded 5 cm shoulder.
        r = np.hypot(xa - 1.6, ya + 0.5)
        shoulder = np.sqrt(np.clip(0.05**2 - (r - 0.10) ** 2, 0.0, None)) + 0.02
        h = np.maximum(h, np.where(r <= 0.10, 0.07, np.where(r <= 0.15, shoulder, 0.0)))
        # Right: a taller box, 0.22 x 0.30, 10 cm.
        h = np.maximum(
            h, np.where((np.abs(xa - 2.3) <= 0.11) & (np.abs(ya + 0.5) <= 0.15), 0.10, 0.0)
        )
        # Right: a sloped hole, bottom r 0.11 at -7 cm, walls (41 deg) rising to the floor
        # at r 0.19.
        r = np.hypot(xa - 0.9, ya + 0.5)
        hole = -np.clip(0.07 * (0.19 - r) / 0.08, 0.0, 0.07)
        return np.where(hole < 0, hole, h)

    def mjcf(self) -> TerrainXml:
        """A height field sampled from :meth:`height` every ``sample`` metres."""
        return height_field_xml("course", self.height, self.x_range, self.y_range, self.sample)


def height_field_xml(
    name: str,
    height: Callable[[npt.ArrayLike, npt.ArrayLike], npt.NDArray[np.float64]],
    x_range: tuple[float, float],
    y_range: tuple[float, float],
    sample: float,
) -> TerrainXml:
    """A terrain as one MuJoCo height field sampled from ``height`` every ``sample`` m.

    The field replaces the floor (``floor`` is False): it is the ground over its extent.
    """
    (x0, x1), (y0, y1) = x_range, y_range
    ncol = round((x1 - x0) / sample) + 1
    nrow = round((y1 - y0) / sample) + 1
    xs = np.linspace(x0, x1, ncol)
    ys = np.linspace(y0, y1, nrow)
    heights = height(xs[None, :], ys[:, None])
    low, high = float(heights.min()), float(heights.max())
    span = max(high - low, 1e-6)
    elevation = (heights - low) / span
    cx, cy = 0.5 * (x0 + x1), 0.5 * (y0 + y1)
    assets = (
        f'<hfield name="{name}" nrow="{nrow}" ncol="{ncol}" '
        f'size="{0.5 * (x1 - x0):.6g} {0.5 * (y1 - y0):.6g} {span:.6g} 0.05"/>'
    )
    body = (
        f'<geom name="{name}" class="terrain" type="hfield" hfield="{name}" '
        f'pos="{cx:.6g} {cy:.6g} {low:.6g}"/>'
    )
    return TerrainXml(
        assets=assets,
        worldbody=body,
        height_fields=(HeightField(name, elevation),),
        floor=False,
    )
