"""The RealSense camera: librealsense recordings made here from simulated depth, played back by
librealsense itself into the map, and the camera's IMU into the robot's attitude."""

from __future__ import annotations

import json
import time

import numpy as np
import pytest
from PIL import Image
from scipy.spatial.transform import Rotation

from footfall.backends.attitude import ImuAttitude
from footfall.cli import main
from footfall.errors import CameraError, ConfigError, DatasetError
from footfall.hardware.realsense import RealSenseStream
from footfall.hardware.realsense_camera import RealSenseCamera
from footfall.hardware.realsense_types import RealSenseFilters, depth_units
from footfall.messages import DepthFrame, ImuReading, LogLine, PoseEstimate
from footfall.robot.spec import camera_placement_from_table, load_spec
from footfall.runtime.bus import InProcessBus
from footfall.sensing.camera import PinholeCamera
from footfall.sim.model import CameraMount
from footfall.sim.survey import MappingSettings, simulate_mapping
from realsense_recordings import Frame, Motion, write_recording

GRAVITY = 9.80665


def _float32(camera: PinholeCamera) -> PinholeCamera:
    """The intrinsics as a recording holds them (librealsense keeps float32)."""
    fx, fy, cx, cy = (float(np.float32(v)) for v in (camera.fx, camera.fy, camera.cx, camera.cy))
    return PinholeCamera(fx, fy, cx, cy, camera.width, camera.height)


@pytest.fixture(scope="module")
def simulated(tmp_path_factory):
    """Depth images of the simulated robot's camera walking the course, in millimetres, with
    the camera's true poses; the same frames as a TUM folder and as a RealSense recording
    (with an IMU that reads gravity in the camera's frame)."""
    bus = InProcessBus()
    depth, poses = [], {}
    bus.subscribe(DepthFrame.TOPIC, depth.append)
    bus.subscribe(PoseEstimate.TOPIC, lambda p: poses.setdefault(p.stamp, p.camera_in_world))
    settings = MappingSettings(
        terrain="course", seconds=2.0, camera=CameraMount(width=160, height=120)
    )
    simulate_mapping(load_spec("default"), settings, bus=bus)
    folder = tmp_path_factory.mktemp("frames")
    (folder / "depth").mkdir()
    frames, truth, motion = [], [], []
    for k, frame in enumerate(depth):
        metres = np.nan_to_num(np.asarray(frame.depth, dtype=np.float64), nan=0.0)
        units = np.clip(np.round(metres * 1000.0), 0, 65535).astype(np.uint16)
        stamp = round(frame.stamp, 6)
        Image.fromarray(units).save(folder / "depth" / f"{k}.png")
        frames.append(Frame(stamp, units, np.full((*units.shape, 3), k % 256, np.uint8)))
        pose = poses[frame.stamp]
        q = pose.rotation.as_quat()
        truth.append(" ".join(repr(float(v)) for v in (stamp, *pose.position, *q)))
        up_in_camera = pose.rotation.inv().apply([0.0, 0.0, GRAVITY])
        motion.append(Motion(stamp, (0.0, 0.0, 0.0), tuple(up_in_camera)))
    (folder / "depth.txt").write_text(
        "\n".join(f"{f.stamp} depth/{k}.png" for k, f in enumerate(frames)) + "\n"
    )
    (folder / "groundtruth.txt").write_text("\n".join(truth) + "\n")
    camera = _float32(depth[0].intrinsics)
    recording = write_recording(folder / "walk.db3", camera, frames, 0.001, motion)
    return folder, recording, camera, frames, motion


