"""The messages footfall's nodes exchange: small frozen values with frames and units in names.

Each type names the topic it travels on by default (``TOPIC``; see ``docs/runtime.md``) and
encodes to bytes and back (:mod:`footfall.messages.codec`). They are one module on purpose:
together they are the interface between the nodes, read and versioned as one. Times are
seconds on the sender's clock; world quantities are in the map (odometry) frame, z up;
poses say which frame they place (``camera_in_world``: maps camera-frame points into the
world).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import StrEnum
from functools import cached_property

import numpy as np
import numpy.typing as npt
from scipy.spatial.transform import Rotation

from footfall.errors import ConfigError, MessageError
from footfall.messages.codec import Message
from footfall.robot.planar import PlanarPose
from footfall.sensing.camera import PinholeCamera
from footfall.sensing.pose import Pose


class Mode(StrEnum):
    """Operating modes of the robot (thesis H7.2.1)."""

    TORQUE_OFF = "torque_off"
    WALKING = "walking"


class GaitState(StrEnum):
    """States of the gait state machine (thesis Table 5.1), plus a safe stop."""

    REST = "rest"
    STEPPING = "stepping"
    FROZEN = "frozen"


def _shaped(name: str, value: npt.ArrayLike, shape: tuple[int, ...], dtype: type) -> np.ndarray:
    a = np.asarray(value, dtype=dtype)
    if a.shape != shape:
        raise MessageError(f"{name} must have shape {shape}, got {a.shape}")
    return a


@dataclass(frozen=True)
class WalkCommand(Message):
    """An operator's command (thesis Appendix B, ``HexapodCommands``), with a yaw rate added.

    Attributes:
        direction: Walk direction in the body frame, ``(x, y)``; normalised on use.
        speed: Body speed along the direction [m/s].
        body_height: Body height above the ground [m].
        yaw_rate: Turning rate about the body z axis [rad/s].
        stamp: When it was sent [s].
    """

    TOPIC = "command"

    direction: tuple[float, float] = (1.0, 0.0)
    speed: float = 0.0
    body_height: float = 0.09
    yaw_rate: float = 0.0
    stamp: float = 0.0

    def __post_init__(self) -> None:
        if len(self.direction) != 2:
            raise ConfigError(f"walk direction must be (x, y), got {self.direction!r}")
        values = (*self.direction, self.speed, self.body_height, self.yaw_rate)
        if not all(math.isfinite(v) for v in values):
            raise ConfigError(f"walk command holds a non-finite value: {self}")
        if self.speed < 0:
            raise ConfigError(
                f"walk speed must be >= 0 (use the direction to reverse), got {self.speed}"
            )
        if self.body_height <= 0:
            raise ConfigError(f"body height must be positive, got {self.body_height}")
        if self.speed > 0 and math.hypot(*self.direction) < 1e-9:
            raise ConfigError("a walk direction of zero length cannot carry a speed")

    @property
    def velocity_in_body(self) -> tuple[float, float]:
        """Commanded body velocity ``(vx, vy)`` [m/s]."""
        norm = math.hypot(*self.direction)
        if self.speed == 0.0 or norm == 0.0:
            return (0.0, 0.0)
        return (self.speed * self.direction[0] / norm, self.speed * self.direction[1] / norm)


@dataclass(frozen=True)
class ModeCommand(Message):
    """The operating mode the operator asks for.

    Attributes:
        mode: Torque-off (servos limp) or walking.
        stamp: When it was sent [s].
    """

    TOPIC = "mode"

    mode: Mode = Mode.TORQUE_OFF
    stamp: float = 0.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "mode", Mode(self.mode))


@dataclass(frozen=True)
class DepthFrame(Message):
    """One depth image with what it takes to turn it into points.

    Attributes:
        stamp: Capture time [s].
        depth: Shape (height, width): float metres, or unsigned integer units.
        intrinsics: The depth camera; the optical frame is x right, y down, z forward.
        camera_in_body: The optical frame's pose in the body frame (the extrinsics).
        depth_scale: Metres per unit of integer depth; None for float metres.
        sequence: Frame number.
        color: Colour image, shape (height, width, 3) ``uint8``, when there is one.
    """

    TOPIC = "depth"
    VERSION = 2  # the intrinsics carry the sensor's noise model

    stamp: float
    depth: npt.NDArray
    intrinsics: PinholeCamera
    camera_in_body: Pose
    depth_scale: float | None = None
    sequence: int = 0
    color: npt.NDArray[np.uint8] | None = None

    def __post_init__(self) -> None:
        if np.ndim(self.depth) != 2:
            raise MessageError(f"depth must be a 2-D image, got shape {np.shape(self.depth)}")


@dataclass(frozen=True)
class ColorImage(Message):
    """A colour image from the body camera, for the operator.

    Attributes:
        stamp: Capture time [s].
        image: Shape (height, width, 3), ``uint8`` RGB.
        sequence: Frame number (that of the depth frame taken with it).
    """

    TOPIC = "color"

    stamp: float
    image: npt.NDArray[np.uint8]
    sequence: int = 0

    def __post_init__(self) -> None:
        shape = np.shape(self.image)
        if len(shape) != 3 or shape[2] != 3:
            raise MessageError(f"a colour image must be (height, width, 3), got {shape}")


@dataclass(frozen=True)
class PoseEstimate(Message):
    """Where the robot is: the pose source's estimate (SLAM, odometry, or the truth).

    A pose source publishes its estimates on ``RAW_TOPIC``; the pose guard checks them
    against odometry and the IMU and publishes what it trusts on ``TOPIC``. What a source
    guarantees (see :mod:`footfall.nodes.sources`): ``stamp`` is the time of the depth image
    the estimate is for (so the map places that image where the camera was); the frames are
    the depth camera's optical frame (x right, y down, z forward) and the body frame, both
    in a z-up world; one estimate per depth image, or at least the camera's rate; and a
    source that has lost track publishes nothing, never a guess (the robot stands once the
    newest estimate is 0.5 s old).

    Attributes:
        stamp: Time the estimate is for [s].
        camera_in_world: The depth camera's optical frame in the world (what visual SLAM
            estimates).
        body_in_world: The body frame in the world.
        aligned_in_world: How far (x, y) the source moved the body since its previous
            estimate to align it with the map it built (footfall's estimator registering
            its images) [m]: a correction towards the map, which the controller leaves out
            of how far the map may have slid under the feet.
    """

    TOPIC = "pose"
    RAW_TOPIC = "pose/raw"
    VERSION = 2  # the alignment with the map

    stamp: float
    camera_in_world: Pose
    body_in_world: Pose
    aligned_in_world: tuple[float, float] = (0.0, 0.0)

    @property
    def planar_body(self) -> PlanarPose:
        """The body's pose in the ground plane."""
        p = self.body_in_world
        x_axis = p.rotation.apply([1.0, 0.0, 0.0])
        return PlanarPose(
            float(p.position[0]), float(p.position[1]), math.atan2(x_axis[1], x_axis[0])
        )


