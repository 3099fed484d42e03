"""Depth sequences in the TUM RGB-D layout, mapped by the same mapping node as a walk.

A sequence folder holds::

    depth.txt         "timestamp filename" per line ('#' starts a comment)
    depth/*.png       16-bit depth, value / 5000 = metres (0 = no reading)
    groundtruth.txt   "t tx ty tz qx qy qz qw": camera-to-world poses

Each depth frame takes the pose nearest in time (within a tolerance). TUM and Redwood
worlds are not z-up: the caller names the world's up axis, and the sequence is rotated so
that axis becomes +z of the map frame.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import numpy.typing as npt
from PIL import Image
from scipy.spatial.transform import Rotation

from footfall.errors import DatasetError
from footfall.mapping.height_map import HeightMapConfig, MapSnapshot
from footfall.messages import DepthFrame, PoseEstimate
from footfall.nodes.mapping import MappingNode
from footfall.runtime.bus import Bus, InProcessBus
from footfall.scoring.walkability import ScoreConfig, ScoreMap
from footfall.sensing.camera import PinholeCamera
from footfall.sensing.pose import Pose

TUM_DEPTH_SCALE = 1.0 / 5000.0  # metres per depth unit


@dataclass(frozen=True)
class SequenceFrame:
    """One depth image of a sequence and the camera pose it was taken from.

    Attributes:
        timestamp: Depth image time [s].
        depth_path: The 16-bit depth PNG.
        camera_pose: Camera (optical frame) pose in the sequence's world.
        pose_time_offset: Pose time minus depth time [s].
    """

    timestamp: float
    depth_path: Path
    camera_pose: Pose
    pose_time_offset: float


def _read_table(path: Path, columns: int) -> list[list[str]]:
    if not path.is_file():
        raise DatasetError(f"missing {path.name} in {path.parent}")
    rows = []
    for number, line in enumerate(path.read_text().splitlines(), start=1):
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        fields = line.split()
        if len(fields) < columns:
            raise DatasetError(
                f"{path.name} line {number}: expected {columns} fields, got {len(fields)}"
            )
        rows.append(fields)
    return rows


def read_tum_sequence(
    folder: str | Path, max_time_difference: float = 0.02
) -> tuple[list[SequenceFrame], int]:
    """Depth frames of a TUM-layout sequence, each with its nearest-in-time pose.

    Args:
        folder: The sequence folder.
        max_time_difference: Frames with no pose this close in time are skipped [s].

    Returns:
        The frames in time order, and how many were skipped for want of a pose.

    Raises:
        DatasetError: Missing files or malformed lines (the file and line are named).
        InvalidPoseError: A pose with a non-unit quaternion.
    """
    root = Path(folder)
    depth_rows = _read_table(root / "depth.txt", 2)
    pose_rows = _read_table(root / "groundtruth.txt", 8)
    if not pose_rows:
        raise DatasetError(f"{root / 'groundtruth.txt'} holds no poses")
    try:
        pose_table = np.array([[float(v) for v in row[:8]] for row in pose_rows])
        depth_times = [float(row[0]) for row in depth_rows]
    except ValueError as exc:
        raise DatasetError(f"{root}: a timestamp or pose value is not a number ({exc})") from exc
    order = np.argsort(pose_table[:, 0])
    pose_table = pose_table[order]
    times = pose_table[:, 0]
    frames = []
    skipped = 0
    for t, row in sorted(zip(depth_times, depth_rows, strict=True), key=lambda item: item[0]):
        k = int(np.searchsorted(times, t))
        candidates = [c for c in (k - 1, k) if 0 <= c < len(times)]
        best = min(candidates, key=lambda c: abs(times[c] - t))
        if abs(times[best] - t) > max_time_difference:
            skipped += 1
            continue
        p = pose_table[best]
        frames.append(
            SequenceFrame(
                t, root / row[1], Pose.from_quaternion(p[1:4], p[4:8]), float(times[best] - t)
            )
        )
    return frames, skipped


def load_depth_png(path: str | Path) -> npt.NDArray[np.uint16]:
    """A 16-bit depth PNG as an array of depth units.

    Raises:
        DatasetError: If the file is missing or not a 16-bit single-channel image.
    """
    p = Path(path)
    if not p.is_file():
        raise DatasetError(f"missing depth image {p}")
    with Image.open(p) as image:
        array = np.array(image)
    if array.ndim != 2 or array.dtype not in (np.uint16, np.int32):
        raise DatasetError(
            f"{p} is not a 16-bit single-channel depth image (got {array.dtype}, {array.shape})"
        )
    return array.astype(np.uint16)


def up_to_z(up: npt.ArrayLike) -> Rotation:
    """The smallest rotation taking the world's up axis to +z."""
    u = np.asarray(up, dtype=np.float64)
    norm = np.linalg.norm(u)
    if u.shape != (3,) or not norm > 0:
        raise DatasetError(f"--up needs a non-zero 3-vector, got {up!r}")
    rotation, _ = Rotation.align_vectors([[0.0, 0.0, 1.0]], [u / norm])
    return rotation


