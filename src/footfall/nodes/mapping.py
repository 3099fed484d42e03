"""The mapping node: depth frames and pose estimates in, height map and score map out.

For each depth frame it takes the pose estimate of the same time (within a tolerance;
without one the frame is skipped and counted), moves the rolling map to stay centred on
the body, integrates the frame from the estimated camera pose and, each frame or on
request, scores the map and publishes one :class:`~footfall.messages.MapUpdate`. When the
pose guard has re-registered the estimate and offers the pose without that as an
alternative, the frame is placed both ways and fused where it fits the map better (by a
clear margin; the re-registered pose otherwise), and the pose taken goes back to the guard
(:mod:`footfall.nodes.pose_guard`). The simulated walk and the replay of a recorded
sequence build their maps here.
"""

from __future__ import annotations

import math
import statistics
import time
from collections import deque

import numpy as np

from footfall.errors import MessageError
from footfall.mapping.engine import HeightMapConfig, MapEngine, open_map
from footfall.mapping.snapshot import MapSnapshot
from footfall.messages import DepthFrame, GroundPrior, LogLine, MapUpdate, PoseEstimate
from footfall.nodes.pose_guard import ALTERNATIVE_POSE_TOPIC, REGISTERED_POSE_TOPIC
from footfall.runtime.bus import Bus
from footfall.scoring.incremental import IncrementalScorer
from footfall.scoring.walkability import ScoreConfig, ScoreMap

# A pose estimate this close in time to a depth frame is the frame's pose [s].
POSE_TOLERANCE_S = 0.02
# Depth frames held while their pose has not arrived.
MAX_PENDING_FRAMES = 4
# Pose estimates held for frames that arrive late (a few seconds at a camera's rate).
POSE_HISTORY = 64
# Per-frame times kept for the timing figures, and camera positions kept for the path.
TIMING_HISTORY = 10_000
PATH_HISTORY = 20_000
# A camera that moved this much and sends the very same image is frozen [m], [rad].
REPEAT_MOTION_M = 0.002
REPEAT_TURN_RAD = 0.002
# The alternative pose is taken when its frame's misfit is below this share of the
# re-registered pose's, and lower by at least ALTERNATIVE_GAIN_M [m].
ALTERNATIVE_SHARE = 0.4
ALTERNATIVE_GAIN_M = 0.002


