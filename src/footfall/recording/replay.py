"""Replay a recording through the same mapping and scoring nodes as a live run.

Depth images (``sensor_msgs/Image``, ``16UC1`` millimetres or ``32FC1`` metres) with their
``CameraInfo`` and a camera pose (a ``PoseStamped`` or ``Odometry`` topic, or TF between
two frames) become footfall's depth frames and pose estimates on an in-process bus, where
a :class:`MappingNode` builds the map. footfall's own recordings also carry the body pose,
the ground prior, the camera's noise and range limits, and the mapping settings, so they
replay in publish order to the very map the live run built, bit for bit.

A ROS bag's poses are read first; each depth image then takes the pose nearest in time
(within ``max_pose_gap_s``; images without one are counted, not mapped).
"""

from __future__ import annotations

import bisect
import time
from collections import deque
from collections.abc import Callable
from typing import Any

import numpy as np

from footfall.errors import ConfigError, DatasetError, FootfallError
from footfall.mapping.engine import HeightMapConfig
from footfall.messages import DepthFrame, GroundPrior, PoseEstimate
from footfall.messages.codec import Message
from footfall.nodes.mapping import MappingNode
from footfall.recording.reader import RecordedMessage, Recording
from footfall.recording.replay_request import ReplayCounts, ReplayRequest
from footfall.recording.ros_decode import (
    TransformHistory,
    TransformTree,
    depth_array,
    pose_of,
)
from footfall.recording.ros_types import BODY_FRAME, CAMERA_FRAME, WORLD_FRAME, seconds
from footfall.recording.writer import restored_settings
from footfall.runtime.bus import InProcessBus
from footfall.scoring.walkability import ScoreConfig
from footfall.sensing.camera import PinholeCamera
from footfall.sensing.noise import DepthNoiseModel, sensor_noise
from footfall.sensing.pose import Pose

# What a decoded message with a field missing or out of range raises on the way to a frame.
CORRUPT_DATA = (KeyError, ValueError, TypeError, IndexError, AttributeError, OverflowError)
POSE_TYPES = ("geometry_msgs/msg/PoseStamped", "nav_msgs/msg/Odometry")
DEPTH_TYPES = ("sensor_msgs/msg/Image", "sensor_msgs/msg/CompressedImage")


def _camera(info: Any, noise: DepthNoiseModel, limits: tuple[float, float]) -> PinholeCamera:
    k = np.asarray(info.k if hasattr(info, "k") else info.K, dtype=np.float64)  # ROS 1: K
    return PinholeCamera(
        float(k[0]), float(k[4]), float(k[2]), float(k[5]), int(info.width), int(info.height),
        limits[0], limits[1], noise,
    )  # fmt: skip


def _pick(recording: Recording, given: str | None, types: tuple[str, ...], what: str) -> str:
    if given is not None:
        found = recording.require(given, what)
        if found not in types:
            raise DatasetError(f"{given} is a {found}, not a {what} ({', '.join(types)})")
        return given
    candidates = sorted(t for t, k in recording.channels.items() if k in types)
    if what == "depth image":
        candidates = [t for t in candidates if "depth" in t] or candidates
    if len(candidates) != 1:
        listed = ", ".join(candidates) or "none"
        hint = " (or --tf-frames WORLD CAMERA to look it up in TF)" if what == "camera pose" else ""
        raise DatasetError(f"{recording.path}: name the {what} topic{hint}; candidates: {listed}")
    return candidates[0]


