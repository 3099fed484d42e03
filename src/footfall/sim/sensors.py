"""The simulated robot's camera and pose source, as nodes.

The camera node renders MuJoCo's depth buffer at the camera rate and publishes each image
with its intrinsics and extrinsics. The pose node answers every image with the pose the
camera had when it was taken, as visual SLAM does (thesis §3.3): the simulator's truth, or
that truth with SLAM-like drift and jitter.

Given a node thread (a robot on the wall clock), the camera keeps the robot's joint state
at each frame's time and renders it on that thread, as a real camera exposes while the
controller runs on: the control loop pays only the copy of the state.
"""

from __future__ import annotations

import statistics
import time
from collections import deque

import mujoco
import numpy as np
import numpy.typing as npt
from scipy.spatial.transform import Rotation

from footfall.errors import ConfigError
from footfall.messages import ColorImage, DepthFrame, PoseEstimate
from footfall.nodes.mapping import TIMING_HISTORY
from footfall.nodes.sources import SourceSetup
from footfall.runtime.bus import Bus
from footfall.runtime.node_thread import NodeThread
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
        thread: Render there (``bus`` is then that thread's bus), not in :meth:`tick`.

    Attributes:
        frame_data: The simulator state the latest frame was rendered from (the
            simulator's own without a thread; a copy of its kinematics with one).
    """

    name = "camera"

    def __init__(
        self,
        bus: Bus,
        backend: MujocoHexapod,
        mount: CameraMount,
        color: bool = False,
        color_hz: float | None = None,
        thread: NodeThread | None = None,
    ) -> None:
        self.bus = bus
        self.backend = backend
        self.thread = thread
        self.frame_data = backend.data if thread is None else mujoco.MjData(backend.model)
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
        thread = setup.thread
        bus = setup.thread_bus if thread is not None and setup.thread_bus is not None else None
        if bus is None:
            thread, bus = None, setup.bus
        return cls(
            bus,
            simulator,
            setup.mount,
            color=setup.color,
            color_hz=setup.color_hz,
            thread=thread,
        )

    def tick(self, t: float) -> bool:
        """Take a frame if one is due at time ``t`` [s]; True when it did.

        Without a thread the frame is rendered and published now; with one, the joint
        state is kept and the frame rendered there (a newer frame replaces one still waiting
        for it).
        """
        if t + 1e-9 < self._next_frame:
            return False
        while self._next_frame <= t + 1e-9:  # frames missed in an overrun are not caught up
            self._next_frame += self.period
        color = self.color and t + 1e-9 >= self._next_color
        if color:
            # Rendered only as often as it is wanted: a render is the camera's main cost.
            self._next_color = max(self._next_color + self.color_period, t)
        if self.thread is None:
            self._capture(t, color)
        else:
            data = self.backend.data
            self.thread.call(self.name, self._capture_state, t, color, data.qpos.copy())
        return True

    def _capture_state(self, t: float, color: bool, qpos: npt.NDArray[np.float64]) -> None:
        """Render the robot as it stood at ``t`` (joint positions ``qpos``)."""
        data, model = self.frame_data, self.backend.model
        data.qpos[:] = qpos
        mujoco.mj_kinematics(model, data)
        mujoco.mj_camlight(model, data)
        self._capture(t, color)

    def _capture(self, t: float, color: bool) -> None:
        t0 = time.perf_counter()
        depth, _ = self.camera.capture(self.frame_data)
        self.render_ms.append(1e3 * (time.perf_counter() - t0))
        self.frames += 1
        frame = DepthFrame(
            t, depth, self.camera.intrinsics, self.camera_in_body, sequence=self.frames
        )
        self.bus.publish(DepthFrame.TOPIC, frame)
        if color:
            image = self.camera.capture_color(self.frame_data)
            self.bus.publish(ColorImage.TOPIC, ColorImage(t, image, frame.sequence))

    def timing(self) -> dict[str, float]:
        """Median render time [ms]."""
        ms = self.render_ms
        return {"render_ms_median": statistics.median(ms) if ms else float("nan")}

    def close(self) -> None:
        """Release the renderer (on its thread, after the frames waiting there)."""
        if self.thread is not None:
            self.thread.call("close", self.camera.close)
        else:
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
        true_pose = self.camera.camera.pose(self.camera.frame_data)
        pose = self.noise.estimate(true_pose, frame.stamp) if self.noise is not None else true_pose
        estimate = PoseEstimate(frame.stamp, pose, pose.compose(self._body_in_camera))
        self.bus.publish(self.topic, estimate)
