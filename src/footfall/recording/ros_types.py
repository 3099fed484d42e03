"""footfall's messages as ROS 2 messages, CDR-encoded, for MCAP files and ROS bags.

Standard types where they exist, so Foxglove, rerun and ROS 2 tools open a recording:

=================  =====================================  ===============================
footfall topic     ROS 2 channel                          type
=================  =====================================  ===============================
depth              /camera/depth/image_raw                sensor_msgs/Image (32FC1, 16UC1)
                   /camera/depth/camera_info              sensor_msgs/CameraInfo
color, depth       /camera/color/image_raw                sensor_msgs/Image (rgb8)
pose               /camera/pose                           geometry_msgs/PoseStamped
                   /tf (world -> base_link, camera)       tf2_msgs/TFMessage
pose/raw           /footfall/pose/raw                     footfall_msgs/Encoded
pose/odometry      /odometry                              nav_msgs/Odometry (body, covariance)
map                /map/grid                              grid_map_msgs/GridMap
                   /map/occupancy                         nav_msgs/OccupancyGrid
effector_targets   /effector_targets, /tf (foot_0..5)     footfall_msgs/EffectorTargets
joint_targets      /joint_targets                         sensor_msgs/JointState
state              /joint_states, /imu                    sensor_msgs/JointState, Imu
imu                /camera/imu                            sensor_msgs/Imu (no orientation)
status             /gait_status                           footfall_msgs/GaitStatus
touchdown          /touchdowns                            footfall_msgs/Touchdown
ground_prior       /ground_prior                          footfall_msgs/GroundPrior
command            /command                               footfall_msgs/WalkCommand
log                /rosout                                rcl_interfaces/Log
plan               /biped/path                            nav_msgs/Path
=================  =====================================  ===============================

Every footfall message also without a faithful ROS type (the biped's obstacles, plans and
services, the operating mode) goes on ``/footfall/<topic>`` as ``footfall_msgs/Encoded``,
its footfall byte encoding. The footfall types' ``.msg`` definitions, and grid_map's, are
embedded in the file's schemas like the standard ones. It is one module: every message's
ROS 2 form stands beside this table, one converter per row.
"""

from __future__ import annotations

import math
from functools import cache
from typing import Any

import numpy as np
import numpy.typing as npt
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from footfall.messages import (
    DepthFrame,
    EffectorTargets,
    GaitStatus,
    GroundPrior,
    JointTargets,
    LogLine,
    MapUpdate,
    OdometryEstimate,
    PoseEstimate,
    RobotState,
    Touchdown,
    WalkCommand,
)
from footfall.messages.codec import Message
from footfall.sensing.pose import Pose

WORLD_FRAME = "world"
BODY_FRAME = "base_link"
CAMERA_FRAME = "camera_optical"
LEG_NAMES = ("rf", "rm", "rb", "lf", "lm", "lb")
JOINT_NAMES = tuple(f"{leg}_{joint}" for leg in LEG_NAMES for joint in ("coxa", "femur", "tibia"))

FOOTFALL_MSGS = {
    "footfall_msgs/msg/EffectorTargets": """
std_msgs/Header header
float64[18] feet_in_body
float64[18] foot_velocities_in_body
bool[6] swinging
float64[18] feet_in_world
""",
    "footfall_msgs/msg/GaitStatus": """
std_msgs/Header header
string mode
string state
string frozen_reason
string frozen_leg
float64 body_x
float64 body_y
float64 body_yaw
float64 body_z
int32 steps_taken
int32 footholds_adjusted
float64 command_age
int32 messages_dropped
""",
    "footfall_msgs/msg/Touchdown": """
std_msgs/Header header
int32 leg
geometry_msgs/Point nominal
geometry_msgs/Point chosen
""",
    "footfall_msgs/msg/GroundPrior": """
std_msgs/Header header
geometry_msgs/Point body_position
float64 ground_z
float64 radius
""",
    "footfall_msgs/msg/WalkCommand": """
std_msgs/Header header
float64 direction_x
float64 direction_y
float64 speed
float64 body_height
float64 yaw_rate
""",
    "footfall_msgs/msg/Encoded": """
string type
uint16 version
uint8[] data
""",
    "grid_map_msgs/msg/GridMapInfo": """
float64 resolution
float64 length_x
float64 length_y
geometry_msgs/Pose pose
""",
    "grid_map_msgs/msg/GridMap": """
std_msgs/Header header
grid_map_msgs/GridMapInfo info
string[] layers
string[] basic_layers
std_msgs/Float32MultiArray[] data
uint16 outer_start_index
uint16 inner_start_index
""",
}


