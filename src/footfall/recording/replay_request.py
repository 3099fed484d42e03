"""What ``footfall replay`` is asked to replay, and what it counted on the way."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from footfall.sensing.pose import Pose


@dataclass(frozen=True)
class ReplayRequest:
    """What to replay (the options of ``footfall replay``).

    Attributes:
        path: A footfall MCAP file, a ROS 2 bag (folder or ``.mcap``) or a ROS 1 ``.bag``.
        rate: Playback speed against the recording's clock; ignored with ``fast``.
        fast: Play as fast as the mapping goes.
        depth_topic: The depth image topic; None to pick the one there is.
        info_topic: Its ``CameraInfo`` topic; None for the one beside it.
        pose_topic: A ``PoseStamped`` or ``Odometry`` topic of the depth camera's optical
            frame in a z-up world.
        tf_frames: ``(world, camera)`` frames to look the camera's pose up in TF instead.
        sensor: The depth sensor's noise model (recordings that do not carry one).
        fusion: Per-cell fusion rule; None: the recording's, else ``variance``.
        max_pose_gap_s: Largest time between a depth image and its pose [s].
        camera_height: For a recording with no pose: the camera's fixed height over the
            floor [m] (with ``camera_pitch_deg`` and ``camera_roll_deg``).
        camera_pitch_deg: How far that camera looks down [deg].
        camera_roll_deg: How far its right side dips [deg].
        pose: ``"recorded"`` (a pose topic, TF or the fixed camera) or ``"odometry"``:
            tracked from the depth images (:mod:`footfall.odometry.poses`), the first
            frame over the floor it sees or at the fixed camera's pose.
    """

    path: Path
    rate: float = 1.0
    fast: bool = False
    depth_topic: str | None = None
    info_topic: str | None = None
    pose_topic: str | None = None
    tf_frames: tuple[str, str] | None = None
    sensor: str = "kinect"
    fusion: str | None = None
    max_pose_gap_s: float = 0.05
    camera_height: float | None = None
    camera_pitch_deg: float | None = None
    camera_roll_deg: float | None = None
    pose: str = "recorded"

    def fixed_camera(self) -> tuple[Pose, Pose] | None:
        """The fixed camera pose given, and the map centre 2 m ahead of it; or None."""
        if self.camera_height is None:
            return None
        from footfall.pointcloud.ground import CameraOverFloor

        floor = CameraOverFloor.from_angles(
            self.camera_height,
            math.radians(self.camera_pitch_deg or 0.0),
            math.radians(self.camera_roll_deg or 0.0),
        )
        camera = Pose(np.array([0.0, 0.0, floor.height_m]), floor.rotation_camera_to_map)
        forward = camera.rotation.apply([0.0, 0.0, 1.0])
        forward[2] = 0.0
        ahead = forward / max(float(np.linalg.norm(forward)), 1e-9) * 2.0
        return camera, Pose(camera.position + ahead, camera.rotation)


@dataclass
class ReplayCounts:
    """What became of a recording's messages."""

    depth_images: int = 0
    frames_mapped: int = 0
    frames_without_pose: int = 0
    frames_without_info: int = 0
    time_gaps: int = 0
    longest_gap_s: float = 0.0
