"""A mapping run in simulation: the robot walks a terrain while its camera builds the map."""

from __future__ import annotations

import itertools
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from footfall.checks import require_positive
from footfall.control_loop import run_control_loop
from footfall.errors import ConfigError
from footfall.mapping.engine import HeightMapConfig
from footfall.mapping.snapshot import MapSnapshot
from footfall.messages import WalkCommand
from footfall.motion.gait import GaitConfig
from footfall.motion.walker import WalkController
from footfall.nodes.mapping import MappingNode
from footfall.robot.planar import PlanarPose
from footfall.robot.spec import HexapodSpec
from footfall.runtime.bus import InProcessBus
from footfall.scoring.walkability import ScoreConfig, ScoreMap, score_map
from footfall.sensing.pose import SlamNoise, SlamNoiseConfig
from footfall.sim.hexapod import MujocoHexapod
from footfall.sim.model import CameraMount
from footfall.sim.sensors import SimCameraNode, SimPoseNode, true_body_pose
from footfall.sim.terrain import Terrain
from footfall.sim.terrains import make_terrain

NOISE_MODELS = ("none", "slam")
# A map cell within this many cells of a near-vertical wall is left out of the height error:
# its footprint straddles two heights, so no single value is right.
EDGE_EXCLUSION_CELLS = 1
# Surface steeper than this (rise over run) counts as a vertical wall.
VERTICAL_SLOPE = 2.0
# Cells within this distance of the body's path count for coverage [m].
PATH_HALF_WIDTH = 0.1


@dataclass(frozen=True)
class MappingSettings:
    """What to map.

    Attributes:
        terrain: Terrain name.
        seconds: Walking time [s].
        noise: ``"none"`` (true camera poses) or ``"slam"`` (drift and jitter).
        seed: Seed of the terrain and the pose noise.
        speed: Walking speed [m/s].
        camera: Depth camera mount and intrinsics.
        map: Height map settings.
        score: Score settings.
        slam: Pose noise magnitudes for ``noise="slam"``.
    """

    terrain: str = "course"
    seconds: float = 20.0
    noise: str = "none"
    seed: int = 0
    speed: float = 0.12
    camera: CameraMount = field(default_factory=CameraMount)
    map: HeightMapConfig = field(default_factory=HeightMapConfig)
    score: ScoreConfig = field(default_factory=ScoreConfig)
    slam: SlamNoiseConfig = field(default_factory=SlamNoiseConfig)

    def __post_init__(self) -> None:
        if self.noise not in NOISE_MODELS:
            raise ConfigError(
                f"unknown noise model {self.noise!r}; choose one of {', '.join(NOISE_MODELS)}"
            )
        require_positive("mapping", seconds=self.seconds)


@dataclass(frozen=True)
class MappingResult:
    """Outcome of a mapping run.

    Attributes:
        snapshot: The final map window.
        scores: Its score map.
        path_xy: True body positions over the run, shape (n, 2) [m].
        terrain: The terrain walked.
        metrics: Summary (the ``metrics.json`` content).
    """

    snapshot: MapSnapshot
    scores: ScoreMap
    path_xy: npt.NDArray[np.float64]
    terrain: Terrain
    metrics: dict[str, object]


def vertical_edge_cells(
    terrain: Terrain, snapshot: MapSnapshot, margin_cells: int = EDGE_EXCLUSION_CELLS
) -> npt.NDArray[np.bool_]:
    """Cells within ``margin_cells`` of a near-vertical wall of the true terrain.

    The true surface is sampled four times per cell side; a sample whose finite-difference
    slope exceeds ``VERTICAL_SLOPE`` marks a wall.
    """
    sub = 4
    res = snapshot.resolution
    n = snapshot.size
    offsets = (np.arange(n * sub) + 0.5) * res / sub
    xs = snapshot.origin[0] + offsets
    ys = snapshot.origin[1] + offsets
    fine = terrain.height(xs[:, None], ys[None, :])
    step = res / sub
    steep = np.zeros(fine.shape, dtype=bool)
    steep[1:, :] |= np.abs(np.diff(fine, axis=0)) / step > VERTICAL_SLOPE
    steep[:-1, :] |= np.abs(np.diff(fine, axis=0)) / step > VERTICAL_SLOPE
    steep[:, 1:] |= np.abs(np.diff(fine, axis=1)) / step > VERTICAL_SLOPE
    steep[:, :-1] |= np.abs(np.diff(fine, axis=1)) / step > VERTICAL_SLOPE
    wall = steep.reshape(n, sub, n, sub).any(axis=(1, 3))
    grown = wall.copy()
    for _ in range(margin_cells):
        g = grown.copy()
        g[1:, :] |= grown[:-1, :]
        g[:-1, :] |= grown[1:, :]
        g[:, 1:] |= grown[:, :-1]
        g[:, :-1] |= grown[:, 1:]
        grown = g
    return grown


