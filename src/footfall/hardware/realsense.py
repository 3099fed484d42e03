"""Intel RealSense depth cameras through librealsense's own binding (``pyrealsense2``).

Two ways in, one path: a **live device** (by serial number, or the only one connected) or a
**recording** made by librealsense's own tools (the RealSense Viewer, ``rs-record``, a
``rs2::recorder``: ``.bag``, or ``.db3`` from librealsense 2.57 on), played back by
librealsense itself. Either way the device's sensors are started with a callback that turns
each frame into footfall's types at once:

- depth (``z16``) as its raw 16-bit units with the depth units [m per unit], the stream's
  intrinsics as a :class:`~footfall.sensing.camera.PinholeCamera` (the RealSense noise
  model) and the device's timestamp [s];
- colour (``rgb8``, or ``bgr8`` turned to RGB): the newest image goes with the next depth
  image;
- the gyro [rad/s] and accelerometer [m/s^2] of a D435i or D455, in the depth camera's
  optical frame (through librealsense's IMU-to-depth extrinsics).

librealsense's post-processing filters (decimation, spatial, temporal, hole filling) run on
depth as it arrives, in the order librealsense recommends, and a decimated image comes with
its decimated intrinsics. A recording plays as fast as it is read (none dropped: the callback
waits for room) unless asked to play at its own pace, as a camera would.
"""

from __future__ import annotations

import contextlib
import queue
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from footfall.errors import CameraError, DatasetError
from footfall.hardware.realsense_types import (
    DepthImage,
    MotionSample,
    RealSenseFilters,
    depth_units,
    extrinsics_pose,
    import_realsense,
    pinhole,
)
from footfall.sensing.pose import Pose

# Live streams when none are asked for: a D435i's depth and colour at 424 x 240, 15 fps.
LIVE_SIZE = (424, 240)
LIVE_FPS = 15
# Items waiting for the robot: a live camera drops the oldest beyond this.
QUEUE_ITEMS = 512
# A recording's items read ahead of the reader.
PLAYBACK_ITEMS = 8
# A recording has ended once librealsense said so and no frame has come for this long: the
# status may come while its sensors' last frames are still being handed over [s].
ENDED_QUIET_S = 0.2


def imu_in_camera(rs: Any, profiles: list[tuple[Any, list[Any]]], depth: Any) -> Pose | None:
    """The IMU's pose in the depth optical frame of profile ``depth``; None without an IMU."""
    motion = [p for _, ps in profiles for p in ps if p.stream_type() == rs.stream.gyro]
    motion += [p for _, ps in profiles for p in ps if p.stream_type() == rs.stream.accel]
    if not motion:
        return None
    try:
        return extrinsics_pose(motion[0].get_extrinsics_to(depth))
    except RuntimeError:
        # No extrinsics recorded: the D4xx IMU axes are the depth camera's.
        return Pose.identity()


