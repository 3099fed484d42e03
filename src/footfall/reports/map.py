"""A height map and score map, as ``footfall map`` builds it: in simulation or from a recording."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from footfall.errors import ConfigError, DatasetError
from footfall.mapping.drift import DriftConfig
from footfall.mapping.engine import HeightMapConfig
from footfall.mapping.snapshot import MapSnapshot
from footfall.reports import write_json
from footfall.scoring.walkability import ScoreConfig, ScoreMap
from footfall.sensing.pose import Pose

if TYPE_CHECKING:
    from footfall.datasets.tum import SequenceMap
    from footfall.recording.session import Recorders
    from footfall.runtime.bus import InProcessBus


@dataclass(frozen=True)
class MapRequest:
    """What to map (the options of ``footfall map``).

    Attributes:
        terrain: Terrain to walk and map in simulation.
        seconds: Walking time [s].
        noise: Pose noise model, ``"none"`` or ``"slam"``.
        seed: Seed of the terrain and the noise.
        image_size: Depth image width and height [px].
        fusion: Per-cell fusion rule; None: ``latest`` in simulation, ``variance`` (the
            sensor's noise averaged down over frames) for a recording.
        drift_compensation: Register every frame vertically against the map before fusing
            it (:mod:`footfall.mapping.drift`).
        max_cell_spread: In-frame height range of a cell, beyond the sensor's noise, above
            which it straddles an edge [m]; None for the score's default.
        tum: A TUM-layout sequence (or, with a camera pose, a depth PNG or a folder of
            them) to map instead of simulating.
        intrinsics: ``fx, fy, cx, cy`` of the recording's depth camera [px].
        up: The recorded world's up axis.
        depth_scale: Metres per depth unit of the recording.
        sensor: The recording's sensor class, for its noise model
            (:mod:`footfall.sensing.noise`).
        camera_height: Camera height above the floor [m], for frames without a trajectory.
        camera_pitch_deg: How far the camera looks down [deg], likewise.
        camera_roll_deg: How far its right side dips [deg], likewise.
        record: An ``.mcap`` file to record every bus message to.
        rerun: An ``.rrd`` file to log the run to for the rerun viewer.
        rerun_spawn: Open a rerun viewer on the run.
        realsense: A RealSense recording (``.bag``, ``.db3``) to map instead of simulating.
        trajectory: The camera's poses for a RealSense recording (TUM format).
        realsense_options: librealsense's depth filters (``decimation``, ``spatial``,
            ``temporal``, ``hole_filling``).
        pose: Where a TUM sequence's poses come from: ``"recorded"`` (its groundtruth.txt)
            or ``"odometry"`` (tracked from its depth images, :mod:`footfall.odometry`).
    """

    terrain: str = "course"
    seconds: float = 20.0
    noise: str = "none"
    seed: int = 0
    image_size: tuple[int, int] = (640, 480)
    fusion: str | None = None
    max_cell_spread: float | None = None
    drift_compensation: bool = False
    tum: Path | None = None
    intrinsics: tuple[float, float, float, float] = (525.0, 525.0, 319.5, 239.5)
    up: tuple[float, float, float] = (0.0, 0.0, 1.0)
    depth_scale: float = 1.0 / 5000.0
    sensor: str = "kinect"
    camera_height: float | None = None
    camera_pitch_deg: float | None = None
    camera_roll_deg: float | None = None
    record: Path | None = None
    rerun: Path | None = None
    rerun_spawn: bool = False
    realsense: Path | None = None
    trajectory: Path | None = None
    realsense_options: dict[str, str] = field(default_factory=dict)
    pose: str = "recorded"

    @property
    def fixed_camera(self) -> bool:
        """Whether the recording's frames are taken from a given camera pose."""
        return any(
            v is not None for v in (self.camera_height, self.camera_pitch_deg, self.camera_roll_deg)
        )


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

    @classmethod
    def of_sequence(cls, sequence: SequenceMap, score_config: ScoreConfig) -> MapReport:
        """The report of a mapped recording (its path is the camera's)."""
        return cls(
            sequence.snapshot,
            sequence.scores,
            sequence.camera_path_xy,
            "camera path",
            sequence.metrics,
            score_config,
        )

    def to_json(self) -> dict[str, object]:
        """The ``metrics.json`` content."""
        return dict(self.metrics)

    def write(self, out: Path) -> list[Path]:
        """Write ``heightmap.png``, ``scoremap.png``, ``metrics.json`` and ``map.npz``."""
        from footfall.plots import plot_height_map, plot_score_map

        out.mkdir(parents=True, exist_ok=True)
        s = self.snapshot
        paths = [out / "heightmap.png", out / "scoremap.png", out / "metrics.json"]
        paths.append(write_map_npz(out / "map.npz", s, self.scores))
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


