"""Map engines: what the mapping node needs of the rolling height map, and who provides it.

:class:`MapEngine` is the handful of methods the mapping node, the replayer and the
benchmarks call; :class:`~footfall.mapping.height_map.HeightMap` (compiled with numba, on
the CPU) is the first engine. Another (a GPU one) implements the same methods in one
module and joins :data:`MAP_ENGINES` with one line; ``HeightMapConfig.engine`` picks it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from enum import StrEnum
from typing import Protocol

import numpy.typing as npt

from footfall.checks import require_non_negative
from footfall.errors import ConfigError
from footfall.mapping.drift import DriftConfig
from footfall.mapping.snapshot import MapSnapshot
from footfall.registry import Registry
from footfall.sensing.camera import DepthStats, PinholeCamera
from footfall.sensing.pose import Pose


class FusionRule(StrEnum):
    """How a new observation of a cell combines with what the map holds."""

    LATEST = "latest"
    MAX = "max"
    VARIANCE = "variance"


@dataclass(frozen=True)
class HeightMapConfig:
    """Height map settings.

    Attributes:
        size: Cells per side, N.
        resolution: Cell side [m].
        fusion: Fusion rule across frames.
        range_noise: Depth noise coefficient of the ``variance`` rule: the standard deviation
            of a reading at range r is ``range_noise * r^2`` [1/m].
        process_noise: Standard deviation added to a cell per update (``variance``) [m].
        gate: Innovation gate of the ``variance`` rule [standard deviations].
        noise_spread_sigmas: In-frame height range of a cell the camera's noise alone
            explains [standard deviations of the noise at the cell's range].
        drift: Vertical drift compensation of each frame against the map (off by default;
            see :mod:`footfall.mapping.drift`).
        engine: The map engine that keeps the map, a name in ``MAP_ENGINES``.
    """

    size: int = 256
    resolution: float = 0.02
    fusion: FusionRule = FusionRule.LATEST
    range_noise: float = 0.003
    process_noise: float = 0.002
    gate: float = 4.0
    noise_spread_sigmas: float = 6.0
    drift: DriftConfig = field(default_factory=DriftConfig)
    engine: str = "numba"

    def __post_init__(self) -> None:
        object.__setattr__(self, "fusion", FusionRule(self.fusion))
        MAP_ENGINES.check(self.engine)
        if self.size < 8:
            raise ConfigError(f"height map size must be >= 8 cells, got {self.size}")
        if not (math.isfinite(self.resolution) and 1e-4 <= self.resolution <= 100.0):
            raise ConfigError(
                f"height map resolution must lie in [0.0001, 100] m, got {self.resolution}"
            )
        require_non_negative(
            "height map",
            range_noise=self.range_noise,
            process_noise=self.process_noise,
            gate=self.gate,
            noise_spread_sigmas=self.noise_spread_sigmas,
        )

    @property
    def extent(self) -> float:
        """Side of the mapped square [m]."""
        return self.size * self.resolution


@dataclass(frozen=True)
class IntegrationStats:
    """What became of one frame's readings.

    Attributes:
        depth: Pixel counts (valid, zero, non-finite, negative, out of range).
        outside: Valid readings that fell outside the map window.
        cells_updated: Map cells the frame wrote.
        vertical_offset_m: The frame's height above the map where they overlap, taken out
            before fusion (drift compensation) [m]; NaN when not estimated.
        inconsistent: The frame was not fused: its offset jumped, beyond drift.
        settled: The offset moved to a new level that several frames agree on.
    """

    depth: DepthStats
    outside: int
    cells_updated: int
    vertical_offset_m: float = math.nan
    inconsistent: bool = False
    settled: bool = False


class MapEngine(Protocol):
    """A rolling height map in the world (map) frame, z up.

    Attributes:
        config: Its settings.
    """

    config: HeightMapConfig

    def integrate_depth(
        self,
        depth: npt.ArrayLike,
        camera: PinholeCamera,
        camera_pose: Pose,
        depth_scale: float | None = None,
        stride: int = 1,
    ) -> IntegrationStats:
        """Fuse one depth image taken from ``camera_pose`` (the optical frame in the world).

        Raises:
            DepthImageError: On a malformed image; the map keeps what it held.
        """
        ...

    def misfit(
        self,
        depth: npt.ArrayLike,
        camera: PinholeCamera,
        camera_pose: Pose,
        depth_scale: float | None = None,
        stride: int = 1,
    ) -> float:
        """How far an image placed at ``camera_pose`` lies from the map, without fusing [m]."""
        ...

    def assume_ground(
        self, points_in_world: npt.ArrayLike, sensor_position: npt.ArrayLike
    ) -> IntegrationStats:
        """Take ground known without seeing it into unknown cells, until frames confirm it."""
        ...

    def recentre(self, centre: tuple[float, float]) -> None:
        """Move the window to be centred on a world point [m]; cells leaving are erased."""
        ...

    def snapshot(self) -> MapSnapshot:
        """The window as arrays ordered by world position."""
        ...


class MapEngineFactory(Protocol):
    """A registered engine: a class (or any callable) making an engine."""

    def __call__(self, config: HeightMapConfig, centre: tuple[float, float]) -> MapEngine:
        """An empty map centred on ``centre`` [m]."""
        ...


MAP_ENGINES: Registry[MapEngineFactory] = Registry("map engine")

MAP_ENGINES.register("numba", "footfall.mapping.height_map:HeightMap")


def open_map(
    config: HeightMapConfig | None = None, centre: tuple[float, float] = (0.0, 0.0)
) -> MapEngine:
    """An empty map from the engine ``config.engine`` names, centred on ``centre`` [m]."""
    config = config or HeightMapConfig()
    return MAP_ENGINES.get(config.engine)(config, centre)
