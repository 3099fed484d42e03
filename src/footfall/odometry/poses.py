"""Depth odometry as a pose source: the camera's pose in a z-up world, frame by frame.

The odometry's world is its first frame's optical frame. To map, that frame is put over
the floor: where the caller says (a camera's height, pitch and roll), or over the floor
the first frame sees (RANSAC: the lowest large plane within ``FLOOR_TILT_DEG`` of the
camera's down, the camera ``FLOOR_CAMERA_HEIGHTS_M`` above it). A frame that did not
register has no pose: its depth would land where the camera last was.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from footfall.errors import DatasetError
from footfall.odometry.registration import DepthOdometry, OdometryConfig, OdometryStep
from footfall.sensing.camera import PinholeCamera
from footfall.sensing.pose import Pose

# The floor of a sequence tracked without poses: the lowest large plane in its first frame
# within this of the camera's down (a camera held level, or looking down) [deg]...
FLOOR_TILT_DEG = 60.0
# ...with the camera this high above it [m].
FLOOR_CAMERA_HEIGHTS_M = (0.05, 3.0)


def first_frame_over_floor(
    depth: npt.NDArray, camera: PinholeCamera, depth_scale: float | None
) -> Pose:
    """The first camera's pose over the floor it sees: z up, on the floor below it.

    Raises:
        DatasetError: No floor in view (the error says to give the camera's pose).
    """
    from footfall.pointcloud.ground import CameraOverFloor, find_ground

    points, _ = camera.depth_to_points(depth, depth_scale, stride=4)
    try:
        floor = find_ground(
            points,
            (0.0, -1.0, 0.0),  # up, for a camera held level: against its image's rows
            math.radians(FLOOR_TILT_DEG),
            below_origin=True,
            height_range_m=FLOOR_CAMERA_HEIGHTS_M,
        )
    except DatasetError as exc:
        raise DatasetError(
            f"no floor in the first frame to put the odometry's world on ({exc}): give the "
            "camera's pose over the floor with --camera-height and --camera-pitch-deg"
        ) from exc
    over = CameraOverFloor.from_up(floor.normal, floor.offset_m)
    return Pose(np.array([0.0, 0.0, over.height_m]), over.rotation_camera_to_map)


class OdometryPoses:
    """Each depth frame's camera pose in a z-up world, from depth odometry.

    Args:
        first_pose: The first frame's pose over the floor; None: found in that frame.
        config: Odometry settings.
    """

    def __init__(self, first_pose: Pose | None = None, config: OdometryConfig | None = None):
        self.first_pose = first_pose
        self.config = config or OdometryConfig()
        self.odometry: DepthOdometry | None = None
        self.last_step: OdometryStep | None = None

    def pose(
        self, depth: npt.NDArray, camera: PinholeCamera, depth_scale: float | None, stamp: float
    ) -> Pose | None:
        """The camera's pose for this frame; None when it did not register.

        Raises:
            TrackingLostError: Frames in a row did not register.
            DatasetError: No floor in the first frame, and no first pose given.
        """
        if self.odometry is None:
            self.odometry = DepthOdometry(camera, self.config)
            if self.first_pose is None:
                self.first_pose = first_frame_over_floor(depth, camera, depth_scale)
        assert self.first_pose is not None
        self.last_step = self.odometry.track(depth, stamp, depth_scale)
        if not self.last_step.registered:
            return None
        return self.first_pose.compose(self.last_step.camera_in_world)