def map_accuracy(terrain: Terrain, snapshot: MapSnapshot) -> dict[str, float | int]:
    """Height error of the known cells against the terrain's true height at cell centres."""
    xs, ys = snapshot.centres()
    truth = terrain.height(xs, ys)
    edges = vertical_edge_cells(terrain, snapshot)
    scored = snapshot.known & ~edges
    error = (snapshot.heights - truth)[scored]
    return {
        "height_rmse_m": float(np.sqrt(np.mean(error**2))) if error.size else float("nan"),
        "height_error_p95_m": float(np.percentile(np.abs(error), 95))
        if error.size
        else float("nan"),
        "height_error_mean_m": float(np.mean(error)) if error.size else float("nan"),
        "cells_known": int(snapshot.known.sum()),
        "cells_scored": int(scored.sum()),
        "edge_cells_excluded": int((snapshot.known & edges).sum()),
    }


def path_coverage(
    snapshot: MapSnapshot, path_xy: npt.NDArray[np.float64], half_width: float = PATH_HALF_WIDTH
) -> float:
    """Known fraction of the map cells within ``half_width`` of the path (inside the window)."""
    xs, ys = snapshot.centres()
    cells = np.stack([xs.ravel(), ys.ravel()], axis=1)
    near = np.zeros(cells.shape[0], dtype=bool)
    points = path_xy[:: max(1, len(path_xy) // 400)]
    for a, b in itertools.pairwise(points):
        ab = b - a
        t = np.clip(((cells - a) @ ab) / max(float(ab @ ab), 1e-12), 0.0, 1.0)
        near |= np.linalg.norm(cells - (a + t[:, None] * ab), axis=1) <= half_width
    near = near.reshape(xs.shape)
    return float(snapshot.known[near].mean()) if near.any() else float("nan")


def simulate_mapping(
    spec: HexapodSpec,
    settings: MappingSettings,
    on_tick: Callable[[float], None] | None = None,
    bus: InProcessBus | None = None,
    on_mapping: Callable[[MappingNode], None] | None = None,
    terrain: Terrain | None = None,
) -> MappingResult:
    """Walk the (blind) robot across a terrain while mapping it with the body camera.

    Args:
        spec: The robot.
        settings: What to map.
        on_tick: Progress callback with the walk time [s].
        bus: The bus to run the nodes on (a recorder may tap it); a new one by default.
        on_mapping: Called with the mapping node once it stands.
        terrain: The terrain, made to measure; by default ``settings.terrain`` at
            ``settings.seed``.

    Returns:
        The final map, its scores and the metrics.
    """
    rng = np.random.default_rng(settings.seed)
    if terrain is None:
        terrain = make_terrain(settings.terrain, seed=settings.seed)
    backend = MujocoHexapod(spec, terrain, settings.camera)
    backend.advance(0.3)
    noise = SlamNoise(settings.slam, rng) if settings.noise == "slam" else None
    bus = bus if bus is not None else InProcessBus()
    body = true_body_pose(backend).position
    mapping = MappingNode(
        bus, settings.map, settings.score, publish_every_frame=False, centre=(body[0], body[1])
    )
    if on_mapping is not None:
        on_mapping(mapping)
    camera = SimCameraNode(bus, backend, settings.camera)
    SimPoseNode(bus, camera, noise)
    controller = WalkController(
        spec, GaitConfig(kind="tripod"), initial_pose=PlanarPose(*terrain.start)
    )
    command = WalkCommand(speed=settings.speed, body_height=spec.body_height)

    def sense(t: float) -> None:
        if on_tick is not None:
            on_tick(t)
        camera.tick(t)

    log = run_control_loop(backend, controller, command, settings.seconds, on_tick=sense, bus=bus)
    camera.close()
    snapshot = mapping.height_map.snapshot()
    t0 = time.perf_counter()
    scores = score_map(snapshot, settings.score)
    score_ms = 1e3 * (time.perf_counter() - t0)
    path = log.array("body_position_in_world")[:, :2]
    metrics: dict[str, object] = {
        **map_accuracy(terrain, snapshot),
        "coverage": path_coverage(snapshot, path),
        "frames": mapping.frames,
        **mapping.timing(),
        **camera.timing(),
        "score_ms": score_ms,
        "pixels_dropped": mapping.pixels_dropped,
        "points_outside_map": mapping.points_outside,
        "valid_fraction_of_known": float(scores.valid[snapshot.known].mean())
        if snapshot.known.any()
        else 0.0,
        "terrain": settings.terrain,
        "noise": settings.noise,
        "seed": settings.seed,
        "sim_seconds": settings.seconds,
        "image_size": [settings.camera.width, settings.camera.height],
        "map_size_cells": settings.map.size,
        "map_resolution_m": settings.map.resolution,
        "fusion": settings.map.fusion.value,
        "mujoco_warnings": backend.warnings(),
    }
    return MappingResult(snapshot, scores, path, terrain, metrics)
