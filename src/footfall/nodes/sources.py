"""Camera and pose sources: the nodes that bring depth images and pose estimates in.

A **camera source** publishes :class:`~footfall.messages.DepthFrame` on ``DepthFrame.TOPIC``
(and, asked for colour, :class:`~footfall.messages.ColorImage`): depth in metres, NaN where
nothing was measured, with the intrinsics and the optical frame in the body frame. The
robot calls ``tick(t)`` every control tick; a source takes a frame when one is due (a
simulator renders; a driver hands over the newest frame its device delivered) and stamps
it with the time the image was taken.

A **pose source** answers with :class:`~footfall.messages.PoseEstimate` on
``PoseEstimate.RAW_TOPIC``, which the pose guard checks before the map and the controller
use it. Its guarantees: the stamp is the depth image's; ``camera_in_world`` is the depth
camera's optical frame and ``body_in_world`` the body frame, in a z-up world; one estimate
per depth image (at least the camera's rate); a lost track publishes nothing (the robot
stands once the newest estimate is 0.5 s old, and walks on when estimates return).

Each kind joins its registry with one line; ``footfall robot --camera NAME --pose NAME``
and :class:`~footfall.sim.walk.WalkSettings` choose by name.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Protocol

from footfall.registry import Registry

if TYPE_CHECKING:  # the robot's parser lists the sources without loading the bus
    from footfall.backends import HexapodBackend
    from footfall.robot.spec import HexapodSpec
    from footfall.runtime.bus import Bus
    from footfall.runtime.node_thread import NodeThread


@dataclass(frozen=True)
class SourceSetup:
    """What a camera or pose source is started with.

    Attributes:
        bus: Where it publishes (the robot's bus, or a faulty link in front of it).
        backend: The robot (a simulator renders through it; a driver may read its clock).
        mount: The camera's settings (a simulator's :class:`~footfall.sim.model.CameraMount`).
        color: Publish colour images too (for a station).
        color_hz: At most this many colour images a second (a simulator renders no more
            than are sent); None: one with every depth image.
        camera: The camera source whose images a pose source answers; None for a camera.
        options: Source-specific settings (a device's serial number, a SLAM's config).
        thread: The robot's perception thread, where a camera may do its heavy work (a
            simulator's render) rather than in ``tick``; it then publishes on
            ``thread_bus`` from there, and the pose source answers it there. None: no
            such thread (a simulated walk, repeatable to the bit).
        thread_bus: That thread's bus.
        spec: The robot (an estimator's leg kinematics), when known.
        seed: The run's seed, for a simulated sensor's noise.
    """

    bus: Bus
    backend: HexapodBackend
    mount: object = None
    color: bool = False
    camera: CameraSource | None = None
    color_hz: float | None = None
    options: dict[str, str] = field(default_factory=dict)
    thread: NodeThread | None = None
    thread_bus: Bus | None = None
    spec: HexapodSpec | None = None
    seed: int = 0


class CameraSource(Protocol):
    """A depth camera on the robot, as a node.

    Attributes:
        name: The node's name in logs.

    A camera that took the setup's thread says so with a ``thread`` attribute (its pose
    source is then opened on that thread's bus); others publish from ``tick``.
    """

    name: str

    def tick(self, t: float) -> bool:
        """Publish a frame if one is due at ``t`` [s]; True when it did."""
        ...

    def timing(self) -> dict[str, float]:
        """Timing figures for the walk's metrics (may be empty)."""
        ...

    def close(self) -> None:
        """Release the device or renderer."""
        ...


class PoseSource(Protocol):
    """A pose estimator on the robot, as a node.

    It subscribes to what it needs when opened, and publishes ``PoseEstimate`` on
    ``PoseEstimate.RAW_TOPIC``.

    Attributes:
        name: The node's name in logs.
    """

    name: str


class CameraFactory(Protocol):
    """A registered camera source: a class (or any object) with ``open``."""

    def open(self, setup: SourceSetup) -> CameraSource:
        """The camera, publishing on ``setup.bus``."""
        ...


class PoseFactory(Protocol):
    """A registered pose source: a class (or any object) with ``open``."""

    def open(self, setup: SourceSetup) -> PoseSource:
        """The pose source, answering ``setup.camera``'s images on ``setup.bus``."""
        ...


CAMERAS: Registry[CameraFactory] = Registry("camera source")
POSES: Registry[PoseFactory] = Registry("pose source")

CAMERAS.register("sim", "footfall.sim.sensors:SimCameraNode")
POSES.register("sim", "footfall.sim.sensors:SimPoseNode")
CAMERAS.register("network", "footfall.nodes.network_sources:NetworkCamera")
POSES.register("network", "footfall.nodes.network_sources:NetworkPose")
CAMERAS.register("realsense", "footfall.hardware.realsense_camera:RealSenseCamera")
POSES.register("trajectory", "footfall.nodes.trajectory_pose:TrajectoryPose")
POSES.register("estimator", "footfall.nodes.estimator_pose:EstimatorPose")
