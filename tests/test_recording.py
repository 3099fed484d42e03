"""Recordings: a run to MCAP and back to the same map; ROS 2 and ROS 1 bags replayed."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from conftest import shared_data
from footfall.cli import main
from footfall.errors import DatasetError
from footfall.recording.replay import Replayer
from footfall.recording.replay_request import ReplayRequest
from footfall.recording.ros_types import typestore
from footfall.recording.session import Recorders
from footfall.runtime.bus import InProcessBus
from footfall.sim.walk import simulate_walk
from footfall.sim.walk_request import WalkRequest, prepare_walk

LAYERS = ("heights", "known", "spread", "variance")


@pytest.fixture(scope="module")
def recorded_walk(tmp_path_factory):
    """A seeded 3 s stairs walk recorded to MCAP, and its live map."""
    path = tmp_path_factory.mktemp("rec") / "walk.mcap"
    job = prepare_walk(WalkRequest(terrain="stairs", seconds=3.0, seed=3))
    robots = []
    with Recorders(path) as recorders:

        def built(robot):
            robots.append(robot)
            recorders.mapping_started(robot.mapping)

        bus = recorders.attach(InProcessBus())
        simulate_walk(job.spec, job.settings, terrain=job.terrain, bus=bus, on_build=built)
    return path, robots[0].mapping.height_map.snapshot(), robots[0].mapping.frames


def test_a_recorded_walk_replays_to_the_same_map(recorded_walk):
    """Bit-identical height, known, spread and variance arrays from the replay."""
    path, live, frames = recorded_walk
    mapping = Replayer(ReplayRequest(path, fast=True)).run()
    replayed = mapping.height_map.snapshot()
    assert mapping.frames == frames > 20
    assert replayed.origin == live.origin
    for layer in LAYERS:
        np.testing.assert_array_equal(getattr(replayed, layer), getattr(live, layer), err_msg=layer)


def test_every_channel_has_a_schema_the_mcap_reader_reads(recorded_walk):
    """The mcap library opens the file; every channel has a ros2msg schema, CDR messages;
    the standard and footfall types are there."""
    from mcap.reader import make_reader

    path, _, _ = recorded_walk
    with path.open("rb") as stream:
        summary = make_reader(stream).get_summary()
    channels = {c.topic: c for c in summary.channels.values()}
    for channel in channels.values():
        schema = summary.schemas[channel.schema_id]
        assert schema.encoding == "ros2msg" and schema.data and channel.message_encoding == "cdr"
    types = {t: summary.schemas[c.schema_id].name for t, c in channels.items()}
    assert types["/camera/depth/image_raw"] == "sensor_msgs/msg/Image"
    assert types["/camera/depth/camera_info"] == "sensor_msgs/msg/CameraInfo"
    assert types["/camera/pose"] == "geometry_msgs/msg/PoseStamped"
    assert types["/tf"] == "tf2_msgs/msg/TFMessage"
    assert types["/map/grid"] == "grid_map_msgs/msg/GridMap"
    assert types["/map/occupancy"] == "nav_msgs/msg/OccupancyGrid"
    assert types["/effector_targets"] == "footfall_msgs/msg/EffectorTargets"
    assert types["/gait_status"] == "footfall_msgs/msg/GaitStatus"
    gait = summary.schemas[channels["/gait_status"].schema_id].data.decode()
    assert "string frozen_reason" in gait and "MSG: std_msgs/Header" in gait


def _redwood_bag(tmp_path: Path, storage: str, tum: Path, bogus_hash: bool = False) -> Path:
    """The shared Redwood frames as a ROS 2 bag written with rosbags: 16UC1 depth (the
    millimetre PNGs), CameraInfo and PoseStamped (the converted sequence's camera poses,
    its y-up world turned z-up)."""
    from PIL import Image
    from rosbags.rosbag2 import StoragePlugin, Writer

    from footfall.datasets.tum import read_tum_sequence, up_to_z
    from footfall.messages import DepthFrame
    from footfall.recording import ros_types as rt
    from footfall.sensing.camera import PinholeCamera
    from footfall.sensing.pose import Pose

    source = shared_data("rgbd/redwood_livingroom")
    store = typestore()
    bag = tmp_path / f"redwood_{storage}"
    align = Pose(np.zeros(3), up_to_z((0.0, 1.0, 0.0)))
    camera = PinholeCamera(525, 525, 319.5, 239.5, 640, 480)
    frames, _ = read_tum_sequence(tum)
    files = sorted((source / "depth").glob("*.png"))
    plugin = StoragePlugin.MCAP if storage == "mcap" else StoragePlugin.SQLITE3
    kinds = ("sensor_msgs/msg/Image", "sensor_msgs/msg/CameraInfo", "geometry_msgs/msg/PoseStamped")
    with Writer(bag, version=9, storage_plugin=plugin) as writer:
        image_c, info_c, pose_c = (
            writer.add_connection(topic, kind, typestore=store)
            for topic, kind in zip(
                ("/depth", "/depth/camera_info", "/camera_pose"), kinds, strict=True
            )
        )
        for file, frame in zip(files, frames, strict=True):
            t, ns = frame.timestamp, round(frame.timestamp * 1e9)
            mm = np.array(Image.open(file)).astype(np.uint16)
            depth = DepthFrame(t, mm, camera, Pose.identity(), 0.001)
            pose = align.compose(frame.camera_pose)
            stamped = store.types[kinds[2]](header=rt.header(t, "world"), pose=rt._pose(pose))
            writer.write(info_c, ns, store.serialize_cdr(rt.camera_info(depth), kinds[1]))
            writer.write(image_c, ns, store.serialize_cdr(rt.depth_image(depth), kinds[0]))
            writer.write(pose_c, ns, store.serialize_cdr(stamped, kinds[2]))
    if bogus_hash:  # a type hash from "another release": rosbags refuses the bag as a whole
        meta = bag / "metadata.yaml"
        lines = meta.read_text().split("\n")
        pose_line = next(k for k, line in enumerate(lines) if kinds[2] in line)
        hashed = next(
            k for k in range(pose_line, len(lines)) if "type_description_hash" in lines[k]
        )
        lines[hashed] = lines[hashed].split(":")[0] + ": RIHS01_" + "0" * 64
        meta.write_text("\n".join(lines))
    return bag


@pytest.mark.parametrize(
    ("storage", "bogus_hash"), [("sqlite3", False), ("mcap", False), ("mcap", True)]
)
def test_a_ros2_bag_replays_to_the_map_of_the_converted_sequence(tmp_path, storage, bogus_hash):
    """A ROS 2 bag of the Redwood frames replays to the same map as `footfall map --tum` of
    the converted sequence (bit for bit: millimetres and TUM units give the same metres),
    also when rosbags refuses the bag's type hashes (read file by file instead)."""
    source = shared_data("rgbd/redwood_livingroom")
    assert main(["convert", "redwood", str(source), str(tmp_path / "tum")]) == 0
    bag = _redwood_bag(tmp_path, storage, tmp_path / "tum", bogus_hash)
    _map_tum(tmp_path / "tum", tmp_path / "m")
    args = [
        "replay",
        str(bag),
        "--fast",
        "--pose-topic",
        "/camera_pose",
        "--out",
        str(tmp_path / "r"),
    ]
    assert main(args) == 0
    live, replayed = np.load(tmp_path / "m" / "map.npz"), np.load(tmp_path / "r" / "map.npz")
    for layer in ("height", "variance", "spread", "score", "valid", "known", "origin_xy_m"):
        np.testing.assert_array_equal(replayed[layer], live[layer], err_msg=layer)
    metrics = json.loads((tmp_path / "r" / "metrics.json").read_text())
    assert metrics["frames"] == 5 and metrics["floor_valid_fraction"] >= 0.9


