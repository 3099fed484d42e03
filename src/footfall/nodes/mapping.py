"""The mapping node: depth frames and pose estimates in, height map and score map out.

For each depth frame it takes the pose estimate of the same time (within a tolerance;
without one the frame is skipped and counted), moves the rolling map to stay centred on
the body, integrates the frame from the estimated camera pose and, each frame or on
request, scores the map and publishes one :class:`~footfall.messages.MapUpdate`. The
simulated walk and the replay of a recorded sequence build their maps here.
"""

from __future__ import annotations

import statistics
import time
from collections import deque

import numpy as np

from footfall.mapping.height_map import HeightMap, HeightMapConfig, MapSnapshot
from footfall.messages import DepthFrame, GroundPrior, LogLine, MapUpdate, PoseEstimate
from footfall.runtime.bus import Bus
from footfall.scoring.walkability import ScoreConfig, ScoreMap, score_map

# A pose estimate this close in time to a depth frame is the frame's pose [s].
POSE_TOLERANCE_S = 0.02
# Depth frames held while their pose has not arrived.
MAX_PENDING_FRAMES = 4


def map_update(stamp: float, sequence: int, snapshot: MapSnapshot, scores: ScoreMap) -> MapUpdate:
    """A map update message from a snapshot and its scores."""
    return MapUpdate(
        stamp=stamp,
        sequence=sequence,
        heights=snapshot.heights,
        known=snapshot.known,
        spread=snapshot.spread,
        slope=scores.slope,
        proximity=scores.proximity,
        score=scores.score,
        valid=scores.valid,
        origin=snapshot.origin,
        resolution=snapshot.resolution,
    )


def snapshot_of(update: MapUpdate) -> MapSnapshot:
    """The height-map snapshot a map update carries."""
    return MapSnapshot(
        heights=update.heights,
        known=update.known,
        origin=(float(update.origin[0]), float(update.origin[1])),
        resolution=update.resolution,
        spread=update.spread,
    )


def scores_of(update: MapUpdate) -> ScoreMap:
    """The score map a map update carries."""
    return ScoreMap(
        update.slope,
        update.proximity,
        update.score,
        update.valid,
        (float(update.origin[0]), float(update.origin[1])),
        update.resolution,
    )


class MappingNode:
    """Rolling height map and walkability scores from depth and pose.

    Args:
        bus: The bus.
        map_config: Height map settings.
        score_config: Score settings.
        publish_every_frame: Score and publish after every frame; otherwise only on
            :meth:`publish`.
        centre: World ``(x, y)`` the map starts centred on [m].
        stride: Use every ``stride``-th pixel row and column of the depth images.
    """

    name = "mapping"

    def __init__(
        self,
        bus: Bus,
        map_config: HeightMapConfig | None = None,
        score_config: ScoreConfig | None = None,
        publish_every_frame: bool = True,
        centre: tuple[float, float] = (0.0, 0.0),
        stride: int = 1,
    ) -> None:
        self.bus = bus
        self.score_config = score_config or ScoreConfig()
        self.height_map = HeightMap(map_config, centre=centre)
        self.initial_centre = (float(centre[0]), float(centre[1]))
        self.publish_every_frame = publish_every_frame
        self.stride = stride
        self.scores: ScoreMap | None = None
        self.sequence = 0
        self.frames = 0
        self.frames_skipped_no_pose = 0
        self.pixels_dropped = 0
        self.points_outside = 0
        self.update_ms: list[float] = []
        self.camera_path_xy: list[tuple[float, float]] = []
        self._pose: PoseEstimate | None = None
        self._pending: deque[DepthFrame] = deque()
        bus.subscribe(PoseEstimate.TOPIC, self._on_pose)
        bus.subscribe(DepthFrame.TOPIC, self._on_depth)
        bus.subscribe(GroundPrior.TOPIC, self._on_ground_prior)

    def _on_pose(self, message: PoseEstimate) -> None:
        self._pose = message
        while self._pending:
            frame = self._pending.popleft()
            if abs(message.stamp - frame.stamp) <= POSE_TOLERANCE_S:
                self._integrate(frame, message)
            elif frame.stamp > message.stamp:
                self._pending.appendleft(frame)  # its pose is still to come
                break
            else:
                self._skip(frame, "no pose estimate of its time")

    def _on_ground_prior(self, prior: GroundPrior) -> None:
        """Mark a disc around the standing robot as known ground (a proprioceptive prior).

        The camera looks ahead and never sees under or beside the robot, where its first
        steps land; cells the camera sees replace these.
        """
        res = self.height_map.config.resolution
        offsets = np.arange(-prior.radius, prior.radius + res, res)
        gx, gy = np.meshgrid(offsets, offsets)
        inside = np.hypot(gx, gy) <= prior.radius
        body = np.asarray(prior.body_position_in_world, dtype=np.float64)
        xy = body[:2] + np.stack([gx[inside], gy[inside]], axis=1)
        points = np.column_stack([xy, np.full(len(xy), prior.ground_z)])
        self.height_map.integrate_points(points, body)

    def _skip(self, frame: DepthFrame, why: str) -> None:
        self.frames_skipped_no_pose += 1
        self.bus.publish(
            LogLine.TOPIC,
            LogLine(frame.stamp, self.name, "warning", f"depth frame {frame.sequence}: {why}"),
        )

    def _on_depth(self, frame: DepthFrame) -> None:
        pose = self._pose
        if pose is not None and abs(pose.stamp - frame.stamp) <= POSE_TOLERANCE_S:
            self._integrate(frame, pose)
            return
        if pose is not None and pose.stamp > frame.stamp:
            self._skip(frame, "older than the latest pose estimate")
            return
        self._pending.append(frame)  # wait for its pose
        if len(self._pending) > MAX_PENDING_FRAMES:
            self._skip(self._pending.popleft(), "no pose estimate arrived for it")

    def _integrate(self, frame: DepthFrame, pose: PoseEstimate) -> None:
        t0 = time.perf_counter()
        body = pose.body_in_world.position
        self.height_map.recentre((float(body[0]), float(body[1])))
        stats = self.height_map.integrate_depth(
            frame.depth,
            frame.intrinsics,
            pose.camera_in_world,
            depth_scale=frame.depth_scale,
            stride=self.stride,
        )
        update = self._score(frame.stamp) if self.publish_every_frame else None
        self.update_ms.append(1e3 * (time.perf_counter() - t0))
        self.frames += 1
        self.pixels_dropped += stats.depth.dropped
        self.points_outside += stats.outside
        camera = pose.camera_in_world.position
        self.camera_path_xy.append((float(camera[0]), float(camera[1])))
        if update is not None:
            self.bus.publish(MapUpdate.TOPIC, update)

    def _score(self, stamp: float) -> MapUpdate:
        snapshot = self.height_map.snapshot()
        self.scores = score_map(snapshot, self.score_config)
        self.sequence += 1
        return map_update(stamp, self.sequence, snapshot, self.scores)

    def publish(self, stamp: float) -> MapUpdate:
        """Score the map as it stands and publish it; returns the update."""
        update = self._score(stamp)
        self.bus.publish(MapUpdate.TOPIC, update)
        return update

    def timing(self) -> dict[str, float]:
        """Median per-frame time of integration (and scoring, when every frame) [ms]."""
        return {
            "map_update_ms_median": statistics.median(self.update_ms)
            if self.update_ms
            else float("nan")
        }
