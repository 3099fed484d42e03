"""RealSense recordings mapped by the same mapping node as a walk (``footfall map --realsense``).

librealsense plays the recording (:mod:`footfall.hardware.realsense`); each depth image goes
to the map with its camera pose: from a trajectory file (``t tx ty tz qx qy qz qw``, the
optical frame in the world, ``t`` on the recording's clock [s]) matched by the image's
timestamp, or, for a camera that did not move, one given pose. Depth keeps its 16-bit units
and the recording's depth units, so the map is the one the same images make given directly.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import numpy.typing as npt

from footfall.datasets.tum import SequenceMap, finish_sequence_map, fixed_view_centre
from footfall.errors import DatasetError
from footfall.hardware.realsense import RealSenseStream
from footfall.hardware.realsense_types import DepthImage, RealSenseFilters
from footfall.mapping.engine import HeightMapConfig
from footfall.messages import DepthFrame, PoseEstimate
from footfall.nodes.mapping import MappingNode
from footfall.runtime.bus import InProcessBus
from footfall.scoring.walkability import ScoreConfig
from footfall.sensing.pose import Pose
from footfall.sensing.trajectory import Trajectory, up_to_z

# Images further than this from every pose of the trajectory are skipped [s].
MAX_TIME_DIFFERENCE = 0.02


def map_realsense_recording(
    path: str | Path,
    map_config: HeightMapConfig | None = None,
    score_config: ScoreConfig | None = None,
    trajectory: str | Path | None = None,
    up: npt.ArrayLike = (0.0, 0.0, 1.0),
    camera_pose: Pose | None = None,
    filters: RealSenseFilters | None = None,
    bus: InProcessBus | None = None,
    on_mapping: Callable[[MappingNode], None] | None = None,
) -> SequenceMap:
    """Build the height map of a RealSense recording.

    Args:
        path: The recording (``.bag`` or ``.db3``).
        map_config: Height map settings.
        score_config: Score settings.
        trajectory: The camera's poses, TUM format, on the recording's clock.
        up: The trajectory world's up axis.
        camera_pose: The optical frame's fixed pose in a z-up world, without a trajectory.
        filters: librealsense's post-processing of depth.
        bus: The bus to play on (a recorder may tap it); a new one by default.
        on_mapping: Called with the mapping node once it stands.

    Returns:
        The map, its scores, the camera path and metrics (with ``imu_samples``, the gyro
        and accelerometer samples the recording holds).

    Raises:
        DatasetError: The recording or trajectory does not read, holds no depth stream, or
            no image has a pose.
    """
    if (trajectory is None) == (camera_pose is None):
        raise DatasetError("give the camera's poses: a trajectory file or one fixed pose")
    poses = Trajectory.read(trajectory) if trajectory is not None else None
    align = Pose(np.zeros(3), up_to_z(up))
    bus = bus if bus is not None else InProcessBus()
    stream = RealSenseStream.open_file(path, filters)
    mapping: MappingNode | None = None
    path_xy: list[npt.NDArray[np.float64]] = []
    skipped = imu = 0
    last: DepthImage | None = None
    try:
        while (item := stream.get()) is not None:
            if not isinstance(item, DepthImage):
                imu += 1
                continue
            if poses is not None:
                found = poses.nearest(item.device_time, MAX_TIME_DIFFERENCE)
                if found is None:
                    skipped += 1
                    continue
                pose = centre = align.compose(found[0])
            else:
                assert camera_pose is not None
                pose, centre = camera_pose, fixed_view_centre(camera_pose)
            if mapping is None:
                mapping = MappingNode(
                    bus,
                    map_config,
                    score_config,
                    publish_every_frame=False,
                    centre=(float(centre.position[0]), float(centre.position[1])),
                )
                if on_mapping is not None:
                    on_mapping(mapping)
            stamp = item.device_time
            bus.publish(PoseEstimate.TOPIC, PoseEstimate(stamp, pose, centre))
            frame = DepthFrame(
                stamp, item.depth, item.camera, Pose.identity(), item.depth_scale, item.number
            )
            bus.publish(DepthFrame.TOPIC, frame)
            path_xy.append(pose.position[:2])
            last = item
    finally:
        stream.close()
    if mapping is None or last is None:
        raise DatasetError(
            f"{path}: no depth image has a pose within {MAX_TIME_DIFFERENCE} s of its time"
            if skipped
            else f"{path}: the recording holds no depth image"
        )
    counts = {"frames_skipped_no_pose": skipped, "imu_samples": imu}
    return finish_sequence_map(mapping, last.device_time, np.array(path_xy), counts)