@dataclass(frozen=True)
class OdometryEstimate(Message):
    """The robot's own estimate of its body at every control tick, with its uncertainty.

    footfall's estimator (``--pose estimator``) publishes one a tick, as a legged robot's
    state estimator does, beside the :class:`PoseEstimate` it answers each depth image with.

    Attributes:
        stamp: Time [s], on the controller's clock.
        body_in_world: The body frame in the world.
        velocity_in_world: The body's velocity, shape (3,) [m/s].
        covariance: Diagonal covariance of x, y, z [m^2] and roll, pitch, yaw [rad^2],
            shape (6,).
        tracking: True when the estimate may be used; False while the estimator calibrates
            or once it is lost.
    """

    TOPIC = "pose/odometry"

    stamp: float
    body_in_world: Pose
    velocity_in_world: npt.NDArray[np.float64]
    covariance: npt.NDArray[np.float64]
    tracking: bool

    def __post_init__(self) -> None:
        for name, shape in (("velocity_in_world", (3,)), ("covariance", (6,))):
            object.__setattr__(self, name, _shaped(name, getattr(self, name), shape, np.float64))


@dataclass(frozen=True)
class ImuReading(Message):
    """One reading of an inertial unit, turned into the body frame.

    A robot whose backend has no IMU takes its attitude from one of these (a RealSense
    D435i's, through its camera-to-body extrinsics).

    Attributes:
        stamp: Measurement time on the robot's clock [s].
        angular_velocity_body_in_body: Gyro rates, shape (3,) [rad/s].
        specific_force_body_in_body: Accelerometer reading, shape (3,) [m/s^2]: at rest it
            points up, 9.81 m/s^2 long (the reaction to gravity).
    """

    TOPIC = "imu"

    stamp: float
    angular_velocity_body_in_body: npt.NDArray[np.float64]
    specific_force_body_in_body: npt.NDArray[np.float64]