def write_map_npz(path: Path, snapshot: MapSnapshot, scores: ScoreMap) -> Path:
    """Write the map as arrays to an ``.npz`` file.

    Arrays ``height`` [m], ``variance`` [m^2], ``spread`` [m], ``score``, ``valid``,
    ``known``, each N x N with row = y and column = x in the map frame (NaN where
    unknown), and ``resolution_m``, ``origin_xy_m`` (the map-frame position of the outer
    corner of cell [0, 0]).
    """

    def grid(values: npt.NDArray | None, fill: float = np.nan) -> npt.NDArray:
        if values is None:
            return np.full(snapshot.heights.T.shape, fill)
        return np.ascontiguousarray(values.T)

    np.savez_compressed(
        path,
        height=grid(snapshot.heights),
        variance=grid(snapshot.variance),
        spread=grid(snapshot.spread),
        score=grid(scores.score),
        valid=grid(scores.valid),
        known=grid(snapshot.known),
        resolution_m=np.float64(snapshot.resolution),
        origin_xy_m=np.asarray(snapshot.origin, dtype=np.float64),
        layout=np.str_("row = y, column = x; origin_xy_m is the corner of cell [0, 0]"),
    )
    return path


def score_config_for(request: MapRequest) -> ScoreConfig:
    """The score settings of a request."""
    if request.max_cell_spread is None:
        return ScoreConfig()
    return ScoreConfig(max_cell_spread=request.max_cell_spread)


def run_map(request: MapRequest, on_tick: Callable[[float], None] | None = None) -> MapReport:
    """Build the map a request asks for.

    Args:
        request: What to map.
        on_tick: Progress callback with the walk time [s] (simulation only).

    Raises:
        DatasetError: A recording without depth images, or malformed.
    """
    recorded = request.tum is not None or request.realsense is not None
    if request.tum is not None and request.realsense is not None:
        raise ConfigError("map one recording: --tum or --realsense")
    if request.trajectory is not None and request.realsense is None:
        raise ConfigError("--trajectory goes with --realsense (a TUM sequence has its own)")
    if request.pose not in ("recorded", "odometry"):
        raise ConfigError(f"--pose is recorded or odometry, got {request.pose!r}")
    if request.pose == "odometry" and request.tum is None:
        raise ConfigError("--pose odometry tracks a TUM-layout sequence: give --tum")
    fusion = request.fusion or ("variance" if recorded else "latest")
    map_config = HeightMapConfig(
        fusion=fusion, drift=DriftConfig(enabled=request.drift_compensation)
    )
    score_config = score_config_for(request)
    from footfall.recording.session import Recorders
    from footfall.runtime.bus import InProcessBus

    with Recorders(request.record, request.rerun, request.rerun_spawn) as recorders:
        bus = recorders.attach(InProcessBus())
        if request.realsense is not None:
            return _map_realsense(request, map_config, score_config, bus, recorders)
        if recorded:
            return _map_recording(request, map_config, score_config, bus, recorders)
        return _map_simulation(request, map_config, score_config, on_tick, bus, recorders)


def _map_simulation(
    request: MapRequest,
    map_config: HeightMapConfig,
    score_config: ScoreConfig,
    on_tick: Callable[[float], None] | None,
    bus: InProcessBus,
    recorders: Recorders,
) -> MapReport:
    """Map a terrain in simulation."""
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
    survey = simulate_mapping(
        load_spec("default"),
        settings,
        on_tick=on_tick,
        bus=bus,
        on_mapping=recorders.mapping_started,
    )
    return MapReport(
        survey.snapshot, survey.scores, survey.path_xy, "robot path", survey.metrics, score_config
    )