@dataclass(frozen=True)
class SequenceMap:
    """A mapped sequence.

    Attributes:
        snapshot: Final map window (z up).
        scores: Its score map.
        camera_path_xy: Camera positions in the map frame, shape (n, 2) [m].
        metrics: Summary figures.
    """

    snapshot: MapSnapshot
    scores: ScoreMap
    camera_path_xy: npt.NDArray[np.float64]
    metrics: dict[str, object]


def floor_flatness(snapshot: MapSnapshot, band: float = 0.03) -> dict[str, float | int]:
    """Spread of the floor's cell heights.

    The floor is the lowest well-populated height level; its cells are those within
    ``band`` of that level [m].
    """
    heights = snapshot.heights[snapshot.known]
    if heights.size == 0:
        return {"floor_cells": 0}
    bins = np.arange(heights.min(), heights.max() + 0.01, 0.01)
    if bins.size < 2:
        level = float(np.median(heights))
    else:
        counts, edges = np.histogram(heights, bins=bins)
        populated = np.flatnonzero(counts >= 0.05 * counts.max())
        level = float(0.5 * (edges[populated[0]] + edges[populated[0] + 1]))
    floor = heights[np.abs(heights - level) <= band]
    return {
        "floor_cells": int(floor.size),
        "floor_height_median_m": float(np.median(floor)),
        "floor_height_std_m": float(np.std(floor)),
        "floor_height_spread_m": float(np.percentile(floor, 95) - np.percentile(floor, 5)),
    }


class TumSequenceSource:
    """A recorded sequence as the camera and pose source of a graph.

    Each frame goes out as its pose estimate (the recorded camera pose, turned so the
    world's up axis is +z; the camera is the body) followed by its depth image.

    Args:
        bus: The bus.
        folder: TUM-layout sequence.
        camera: Depth intrinsics.
        up: The world's up axis in the sequence's coordinates.
        depth_scale: Metres per depth unit.

    Raises:
        DatasetError: Missing or malformed files, or no frame with a pose.
    """

    name = "recording"

    def __init__(
        self,
        bus: Bus,
        folder: str | Path,
        camera: PinholeCamera,
        up: npt.ArrayLike,
        depth_scale: float = TUM_DEPTH_SCALE,
    ) -> None:
        self.bus = bus
        self.camera = camera
        self.depth_scale = depth_scale
        self.frames, self.skipped = read_tum_sequence(folder)
        if not self.frames:
            raise DatasetError(f"{folder}: no depth frame has a pose within tolerance")
        align = Pose(np.zeros(3), up_to_z(up))
        self.poses = [align.compose(f.camera_pose) for f in self.frames]

    def play(self) -> int:
        """Publish every frame, as fast as they load; returns how many."""
        camera_in_body = Pose(np.zeros(3), Rotation.identity())
        for number, (frame, pose) in enumerate(zip(self.frames, self.poses, strict=True), 1):
            depth = load_depth_png(frame.depth_path)
            self.bus.publish(PoseEstimate.TOPIC, PoseEstimate(frame.timestamp, pose, pose))
            image = DepthFrame(
                frame.timestamp, depth, self.camera, camera_in_body, self.depth_scale, number
            )
            self.bus.publish(DepthFrame.TOPIC, image)
        return len(self.frames)


def map_tum_sequence(
    folder: str | Path,
    camera: PinholeCamera,
    up: npt.ArrayLike,
    map_config: HeightMapConfig | None = None,
    score_config: ScoreConfig | None = None,
    depth_scale: float = TUM_DEPTH_SCALE,
    stride: int = 1,
) -> SequenceMap:
    """Build the height map of a recorded sequence, following the camera.

    Args:
        folder: TUM-layout sequence.
        camera: Depth intrinsics.
        up: The world's up axis in the sequence's coordinates, e.g. ``(0, 1, 0)``.
        map_config: Height map settings.
        score_config: Score settings.
        depth_scale: Metres per depth unit.
        stride: Use every ``stride``-th pixel row and column.

    Returns:
        The map, its scores, the camera path and metrics.
    """
    bus = InProcessBus()
    source = TumSequenceSource(bus, folder, camera, up, depth_scale)
    start = source.poses[0].position
    mapping = MappingNode(
        bus,
        map_config,
        score_config,
        publish_every_frame=False,
        centre=(float(start[0]), float(start[1])),
        stride=stride,
    )
    source.play()
    mapping.publish(source.frames[-1].timestamp)
    snapshot = mapping.height_map.snapshot()
    scores = mapping.scores
    assert scores is not None
    path = np.array([p.position[:2] for p in source.poses])
    metrics: dict[str, object] = {
        "frames": mapping.frames,
        "frames_skipped_no_pose": source.skipped + mapping.frames_skipped_no_pose,
        **mapping.timing(),
        "cells_known": int(snapshot.known.sum()),
        "pixels_dropped": mapping.pixels_dropped,
        "points_outside_map": mapping.points_outside,
        **floor_flatness(snapshot),
    }
    return SequenceMap(snapshot, scores, path, metrics)