@dataclass(frozen=True)
class GroundPrior(Message):
    """The ground around a standing robot, known from its feet before the camera sees it.

    Attributes:
        stamp: When [s].
        body_position_in_world: The body, shape (3,) [m]; the disc is centred under it.
        ground_z: Ground height under the feet [m].
        radius: Radius of the disc taken as ground [m].
    """

    TOPIC = "ground_prior"

    stamp: float
    body_position_in_world: npt.NDArray[np.float64]
    ground_z: float
    radius: float


@dataclass(frozen=True)
class MapUpdate(Message):
    """The height map and its scores (thesis §4, §6.2), as one stamped window.

    Arrays are N x N, index ``[i, j]`` along world ``x`` and ``y``; cell ``[0, 0]``'s corner
    is at ``origin``.

    Attributes:
        stamp: Time of the depth frame it includes last [s].
        sequence: Update number, counting from 1.
        heights: Cell heights [m]; NaN where unknown.
        known: Cells observed.
        spread: Largest in-frame height range of each cell [m], NaN where unknown; None
            when the map keeps none.
        slope: Height gradient, rise over run; NaN where unknown. None when the map came
            over a radio link, which carries only what the station draws.
        proximity: Edge proximity [m]; NaN where unknown. None as ``slope``.
        score: Walkability score (lower is better); NaN where unknown.
        valid: Cells a foot may use.
        origin: World ``(x, y)`` of the corner of cell ``[0, 0]`` [m].
        resolution: Cell side [m].
    """

    TOPIC = "map"
    VERSION = 2  # slope and proximity may be absent (a radio link's map)

    stamp: float
    sequence: int
    heights: npt.NDArray[np.float64]
    known: npt.NDArray[np.bool_]
    spread: npt.NDArray[np.float64] | None
    slope: npt.NDArray[np.float64] | None
    proximity: npt.NDArray[np.float64] | None
    score: npt.NDArray[np.float64]
    valid: npt.NDArray[np.bool_]
    origin: tuple[float, float]
    resolution: float

    def __post_init__(self) -> None:
        shape = np.shape(self.heights)
        if len(shape) != 2:
            raise MessageError(f"map heights must be 2-D, got shape {shape}")
        for name in ("known", "slope", "proximity", "score", "valid", "spread"):
            value = getattr(self, name)
            if value is not None and np.shape(value) != shape:
                raise MessageError(f"map {name} has shape {np.shape(value)}, heights {shape}")
        if not (math.isfinite(self.resolution) and self.resolution > 0):
            raise MessageError(f"map resolution must be positive, got {self.resolution}")


@dataclass(frozen=True)
class EffectorTargets(Message):
    """Where each foot should be now (thesis Table B.7, ``EffectorTargets``).

    Attributes:
        stamp: Controller time [s].
        feet_in_body: Foot-sphere centre targets in the body frame, shape (6, 3) [m], after
            attitude and height feedback.
        foot_velocities_in_body: Their rates in the body frame, shape (6, 3) [m/s].
        swinging: Which feet swing, shape (6,).
        feet_in_world: The same targets in the world (map) frame, shape (6, 3) [m].
    """

    TOPIC = "effector_targets"

    stamp: float
    feet_in_body: npt.NDArray[np.float64]
    foot_velocities_in_body: npt.NDArray[np.float64]
    swinging: npt.NDArray[np.bool_]
    feet_in_world: npt.NDArray[np.float64]

    def __post_init__(self) -> None:
        for name in ("feet_in_body", "foot_velocities_in_body", "feet_in_world"):
            object.__setattr__(self, name, _shaped(name, getattr(self, name), (6, 3), np.float64))
        object.__setattr__(self, "swinging", _shaped("swinging", self.swinging, (6,), bool))


