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

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import numpy.typing as npt
from PIL import Image

from footfall.datasets.floor import floor_flatness
from footfall.errors import DatasetError
from footfall.mapping.engine import HeightMapConfig
from footfall.mapping.snapshot import MapSnapshot
from footfall.messages import DepthFrame, PoseEstimate
from footfall.nodes.mapping import MappingNode
from footfall.runtime.bus import Bus, InProcessBus
from footfall.scoring.walkability import ScoreConfig, ScoreMap
from footfall.sensing.camera import PinholeCamera
from footfall.sensing.pose import Pose
from footfall.sensing.trajectory import Trajectory, read_table, up_to_z

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
    depth_rows = read_table(root / "depth.txt", 2)
    trajectory = Trajectory.read(root / "groundtruth.txt")
    try:
        depth_times = [float(row[0]) for row in depth_rows]
    except ValueError as exc:
        raise DatasetError(f"{root}: a timestamp is not a number ({exc})") from exc
    frames = []
    skipped = 0
    for t, row in sorted(zip(depth_times, depth_rows, strict=True), key=lambda item: item[0]):
        found = trajectory.nearest(t, max_time_difference)
        if found is None:
            skipped += 1
            continue
        pose, offset = found
        frames.append(SequenceFrame(t, root / row[1], pose, offset))
    return frames, skipped


def stamped_depth_images(path: str | Path, fps: float = 30.0) -> list[tuple[float, Path]]:
    """A sequence's depth images and their times, in time order.

    Args:
        path: One depth PNG; or a folder with ``depth.txt``, else ``depth/*.png``, else
            ``*depth*.png`` (stamped ``i / fps``).
        fps: Frame rate for files without timestamps [Hz].

    Raises:
        DatasetError: No depth image at ``path``, or a malformed ``depth.txt``.
    """
    p = Path(path)
    if p.is_file():
        return [(0.0, p)]
    if not p.is_dir():
        raise DatasetError(f"missing depth image or sequence {p}")
    if (p / "depth.txt").is_file():
        rows = read_table(p / "depth.txt", 2)
        try:
            stamped = sorted((float(r[0]), p / r[1]) for r in rows)
        except ValueError as exc:
            raise DatasetError(f"{p / 'depth.txt'}: a timestamp is not a number ({exc})") from exc
    else:
        files = sorted((p / "depth").glob("*.png")) or sorted(p.glob("*depth*.png"))
        stamped = [(k / fps, f) for k, f in enumerate(files)]
    if not stamped:
        raise DatasetError(f"no depth image in {p} (depth.txt, depth/*.png or *depth*.png)")
    return stamped


def read_fixed_view(path: str | Path, camera_pose: Pose, fps: float = 30.0) -> list[SequenceFrame]:
    """Depth frames all taken from one known camera pose (no trajectory).

    Args:
        path: As :func:`stamped_depth_images` reads it.
        camera_pose: The optical frame's pose in the (z-up) world.
        fps: Frame rate for files without timestamps [Hz].

    Raises:
        DatasetError: No depth image at ``path``.
    """
    return [SequenceFrame(t, f, camera_pose, 0.0) for t, f in stamped_depth_images(path, fps)]


def load_depth_png(path: str | Path) -> npt.NDArray[np.uint16]:
    """A 16-bit depth PNG as an array of depth units.

    Raises:
        DatasetError: If the file is missing or not a 16-bit single-channel image.
    """
    p = Path(path)
    if not p.is_file():
        raise DatasetError(f"missing depth image {p}")
    try:
        with Image.open(p) as image:
            array = np.array(image)
    except (OSError, ValueError, SyntaxError) as exc:  # PIL's kinds of unreadable image
        raise DatasetError(f"{p}: not a readable image ({exc})") from exc
    if array.ndim != 2 or array.dtype not in (np.uint16, np.int32):
        raise DatasetError(
            f"{p} is not a 16-bit single-channel depth image (got {array.dtype}, {array.shape})"
        )
    return array.astype(np.uint16)