@cache
def typestore():
    """ROS 2 Humble's standard types plus footfall's and grid_map's."""
    store = get_typestore(Stores.ROS2_HUMBLE)
    types: dict[str, Any] = {}
    for name, text in FOOTFALL_MSGS.items():
        types.update(get_types_from_msg(text.strip() + "\n", name))
    store.register(types)
    return store


def msgdef(typename: str) -> str:
    """The ``ros2msg`` schema text of a type, with its dependencies."""
    text, _ = typestore().generate_msgdef(typename, ros_version=2)
    return text


def _t(name: str) -> Any:
    return typestore().types[name]


def ros_time(stamp: float) -> Any:
    """A ``builtin_interfaces/Time`` of a time in seconds."""
    ns = round(stamp * 1e9)
    return _t("builtin_interfaces/msg/Time")(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)


def seconds(time: Any) -> float:
    """Seconds of a ``builtin_interfaces/Time``."""
    return time.sec + time.nanosec * 1e-9


def header(stamp: float, frame: str) -> Any:
    """A ``std_msgs/Header``."""
    return _t("std_msgs/msg/Header")(stamp=ros_time(stamp), frame_id=frame)


def _point(p: npt.ArrayLike) -> Any:
    x, y, z = (float(v) for v in np.asarray(p, dtype=np.float64))
    return _t("geometry_msgs/msg/Point")(x=x, y=y, z=z)


def _quaternion(pose: Pose) -> Any:
    x, y, z, w = (float(v) for v in pose.rotation.as_quat())
    return _t("geometry_msgs/msg/Quaternion")(x=x, y=y, z=z, w=w)


def _pose(pose: Pose) -> Any:
    return _t("geometry_msgs/msg/Pose")(
        position=_point(pose.position), orientation=_quaternion(pose)
    )


def _transform(stamp: float, parent: str, child: str, pose: Pose) -> Any:
    x, y, z = (float(v) for v in pose.position)
    translation = _t("geometry_msgs/msg/Vector3")(x=x, y=y, z=z)
    transform = _t("geometry_msgs/msg/Transform")(
        translation=translation, rotation=_quaternion(pose)
    )
    return _t("geometry_msgs/msg/TransformStamped")(
        header=header(stamp, parent), child_frame_id=child, transform=transform
    )


def tf_message(transforms: list[Any]) -> Any:
    """A ``tf2_msgs/TFMessage``."""
    return _t("tf2_msgs/msg/TFMessage")(transforms=transforms)


def image(stamp: float, frame: str, array: npt.NDArray, encoding: str) -> Any:
    """A ``sensor_msgs/Image`` of a little-endian array (rows, cols[, channels])."""
    data = np.ascontiguousarray(array)
    height, width = data.shape[:2]
    return _t("sensor_msgs/msg/Image")(
        header=header(stamp, frame),
        height=height,
        width=width,
        encoding=encoding,
        is_bigendian=0,
        step=data.strides[0],
        data=np.frombuffer(data.tobytes(), dtype=np.uint8),
    )