def _map_tum(tum: Path, out: Path) -> None:
    assert main(["map", "--tum", str(tum), "--up", "0", "1", "0", "--out", str(out)]) == 0


def test_converted_mcap_replays_to_the_same_map(tmp_path):
    """`footfall convert redwood X file.mcap` then `footfall replay` = `footfall map --tum`."""
    source = shared_data("rgbd/redwood_livingroom")
    assert main(["convert", "redwood", str(source), str(tmp_path / "r.mcap")]) == 0
    assert main(["convert", "redwood", str(source), str(tmp_path / "tum")]) == 0
    _map_tum(tmp_path / "tum", tmp_path / "m")
    assert main(["replay", str(tmp_path / "r.mcap"), "--fast", "--out", str(tmp_path / "p")]) == 0
    live, replayed = np.load(tmp_path / "m" / "map.npz"), np.load(tmp_path / "p" / "map.npz")
    for layer in ("height", "score", "valid", "known"):
        np.testing.assert_array_equal(replayed[layer], live[layer], err_msg=layer)


def _flat_floor_depth(camera, floor) -> np.ndarray:
    """Exact 32FC1 depth of a flat floor seen by ``camera`` from ``floor`` (a pose over it)."""
    u, v = np.meshgrid(np.arange(camera.width), np.arange(camera.height))
    rays = np.stack(
        [(u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy, np.ones(u.shape)], -1
    )
    down = floor.rotation_camera_to_map.apply(rays.reshape(-1, 3))[:, 2]
    depth = np.where(down < -1e-6, floor.height_m / -down, 0.0)
    return depth.reshape(camera.height, camera.width).astype("<f4")


def test_a_ros1_bag_replays(tmp_path):
    """A ROS 1 bag (rosbags' writer, ROS 1 types) of a flat floor, 32FC1 depth and the
    camera's PoseStamped: replays to a flat floor at z = 0."""
    from rosbags.rosbag1 import Writer
    from rosbags.typesys import Stores, get_typestore

    from footfall.pointcloud.ground import CameraOverFloor
    from footfall.sensing.camera import PinholeCamera
    from footfall.sensing.pose import Pose

    ros1 = get_typestore(Stores.ROS1_NOETIC)
    T = ros1.types
    camera = PinholeCamera(120, 120, 79.5, 59.5, 160, 120)
    floor = CameraOverFloor.from_angles(0.6, np.radians(40))
    depth = _flat_floor_depth(camera, floor)

    def header(t, frame):
        stamp = T["builtin_interfaces/msg/Time"](sec=int(t), nanosec=round((t % 1) * 1e9))
        return T["std_msgs/msg/Header"](seq=0, stamp=stamp, frame_id=frame)

    def stamped(t, pose):
        x, y, z = pose.position
        qx, qy, qz, qw = pose.rotation.as_quat()
        return T["geometry_msgs/msg/PoseStamped"](
            header=header(t, "odom"),
            pose=T["geometry_msgs/msg/Pose"](
                position=T["geometry_msgs/msg/Point"](x=x, y=y, z=z),
                orientation=T["geometry_msgs/msg/Quaternion"](x=qx, y=qy, z=qz, w=qw),
            ),
        )

    pose = Pose(np.array([1.0, 0.5, 0.6]), floor.rotation_camera_to_map)
    roi = T["sensor_msgs/msg/RegionOfInterest"](
        x_offset=0, y_offset=0, height=0, width=0, do_rectify=False
    )
    names = ("geometry_msgs/msg/PoseStamped", "sensor_msgs/msg/CameraInfo", "sensor_msgs/msg/Image")
    topics = ("/cam/pose", "/cam/depth/camera_info", "/cam/depth/image")
    bag = tmp_path / "floor.bag"
    with Writer(bag) as writer:
        connections = [
            writer.add_connection(topic, name, typestore=ros1)
            for topic, name in zip(topics, names, strict=True)
        ]
        for k in range(3):
            t = 0.1 * k + 0.01
            info = T[names[1]](
                header=header(t, "cam"), height=120, width=160, distortion_model="plumb_bob",
                D=np.zeros(5), K=camera.matrix.ravel(), R=np.eye(3).ravel(),
                P=np.hstack([camera.matrix, np.zeros((3, 1))]).ravel(), binning_x=0,
                binning_y=0, roi=roi,
            )  # fmt: skip
            image = T[names[2]](
                header=header(t, "cam"), height=120, width=160, encoding="32FC1",
                is_bigendian=0, step=160 * 4, data=np.frombuffer(depth.tobytes(), np.uint8),
            )  # fmt: skip
            for c, msg, name in zip(
                connections, (stamped(t, pose), info, image), names, strict=True
            ):
                writer.write(c, round(t * 1e9), ros1.serialize_ros1(msg, name))
    out = tmp_path / "out"
    args = ["replay", str(bag), "--fast", "--pose-topic", "/cam/pose", "--out", str(out)]
    assert main(args) == 0
    arrays = np.load(out / "map.npz")
    heights = arrays["height"][arrays["known"]]
    assert heights.size > 100 and np.abs(heights).max() < 0.01
    assert json.loads((out / "metrics.json").read_text())["frames"] == 3


def test_replay_errors_name_the_problem(tmp_path, recorded_walk):
    """A missing file, a missing topic, and a file that is not a recording."""
    with pytest.raises(DatasetError, match="missing recording"):
        Replayer(ReplayRequest(tmp_path / "none.mcap"))
    path, _, _ = recorded_walk
    with pytest.raises(DatasetError, match="no depth image topic '/nope'"):
        Replayer(ReplayRequest(path, depth_topic="/nope"))
    junk = tmp_path / "junk.mcap"
    junk.write_bytes(b"not an mcap file at all")
    with pytest.raises(DatasetError, match="not a readable MCAP"):
        Replayer(ReplayRequest(junk))
    truncated = tmp_path / "cut.mcap"
    truncated.write_bytes(path.read_bytes()[:200_000])
    with pytest.raises(DatasetError):
        Replayer(ReplayRequest(truncated, fast=True)).run()


def test_walk_record_option_writes_a_replayable_file(tmp_path):
    """`footfall walk --record` writes an MCAP file `footfall replay` maps."""
    rec = tmp_path / "w.mcap"
    assert (
        main(
            [
                "walk",
                "--terrain",
                "course",
                "--seconds",
                "1.5",
                "--record",
                str(rec),
                "--out",
                str(tmp_path / "w"),
            ]
        )
        == 0
    )
    assert rec.stat().st_size > 0
    assert main(["replay", str(rec), "--fast", "--out", str(tmp_path / "r")]) == 0
    assert json.loads((tmp_path / "r" / "metrics.json").read_text())["frames"] > 5


@pytest.mark.parametrize("source", ["sim", "tum"])
def test_map_record_replays_to_the_map_it_wrote(tmp_path, source):
    """`footfall map --record` (simulated terrain, or a recorded sequence) and `footfall
    replay` of that file write the same map.npz."""
    out, rec = tmp_path / "m", tmp_path / "m.mcap"
    if source == "sim":
        args = ["map", "--terrain", "stairs", "--seconds", "2", "--image-size", "160", "120"]
    else:
        tum = tmp_path / "tum"
        assert (
            main(["convert", "redwood", str(shared_data("rgbd/redwood_livingroom")), str(tum)]) == 0
        )
        args = ["map", "--tum", str(tum), "--up", "0", "1", "0"]
    assert main([*args, "--record", str(rec), "--out", str(out)]) == 0
    assert main(["replay", str(rec), "--fast", "--out", str(tmp_path / "r")]) == 0
    live, replayed = np.load(out / "map.npz"), np.load(tmp_path / "r" / "map.npz")
    for layer in ("height", "variance", "spread", "score", "valid", "known", "origin_xy_m"):
        np.testing.assert_array_equal(replayed[layer], live[layer], err_msg=layer)


def test_rerun_recording_holds_the_run(tmp_path, recorded_walk):
    """A walk logged with --rerun loads back with rerun's own reader and holds the depth
    image, the cloud, the map surface and score, footholds, body and feet, swing paths and
    the body series; the biped's obstacles, path, footsteps and COM log too."""
    pytest.importorskip("rerun")
    from rerun.chunk import RrdReader

    from footfall.messages.biped import BipedPlan, Obstacles
    from footfall.recording.rerun_log import RerunLogger

    rrd = tmp_path / "walk.rrd"
    args = ["walk", "--terrain", "stairs", "--seconds", "2.5", "--rerun", str(rrd)]
    assert main([*args, "--out", str(tmp_path / "w")]) == 0
    entities = set(RrdReader(rrd).store().schema().entity_paths())
    for entity in (
        "/world/camera/depth",
        "/world/points",
        "/world/map/surface",
        "/map/score",
        "/world/footholds/nominal",
        "/world/footholds/chosen",
        "/world/body",
        "/world/feet/rf",
        "/world/swing",
        "/plots/body_height_m",
        "/plots/tilt_deg",
    ):
        assert entity in entities, entity
    biped = tmp_path / "biped.rrd"
    logger = RerunLogger(biped)
    logger.tap("obstacles", Obstacles(0.0, np.array([1.0]), np.array([0.5]), np.array([0.3])))
    plan = BipedPlan(
        0.0,
        np.array([[0.0, 0.0], [2.0, 0.0]]),
        np.array([[0.1, -0.1, 0.0], [0.3, 0.1, 0.0]]),
        np.array([False, True]),
        np.array([[0.0, 0.0], [0.2, 0.0]]),
        2.0,
        0,
    )
    logger.tap("plan", plan)
    logger.close()
    entities = set(RrdReader(biped).store().schema().entity_paths())
    for entity in ("obstacles", "path", "footsteps", "com"):
        assert f"/world/biped/{entity}" in entities, entity


def test_replay_logs_to_rerun(tmp_path, recorded_walk):
    """`footfall replay --rerun` logs the replayed depth, cloud and final map."""
    pytest.importorskip("rerun")
    from rerun.chunk import RrdReader

    path, _, _ = recorded_walk
    rrd = tmp_path / "replay.rrd"
    assert (
        main(["replay", str(path), "--fast", "--rerun", str(rrd), "--out", str(tmp_path / "o")])
        == 0
    )
    entities = set(RrdReader(rrd).store().schema().entity_paths())
    assert {"/world/camera/depth", "/world/points", "/world/map/surface", "/map/score"} <= entities


def test_compressed_depth_and_bad_encodings(tmp_path):
    """image_transport's compressedDepth PNG decodes to millimetres; a colour encoding on
    the depth topic is refused by name."""
    import io

    from PIL import Image

    from footfall.recording.ros_decode import depth_array

    store = typestore()
    mm = (np.arange(48 * 64).reshape(48, 64) % 4000 + 500).astype(np.uint16)
    png = io.BytesIO()
    Image.fromarray(mm).save(png, format="PNG")
    header = store.types["std_msgs/msg/Header"](
        stamp=store.types["builtin_interfaces/msg/Time"](sec=0, nanosec=0), frame_id="cam"
    )
    compressed = store.types["sensor_msgs/msg/CompressedImage"](
        header=header,
        format="16UC1; compressedDepth png",
        data=np.frombuffer(bytes(12) + png.getvalue(), np.uint8),
    )
    depth, scale = depth_array(compressed)
    np.testing.assert_array_equal(depth, mm)
    assert scale == 0.001
    from footfall.recording import ros_types as rt

    colour = rt.image(0.0, "cam", np.zeros((4, 4, 3), np.uint8), "rgb8")
    with pytest.raises(DatasetError, match="'rgb8' is not depth"):
        depth_array(colour)


def test_a_bag_without_poses_replays_from_a_fixed_camera(tmp_path):
    """A ROS 2 bag of depth alone (the TUM frame as 16UC1 mm, with CameraInfo): with the
    camera's height and pitch given, the replay scores the real floor valid, as `footfall map`
    does with the same pose."""
    from PIL import Image
    from rosbags.rosbag2 import Writer

    from footfall.messages import DepthFrame
    from footfall.recording import ros_types as rt
    from footfall.sensing.camera import PinholeCamera
    from footfall.sensing.pose import Pose

    units = np.array(Image.open(shared_data("rgbd/tum_frame/TUM_depth.png"))).astype(np.uint32)
    mm = (units // 5).astype(np.uint16)
    store = typestore()
    frame = DepthFrame(
        0.0, mm, PinholeCamera(525, 525, 319.5, 239.5, 640, 480), Pose.identity(), 0.001
    )
    bag = tmp_path / "depth_only"
    with Writer(bag, version=9) as writer:
        info_c = writer.add_connection(
            "/cam/depth/camera_info", "sensor_msgs/msg/CameraInfo", typestore=store
        )
        image_c = writer.add_connection(
            "/cam/depth/image_raw", "sensor_msgs/msg/Image", typestore=store
        )
        writer.write(
            info_c, 1, store.serialize_cdr(rt.camera_info(frame), "sensor_msgs/msg/CameraInfo")
        )
        writer.write(
            image_c, 1, store.serialize_cdr(rt.depth_image(frame), "sensor_msgs/msg/Image")
        )
    with pytest.raises(DatasetError, match="tf-frames"):
        Replayer(ReplayRequest(bag))
    out = tmp_path / "out"
    args = ["replay", str(bag), "--fast", "--camera-height", "1.8", "--camera-pitch-deg", "29.2"]
    assert main([*args, "--out", str(out)]) == 0
    metrics = json.loads((out / "metrics.json").read_text())
    assert metrics["pose_source"] == "fixed camera" and metrics["frames"] == 1
    assert metrics["floor_valid_fraction"] >= 0.9


def test_a_bag_tf_is_looked_up_at_each_images_time(tmp_path):
    """A ROS 2 bag whose TF (odom -> base at 100 Hz while moving, base -> cam static) is
    written after the images it belongs to: each image takes the transform of its own
    stamp, so the replayed camera path is where the camera was."""
    from rosbags.rosbag2 import Writer

    from footfall.messages import DepthFrame
    from footfall.pointcloud.ground import CameraOverFloor
    from footfall.recording import ros_types as rt
    from footfall.sensing.camera import PinholeCamera
    from footfall.sensing.pose import Pose

    store = typestore()
    camera = PinholeCamera(120, 120, 79.5, 59.5, 160, 120)
    floor = CameraOverFloor.from_angles(0.6, np.radians(40))
    depth = _flat_floor_depth(camera, floor)
    identity = Pose.identity().rotation
    camera_in_base = Pose(np.array([0.0, 0.0, 0.6]), floor.rotation_camera_to_map)
    kinds = ("tf2_msgs/msg/TFMessage", "sensor_msgs/msg/CameraInfo", "sensor_msgs/msg/Image")
    bag = tmp_path / "moving"
    image_times = [0.103 + 0.1 * k for k in range(5)]
    with Writer(bag, version=9) as writer:
        tf_c, static_c, info_c, image_c = (
            writer.add_connection(topic, kind, typestore=store)
            for topic, kind in zip(
                ("/tf", "/tf_static", "/cam/depth/camera_info", "/cam/depth/image"),
                (kinds[0], kinds[0], kinds[1], kinds[2]),
                strict=True,
            )
        )
        static = rt.tf_message([rt._transform(0.0, "base", "cam", camera_in_base)])
        writer.write(static_c, 0, store.serialize_cdr(static, kinds[0]))
        frame = DepthFrame(0.0, depth, camera, Pose.identity())
        for t in image_times:  # the images first, their TF later (as a slow TF publisher does)
            ns = round(t * 1e9)
            writer.write(info_c, ns, store.serialize_cdr(rt.camera_info(frame), kinds[1]))
            writer.write(
                image_c, ns, store.serialize_cdr(rt.image(t, "cam", depth, "32FC1"), kinds[2])
            )
        for k in range(60):
            t = 0.01 * k
            base = Pose(np.array([0.5 * t, 0.0, 0.0]), identity)
            tf = rt.tf_message([rt._transform(t, "odom", "base", base)])
            writer.write(tf_c, round(t * 1e9) + 300_000_000, store.serialize_cdr(tf, kinds[0]))
    replayer = Replayer(ReplayRequest(bag, fast=True, tf_frames=("odom", "cam")))
    mapping = replayer.run()
    path = np.array(mapping.camera_path_xy)
    assert len(path) == 5
    np.testing.assert_allclose(path[:, 0], [0.5 * (0.1 + 0.1 * k) for k in range(5)], atol=1e-9)