def check_depth_units(depth: npt.NDArray, depth_scale: float, path: str | Path) -> None:
    """Refuse a depth image that is not plausible metres under ``depth_scale``.

    Raises:
        DatasetError: Next to no reading; a median depth outside 0.25-12 m (millimetres
            read as TUM units, raw disparity); or neighbouring pixels that jump by 5 %
            of the depth as a rule (bytes swapped or bits rotated), naming the file.
    """
    d = np.asarray(depth)
    if d.ndim == 2 and d.shape[0] >= 64:
        d = d[::4]  # every frame of a recording is checked: a quarter of its rows tell
    readings = d[d > 0]
    if readings.size < 0.01 * d.size:
        raise DatasetError(f"{path}: holds almost no depth reading ({readings.size} pixels)")
    median_m = float(np.median(readings)) * depth_scale
    if not 0.25 <= median_m <= 12.0:
        raise DatasetError(
            f"{path}: median depth {median_m:.3g} m at {depth_scale:g} m per unit is not a "
            "plausible scene (millimetres read as TUM units? raw disparity?): check --depth-scale"
        )
    left, right = d[:, :-1].astype(np.float64), d[:, 1:].astype(np.float64)
    both = (left > 0) & (right > 0)
    if both.sum() > 100:
        jump = np.abs(left[both] - right[both]) / np.maximum(left[both], right[both])
        if float(np.median(jump)) > 0.05:
            raise DatasetError(
                f"{path}: neighbouring pixels differ by {np.median(jump):.0%} of their depth as "
                "a rule: not a depth image in this convention (bytes swapped? bits rotated?)"
            )


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


class TumSequenceSource:
    """A recorded sequence as the camera and pose source of a graph.

    Each frame goes out as its pose estimate (the recorded camera pose, turned so the
    world's up axis is +z; the camera is the body) followed by its depth image. Without a
    trajectory, every frame is taken from one known camera pose, and the map centres a
    little ahead of the camera, on what it sees.

    Args:
        bus: The bus.
        folder: TUM-layout sequence, or (with ``camera_pose``) a depth PNG or a folder of them.
        camera: Depth intrinsics (with the sensor's noise model).
        up: The world's up axis in the sequence's coordinates (ignored with ``camera_pose``).
        depth_scale: Metres per depth unit.
        camera_pose: The optical frame's fixed pose in a z-up world, for frames without a
            trajectory.
        look_ahead_m: How far ahead of a fixed camera the map centres [m].

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
        camera_pose: Pose | None = None,
        look_ahead_m: float = 2.0,
        frame_poses: dict[float, Pose] | None = None,
    ) -> None:
        self.bus = bus
        self.camera = camera
        self.depth_scale = depth_scale
        self.frames_implausible = 0
        if frame_poses is not None:  # poses from elsewhere (odometry), in a z-up world
            stamped = stamped_depth_images(folder)
            self.frames = [
                SequenceFrame(t, f, frame_poses[t], 0.0) for t, f in stamped if t in frame_poses
            ]
            self.skipped = len(stamped) - len(self.frames)
            self.poses = [f.camera_pose for f in self.frames]
            self.centres = self.poses
            return
        if camera_pose is not None:
            self.frames, self.skipped = read_fixed_view(folder, camera_pose), 0
            self.poses = [camera_pose for _ in self.frames]
            centre = fixed_view_centre(camera_pose, look_ahead_m)
            self.centres = [centre for _ in self.frames]
            return
        self.frames, self.skipped = read_tum_sequence(folder)
        if not self.frames:
            raise DatasetError(f"{folder}: no depth frame has a pose within tolerance")
        align = Pose(np.zeros(3), up_to_z(up))
        self.poses = [align.compose(f.camera_pose) for f in self.frames]
        self.centres = self.poses

    def play(self) -> int:
        """Publish every frame, as fast as they load; returns how many.

        The first frame must be plausible depth under the scale (else the whole recording
        is in another convention, and that is an error); a later frame that is not (the
        lens covered, a corrupt file) is skipped and counted in ``frames_implausible``.
        """
        camera_in_body = Pose.identity()
        frames = zip(self.frames, self.poses, self.centres, strict=True)
        published = 0
        for number, (frame, pose, centre) in enumerate(frames, 1):
            try:
                depth = load_depth_png(frame.depth_path)
                check_depth_units(depth, self.depth_scale, frame.depth_path)
            except DatasetError:
                if number == 1:
                    raise
                self.frames_implausible += 1
                continue
            published += 1
            self.bus.publish(PoseEstimate.TOPIC, PoseEstimate(frame.timestamp, pose, centre))
            image = DepthFrame(
                frame.timestamp, depth, self.camera, camera_in_body, self.depth_scale, number
            )
            self.bus.publish(DepthFrame.TOPIC, image)
        return published


def map_tum_sequence(
    folder: str | Path,
    camera: PinholeCamera,
    up: npt.ArrayLike,
    map_config: HeightMapConfig | None = None,
    score_config: ScoreConfig | None = None,
    depth_scale: float = TUM_DEPTH_SCALE,
    stride: int = 1,
    camera_pose: Pose | None = None,
    bus: InProcessBus | None = None,
    on_mapping: Callable[[MappingNode], None] | None = None,
    frame_poses: dict[float, Pose] | None = None,
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
        camera_pose: The camera's fixed pose in a z-up world, for frames without a
            trajectory.
        bus: The bus to play on (a recorder may tap it); a new one by default.
        on_mapping: Called with the mapping node once it stands.
        frame_poses: The camera's pose in a z-up world by depth frame time, instead of
            ``groundtruth.txt`` (frames without one are skipped).

    Returns:
        The map, its scores, the camera path and metrics.
    """
    bus = bus if bus is not None else InProcessBus()
    source = TumSequenceSource(
        bus, folder, camera, up, depth_scale, camera_pose, frame_poses=frame_poses
    )
    start = source.centres[0].position
    mapping = MappingNode(
        bus,
        map_config,
        score_config,
        publish_every_frame=False,
        centre=(float(start[0]), float(start[1])),
        stride=stride,
    )
    if on_mapping is not None:
        on_mapping(mapping)
    source.play()
    path = np.array([p.position[:2] for p in source.poses])
    return finish_sequence_map(
        mapping,
        source.frames[-1].timestamp,
        path,
        {"frames_skipped_no_pose": source.skipped, "frames_implausible": source.frames_implausible},
    )


