"""`footfall robot --hardware` with a RealSense recording as its camera: the emulated servos in
one process (`footfall servo-bus`), the robot in another, a station on zenoh."""

from __future__ import annotations

import math
import signal

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from footfall.messages import DepthFrame, MapUpdate, PoseEstimate
from footfall.robot.spec import load_spec
from footfall.runtime.bus import InProcessBus
from footfall.runtime.zenoh_bus import ZenohBus, ZenohConfig
from footfall.sim.model import CameraMount
from footfall.sim.survey import MappingSettings, simulate_mapping
from realsense_recordings import Frame, Motion, write_recording
from test_realsense import GRAVITY, _float32
from test_robot_network import wait_for
from test_servo_bus_network import footfall, start_servo_bus
from test_zenoh_bus import free_port

# The camera's IMU says the body is pitched this much more than the trajectory does [deg].
EXTRA_PITCH_DEG = 3.0
SECONDS = 10.0
FPS = 15


def _standing_recording(tmp_path):
    """A camera that stands and looks at the course for SECONDS: its depth in millimetres,
    a trajectory that holds its pose, and an IMU that reads the body pitched EXTRA_PITCH_DEG
    further than that pose."""
    bus = InProcessBus()
    depth, poses = [], []
    bus.subscribe(DepthFrame.TOPIC, depth.append)
    bus.subscribe(PoseEstimate.TOPIC, poses.append)
    mount = CameraMount(width=160, height=120)
    simulate_mapping(load_spec("default"), MappingSettings("course", 0.2, camera=mount), bus=bus)
    metres = np.nan_to_num(np.asarray(depth[0].depth, dtype=np.float64), nan=0.0)
    units = np.clip(np.round(metres * 1000.0), 0, 65535).astype(np.uint16)
    camera_in_world = poses[0].camera_in_world
    body_in_world = poses[0].body_in_world
    # The IMU's body: the trajectory's, pitched further about the body's y axis.
    imu_body = body_in_world.rotation * Rotation.from_euler("y", math.radians(EXTRA_PITCH_DEG))
    camera_in_body = body_in_world.inverse().compose(camera_in_world)
    up_in_body = imu_body.inv().apply([0.0, 0.0, GRAVITY])
    up_in_camera = camera_in_body.rotation.inv().apply(up_in_body)
    stamps = [k / FPS for k in range(int(SECONDS * FPS))]
    # A real camera's images differ by their noise (a repeated image is a fault).
    rng = np.random.default_rng(0)
    noise = [rng.integers(-2, 3, units.shape) for _ in stamps]
    frames = [
        Frame(t, np.where(units > 0, units + n, 0).astype(np.uint16))
        for t, n in zip(stamps, noise, strict=True)
    ]
    motion = [Motion(t, (0.0, 0.0, 0.0), tuple(up_in_camera)) for t in stamps]
    recording = write_recording(
        tmp_path / "standing.db3", _float32(depth[0].intrinsics), frames, 0.001, motion, FPS
    )
    q = camera_in_world.rotation.as_quat()
    line = " ".join(repr(float(v)) for v in (*camera_in_world.position, *q))
    trajectory = tmp_path / "trajectory.tum"
    trajectory.write_text("\n".join(f"{t!r} {line}" for t in stamps) + "\n")
    body_pitch = body_in_world.rotation.as_euler("ZYX")[1]
    return recording, trajectory, body_pitch


def test_the_robot_maps_through_a_realsense_recording_and_takes_its_imu(tmp_path):
    """The robot's process plays the recording as its camera: a station receives its depth
    images (16-bit millimetres), a map with known cells, and guarded poses whose tilt is the
    camera IMU's, not the trajectory's (the pose guard takes roll and pitch from the IMU)."""
    recording, trajectory, trajectory_pitch = _standing_recording(tmp_path)
    link = tmp_path / "ttyDXL"
    robot_endpoint = f"tcp/127.0.0.1:{free_port()}"
    server = start_servo_bus(link)
    robot = None
    try:
        robot = footfall(
            "robot", "--hardware", "default", "--port", str(link),
            "--realsense-file", str(recording), "--pose", "trajectory",
            "--pose-option", f"file={trajectory}", "--listen", robot_endpoint,
            "--seconds", "60", "--out", str(tmp_path / "out"),
        )  # fmt: skip
        images: list[DepthFrame] = []
        maps: list[MapUpdate] = []
        guarded: list[PoseEstimate] = []
        with ZenohBus(ZenohConfig(connect=(robot_endpoint,))) as station:
            station.subscribe(DepthFrame.TOPIC, images.append)
            station.subscribe(MapUpdate.TOPIC, maps.append)
            station.subscribe(PoseEstimate.TOPIC, guarded.append)

            def seen() -> bool:
                known = bool(maps) and int(np.count_nonzero(maps[-1].known)) > 500
                return len(images) >= 5 and known and len(guarded) >= 20

            assert wait_for(station, seen, 45), robot.communicate(timeout=5)[0].decode()
            robot.send_signal(signal.SIGINT)
            output = robot.communicate(timeout=20)[0].decode()
        assert robot.returncode == 0, output
    finally:
        for process in (robot, server):
            if process is not None and process.poll() is None:
                process.send_signal(signal.SIGINT)
                process.communicate(timeout=20)
    assert images[-1].depth.dtype == np.uint16 and images[-1].depth_scale == 0.001
    assert images[-1].depth.shape == (120, 160)
    pitch = math.degrees(guarded[-1].body_in_world.rotation.as_euler("ZYX")[1])
    assert pitch == pytest.approx(math.degrees(trajectory_pitch) + EXTRA_PITCH_DEG, abs=0.3)
