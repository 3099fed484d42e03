"""A height map and score map, as ``footfall map`` builds it: in simulation or from a recording."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import numpy.typing as npt

from footfall.errors import DatasetError
from footfall.mapping.height_map import HeightMapConfig, MapSnapshot
from footfall.reports import write_json
from footfall.scoring.walkability import ScoreConfig, ScoreMap

# Largest height range within a flat map cell in one frame for recorded data [m]: a real
# depth sensor's noise spans several millimetres (the simulated camera is noise-free).
REAL_MAX_CELL_SPREAD = 0.01


@dataclass(frozen=True)
class MapRequest:
    """What to map (the options of ``footfall map``).

    Attributes:
        terrain: Terrain to walk and map in simulation.
        seconds: Walking time [s].
        noise: Pose noise model, ``"none"`` or ``"slam"``.
        seed: Seed of the terrain and the noise.
        image_size: Depth image width and height [px].
        fusion: Per-cell fusion rule.
        max_cell_spread: In-frame height range of a cell above which it straddles an edge
            [m]; None for the default (the simulated camera's, or ``REAL_MAX_CELL_SPREAD``
            for a recording).
        tum: A TUM-layout sequence to map instead of simulating.
        intrinsics: ``fx, fy, cx, cy`` of the recording's depth camera [px].
        up: The recorded world's up axis.
        depth_scale: Metres per depth unit of the recording.
    """

    terrain: str = "course"
    seconds: float = 20.0
    noise: str = "none"
    seed: int = 0
    image_size: tuple[int, int] = (640, 480)
    fusion: str = "latest"
    max_cell_spread: float | None = None
    tum: Path | None = None
    intrinsics: tuple[float, float, float, float] = (525.0, 525.0, 319.5, 239.5)
    up: tuple[float, float, float] = (0.0, 0.0, 1.0)
    depth_scale: float = 1.0 / 5000.0


@dataclass(frozen=True)
class MapReport:
    """A built map.

    Attributes:
        snapshot: The final map window.
        scores: Its score map.
        path_xy: The robot's (or the camera's) path, shape (n, 2) [m].
        path_label: What the path is.
        metrics: The ``metrics.json`` content.
        score_config: The score settings used.
    """

    snapshot: MapSnapshot
    scores: ScoreMap
    path_xy: npt.NDArray[np.float64]
    path_label: str
    metrics: dict[str, object]
    score_config: ScoreConfig

    def to_json(self) -> dict[str, object]:
        """The ``metrics.json`` content."""
        return dict(self.metrics)

    def write(self, out: Path) -> list[Path]:
        """Write ``heightmap.png``, ``scoremap.png`` and ``metrics.json`` to ``out``."""
        from footfall.plots import plot_height_map, plot_score_map

        out.mkdir(parents=True, exist_ok=True)
        s = self.snapshot
        paths = [out / "heightmap.png", out / "scoremap.png", out / "metrics.json"]
        plot_height_map(
            s.heights, s.origin, s.resolution, paths[0], self.path_xy, path_label=self.path_label
        )
        plot_score_map(
            self.scores.score,
            self.scores.valid,
            s.origin,
            s.resolution,
            self.score_config.threshold,
            paths[1],
            self.path_xy,
            path_label=self.path_label,
        )
        write_json(paths[2], self.to_json())
        return paths


def score_config_for(request: MapRequest) -> ScoreConfig:
    """The score settings of a request: a recording's noise needs a wider cell spread."""
    if request.max_cell_spread is None and request.tum is None:
        return ScoreConfig()
    spread = REAL_MAX_CELL_SPREAD if request.max_cell_spread is None else request.max_cell_spread
    return ScoreConfig(max_cell_spread=spread)


def run_map(request: MapRequest, on_tick: Callable[[float], None] | None = None) -> MapReport:
    """Build the map a request asks for.

    Args:
        request: What to map.
        on_tick: Progress callback with the walk time [s] (simulation only).

    Raises:
        DatasetError: A recording without depth images, or malformed.
    """
    map_config = HeightMapConfig(fusion=request.fusion)
    score_config = score_config_for(request)
    if request.tum is not None:
        from footfall.datasets.tum import load_depth_png, map_tum_sequence
        from footfall.sensing.camera import PinholeCamera

        first = next(iter(sorted((request.tum / "depth").glob("*.png"))), None)
        if first is None:
            raise DatasetError(f"no depth/*.png in {request.tum}")
        height, width = load_depth_png(first).shape
        camera = PinholeCamera(*request.intrinsics, width, height)
        sequence = map_tum_sequence(
            request.tum, camera, request.up, map_config, score_config, request.depth_scale
        )
        return MapReport(
            sequence.snapshot,
            sequence.scores,
            sequence.camera_path_xy,
            "camera path",
            sequence.metrics,
            score_config,
        )
    from footfall.robot.spec import load_spec
    from footfall.sim.model import CameraMount
    from footfall.sim.survey import MappingSettings, simulate_mapping

    width, height = request.image_size
    settings = MappingSettings(
        terrain=request.terrain,
        seconds=request.seconds,
        noise=request.noise,
        seed=request.seed,
        camera=CameraMount(width=width, height=height),
        map=map_config,
        score=score_config,
    )
    survey = simulate_mapping(load_spec("default"), settings, on_tick=on_tick)
    return MapReport(
        survey.snapshot, survey.scores, survey.path_xy, "robot path", survey.metrics, score_config
    )
