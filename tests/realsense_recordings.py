"""RealSense recordings made without a camera: librealsense's software device, recorded.

A ``software_device`` with a depth sensor (z16, the given intrinsics and depth units), an
optional colour sensor and an optional motion module (gyro, accelerometer) is wrapped in
``pyrealsense2.recorder``; every frame pushed into it is written as a camera's would be, to a
``.db3`` file that ``config.enable_device_from_file`` and ``context.load_device`` play back.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import numpy.typing as npt
import pyrealsense2 as rs

from footfall.sensing.camera import PinholeCamera


@dataclass(frozen=True)
class Frame:
    """A depth image to record: time [s], 16-bit units, and a colour image if any."""

    stamp: float
    depth: npt.NDArray[np.uint16]
    color: npt.NDArray[np.uint8] | None = None


@dataclass(frozen=True)
class Motion:
    """One IMU sample to record, in the depth optical frame: time [s], gyro, accelerometer."""

    stamp: float
    gyro: Sequence[float]
    accel: Sequence[float]


def _intrinsics(camera: PinholeCamera) -> rs.intrinsics:
    i = rs.intrinsics()
    i.width, i.height = camera.width, camera.height
    i.fx, i.fy, i.ppx, i.ppy = camera.fx, camera.fy, camera.cx, camera.cy
    i.model = rs.distortion.brown_conrady
    i.coeffs = [0.0] * 5
    return i


def _video_frame(profile, pixels: np.ndarray, bpp: int, stamp: float, number: int):
    frame = rs.software_video_frame()
    frame.pixels = np.ascontiguousarray(pixels)
    frame.bpp = bpp
    frame.stride = bpp * pixels.shape[1]
    frame.timestamp = 1000.0 * stamp
    frame.domain = rs.timestamp_domain.hardware_clock
    frame.frame_number = number
    frame.profile = profile.as_video_stream_profile()
    return frame


def _motion_frame(profile, values: Sequence[float], stamp: float, number: int):
    vector = rs.vector()
    vector.x, vector.y, vector.z = (float(v) for v in values)
    frame = rs.software_motion_frame()
    frame.data = vector
    frame.timestamp = 1000.0 * stamp
    frame.domain = rs.timestamp_domain.hardware_clock
    frame.frame_number = number
    frame.profile = profile.as_motion_stream_profile()
    return frame


def write_recording(
    path: Path,
    camera: PinholeCamera,
    frames: Sequence[Frame],
    depth_units: float = 0.001,
    motion: Sequence[Motion] = (),
    fps: int = 15,
    depth: bool = True,
) -> Path:
    """Record ``frames`` (and ``motion``) as a RealSense D435i would; returns ``path``.

    Frames are pushed at the pace of their stamps, as a camera delivers them: librealsense
    keeps the time each arrived, and plays a recording back in real time by it. With
    ``depth`` False the recording holds colour only (another stream layout).
    """
    device = rs.software_device()
    device.register_info(rs.camera_info.name, "Intel RealSense D435I (software)")
    device.register_info(rs.camera_info.serial_number, "000000000042")
    streams = []

    def video(name: str, kind, uid: int, bpp: int, fmt):
        sensor = device.add_sensor(name)
        stream = rs.video_stream()
        stream.type, stream.index, stream.uid = kind, 0, uid
        stream.width, stream.height, stream.fps = camera.width, camera.height, fps
        stream.bpp, stream.fmt, stream.intrinsics = bpp, fmt, _intrinsics(camera)
        streams.append((sensor, [sensor.add_video_stream(stream, True)]))
        return sensor

    if depth:
        depth_sensor = video("Stereo Module", rs.stream.depth, 0, 2, rs.format.z16)
        depth_sensor.add_read_only_option(rs.option.depth_units, depth_units)
    has_color = any(f.color is not None for f in frames)
    if has_color:
        video("RGB Camera", rs.stream.color, 1, 3, rs.format.rgb8)
    if motion:
        motion_sensor = device.add_sensor("Motion Module")
        profiles = []
        for uid, (kind, rate) in enumerate(((rs.stream.gyro, 200), (rs.stream.accel, 100)), 2):
            stream = rs.motion_stream()
            stream.type, stream.index, stream.uid = kind, 0, uid
            stream.fps, stream.fmt = rate, rs.format.motion_xyz32f
            stream.intrinsics = rs.motion_device_intrinsic()
            profiles.append(motion_sensor.add_motion_stream(stream, True))
        streams.append((motion_sensor, profiles))
    recorder = rs.recorder(str(path), device)
    delivered = []
    sensors = list(recorder.query_sensors())
    for sensor, (_, chosen) in zip(sensors, streams, strict=True):
        sensor.open(chosen if len(chosen) > 1 else chosen[0])
        sensor.start(lambda f: delivered.append(f.get_frame_number()))
    events = [(f.stamp, 0, k) for k, f in enumerate(frames)]
    events += [(m.stamp, 1, k) for k, m in enumerate(motion)]
    start = time.monotonic()
    first = min(stamp for stamp, _, _ in events)
    for stamp, kind, k in sorted(events):
        time.sleep(max(0.0, start + (stamp - first) - time.monotonic()))
        if kind == 0:
            frame = frames[k]
            if depth:
                streams[0][0].on_video_frame(
                    _video_frame(streams[0][1][0], frame.depth, 2, stamp, k)
                )
            if has_color and frame.color is not None:
                sensor, (profile,) = streams[1 if depth else 0]
                sensor.on_video_frame(_video_frame(profile, frame.color, 3, stamp, k))
        else:
            sensor, (gyro, accel) = streams[-1]
            sensor.on_motion_frame(_motion_frame(gyro, motion[k].gyro, stamp, k))
            sensor.on_motion_frame(_motion_frame(accel, motion[k].accel, stamp, k))
    expected = len(frames) * (int(depth) + int(has_color)) + 2 * len(motion)
    deadline = time.monotonic() + 10.0
    while len(delivered) < expected and time.monotonic() < deadline:
        time.sleep(0.01)
    for sensor in sensors:
        sensor.stop()
        sensor.close()
    del recorder, sensors
    return path
