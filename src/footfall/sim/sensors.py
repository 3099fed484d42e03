"""The simulated robot's camera and pose source, as nodes.

The camera node renders MuJoCo's depth buffer at the camera rate and publishes each image
with its intrinsics and extrinsics. The pose node answers every image with the pose the
camera had when it was taken, as visual SLAM does (thesis §3.3): the simulator's truth, or
that truth with SLAM-like drift and jitter.
"""

from __future__ import annotations

import statistics
import time
from collections import deque

from scipy.spatial.transform import Rotation

from footfall.errors import ConfigError
from footfall.messages import ColorImage, DepthFrame, PoseEstimate
from footfall.nodes.mapping import TIMING_HISTORY
from footfall.nodes.sources import SourceSetup
from footfall.runtime.bus import Bus
from footfall.sensing.pose import Pose, SlamNoise
from footfall.sim.camera import SimDepthCamera
from footfall.sim.hexapod import MujocoHexapod, simulated_robot
from footfall.sim.model import CameraMount


def true_body_pose(backend: MujocoHexapod) -> Pose:
    """The simulated body's true pose in the world."""
    data, torso = backend.data, backend.model.body("torso").id
    return Pose(data.xpos[torso].copy(), Rotation.from_matrix(data.xmat[torso].reshape(3, 3)))


class SimCameraNode:
    """Depth images of a simulated robot's body camera.

    Args:
        bus: The bus.
        backend: The simulated robot (built with the camera mount).
        mount: The camera mount.
        color: Also render and publish colour images (for a station).
        color_hz: At most this many colour images a second; None: one with every frame.
    """

    name = "camera"

    def __init__(
        self,
        bus: Bus,
        backend: MujocoHexapod,
        mount: CameraMount,
        color: bool = False,
        color_hz: float | None = None,
    ) -> None:
        self.bus = bus
        self.backend = backend
        self.camera = SimDepthCamera(backend.model, mount)
        self.period = 1.0 / mount.rate_hz
        self.camera_in_body = (
            true_body_pose(backend).inverse().compose(self.camera.pose(backend.data))
        )
        self.color = color
        self.color_period = 0.0 if color_hz is None else 1.0 / color_hz
        self._next_color = 0.0
        self.render_ms: deque[float] = deque(maxlen=TIMING_HISTORY)
        self.frames = 0
        self._next_frame = 0.0

    @classmethod
    def open(cls, setup: SourceSetup) -> SimCameraNode:
        """The camera of the simulated robot ``setup.backend``, mounted as ``setup.mount``."""
        simulator = simulated_robot(setup.backend)
        if simulator is None:
            raise ConfigError(
                "the simulated camera renders the simulated robot: use --backend sim, or "
                "--camera none to walk blind"
            )
        if not isinstance(setup.mount, CameraMount):
            raise ConfigError("the simulated camera needs a CameraMount")
        return cls(setup.bus, simulator, setup.mount, color=setup.color, color_hz=setup.color_hz)

    def tick(self, t: float) -> bool:
        """Take and publish a frame if one is due at time ``t`` [s]; True when it did."""
        if t + 1e-9 < self._next_frame:
            return False
        while self._next_frame <= t + 1e-9:  # frames missed in an overrun are not caught up
            self._next_frame += self.period
        t0 = time.perf_counter()
        depth, _ = self.camera.capture(self.backend.data)
        self.render_ms.append(1e3 * (time.perf_counter() - t0))
        self.frames += 1
        frame = DepthFrame(
            t, depth, self.camera.intrinsics, self.camera_in_body, sequence=self.frames
        )
        self.bus.publish(DepthFrame.TOPIC, frame)
        if self.color and t + 1e-9 >= self._next_color:
            # Rendered only as often as it is wanted: a render is the camera's main cost.
            self._next_color = max(self._next_color + self.color_period, t)
            image = self.camera.capture_color(self.backend.data)
            self.bus.publish(ColorImage.TOPIC, ColorImage(t, image, frame.sequence))
        return True

    def timing(self) -> dict[str, float]:
        """Median render time [ms]."""
        ms = self.render_ms
        return {"render_ms_median": statistics.median(ms) if ms else float("nan")}

    def close(self) -> None:
        """Release the renderer."""
        self.camera.close()


class SimPoseNode:
    """Pose estimates of a simulated camera, one per depth image.

    Args:
        bus: The bus.
        camera: The camera node whose images it answers.
        noise: SLAM-like noise, or None for the true pose.
        topic: Where the estimates go (the pose guard's raw input on a walking robot).
    """

    name = "pose"

    def __init__(
        self,
        bus: Bus,
        camera: SimCameraNode,
        noise: SlamNoise | None = None,
        topic: str = PoseEstimate.TOPIC,
    ) -> None:
        self.bus = bus
        self.camera = camera
        self.noise = noise
        self.topic = topic
        self._body_in_camera = camera.camera_in_body.inverse()
        bus.subscribe(DepthFrame.TOPIC, self._on_depth)

    @classmethod
    def open(cls, setup: SourceSetup) -> SimPoseNode:
        """The true pose of ``setup.camera`` (the simulated camera) at each of its images."""
        if not isinstance(setup.camera, SimCameraNode):
            raise ConfigError(
                "the simulated pose source answers the simulated camera: --camera sim"
            )
        return cls(setup.bus, setup.camera, topic=PoseEstimate.RAW_TOPIC)

    def _on_depth(self, frame: DepthFrame) -> None:
        true_pose = self.camera.camera.pose(self.camera.backend.data)
        pose = self.noise.estimate(true_pose, frame.stamp) if self.noise is not None else true_pose
        estimate = PoseEstimate(frame.stamp, pose, pose.compose(self._body_in_camera))
        self.bus.publish(self.topic, estimate)