@dataclass(frozen=True)
class JointTargets(Message):
    """What the servos are asked for at one tick.

    Attributes:
        positions: Joint angles, shape (6, 3) [rad].
        velocities: Joint rates, shape (6, 3) [rad/s].
        stamp: Controller time [s].
    """

    TOPIC = "joint_targets"

    positions: npt.NDArray[np.float64]
    velocities: npt.NDArray[np.float64]
    stamp: float = 0.0


@dataclass(frozen=True)
class RobotState(Message):
    """One reading of the robot.

    Attributes:
        time: Backend clock [s].
        joint_positions: Shape (6, 3) [rad].
        joint_velocities: Shape (6, 3) [rad/s].
        orientation_body_in_world: IMU attitude: rotates body-frame vectors into the world.
        angular_velocity_body_in_body: Gyro reading, shape (3,) [rad/s].
        position_body_in_world: Body position, shape (3,) [m], when the backend knows it
            (a simulator's ground truth, a motion-capture system); else None.
        feet_in_world: Foot centres, shape (6, 3) [m], when known; else None.
        feet_in_contact: Which feet touch the ground, shape (6,), when known; else None.
        foot_orientations_in_world: Rotation matrices of the feet (tibia frames), shape
            (6, 3, 3), when known; else None. With them, rolling can be told from sliding.
    """

    TOPIC = "state"

    time: float
    joint_positions: npt.NDArray[np.float64]
    joint_velocities: npt.NDArray[np.float64]
    orientation_body_in_world: Rotation
    angular_velocity_body_in_body: npt.NDArray[np.float64]
    position_body_in_world: npt.NDArray[np.float64] | None = None
    feet_in_world: npt.NDArray[np.float64] | None = None
    feet_in_contact: npt.NDArray[np.bool_] | None = None
    foot_orientations_in_world: npt.NDArray[np.float64] | None = None

    @cached_property
    def roll_pitch(self) -> tuple[float, float]:
        """Body roll and pitch [rad] (intrinsic z-y-x Euler angles of the attitude)."""
        _, pitch, roll = self.orientation_body_in_world.as_euler("ZYX")
        return float(roll), float(pitch)

    @cached_property
    def tilt(self) -> float:
        """Angle between the body z axis and the world z axis [rad]."""
        z_axis = self.orientation_body_in_world.apply([0.0, 0.0, 1.0])
        return float(np.arccos(np.clip(z_axis[2], -1.0, 1.0)))


@dataclass(frozen=True)
class GaitStatus(Message):
    """What the movement node is doing.

    Attributes:
        stamp: Controller time [s].
        mode: The operating mode in force.
        state: Gait state.
        frozen_reason: Why the robot froze or stopped ("" when it did not).
        frozen_leg: The leg named in the reason ("" when none is).
        body_pose: The controller's reference body pose in the world's ground plane.
        body_z: The controller's reference body height in the world [m].
        steps_taken: Steps completed.
        footholds_adjusted: Touchdowns moved off their nominal cell.
        command_age: Seconds since the last command arrived (inf before the first).
        messages_dropped: Messages the robot refused: malformed, or older than one it had.
    """

    TOPIC = "status"
    VERSION = 2

    stamp: float
    mode: Mode
    state: GaitState
    frozen_reason: str
    frozen_leg: str
    body_pose: PlanarPose
    body_z: float
    steps_taken: int
    footholds_adjusted: int
    command_age: float
    messages_dropped: int = 0

    def __post_init__(self) -> None:
        object.__setattr__(self, "mode", Mode(self.mode))
        object.__setattr__(self, "state", GaitState(self.state))


@dataclass(frozen=True)
class Touchdown(Message):
    """A foot came down: where it was meant to land and where the planner put it.

    Attributes:
        stamp: Touchdown time [s].
        leg: Leg index.
        nominal_in_world: Nominal foothold (foot centre), shape (3,) [m].
        chosen_in_world: Planned foothold (foot centre), shape (3,) [m].
    """

    TOPIC = "touchdown"

    stamp: float
    leg: int
    nominal_in_world: npt.NDArray[np.float64]
    chosen_in_world: npt.NDArray[np.float64]


@dataclass(frozen=True)
class LogLine(Message):
    """A line of a node's log (the thesis' ``LOGDATA``).

    Attributes:
        stamp: When [s].
        node: The node that wrote it.
        level: ``"info"``, ``"warning"`` or ``"error"``.
        text: The line.
    """

    TOPIC = "log"

    stamp: float
    node: str
    level: str
    text: str
