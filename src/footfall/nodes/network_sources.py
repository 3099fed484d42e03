"""Camera and pose sources on the network: images and poses another process publishes.

A robot whose camera or pose estimator runs elsewhere (``footfall servo-bus`` in a dry run,
a camera driver on another computer, a SLAM on the base station) takes them from zenoh:
the source joins the network as the sender's name (``footfall/<name>/depth``, ``color``,
``pose``) and hands the newest image to the robot's bus at its control tick. Clocks differ
between processes, so each image is stamped with the robot's time when it is handed over,
and its pose (matched by the sender's stamp) with the same.
"""

from __future__ import annotations

import dataclasses
from collections import OrderedDict

from footfall.errors import ConfigError
from footfall.messages import ColorImage, DepthFrame, PoseEstimate
from footfall.nodes.sources import SourceSetup
from footfall.runtime.bus import Bus

DEFAULT_SENDER = "hexapod-sim"
DEFAULT_ENDPOINT = "tcp/127.0.0.1:7448"
POSES_KEPT = 60  # poses remembered to match images that arrive after them


def _network(options: dict[str, str], kind: str):
    from footfall.runtime.zenoh_bus import ZenohBus, ZenohConfig

    known = {"name", "connect"}
    unknown = sorted(set(options) - known)
    if unknown:
        raise ConfigError(
            f"the network {kind} has no option {', '.join(unknown)}; it takes name, connect"
        )
    return ZenohBus(
        ZenohConfig(
            robot=options.get("name", DEFAULT_SENDER),
            connect=(options.get("connect", DEFAULT_ENDPOINT),),
        )
    )


class NetworkCamera:
    """Depth (and colour) images from the network, restamped on the robot's clock.

    Args:
        bus: The robot's bus.
        network: The network bus under the sender's name.
        color: Hand colour images over too.
    """

    name = "camera"

    def __init__(self, bus: Bus, network, color: bool = False) -> None:
        self.bus = bus
        self.network = network
        self.color = color
        self.frames = 0
        self.poses: OrderedDict[float, PoseEstimate] = OrderedDict()
        self._frame: DepthFrame | None = None
        self._image: ColorImage | None = None
        self._handed: tuple[float, float] | None = None  # (robot's, sender's) stamp
        network.subscribe(DepthFrame.TOPIC, self._on_depth, last=True)
        network.subscribe(ColorImage.TOPIC, self._on_color, last=True)
        network.subscribe(PoseEstimate.TOPIC, self._on_pose)

    @classmethod
    def open(cls, setup: SourceSetup) -> NetworkCamera:
        """Join the network as the sender, through an endpoint.

        ``setup.options``: ``name`` (the sender's, ``hexapod-sim``), ``connect`` (its
        endpoint, ``tcp/127.0.0.1:7448``).
        """
        return cls(setup.bus, _network(setup.options, "camera"), color=setup.color)

    def _on_depth(self, frame: DepthFrame) -> None:
        self._frame = frame

    def _on_color(self, image: ColorImage) -> None:
        self._image = image

    def _on_pose(self, pose: PoseEstimate) -> None:
        self.poses[pose.stamp] = pose
        while len(self.poses) > POSES_KEPT:
            self.poses.popitem(last=False)

    def tick(self, t: float) -> bool:
        """Hand the newest image over, stamped ``t`` [s]; True when there was one."""
        self.network.spin()
        frame, self._frame = self._frame, None
        if frame is None:
            return False
        self.frames += 1
        self._handed = (t, frame.stamp)
        self.bus.publish(DepthFrame.TOPIC, dataclasses.replace(frame, stamp=t))
        if self.color and self._image is not None:
            self.bus.publish(ColorImage.TOPIC, dataclasses.replace(self._image, stamp=t))
            self._image = None
        return True

    def pose_for(self, stamp: float) -> PoseEstimate | None:
        """The sender's pose of the image handed over at ``stamp``, if it came."""
        if self._handed is None or self._handed[0] != stamp:
            return None
        return self.poses.get(self._handed[1])

    def timing(self) -> dict[str, float]:
        """No timing of its own."""
        return {}

    def close(self) -> None:
        """Leave the network."""
        self.network.close()


class NetworkPose:
    """The pose the sender published with each image the network camera hands over.

    Args:
        bus: The robot's bus.
        camera: The network camera whose images it answers.
    """

    name = "pose"

    def __init__(self, bus: Bus, camera: NetworkCamera) -> None:
        self.bus = bus
        self.camera = camera
        bus.subscribe(DepthFrame.TOPIC, self._on_depth)

    @classmethod
    def open(cls, setup: SourceSetup) -> NetworkPose:
        """The poses that came with ``setup.camera``'s images (the network camera)."""
        if not isinstance(setup.camera, NetworkCamera):
            raise ConfigError(
                "the network pose source answers the network camera: --camera network"
            )
        return cls(setup.bus, setup.camera)

    def _on_depth(self, frame: DepthFrame) -> None:
        pose = self.camera.pose_for(frame.stamp)
        if pose is not None:  # a lost track publishes nothing
            self.bus.publish(PoseEstimate.RAW_TOPIC, dataclasses.replace(pose, stamp=frame.stamp))