class RealSenseStream:
    """A device or a recording, its frames handed over in arrival order.

    Use :meth:`open_file` or :meth:`open_device`; :meth:`get` gives the next item
    (:class:`DepthImage` or :class:`MotionSample`), None once a recording has ended.

    Args:
        device: The librealsense device (a playback device for a recording).
        profiles: The stream profiles to start, per sensor.
        filters: Post-processing of depth.
        recording: Whether the device plays a recording (its end ends the stream).
        lossless: Wait for room rather than drop the oldest item (a recording read
            as fast as it goes).

    Raises:
        CameraError: No depth stream.
    """

    def __init__(
        self,
        device: Any,
        profiles: list[tuple[Any, list[Any]]],
        filters: RealSenseFilters,
        recording: bool,
        lossless: bool,
    ) -> None:
        self.rs = import_realsense()
        self.device = device
        self.recording = recording
        self.dropped = 0
        self._lossless = lossless
        self._items: queue.Queue = queue.Queue(PLAYBACK_ITEMS if lossless else QUEUE_ITEMS)
        self._filters = filters.build(self.rs)
        self._color: npt.NDArray[np.uint8] | None = None
        self._ended = threading.Event()
        self._closed = threading.Event()
        self._lock = threading.Lock()
        self._handing_over = 0  # frames inside the callback now
        self._last_frame_at = time.monotonic()
        self._failure: BaseException | None = None
        depth = [p for _, ps in profiles for p in ps if p.stream_type() == self.rs.stream.depth]
        if not depth:
            raise CameraError(f"{self.name()} has no depth stream")
        self._depth_profile = depth[0]
        self.imu_in_camera = imu_in_camera(self.rs, profiles, self._depth_profile)
        self.has_imu = self.imu_in_camera is not None
        self._sensors = []
        if recording:
            device.set_status_changed_callback(self._on_status)
            device.pause()  # until every sensor listens: one started late loses its first frames
        try:
            for sensor, chosen in profiles:
                sensor.open(chosen)
                self._sensors.append(sensor)
                sensor.start(self._on_frame)
            if recording:
                device.resume()
        except RuntimeError as exc:
            self.close()
            raise CameraError(f"{self.name()} would not start: {exc}") from exc

    @classmethod
    def open_file(
        cls, path: str | Path, filters: RealSenseFilters | None = None, realtime: bool = False
    ) -> RealSenseStream:
        """A recording, played by librealsense (as fast as it is read unless ``realtime``).

        Raises:
            DatasetError: No such file, or librealsense cannot read it.
            CameraError: A recording without a depth stream.
        """
        rs = import_realsense()
        path = Path(path)
        if not path.is_file():
            raise DatasetError(f"no RealSense recording {path}")
        try:
            playback = rs.context().load_device(str(path))
        except RuntimeError as exc:
            raise DatasetError(f"{path} is not a recording librealsense reads: {exc}") from exc
        playback.set_real_time(realtime)
        profiles = [(s, list(s.get_stream_profiles())) for s in playback.query_sensors()]
        profiles = [(s, ps) for s, ps in profiles if ps]
        try:
            return cls(playback, profiles, filters or RealSenseFilters(), True, not realtime)
        except CameraError as exc:
            streams = sorted({str(p.stream_type()) for _, ps in profiles for p in ps})
            raise DatasetError(
                f"{path} has no depth stream (it holds {', '.join(streams) or 'no stream'}): {exc}"
            ) from exc

    @classmethod
    def open_device(
        cls,
        serial: str | None = None,
        size: tuple[int, int] = LIVE_SIZE,
        fps: int = LIVE_FPS,
        filters: RealSenseFilters | None = None,
        color: bool = True,
    ) -> RealSenseStream:
        """A connected camera: depth (and colour) at ``size`` and ``fps``, its IMU if it has one.

        Raises:
            CameraError: No camera (or none with that serial number), no depth sensor, or
                no depth stream at that size and rate (the error lists the ones there are).
        """
        rs = import_realsense()
        devices = list(rs.context().query_devices())
        serials = [d.get_info(rs.camera_info.serial_number) for d in devices]
        if not devices:
            raise CameraError("no RealSense camera is connected")
        if serial is None and len(devices) > 1:
            raise CameraError(f"several RealSense cameras ({', '.join(serials)}): give serial=")
        if serial is not None and serial not in serials:
            raise CameraError(
                f"no RealSense camera with serial {serial}; connected: {', '.join(serials)}"
            )
        device = devices[0 if serial is None else serials.index(serial)]
        width, height = size
        chosen: list[tuple[Any, list[Any]]] = []
        for sensor in device.query_sensors():
            picks = []
            for kind, fmt in ((rs.stream.depth, rs.format.z16), (rs.stream.color, rs.format.rgb8)):
                if kind == rs.stream.color and not color:
                    continue
                picks += [
                    p
                    for p in sensor.get_stream_profiles()
                    if p.stream_type() == kind
                    and p.format() == fmt
                    and p.fps() == fps
                    and p.as_video_stream_profile().width() == width
                    and p.as_video_stream_profile().height() == height
                ][:1]
            for kind in (rs.stream.gyro, rs.stream.accel):
                motion = [p for p in sensor.get_stream_profiles() if p.stream_type() == kind]
                picks += sorted(motion, key=lambda p: p.fps())[:1]
            if picks:
                chosen.append((sensor, picks))
        if not any(p.stream_type() == rs.stream.depth for _, ps in chosen for p in ps):
            offered = sorted(
                {
                    f"{p.as_video_stream_profile().width()}x{p.as_video_stream_profile().height()}"
                    f"@{p.fps()}"
                    for s in device.query_sensors()
                    for p in s.get_stream_profiles()
                    if p.stream_type() == rs.stream.depth and p.format() == rs.format.z16
                }
            )
            raise CameraError(
                f"RealSense {serials[devices.index(device)]} has no depth stream at "
                f"{width}x{height}@{fps}; it offers {', '.join(offered) or 'none'}"
            )
        return cls(device, chosen, filters or RealSenseFilters(), False, False)

    def name(self) -> str:
        """The device as its name and serial number say."""
        rs = self.rs
        try:
            name = self.device.get_info(rs.camera_info.name)
            serial = self.device.get_info(rs.camera_info.serial_number)
        except RuntimeError:
            return "the RealSense device"
        return f"{name} {serial}"

    def _on_status(self, status: Any) -> None:
        if status == self.rs.playback_status.stopped:
            self._ended.set()

    def _put(self, item: object) -> None:
        if self._lossless:  # a recording: wait for the reader, lose nothing until closed
            while not self._closed.is_set():
                try:
                    self._items.put(item, timeout=0.1)
                    return
                except queue.Full:
                    continue
            return
        while True:
            try:
                self._items.put_nowait(item)
                return
            except queue.Full:
                try:
                    self._items.get_nowait()
                    self.dropped += 1
                except queue.Empty:
                    pass

    def _on_frame(self, frame: Any) -> None:
        """Librealsense's callback: convert at once (its frame is only lent)."""
        with self._lock:
            self._handing_over += 1
        try:
            self._convert(frame)
        finally:
            with self._lock:
                self._handing_over -= 1
                self._last_frame_at = time.monotonic()

    def _convert(self, frame: Any) -> None:
        rs = self.rs
        try:
            kind = frame.get_profile().stream_type()
            seconds = frame.get_timestamp() / 1000.0
            if kind == rs.stream.depth:
                for step in self._filters:
                    frame = step.process(frame)
                profile = frame.get_profile().as_video_stream_profile()
                units = depth_units(frame.as_depth_frame().get_units())
                with self._lock:  # the newest colour image: its sensor runs on its own thread,
                    color = self._color  # so this instant's may come just after the depth
                image = DepthImage(
                    seconds,
                    int(frame.get_frame_number()),
                    np.asanyarray(frame.get_data()).copy(),
                    units,
                    pinhole(profile.get_intrinsics(), rs),
                    color,
                )
                self._put(image)
            elif kind == rs.stream.color:
                image = np.asanyarray(frame.get_data())
                if frame.get_profile().format() == rs.format.bgr8:
                    image = image[..., ::-1]
                with self._lock:
                    self._color = np.ascontiguousarray(image[..., :3]).copy()
            elif kind in (rs.stream.gyro, rs.stream.accel):
                m = frame.as_motion_frame().get_motion_data()
                vector = np.array([m.x, m.y, m.z], dtype=np.float64)
                assert self.imu_in_camera is not None
                rotated = self.imu_in_camera.rotation.apply(vector)
                name = "gyro" if kind == rs.stream.gyro else "accel"
                self._put(MotionSample(seconds, name, rotated))
        except Exception as exc:  # a callback must not raise into librealsense
            self._failure = exc
            self._ended.set()

    def get(self, timeout: float | None = None) -> DepthImage | MotionSample | None:
        """The next item; None when a recording has ended or ``timeout`` [s] passed.

        Raises:
            CameraError: Converting a frame failed (the error says why).
        """
        deadline = None if timeout is None else time.monotonic() + timeout
        while True:
            if self._failure is not None:
                raise CameraError(f"{self.name()}: {self._failure}") from self._failure
            try:
                return self._items.get(timeout=0.05)
            except queue.Empty:
                if self._ended.is_set() and self._quiet():
                    return None
                if deadline is not None and time.monotonic() > deadline:
                    return None

    def _quiet(self) -> bool:
        """Nothing waits, no frame is being handed over, and none came for a while."""
        with self._lock:
            idle = self._handing_over == 0
            since = time.monotonic() - self._last_frame_at
        return idle and self._items.empty() and since > ENDED_QUIET_S

    def drain(self) -> list[DepthImage | MotionSample]:
        """Every item waiting now, oldest first (a live camera's robot takes them each tick).

        Raises:
            CameraError: Converting a frame failed.
        """
        if self._failure is not None:
            raise CameraError(f"{self.name()}: {self._failure}") from self._failure
        items = []
        while True:
            try:
                items.append(self._items.get_nowait())
            except queue.Empty:
                return items

    @property
    def ended(self) -> bool:
        """A recording has played to its end and everything was taken."""
        return self._ended.is_set() and self._quiet()

    def connected(self) -> bool:
        """Whether the device is still there (a recording always is)."""
        if self.recording:
            return True
        try:
            return bool(self.device.is_connected())
        except RuntimeError:
            return False

    def close(self) -> None:
        """Stop and close every sensor (safe to call twice)."""
        self._ended.set()
        self._closed.set()
        for sensor in self._sensors:
            for step in (sensor.stop, sensor.close):
                with contextlib.suppress(RuntimeError):
                    step()
        self._sensors = []