def depth_image(frame: DepthFrame) -> Any:
    """The depth of a frame: ``32FC1`` metres, or ``16UC1`` millimetres when it is."""
    d = np.asarray(frame.depth)
    units = frame.intrinsics.units_per_metre_for(d, frame.depth_scale)
    if d.dtype.kind == "u" and units and units % 1000 == 0:
        per_mm = int(units) // 1000  # TUM's 1/5000 m: 5 units a millimetre
        if per_mm == 1 or not np.any(d % per_mm):
            return image(frame.stamp, CAMERA_FRAME, (d // per_mm).astype("<u2"), "16UC1")
    if d.dtype.kind == "f":
        return image(frame.stamp, CAMERA_FRAME, d.astype("<f4"), "32FC1")
    metres = frame.intrinsics.to_metres(d, frame.depth_scale)
    return image(frame.stamp, CAMERA_FRAME, metres.astype("<f4"), "32FC1")


def camera_info(frame: DepthFrame) -> Any:
    """The ``sensor_msgs/CameraInfo`` of a frame's (undistorted) depth camera."""
    c = frame.intrinsics
    k = np.array([c.fx, 0.0, c.cx, 0.0, c.fy, c.cy, 0.0, 0.0, 1.0])
    p = np.array([c.fx, 0.0, c.cx, 0.0, 0.0, c.fy, c.cy, 0.0, 0.0, 0.0, 1.0, 0.0])
    roi = _t("sensor_msgs/msg/RegionOfInterest")(
        x_offset=0, y_offset=0, height=0, width=0, do_rectify=False
    )
    return _t("sensor_msgs/msg/CameraInfo")(
        header=header(frame.stamp, CAMERA_FRAME),
        height=c.height,
        width=c.width,
        distortion_model="plumb_bob",
        d=np.zeros(5),
        k=k,
        r=np.eye(3).ravel(),
        p=p,
        binning_x=0,
        binning_y=0,
        roi=roi,
    )


def _grid_map(update: MapUpdate) -> Any:
    """The height, score and validity layers as a ``grid_map_msgs/GridMap``.

    grid_map stores a layer column-major with its first index along -x from the map's
    centre; footfall's ``[i, j]`` runs along +x and +y from the corner, so both flip.
    """
    n, m = update.heights.shape
    res = update.resolution
    centre = Pose(
        np.array([update.origin[0] + 0.5 * n * res, update.origin[1] + 0.5 * m * res, 0.0]),
        Pose.identity().rotation,
    )
    info = _t("grid_map_msgs/msg/GridMapInfo")(
        resolution=res, length_x=n * res, length_y=m * res, pose=_pose(centre)
    )
    layers = {
        "elevation": update.heights,
        "score": update.score,
        "valid": np.where(update.known, update.valid.astype(np.float64), np.nan),
    }
    dim = _t("std_msgs/msg/MultiArrayDimension")
    data = []
    for values in layers.values():
        flipped = np.asarray(values, dtype=np.float64)[::-1, ::-1]
        layout = _t("std_msgs/msg/MultiArrayLayout")(
            dim=[
                dim(label="column_index", size=m, stride=n * m),
                dim(label="row_index", size=n, stride=n),
            ],
            data_offset=0,
        )
        column_major = flipped.astype(np.float32).ravel(order="F")
        data.append(_t("std_msgs/msg/Float32MultiArray")(layout=layout, data=column_major))
    return _t("grid_map_msgs/msg/GridMap")(
        header=header(update.stamp, WORLD_FRAME),
        info=info,
        layers=list(layers),
        basic_layers=["elevation"],
        data=data,
        outer_start_index=0,
        inner_start_index=0,
    )


def _occupancy(update: MapUpdate) -> Any:
    """Walkability as a ``nav_msgs/OccupancyGrid``: 0 valid, 100 invalid, -1 unknown."""
    n, m = update.heights.shape
    cells = np.where(update.valid, 0, 100).astype(np.int8)
    cells[~update.known] = -1
    origin = Pose(np.array([update.origin[0], update.origin[1], 0.0]), Pose.identity().rotation)
    info = _t("nav_msgs/msg/MapMetaData")(
        map_load_time=ros_time(update.stamp),
        resolution=float(update.resolution),
        width=n,
        height=m,
        origin=_pose(origin),
    )
    # Row-major with x fastest: footfall's [i, j] (i along x) transposed.
    return _t("nav_msgs/msg/OccupancyGrid")(
        header=header(update.stamp, WORLD_FRAME), info=info, data=cells.T.ravel()
    )


def encoded(message: Message) -> Any:
    """A footfall message as ``footfall_msgs/Encoded`` (its own byte encoding)."""
    return _t("footfall_msgs/msg/Encoded")(
        type=type(message).__name__,
        version=type(message).VERSION,
        data=np.frombuffer(message.encode(), dtype=np.uint8),
    )


def to_ros(topic: str, message: Message) -> list[tuple[str, str, Any]]:
    """The ROS 2 channel messages of one footfall message: ``(channel, type, message)``."""
    out: list[tuple[str, str, Any]] = []
    if isinstance(message, DepthFrame):
        # The intrinsics first: a reader has them when the image arrives.
        info = camera_info(message)
        out.append(("/camera/depth/camera_info", "sensor_msgs/msg/CameraInfo", info))
        out.append(("/camera/depth/image_raw", "sensor_msgs/msg/Image", depth_image(message)))
        if message.color is not None:
            rgb = image(message.stamp, CAMERA_FRAME, message.color, "rgb8")
            out.append(("/camera/color/image_raw", "sensor_msgs/msg/Image", rgb))
    elif type(message).__name__ == "ImuReading":
        out.append(("/camera/imu", "sensor_msgs/msg/Imu", _imu_reading(message)))
    elif type(message).__name__ == "ColorImage":
        rgb = image(message.stamp, CAMERA_FRAME, message.image, "rgb8")
        out.append(("/camera/color/image_raw", "sensor_msgs/msg/Image", rgb))
    elif isinstance(message, PoseEstimate) and topic != PoseEstimate.TOPIC:
        # A pose source's raw estimate, before the pose guard: kept, not the standard pose.
        out.append((f"/footfall/{topic}", "footfall_msgs/msg/Encoded", encoded(message)))
    elif isinstance(message, PoseEstimate):
        stamped = _t("geometry_msgs/msg/PoseStamped")(
            header=header(message.stamp, WORLD_FRAME), pose=_pose(message.camera_in_world)
        )
        out.append(("/camera/pose", "geometry_msgs/msg/PoseStamped", stamped))
        tf = tf_message(
            [
                _transform(message.stamp, WORLD_FRAME, BODY_FRAME, message.body_in_world),
                _transform(message.stamp, WORLD_FRAME, CAMERA_FRAME, message.camera_in_world),
            ]
        )
        out.append(("/tf", "tf2_msgs/msg/TFMessage", tf))
    elif isinstance(message, OdometryEstimate):
        out.append(("/odometry", "nav_msgs/msg/Odometry", _odometry(message)))
    elif isinstance(message, MapUpdate):
        out.append(("/map/grid", "grid_map_msgs/msg/GridMap", _grid_map(message)))
        out.append(("/map/occupancy", "nav_msgs/msg/OccupancyGrid", _occupancy(message)))
    elif isinstance(message, EffectorTargets):
        targets = _t("footfall_msgs/msg/EffectorTargets")(
            header=header(message.stamp, BODY_FRAME),
            feet_in_body=message.feet_in_body.ravel(),
            foot_velocities_in_body=message.foot_velocities_in_body.ravel(),
            swinging=message.swinging.astype(bool),
            feet_in_world=message.feet_in_world.ravel(),
        )
        out.append(("/effector_targets", "footfall_msgs/msg/EffectorTargets", targets))
        identity = Pose.identity().rotation
        feet = [
            _transform(message.stamp, WORLD_FRAME, f"foot_{LEG_NAMES[k]}", Pose(p, identity))
            for k, p in enumerate(message.feet_in_world)
        ]
        out.append(("/tf", "tf2_msgs/msg/TFMessage", tf_message(feet)))
    elif isinstance(message, JointTargets):
        joints = _t("sensor_msgs/msg/JointState")(
            header=header(message.stamp, BODY_FRAME),
            name=list(JOINT_NAMES),
            position=np.asarray(message.positions, dtype=np.float64).ravel(),
            velocity=np.asarray(message.velocities, dtype=np.float64).ravel(),
            effort=np.zeros(0),
        )
        out.append(("/joint_targets", "sensor_msgs/msg/JointState", joints))
    elif isinstance(message, RobotState):
        out.extend(_robot_state(message))
    elif isinstance(message, GaitStatus):
        out.append(("/gait_status", "footfall_msgs/msg/GaitStatus", _gait_status(message)))
    elif isinstance(message, Touchdown):
        touchdown = _t("footfall_msgs/msg/Touchdown")(
            header=header(message.stamp, WORLD_FRAME),
            leg=int(message.leg),
            nominal=_point(message.nominal_in_world),
            chosen=_point(message.chosen_in_world),
        )
        out.append(("/touchdowns", "footfall_msgs/msg/Touchdown", touchdown))
    elif isinstance(message, GroundPrior):
        prior = _t("footfall_msgs/msg/GroundPrior")(
            header=header(message.stamp, WORLD_FRAME),
            body_position=_point(message.body_position_in_world),
            ground_z=float(message.ground_z),
            radius=float(message.radius),
        )
        out.append(("/ground_prior", "footfall_msgs/msg/GroundPrior", prior))
    elif isinstance(message, WalkCommand):
        command = _t("footfall_msgs/msg/WalkCommand")(
            header=header(message.stamp, BODY_FRAME),
            direction_x=float(message.direction[0]),
            direction_y=float(message.direction[1]),
            speed=float(message.speed),
            body_height=float(message.body_height),
            yaw_rate=float(message.yaw_rate),
        )
        out.append(("/command", "footfall_msgs/msg/WalkCommand", command))
    elif isinstance(message, LogLine):
        level = {"info": 20, "warning": 30, "error": 40}.get(message.level, 20)
        log = _t("rcl_interfaces/msg/Log")(
            stamp=ros_time(message.stamp),
            level=level,
            name=message.node,
            msg=message.text,
            file="",
            function="",
            line=0,
        )
        out.append(("/rosout", "rcl_interfaces/msg/Log", log))
    elif type(message).__name__ == "BipedPlan":
        poses = [
            _t("geometry_msgs/msg/PoseStamped")(
                header=header(message.stamp, WORLD_FRAME),
                pose=_pose(Pose(np.array([x, y, 0.0]), Pose.identity().rotation)),
            )
            for x, y in np.asarray(message.waypoints, dtype=np.float64)
        ]
        path = _t("nav_msgs/msg/Path")(header=header(message.stamp, WORLD_FRAME), poses=poses)
        out.append(("/biped/path", "nav_msgs/msg/Path", path))
        out.append((f"/footfall/{topic}", "footfall_msgs/msg/Encoded", encoded(message)))
    else:
        out.append((f"/footfall/{topic}", "footfall_msgs/msg/Encoded", encoded(message)))
    return out


def _odometry(estimate: OdometryEstimate) -> Any:
    """A ``nav_msgs/Odometry``: the body in the world with its covariance.

    The velocity goes in the body frame, ROS's convention for the twist.
    """
    body = estimate.body_in_world
    vx, vy, vz = (float(v) for v in body.rotation.inv().apply(estimate.velocity_in_world))
    covariance = np.zeros((6, 6))
    covariance[np.diag_indices(6)] = estimate.covariance
    vector = _t("geometry_msgs/msg/Vector3")
    twist = _t("geometry_msgs/msg/Twist")(
        linear=vector(x=vx, y=vy, z=vz), angular=vector(x=0.0, y=0.0, z=0.0)
    )
    return _t("nav_msgs/msg/Odometry")(
        header=header(estimate.stamp, WORLD_FRAME),
        child_frame_id=BODY_FRAME,
        pose=_t("geometry_msgs/msg/PoseWithCovariance")(
            pose=_pose(body), covariance=covariance.ravel()
        ),
        # Velocities are not estimated with a covariance of their own: -1 says unknown.
        twist=_t("geometry_msgs/msg/TwistWithCovariance")(
            twist=twist, covariance=np.full(36, -1.0)
        ),
    )


def _robot_state(state: RobotState) -> list[tuple[str, str, Any]]:
    joints = _t("sensor_msgs/msg/JointState")(
        header=header(state.time, BODY_FRAME),
        name=list(JOINT_NAMES),
        position=np.asarray(state.joint_positions, dtype=np.float64).ravel(),
        velocity=np.asarray(state.joint_velocities, dtype=np.float64).ravel(),
        effort=np.zeros(0),
    )
    x, y, z, w = (float(v) for v in state.orientation_body_in_world.as_quat())
    gx, gy, gz = (float(v) for v in state.angular_velocity_body_in_body)
    vector = _t("geometry_msgs/msg/Vector3")
    unknown = np.full(9, 0.0)
    unknown[0] = -1.0  # no linear acceleration (ROS: covariance[0] = -1)
    imu = _t("sensor_msgs/msg/Imu")(
        header=header(state.time, BODY_FRAME),
        orientation=_t("geometry_msgs/msg/Quaternion")(x=x, y=y, z=z, w=w),
        orientation_covariance=np.zeros(9),
        angular_velocity=vector(x=gx, y=gy, z=gz),
        angular_velocity_covariance=np.zeros(9),
        linear_acceleration=vector(x=0.0, y=0.0, z=0.0),
        linear_acceleration_covariance=unknown,
    )
    return [
        ("/joint_states", "sensor_msgs/msg/JointState", joints),
        ("/imu", "sensor_msgs/msg/Imu", imu),
    ]


def _imu_reading(reading: Any) -> Any:
    """A camera IMU's gyro and accelerometer in the body frame; it gives no orientation."""
    vector = _t("geometry_msgs/msg/Vector3")
    gx, gy, gz = (float(v) for v in reading.angular_velocity_body_in_body)
    ax, ay, az = (float(v) for v in reading.specific_force_body_in_body)
    no_orientation = np.zeros(9)
    no_orientation[0] = -1.0  # ROS: covariance[0] = -1 where a field is not measured
    return _t("sensor_msgs/msg/Imu")(
        header=header(reading.stamp, BODY_FRAME),
        orientation=_t("geometry_msgs/msg/Quaternion")(x=0.0, y=0.0, z=0.0, w=1.0),
        orientation_covariance=no_orientation,
        angular_velocity=vector(x=gx, y=gy, z=gz),
        angular_velocity_covariance=np.zeros(9),
        linear_acceleration=vector(x=ax, y=ay, z=az),
        linear_acceleration_covariance=np.zeros(9),
    )


def _gait_status(status: GaitStatus) -> Any:
    return _t("footfall_msgs/msg/GaitStatus")(
        header=header(status.stamp, WORLD_FRAME),
        mode=str(status.mode.value),
        state=str(status.state.value),
        frozen_reason=status.frozen_reason,
        frozen_leg=status.frozen_leg,
        body_x=float(status.body_pose.x),
        body_y=float(status.body_pose.y),
        body_yaw=float(status.body_pose.yaw),
        body_z=float(status.body_z),
        steps_taken=int(status.steps_taken),
        footholds_adjusted=int(status.footholds_adjusted),
        command_age=float(status.command_age) if math.isfinite(status.command_age) else -1.0,
        messages_dropped=int(status.messages_dropped),
    )