def pose_near(poses: deque[PoseEstimate], stamp: float) -> PoseEstimate | None:
    """The held pose estimate nearest time ``stamp``, if one is within the tolerance."""
    best = None
    for pose in reversed(poses):
        if abs(pose.stamp - stamp) <= POSE_TOLERANCE_S and (
            best is None or abs(pose.stamp - stamp) < abs(best.stamp - stamp)
        ):
            best = pose
        if pose.stamp < stamp - POSE_TOLERANCE_S:
            break
    return best


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
    """The score map a map update carries.

    Raises:
        MessageError: The update came over a radio link without its slope and proximity.
    """
    if update.slope is None or update.proximity is None:
        raise MessageError(
            f"map update {update.sequence} carries no slope or proximity (a radio link's map, "
            "for drawing): a planner needs the robot's own map"
        )
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
        reject_repeats: Set aside a frame that repeats the previous image bit for bit
            although the camera moved (a frozen camera); a robot's own camera does, a
            replay of synthetic images need not.
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
        reject_repeats: bool = False,
    ) -> None:
        self.bus = bus
        self.reject_repeats = reject_repeats
        self.score_config = score_config or ScoreConfig()
        self._scorer = IncrementalScorer(self.score_config)
        self.height_map: MapEngine = open_map(map_config, centre=centre)
        self.initial_centre = (float(centre[0]), float(centre[1]))
        self.publish_every_frame = publish_every_frame
        self.stride = stride
        self.scores: ScoreMap | None = None
        self.sequence = 0
        self.frames = 0
        self.frames_skipped_no_pose = 0
        self.frames_repeated = 0
        self.frames_inconsistent = 0
        self.pixels_dropped = 0
        self.points_outside = 0
        self.largest_offset_m = 0.0
        self.alternatives_taken = 0
        self.update_ms: deque[float] = deque(maxlen=TIMING_HISTORY)
        self.update_cpu_ms: deque[float] = deque(maxlen=TIMING_HISTORY)
        self.camera_path_xy: deque[tuple[float, float]] = deque(maxlen=PATH_HISTORY)
        self._poses: deque[PoseEstimate] = deque(maxlen=POSE_HISTORY)
        self._alternatives: deque[PoseEstimate] = deque(maxlen=POSE_HISTORY)
        self._pending: deque[DepthFrame] = deque()
        self._previous: tuple[DepthFrame, PoseEstimate] | None = None
        bus.subscribe(PoseEstimate.TOPIC, self._on_pose)
        bus.subscribe(DepthFrame.TOPIC, self._on_depth)
        bus.subscribe(GroundPrior.TOPIC, self._on_ground_prior)
        bus.subscribe(ALTERNATIVE_POSE_TOPIC, self._alternatives.append)

    def _pose_at(self, stamp: float) -> PoseEstimate | None:
        """The held pose estimate of time ``stamp``, if one is within the tolerance."""
        return pose_near(self._poses, stamp)

    def _on_pose(self, message: PoseEstimate) -> None:
        if self._poses and message.stamp < self._poses[-1].stamp:
            self._poses.clear()  # time went back (a replay restarted): the history is void
        self._poses.append(message)
        while self._pending:
            frame = self._pending.popleft()
            pose = self._pose_at(frame.stamp)
            if pose is not None:
                self._integrate(frame, pose)
            elif frame.stamp > message.stamp:
                self._pending.appendleft(frame)  # its pose is still to come
                break
            else:
                self._skip(frame, "no pose estimate of its time")

    def _on_ground_prior(self, prior: GroundPrior) -> None:
        """Mark a disc around the standing robot as known ground (a proprioceptive prior).

        The camera looks ahead and never sees under or beside the robot, where its first
        steps land; cells the camera sees replace these, and a disc reaching past a pit's
        rim loses the cells the camera sees through (:meth:`HeightMap.assume_ground`).
        """
        res = self.height_map.config.resolution
        offsets = np.arange(-prior.radius, prior.radius + res, res)
        gx, gy = np.meshgrid(offsets, offsets)
        inside = np.hypot(gx, gy) <= prior.radius
        body = np.asarray(prior.body_position_in_world, dtype=np.float64)
        xy = body[:2] + np.stack([gx[inside], gy[inside]], axis=1)
        points = np.column_stack([xy, np.full(len(xy), prior.ground_z)])
        self.height_map.assume_ground(points, body)

    def _skip(self, frame: DepthFrame, why: str, count: bool = True) -> None:
        if count:
            self.frames_skipped_no_pose += 1
        self.bus.publish(
            LogLine.TOPIC,
            LogLine(frame.stamp, self.name, "warning", f"depth frame {frame.sequence}: {why}"),
        )

    def _on_depth(self, frame: DepthFrame) -> None:
        pose = self._pose_at(frame.stamp)
        if pose is not None:
            self._integrate(frame, pose)
            return
        if self._poses and self._poses[-1].stamp > frame.stamp:
            self._skip(frame, "no pose estimate of its time (older than the latest estimate)")
            return
        self._pending.append(frame)  # wait for its pose
        if len(self._pending) > MAX_PENDING_FRAMES:
            self._skip(self._pending.popleft(), "no pose estimate arrived for it")

    def _repeats_previous(self, frame: DepthFrame, pose: PoseEstimate) -> bool:
        """Whether ``frame`` carries the previous image although the camera moved.

        A real sensor's noise never repeats an image; a simulated one does when nothing
        moves, and then the repeat is harmless. A camera that moved and still sends the
        same image is frozen: its image belongs to another pose.
        """
        if self._previous is None or not self.reject_repeats:
            return False
        last_frame, last_pose = self._previous
        a, b = last_pose.camera_in_world, pose.camera_in_world
        moved = float(np.linalg.norm(a.position - b.position)) > REPEAT_MOTION_M or (
            (a.rotation.inv() * b.rotation).magnitude() > REPEAT_TURN_RAD
        )
        return (
            moved
            and last_frame.depth.shape == frame.depth.shape
            and np.array_equal(last_frame.depth, frame.depth, equal_nan=True)
        )

    def _integrate(self, frame: DepthFrame, pose: PoseEstimate) -> None:
        if self._repeats_previous(frame, pose):
            self.frames_repeated += 1
            self._skip(frame, "repeats the previous image although the camera moved", count=False)
            return
        self._previous = (frame, pose)
        t0, cpu0 = time.perf_counter(), time.thread_time()
        alternative = pose_near(self._alternatives, frame.stamp) if self._alternatives else None
        if alternative is not None:
            pose = self._registered(frame, pose, alternative)
        body = pose.body_in_world.position
        self.height_map.recentre((float(body[0]), float(body[1])))
        stats = self.height_map.integrate_depth(
            frame.depth,
            frame.intrinsics,
            pose.camera_in_world,
            depth_scale=frame.depth_scale,
            stride=self.stride,
        )
        if stats.inconsistent:
            self.frames_inconsistent += 1
            self.bus.publish(
                LogLine.TOPIC,
                LogLine(
                    frame.stamp,
                    self.name,
                    "warning",
                    f"depth frame {frame.sequence}: {stats.vertical_offset_m:+.3f} m off the "
                    "map where they overlap; not fused (its pose is inconsistent)",
                ),
            )
            return
        if math.isfinite(stats.vertical_offset_m):
            self.largest_offset_m = max(self.largest_offset_m, abs(stats.vertical_offset_m))
        update = self._score(frame.stamp) if self.publish_every_frame else None
        self.update_ms.append(1e3 * (time.perf_counter() - t0))
        self.update_cpu_ms.append(1e3 * (time.thread_time() - cpu0))
        self.frames += 1
        self.pixels_dropped += stats.depth.dropped
        self.points_outside += stats.outside
        camera = pose.camera_in_world.position
        self.camera_path_xy.append((float(camera[0]), float(camera[1])))
        if update is not None:
            self.bus.publish(MapUpdate.TOPIC, update)

    def _registered(
        self, frame: DepthFrame, pose: PoseEstimate, alternative: PoseEstimate
    ) -> PoseEstimate:
        """The one of two poses where ``frame`` fits the map, said to the pose guard.

        Without enough overlap to tell, the pose stays and the verdict waits for a frame
        that can tell.
        """
        body = pose.body_in_world.position
        self.height_map.recentre((float(body[0]), float(body[1])))
        misfits = [
            self.height_map.misfit(
                frame.depth,
                frame.intrinsics,
                p.camera_in_world,
                depth_scale=frame.depth_scale,
                stride=self.stride,
            )
            for p in (pose, alternative)
        ]
        if not all(math.isfinite(m) for m in misfits):
            return pose
        ours, theirs = misfits
        chosen = pose
        if theirs < ALTERNATIVE_SHARE * ours and ours - theirs >= ALTERNATIVE_GAIN_M:
            chosen = alternative
            self.alternatives_taken += 1
        self.bus.publish(
            LogLine.TOPIC,
            LogLine(
                frame.stamp,
                self.name,
                "info",
                f"depth frame {frame.sequence} fits the map {1e3 * ours:.1f} mm off at the "
                f"re-registered pose, {1e3 * theirs:.1f} mm at the estimate's own: took the "
                + ("estimate's own" if chosen is alternative else "re-registered"),
            ),
        )
        self._alternatives.clear()
        self.bus.publish(REGISTERED_POSE_TOPIC, chosen)
        return chosen

    def _score(self, stamp: float) -> MapUpdate:
        snapshot = self.height_map.snapshot()
        if self._scorer.config != self.score_config:
            self._scorer = IncrementalScorer(self.score_config)
        self.scores = self._scorer.score(snapshot)
        self.sequence += 1
        return map_update(stamp, self.sequence, snapshot, self.scores)

    def publish(self, stamp: float) -> MapUpdate:
        """Score the map as it stands and publish it; returns the update."""
        update = self._score(stamp)
        self.bus.publish(MapUpdate.TOPIC, update)
        return update

    def counts(self) -> dict[str, float]:
        """Frames set aside, and the largest vertical drift correction [m]."""
        return {
            "frames_skipped_no_pose": self.frames_skipped_no_pose,
            "frames_repeated": self.frames_repeated,
            "frames_inconsistent": self.frames_inconsistent,
            "map_offset_max_m": self.largest_offset_m,
            "frames_at_alternative_pose": self.alternatives_taken,
        }

    def timing(self) -> dict[str, float]:
        """Median per-frame time of integration (and scoring, when every frame) [ms]."""
        return {
            "map_update_ms_median": statistics.median(self.update_ms)
            if self.update_ms
            else float("nan")
        }