def test_a_recording_plays_back_every_frame_as_recorded(simulated):
    """Librealsense plays the recording back: every depth image in order, its 16-bit units,
    its intrinsics and depth units, the device's timestamps, the colour images and every IMU
    sample; decimation halves the image and its intrinsics."""
    _, recording, camera, frames, motion = simulated
    stream = RealSenseStream.open_file(recording)
    items = []
    while (item := stream.get(timeout=10.0)) is not None:
        items.append(item)
    stream.close()
    images = [i for i in items if hasattr(i, "depth")]
    assert [i.device_time for i in images] == pytest.approx([f.stamp for f in frames], abs=1e-9)
    for image, frame in zip(images, frames, strict=True):
        np.testing.assert_array_equal(image.depth, frame.depth)
    assert images[0].depth_scale == 0.001
    assert images[0].camera == PinholeCamera(
        camera.fx, camera.fy, camera.cx, camera.cy, camera.width, camera.height,
        noise=images[0].camera.noise,
    )  # fmt: skip
    # Colour streams on its own thread: each depth image carries the newest colour image
    # that had come (frame k's is filled with k), so colour never goes back in time, is
    # there for most images and for the last, and is always one of the recorded ones.
    shades = [int(i.color[0, 0, 0]) for i in images if i.color is not None]
    assert len(shades) >= len(images) // 2 and images[-1].color is not None
    assert shades == sorted(shades) and set(shades) <= {k % 256 for k in range(len(frames))}
    for image in images:
        if image.color is not None:
            assert (image.color == image.color[0, 0, 0]).all()
    samples = [i for i in items if hasattr(i, "kind")]
    assert len(samples) == 2 * len(motion) and stream.has_imu
    accel = [s.vector_in_camera for s in samples if s.kind == "accel"]
    np.testing.assert_allclose(accel, [m.accel for m in motion], atol=1e-5)  # float32
    halved = RealSenseStream.open_file(recording, RealSenseFilters(decimation=2, hole_filling=True))
    first = halved.get(timeout=10.0)
    while not hasattr(first, "depth"):
        first = halved.get(timeout=10.0)
    halved.close()
    assert first.depth.shape == (camera.height // 2, camera.width // 2)
    assert first.camera.fx == pytest.approx(camera.fx / 2, rel=0.02)


def test_map_of_a_recording_is_the_map_of_the_same_frames(simulated, tmp_path):
    """`footfall map --realsense FILE --trajectory T` and `footfall map --tum` on the same
    frames and poses give the same map, every layer equal: the depth keeps its 16-bit units
    and the recording's depth units (librealsense's float32 0.001 read back as 0.001), and the
    TUM run is given the intrinsics the recording holds (float32)."""
    folder, recording, camera, frames, motion = simulated
    direct, played = tmp_path / "direct", tmp_path / "played"
    intrinsics = [repr(v) for v in (camera.fx, camera.fy, camera.cx, camera.cy)]
    assert main(
        ["map", "--tum", str(folder), "--depth-scale", "0.001", "--sensor", "realsense",
         "--intrinsics", *intrinsics, "--out", str(direct)]
    ) == 0  # fmt: skip
    assert main(
        ["map", "--realsense", str(recording), "--trajectory", str(folder / "groundtruth.txt"),
         "--out", str(played)]
    ) == 0  # fmt: skip
    a, b = np.load(direct / "map.npz"), np.load(played / "map.npz")
    assert sorted(a.files) == sorted(b.files)
    for layer in a.files:
        np.testing.assert_array_equal(a[layer], b[layer], err_msg=layer)
    assert np.isfinite(a["height"]).sum() > 500 and a["valid"].sum() > 500
    metrics = json.loads((played / "metrics.json").read_text())
    assert metrics["frames"] == len(frames) and metrics["imu_samples"] == 2 * len(motion)


def test_bad_recordings_and_options_are_named(simulated, tmp_path, capsys):
    """A recording without depth, a missing file, a recording without poses, filters out of
    range, no camera connected: each a clear error naming the problem."""
    _, recording, camera, frames, _ = simulated
    colour_only = write_recording(tmp_path / "colour.db3", camera, frames[:3], depth=False)
    with pytest.raises(DatasetError, match="no depth stream"):
        RealSenseStream.open_file(colour_only)
    with pytest.raises(DatasetError, match="no RealSense recording"):
        RealSenseStream.open_file(tmp_path / "missing.db3")
    (tmp_path / "text.db3").write_text("not a recording")
    with pytest.raises(DatasetError, match="not a recording"):
        RealSenseStream.open_file(tmp_path / "text.db3")
    with pytest.raises(ConfigError, match="decimation 9"):
        RealSenseFilters.from_options({"decimation": "9"})
    with pytest.raises(ConfigError, match="spatial"):
        RealSenseFilters.from_options({"spatial": "yes"})
    out = tmp_path / "out"
    assert main(["map", "--realsense", str(recording), "--out", str(out)]) == 2
    assert "--trajectory" in capsys.readouterr().out
    assert main(["map", "--realsense", str(colour_only), "--camera-height", "0.3",
                 "--out", str(out)]) == 2  # fmt: skip
    assert "no depth stream" in capsys.readouterr().out
    assert depth_units(np.float32(0.001)) == 0.001
    with pytest.raises(CameraError, match="no RealSense camera is connected"):
        RealSenseStream.open_device()


def test_the_camera_source_stamps_on_the_robot_clock_and_counts_a_stall(simulated):
    """As the robot's camera: each tick hands over the newest depth image with its scale and
    the camera's pose on the body, stamped on the robot's clock no later than the tick; the
    IMU readings arrive in the body frame; at the recording's end the camera stalls once,
    says so, and the robot's bus gets no more images."""
    _, recording, _, frames, _ = simulated
    bus = InProcessBus()
    images, imu, log = [], [], []
    bus.subscribe(DepthFrame.TOPIC, images.append)
    bus.subscribe(ImuReading.TOPIC, imu.append)
    bus.subscribe(LogLine.TOPIC, log.append)
    stream = RealSenseStream.open_file(recording, realtime=True)
    table = {"position": [0.1, 0.0, 0.05], "pitch_deg": 25.0}
    mount = camera_placement_from_table(table).optical_in_body()
    source = RealSenseCamera(bus, stream, mount, stall=0.5)
    start = frames[0].stamp
    t = 10.0
    try:
        while t < 10.0 + (frames[-1].stamp - start) + 2.0:
            source.tick(t)
            bus.spin()
            t += 0.01
            time.sleep(0.01)
    finally:
        source.close()
    assert 0.5 * len(frames) < len(images) <= len(frames)
    assert all(i.stamp <= 10.0 + (frames[-1].stamp - start) + 2.0 for i in images)
    assert [i.stamp for i in images] == sorted(i.stamp for i in images)
    assert images[0].depth_scale == 0.001 and images[0].camera_in_body == mount
    assert imu and np.linalg.norm(imu[0].specific_force_body_in_body) == pytest.approx(
        GRAVITY, rel=1e-4
    )
    assert source.stalls == 1
    assert any("recording has ended" in line.text for line in log)


def test_the_camera_imu_gives_the_robot_its_attitude():
    """Readings of a body pitched 4 degrees and rolled -3 degrees, turned into the body frame:
    the attitude filter settles on that tilt and takes its heading from the pose source."""
    bus = InProcessBus()
    attitude = ImuAttitude(bus, tilt_time_s=0.2)
    tilt = Rotation.from_euler("ZYX", [0.0, np.radians(4.0), np.radians(-3.0)])
    force = tilt.inv().apply([0.0, 0.0, GRAVITY])
    for k in range(400):
        bus.publish(ImuReading.TOPIC, ImuReading(0.005 * k, np.zeros(3), force))
        bus.spin()
    _, pitch, roll = np.degrees(attitude()[0].as_euler("ZYX"))
    assert (pitch, roll) == (pytest.approx(4.0, abs=0.05), pytest.approx(-3.0, abs=0.05))
    from footfall.sensing.pose import Pose

    body = Pose(np.zeros(3), Rotation.from_euler("z", 0.5))
    bus.publish(PoseEstimate.TOPIC, PoseEstimate(2.0, body, body))
    bus.publish(ImuReading.TOPIC, ImuReading(2.0, np.zeros(3), force))
    bus.spin()
    yaw, pitch, roll = np.degrees(attitude()[0].as_euler("ZYX"))
    assert yaw == pytest.approx(np.degrees(0.5)) and pitch == pytest.approx(4.0, abs=0.05)


def test_the_camera_table_places_the_camera_on_the_body():
    """[camera] position and pitch: the optical axis looks ahead and down by the pitch; an
    unknown key is named."""
    table = {"position": [0.13, 0.0, 0.08], "pitch_deg": 30.0}
    pose = camera_placement_from_table(table).optical_in_body()
    forward = pose.rotation.apply([0.0, 0.0, 1.0])
    np.testing.assert_allclose(forward, [np.cos(np.radians(30)), 0, -np.sin(np.radians(30))])
    np.testing.assert_allclose(pose.rotation.apply([1.0, 0.0, 0.0]), [0.0, -1.0, 0.0], atol=1e-12)
    with pytest.raises(ConfigError, match="tilt"):
        camera_placement_from_table({"tilt": 3})


def test_imu_readings_record_as_ros_imu_messages():
    """In an MCAP file or a bag, the camera's IMU is a sensor_msgs/Imu on /camera/imu: its
    rates and specific force in the body frame, the orientation marked as not measured."""
    from footfall.recording.ros_types import to_ros

    reading = ImuReading(1.5, np.array([0.1, -0.2, 0.3]), np.array([0.4, 0.0, 9.8]))
    [(channel, kind, imu)] = to_ros(ImuReading.TOPIC, reading)
    assert (channel, kind) == ("/camera/imu", "sensor_msgs/msg/Imu")
    assert (imu.angular_velocity.x, imu.angular_velocity.y, imu.angular_velocity.z) == (
        0.1, -0.2, 0.3,
    )  # fmt: skip
    assert (imu.linear_acceleration.x, imu.linear_acceleration.z) == (0.4, 9.8)
    assert imu.orientation_covariance[0] == -1.0
    assert imu.header.stamp.sec == 1 and imu.header.stamp.nanosec == 500_000_000