class Replayer:
    """Feed a recording's depth and poses to a mapping node.

    Args:
        request: What to replay.
        taps: Callbacks that see every message the replay publishes (a rerun logger).
    """

    def __init__(
        self, request: ReplayRequest, taps: list[Callable[[str, Message], None]] | None = None
    ) -> None:
        self.request = request
        self.recording = Recording(request.path)
        self.taps = list(taps or [])
        self.counts = ReplayCounts()
        self.mapping: MappingNode | None = None
        self.history: TransformHistory | None = None
        self._previous_stamp: float | None = None
        self._periods: deque[float] = deque(maxlen=50)
        meta = self.recording.metadata
        self.footfall = "footfall/recording" in meta
        camera = meta.get("footfall/camera", {})
        if camera:
            try:
                self.noise = DepthNoiseModel(
                    float(camera["noise_base_m"]),
                    float(camera["noise_quadratic_per_m"]),
                    float(camera["noise_offset_m"]),
                )
                self.limits = (float(camera["min_range_m"]), float(camera["max_range_m"]))
            except (KeyError, ValueError) as exc:
                if isinstance(exc, FootfallError):
                    raise
                raise DatasetError(
                    f"{request.path}: malformed footfall/camera metadata ({exc!r})"
                ) from exc
        else:
            self.noise = sensor_noise(request.sensor)
            self.limits = (0.0, 10.0)
        self.depth_topic = _pick(self.recording, request.depth_topic, DEPTH_TYPES, "depth image")
        info = request.info_topic
        if info is None:
            beside = self.depth_topic.rsplit("/", 1)[0] + "/camera_info"
            info = beside if beside in self.recording.channels else None
        self.info_topic = _pick(
            self.recording, info, ("sensor_msgs/msg/CameraInfo",), "camera info"
        )
        self.tf_frames = request.tf_frames
        self.pose_topic = request.pose_topic
        self.fixed = request.fixed_camera()
        self.odometry = None
        if request.pose == "odometry":
            from footfall.odometry.poses import OdometryPoses

            if self.tf_frames is not None or self.pose_topic is not None:
                raise ConfigError("--pose odometry excludes --pose-topic and --tf-frames")
            self.odometry = OdometryPoses(None if self.fixed is None else self.fixed[0])
            self.fixed = None
            return
        if request.pose != "recorded":
            raise ConfigError(f"--pose is recorded or odometry, got {request.pose!r}")
        if self.fixed is not None:
            if self.tf_frames is not None or self.pose_topic is not None:
                raise ConfigError("a fixed camera pose excludes --pose-topic and --tf-frames")
            return
        if self.footfall and self.tf_frames is None and self.pose_topic is None:
            self.tf_frames = (WORLD_FRAME, CAMERA_FRAME)
        if self.tf_frames is None and self.pose_topic is None:
            self.pose_topic = _pick(self.recording, None, POSE_TYPES, "camera pose")
        if self.pose_topic is not None:
            _pick(self.recording, self.pose_topic, POSE_TYPES, "camera pose")
        elif "/tf" not in self.recording.channels and "/tf_static" not in self.recording.channels:
            raise DatasetError(f"{request.path}: no /tf topic to look the camera pose up in")

    def map_config(self) -> tuple[HeightMapConfig, ScoreConfig, int]:
        """The mapping settings: the recording's, else footfall map's for a recording."""
        m = self.recording.metadata.get("footfall/mapping")
        fusion = self.request.fusion
        if m is None:
            return HeightMapConfig(fusion=fusion or "variance"), ScoreConfig(), 1

        try:
            map_values = restored_settings(HeightMapConfig, "map", m)
            if fusion is not None:
                map_values["fusion"] = fusion
            score = ScoreConfig(**restored_settings(ScoreConfig, "score", m))  # type: ignore[arg-type]
            config = HeightMapConfig(**map_values)  # type: ignore[arg-type]
            stride = int(m.get("stride", "1"))
        except (ValueError, TypeError) as exc:
            raise DatasetError(
                f"{self.request.path}: malformed footfall/mapping metadata: {exc}"
            ) from exc
        return config, score, stride

    def _poses(self) -> tuple[list[float], list[Pose]]:
        times: list[float] = []
        poses: list[Pose] = []
        assert self.pose_topic is not None
        for m in self.recording.messages({self.pose_topic}):
            body = m.message.pose.pose if m.typename.startswith("nav_msgs") else m.message.pose
            times.append(seconds(m.message.header.stamp))
            poses.append(pose_of(body))
        order = np.argsort(times, kind="stable")
        return [times[k] for k in order], [poses[k] for k in order]

    def _mapping_at(self, bus: InProcessBus, xy: tuple[float, float]) -> MappingNode:
        """The mapping node, started centred on ``xy`` (the recording's centre if it has one)."""
        if self.mapping is None:
            config, score, stride = self.map_config()
            meta = self.recording.metadata.get("footfall/mapping", {})
            try:
                if "centre_x" in meta:
                    xy = (float(meta["centre_x"]), float(meta["centre_y"]))
                self.mapping = MappingNode(
                    bus,
                    config,
                    score,
                    False,
                    centre=xy,
                    stride=stride,
                    reject_repeats=meta.get("reject_repeats") == "True",
                )
            except (ValueError, KeyError) as exc:
                raise DatasetError(
                    f"{self.request.path}: malformed footfall/mapping metadata: {exc}"
                ) from exc
        return self.mapping

    def run(self) -> MappingNode:
        """Replay the recording; returns the mapping node with the map it built and scored.

        Raises:
            DatasetError: No image could be mapped, or a message is corrupt or malformed.
        """
        try:
            return self._replay()
        except FootfallError:
            raise
        except CORRUPT_DATA as exc:  # a field missing or out of range in a decoded message
            raise DatasetError(
                f"{self.request.path}: a corrupt or malformed message ({type(exc).__name__}: {exc})"
            ) from exc

    def _replay(self) -> MappingNode:
        bus = InProcessBus()
        for tap in self.taps:
            bus.tap(tap)
        self.mapping = None
        if "centre_x" in self.recording.metadata.get("footfall/mapping", {}):
            self._mapping_at(bus, (0.0, 0.0))
        times, poses = self._poses() if self.pose_topic is not None else ([], [])
        if not self.footfall and self.tf_frames is not None and self.fixed is None:
            self.history = TransformHistory()
            for m in self.recording.messages({"/tf", "/tf_static"}):
                self.history.add(m.message, static=m.topic == "/tf_static")
        tree = TransformTree()
        topics = {self.depth_topic, self.info_topic, "/tf", "/tf_static", "/ground_prior"}
        info = None
        last_stamp = 0.0
        start_wall, start_log = time.monotonic(), None
        for m in self.recording.messages(topics):
            if not self.request.fast:
                start_log = m.log_time_ns if start_log is None else start_log
                due = (m.log_time_ns - start_log) * 1e-9 / max(self.request.rate, 1e-9)
                time.sleep(max(0.0, due - (time.monotonic() - start_wall)))
            if m.topic in ("/tf", "/tf_static"):
                tree.add(m.message)
                if self.footfall and self.pose_topic is None and self.odometry is None:
                    self._publish_tf_pose(bus, m, tree)
            elif m.topic == "/ground_prior" and self.mapping is not None:
                g = m.message
                position = np.array([g.body_position.x, g.body_position.y, g.body_position.z])
                bus.publish(
                    GroundPrior.TOPIC,
                    GroundPrior(seconds(g.header.stamp), position, g.ground_z, g.radius),
                )
            elif m.topic == self.info_topic:
                info = m.message
            elif m.topic == self.depth_topic:
                self.counts.depth_images += 1
                if info is None:
                    self.counts.frames_without_info += 1
                    continue
                stamp = seconds(m.message.header.stamp)
                self._note_gap(stamp)
                if self.fixed is not None:
                    camera, centre = self.fixed
                    self._mapping_at(bus, (float(centre.position[0]), float(centre.position[1])))
                    bus.publish(PoseEstimate.TOPIC, PoseEstimate(stamp, camera, centre))
                elif self.odometry is not None or not self.footfall:
                    pose = self._pose_at(stamp, times, poses, tree, m.message, info)
                    if pose is None:
                        self.counts.frames_without_pose += 1
                        continue
                    self._mapping_at(bus, (float(pose.position[0]), float(pose.position[1])))
                    bus.publish(PoseEstimate.TOPIC, PoseEstimate(stamp, pose, pose))
                if self.mapping is None:  # a footfall recording's image before any pose
                    self.counts.frames_without_pose += 1
                    continue
                depth, scale = depth_array(m.message)
                camera = _camera(info, self.noise, self.limits)
                before = self.mapping.frames
                number = self.counts.depth_images
                frame = DepthFrame(stamp, depth, camera, Pose.identity(), scale, number)
                bus.publish(DepthFrame.TOPIC, frame)
                self.counts.frames_mapped += self.mapping.frames - before
                last_stamp = stamp
        if self.mapping is None or self.mapping.frames == 0:
            raise DatasetError(f"{self.request.path}: no depth image could be mapped")
        self.counts.frames_mapped = self.mapping.frames
        self.mapping.publish(last_stamp)
        return self.mapping

    def _note_gap(self, stamp: float) -> None:
        """Count depth images more than three typical periods after the one before."""
        previous, self._previous_stamp = self._previous_stamp, stamp
        if previous is None:
            return
        gap = stamp - previous
        self._periods.append(gap)
        typical = float(np.median(self._periods))
        if len(self._periods) > 3 and gap > 3.0 * typical:
            self.counts.time_gaps += 1
        self.counts.longest_gap_s = max(self.counts.longest_gap_s, gap)

    def _publish_tf_pose(self, bus: InProcessBus, m: RecordedMessage, tree: TransformTree) -> None:
        """Publish a pose estimate from a footfall recording's TF message of the camera."""
        children = {t.child_frame_id for t in m.message.transforms}
        world, camera_frame = self.tf_frames  # type: ignore[misc]
        if camera_frame not in children:
            return
        camera = tree.lookup(world, camera_frame)
        body = tree.lookup(world, BODY_FRAME) if BODY_FRAME in children else camera
        if camera is None or body is None:
            return
        stamp = seconds(m.message.transforms[0].header.stamp)
        self._mapping_at(bus, (float(body.position[0]), float(body.position[1])))
        bus.publish(PoseEstimate.TOPIC, PoseEstimate(stamp, camera, body))

    def _pose_at(
        self,
        stamp: float,
        times: list[float],
        poses: list[Pose],
        tree: TransformTree,
        image: Any,
        info: Any,
    ) -> Pose | None:
        """The camera's pose for a depth image: odometry's, TF's or the nearest recorded."""
        if self.odometry is not None:
            depth, scale = depth_array(image)
            return self.odometry.pose(depth, _camera(info, self.noise, self.limits), scale, stamp)
        if self.tf_frames is not None:
            if self.history is not None:  # a bag's TF, at the image's time
                tree = self.history.tree_at(stamp, self.request.max_pose_gap_s)
            return tree.lookup(*self.tf_frames)
        k = bisect.bisect_left(times, stamp)
        best = min((c for c in (k - 1, k) if 0 <= c < len(times)), default=None,
                   key=lambda c: abs(times[c] - stamp))  # fmt: skip
        if best is None or abs(times[best] - stamp) > self.request.max_pose_gap_s:
            return None
        return poses[best]
