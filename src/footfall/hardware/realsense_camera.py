"""The robot's RealSense camera as a camera source node (``--camera realsense``).

Each control tick hands over what the camera delivered since the last: the newest depth
image as a :class:`~footfall.messages.DepthFrame` (16-bit units with their scale, the
intrinsics, the camera's pose on the body), its colour image when asked, and every gyro
sample as an :class:`~footfall.messages.ImuReading` in the body frame (with the newest
accelerometer sample), which gives a robot without an IMU its attitude
(:class:`~footfall.backends.attitude.ImuAttitude`).

Stamps are on the robot's clock: the device's timestamp plus the smallest offset between the
two clocks seen so far, so an image keeps its capture time rather than its hand-over time,
whatever clock the device stamps with. A camera that delivers no depth for ``stall`` seconds
(unplugged, a recording at its end) is a stall: counted, said in the log once, and the robot
stands because its map and pose go stale; images that return end it.

The camera's pose on the body comes from the robot's TOML ``[camera]`` table::

    [camera]
    position = [0.13, 0.0, 0.08]   # optical centre in the body frame [m]
    pitch_deg = 30.0               # optical axis below the body's x axis
    roll_deg = 0.0                 # about the optical axis, right side down
    yaw_deg = 0.0                  # to the left of the body's x axis

(else the simulated robot's mount).
"""

from __future__ import annotations

from collections import OrderedDict

import numpy as np

from footfall.errors import ConfigError
from footfall.hardware.realsense import LIVE_FPS, LIVE_SIZE, RealSenseStream
from footfall.hardware.realsense_types import (
    FILTERS,
    DepthImage,
    MotionSample,
    RealSenseFilters,
)
from footfall.messages import ColorImage, DepthFrame, ImuReading, LogLine
from footfall.nodes.sources import SourceSetup
from footfall.robot.spec import CameraPlacement, load_spec
from footfall.runtime.bus import Bus
from footfall.sensing.pose import Pose

# Seconds without depth before the camera counts a stall.
STALL_SECONDS = 1.0
# Device stamps remembered to answer which image was handed over when.
STAMPS_KEPT = 60
OPTIONS = ("file", "serial", "width", "height", "fps", "realtime", "robot", "stall", *FILTERS)


def _camera_placement(robot: str | None, mount: object) -> CameraPlacement:
    """The camera's place on the body: the robot's ``[camera]`` table, else the mount's."""
    if robot is not None:
        return load_spec(robot).camera
    placement = getattr(mount, "placement", None)
    return placement if isinstance(placement, CameraPlacement) else CameraPlacement()