def _fixed_camera_pose(request: MapRequest) -> Pose:
    """The camera's pose over the floor the request gives.

    Raises:
        ConfigError: No camera height.
    """
    import math

    from footfall.pointcloud.ground import CameraOverFloor

    if request.camera_height is None:
        raise ConfigError("a fixed camera pose needs --camera-height (and its pitch and roll)")
    floor = CameraOverFloor.from_angles(
        request.camera_height,
        math.radians(request.camera_pitch_deg or 0.0),
        math.radians(request.camera_roll_deg or 0.0),
    )
    return Pose(np.array([0.0, 0.0, floor.height_m]), floor.rotation_camera_to_map)


def _map_realsense(
    request: MapRequest,
    map_config: HeightMapConfig,
    score_config: ScoreConfig,
    bus: InProcessBus,
    recorders: Recorders,
) -> MapReport:
    """Map a RealSense recording, by its trajectory or from a given camera pose."""
    from footfall.datasets.realsense import map_realsense_recording
    from footfall.hardware.realsense_types import RealSenseFilters

    assert request.realsense is not None
    if request.trajectory is None and not request.fixed_camera:
        raise ConfigError(
            "a RealSense recording needs the camera's poses: --trajectory FILE (TUM format), "
            "or --camera-height and --camera-pitch-deg for a camera that did not move"
        )
    sequence = map_realsense_recording(
        request.realsense,
        map_config,
        score_config,
        trajectory=request.trajectory,
        up=request.up,
        camera_pose=None if request.trajectory is not None else _fixed_camera_pose(request),
        filters=RealSenseFilters.from_options(dict(request.realsense_options)),
        bus=bus,
        on_mapping=recorders.mapping_started,
    )
    return MapReport.of_sequence(sequence, score_config)


def _map_recording(
    request: MapRequest,
    map_config: HeightMapConfig,
    score_config: ScoreConfig,
    bus: InProcessBus,
    recorders: Recorders,
) -> MapReport:
    """Map a recorded sequence, or frames from a given camera pose."""
    from footfall.datasets.tum import load_depth_png, map_tum_sequence, read_fixed_view
    from footfall.sensing.camera import PinholeCamera
    from footfall.sensing.noise import sensor_noise

    assert request.tum is not None
    pose = frame_poses = None
    tracked: dict[str, object] = {}
    if request.pose == "odometry":
        from footfall.reports.odometry import OdometryRequest, odometry_over_floor

        frame_poses, report = odometry_over_floor(
            OdometryRequest(request.tum, request.intrinsics, request.depth_scale),
            _fixed_camera_pose(request) if request.fixed_camera else None,
        )
        tracked = {"odometry": report.to_json()}
        first = read_fixed_view(request.tum, Pose.identity())[0].depth_path
    elif request.fixed_camera:
        pose = _fixed_camera_pose(request)
        first = read_fixed_view(request.tum, pose)[0].depth_path
    else:
        first = read_fixed_view(request.tum, Pose.identity())[0].depth_path
        if request.tum.is_file() or not (request.tum / "groundtruth.txt").is_file():
            raise DatasetError(
                f"{request.tum} has no trajectory (groundtruth.txt): give the camera's pose "
                "over the floor with --camera-height and --camera-pitch-deg"
            )
    height, width = load_depth_png(first).shape
    camera = PinholeCamera(*request.intrinsics, width, height, noise=sensor_noise(request.sensor))
    sequence = map_tum_sequence(
        request.tum,
        camera,
        request.up,
        map_config,
        score_config,
        request.depth_scale,
        camera_pose=pose,
        bus=bus,
        on_mapping=recorders.mapping_started,
        frame_poses=frame_poses,
    )
    sequence.metrics.update(tracked)
    return MapReport.of_sequence(sequence, score_config)
