"""A pose source that reads the camera's poses from a trajectory file (``--pose trajectory``).

For a recording whose camera poses were estimated elsewhere (a SLAM run over it, a
motion-capture system), as a TUM-format trajectory: ``t tx ty tz qx qy qz qw`` per line, the
optical frame in the world, ``t`` on the recording's clock. Each depth image the camera hands
over is answered with the pose nearest its capture time (the camera's own timestamp where
the camera source keeps it, as the RealSense camera does; else the image's stamp), the
body's pose following from the camera's pose on the body. An image without a pose within
the tolerance gets none, as a lost track.
"""

from __future__ import annotations

import numpy as np

from footfall.errors import ConfigError
from footfall.messages import DepthFrame, PoseEstimate
from footfall.nodes.sources import CameraSource, SourceSetup
from footfall.runtime.bus import Bus
from footfall.sensing.pose import Pose
from footfall.sensing.trajectory import Trajectory, up_to_z

# Images further than this from every pose of the trajectory get none [s].
MAX_TIME_DIFFERENCE = 0.02


class TrajectoryPose:
    """Poses of a trajectory file answering the camera's images.

    Args:
        bus: The robot's bus.
        trajectory: The camera's poses.
        camera: The camera source (its ``device_time`` gives an image's capture time).
        up: The trajectory world's up axis (turned to +z).
        tolerance: Largest image-to-pose time difference [s].
    """

    name = "pose"

    def __init__(
        self,
        bus: Bus,
        trajectory: Trajectory,
        camera: CameraSource | None = None,
        up: tuple[float, float, float] = (0.0, 0.0, 1.0),
        tolerance: float = MAX_TIME_DIFFERENCE,
    ) -> None:
        self.bus = bus
        self.trajectory = trajectory
        self.camera = camera
        self.tolerance = tolerance
        self.align = Pose(np.zeros(3), up_to_z(up))
        self.answered = 0
        self.unanswered = 0
        bus.subscribe(DepthFrame.TOPIC, self._on_depth)

    @classmethod
    def open(cls, setup: SourceSetup) -> TrajectoryPose:
        """``setup.options``: ``file`` (the trajectory), ``up`` (``X,Y,Z``; ``0,0,1``).

        Raises:
            ConfigError: No file, an unknown option, or a malformed up axis.
            DatasetError: A trajectory that does not read.
        """
        options = dict(setup.options)
        unknown = sorted(set(options) - {"file", "up"})
        if unknown:
            raise ConfigError(
                f"the trajectory pose source has no option {', '.join(unknown)}; it takes file, up"
            )
        if "file" not in options:
            raise ConfigError("the trajectory pose source needs file=PATH (a TUM trajectory)")
        try:
            up = tuple(float(v) for v in options.get("up", "0,0,1").split(","))
        except ValueError:
            up = ()
        if len(up) != 3 or not np.all(np.isfinite(up)) or not np.any(up):
            raise ConfigError(f"up={options.get('up')!r} is not an axis X,Y,Z")
        trajectory = Trajectory.read(options["file"])
        return cls(setup.bus, trajectory, setup.camera, up)  # type: ignore[arg-type]

    def _on_depth(self, frame: DepthFrame) -> None:
        device_time = getattr(self.camera, "device_time", None)
        when = device_time(frame.stamp) if callable(device_time) else None
        found = self.trajectory.nearest(frame.stamp if when is None else when, self.tolerance)
        if found is None:
            self.unanswered += 1
            return
        camera_in_world = self.align.compose(found[0])
        body_in_world = camera_in_world.compose(frame.camera_in_body.inverse())
        self.answered += 1
        self.bus.publish(
            PoseEstimate.RAW_TOPIC, PoseEstimate(frame.stamp, camera_in_world, body_in_world)
        )