class RealSenseCamera:
    """A RealSense camera (live or a recording) handing its images to the robot's bus.

    Args:
        bus: The robot's bus.
        stream: The device or recording.
        camera_in_body: The depth optical frame on the body.
        color: Hand colour images over too.
        stall: Seconds without depth before a stall is counted.
    """

    name = "camera"

    def __init__(
        self,
        bus: Bus,
        stream: RealSenseStream,
        camera_in_body: Pose,
        color: bool = False,
        stall: float = STALL_SECONDS,
    ) -> None:
        self.bus = bus
        self.stream = stream
        self.camera_in_body = camera_in_body
        self.color = color
        self.stall = stall
        self.has_imu = stream.has_imu
        self.frames = 0
        self.stalls = 0
        self.imu_readings = 0
        self._offset: float | None = None
        self._last_depth_t: float | None = None
        self._stalled = False
        self._accel_in_body: np.ndarray | None = None
        self._device_stamps: OrderedDict[float, float] = OrderedDict()

    @classmethod
    def open(cls, setup: SourceSetup) -> RealSenseCamera:
        """A recording (``file=PATH``) or a live camera (``serial=``, or the only one).

        ``setup.options``: ``file`` or ``serial``; ``width``, ``height``, ``fps`` (live:
        424 x 240 at 15 by default); ``realtime`` (a recording at its own pace, 1 by
        default); the filters ``decimation``, ``spatial``, ``temporal``, ``hole_filling``;
        ``robot`` (the TOML whose ``[camera]`` table places the camera); ``stall`` [s].

        Raises:
            ConfigError: An unknown option or a bad value.
            CameraError: No camera, no depth stream.
            DatasetError: A recording that is missing or unreadable.
        """
        options = dict(setup.options)
        unknown = sorted(set(options) - set(OPTIONS))
        if unknown:
            raise ConfigError(
                f"the RealSense camera has no option {', '.join(unknown)}; it takes "
                f"{', '.join(OPTIONS)}"
            )
        filters = RealSenseFilters.from_options(options)
        if "file" in options and "serial" in options:
            raise ConfigError("the RealSense camera takes file= or serial=, not both")
        try:
            stall = float(options.get("stall", STALL_SECONDS))
            if "file" in options:
                realtime = bool(int(options.get("realtime", "1")))
                stream = RealSenseStream.open_file(options["file"], filters, realtime=realtime)
            else:
                size = (
                    int(options.get("width", LIVE_SIZE[0])),
                    int(options.get("height", LIVE_SIZE[1])),
                )
                fps = int(options.get("fps", LIVE_FPS))
                stream = RealSenseStream.open_device(
                    options.get("serial"), size, fps, filters, color=setup.color
                )
        except ValueError as exc:
            raise ConfigError(f"a RealSense camera option is not a number: {exc}") from exc
        try:
            pose = _camera_placement(options.get("robot"), setup.mount).optical_in_body()
        except ConfigError:
            stream.close()
            raise
        return cls(setup.bus, stream, pose, color=setup.color, stall=stall)

    def _robot_time(self, device_time: float, t: float) -> float:
        """A device stamp on the robot's clock (never after ``t``)."""
        offset = t - device_time
        if self._offset is None or offset < self._offset:
            self._offset = offset
        return device_time + self._offset

    def tick(self, t: float) -> bool:
        """Hand over what came since the last tick; True when a depth image went out.

        Raises:
            CameraError: The camera failed to deliver a frame (a conversion error).
        """
        newest: DepthImage | None = None
        for item in self.stream.drain():
            if isinstance(item, DepthImage):
                newest = item
            elif isinstance(item, MotionSample):
                self._on_motion(item, t)
        if newest is None:
            self._check_stall(t)
            return False
        self._last_depth_t = t
        if self._stalled:
            self._stalled = False
            self._log(t, "info", "depth images are coming again")
        stamp = max(self._robot_time(newest.device_time, t), 0.0)
        self._device_stamps[stamp] = newest.device_time
        while len(self._device_stamps) > STAMPS_KEPT:
            self._device_stamps.popitem(last=False)
        self.frames += 1
        frame = DepthFrame(
            stamp,
            newest.depth,
            newest.camera,
            self.camera_in_body,
            depth_scale=newest.depth_scale,
            sequence=newest.number,
        )
        self.bus.publish(DepthFrame.TOPIC, frame)
        if self.color and newest.color is not None:
            self.bus.publish(ColorImage.TOPIC, ColorImage(stamp, newest.color, newest.number))
        return True

    def _on_motion(self, sample: MotionSample, t: float) -> None:
        in_body = self.camera_in_body.rotation.apply(sample.vector_in_camera)
        if sample.kind == "accel":
            self._accel_in_body = in_body
            return
        if self._accel_in_body is None:
            return  # no attitude without gravity's direction yet
        stamp = max(self._robot_time(sample.device_time, t), 0.0)
        self.imu_readings += 1
        self.bus.publish(ImuReading.TOPIC, ImuReading(stamp, in_body, self._accel_in_body))

    def _check_stall(self, t: float) -> None:
        if self._last_depth_t is None:
            self._last_depth_t = t  # the wait for a first image starts at the first tick
        since = self._last_depth_t
        if self._stalled or t - since < self.stall:
            return
        self._stalled = True
        self.stalls += 1
        if not self.stream.connected():
            why = "the camera is unplugged"
        elif self.stream.ended:
            why = "the recording has ended"
        else:
            why = f"no depth image for {t - since:.1f} s"
        self._log(t, "warning", f"camera stalled: {why}; the robot stands until images return")

    def _log(self, t: float, level: str, text: str) -> None:
        self.bus.publish(LogLine.TOPIC, LogLine(t, self.name, level, text))

    def device_time(self, stamp: float) -> float | None:
        """The device's timestamp of the image handed over at ``stamp``, if it was recent."""
        return self._device_stamps.get(stamp)

    def timing(self) -> dict[str, float]:
        """Images handed over, stalls, IMU readings and items dropped by a slow robot."""
        return {
            "frames": float(self.frames),
            "stalls": float(self.stalls),
            "imu_readings": float(self.imu_readings),
            "dropped": float(self.stream.dropped),
        }

    def close(self) -> None:
        """Stop the camera."""
        self.stream.close()