def finish_sequence_map(
    mapping: MappingNode,
    stamp: float,
    camera_path_xy: npt.NDArray[np.float64],
    counts: dict[str, int],
) -> SequenceMap:
    """The map of a played sequence: scored at ``stamp``, with its metrics.

    Args:
        mapping: The mapping node the sequence played into.
        stamp: The last frame's time [s].
        camera_path_xy: Camera positions, shape (n, 2) [m].
        counts: The source's own counts; ``frames_skipped_no_pose`` adds the node's.
    """
    mapping.publish(stamp)
    snapshot = mapping.height_map.snapshot()
    scores = mapping.scores
    assert scores is not None
    skipped = counts.get("frames_skipped_no_pose", 0) + mapping.frames_skipped_no_pose
    metrics: dict[str, object] = {
        "frames": mapping.frames,
        **counts,
        "frames_skipped_no_pose": skipped,
        **mapping.timing(),
        "cells_known": int(snapshot.known.sum()),
        "pixels_dropped": mapping.pixels_dropped,
        "points_outside_map": mapping.points_outside,
        **floor_flatness(snapshot, scores.valid, window_cells=mapping.score_config.kernel_size),
    }
    return SequenceMap(snapshot, scores, camera_path_xy, metrics)


def fixed_view_centre(camera_pose: Pose, look_ahead_m: float = 2.0) -> Pose:
    """Where a map follows a camera that does not move: ``look_ahead_m`` ahead of it, level."""
    forward = camera_pose.rotation.apply([0.0, 0.0, 1.0])
    forward[2] = 0.0
    norm = float(np.linalg.norm(forward))
    ahead = forward / norm * look_ahead_m if norm > 1e-9 else np.zeros(3)
    return Pose(camera_pose.position + ahead, camera_pose.rotation)
