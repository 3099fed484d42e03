"""Robot description of a six-legged walker: body, leg mounts, leg geometry and servos.

A :class:`HexapodSpec` is a frozen value loaded from TOML (see ``robots/default.toml``).
Angles in the files are in degrees (keys end in ``_deg``); inside the spec everything is SI.
Legs are listed counter-clockwise seen from above, starting at the front-left leg, so that
legs ``i``, ``i + 2`` and ``i + 4`` form a tripod (thesis eq. 5.15).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from footfall.checks import require_non_negative, require_positive
from footfall.errors import ConfigError
from footfall.robots import read_description

if TYPE_CHECKING:
    from footfall.sensing.pose import Pose

NUM_LEGS = 6
BUILTIN_ROBOTS = ("default", "phantomx")


def _require(condition: bool, message: str) -> None:
    if not condition:
        raise ConfigError(message)


@dataclass(frozen=True)
class JointLimits:
    """Joint ranges of one leg [rad], as ``(lower, upper)`` pairs.

    In the convention of ``docs/frames.md``: coxa yaw about the leg's z, femur elevation
    above horizontal, tibia angle relative to the femur's extension (negative bends down).
    """

    coxa: tuple[float, float] = (math.radians(-60.0), math.radians(60.0))
    femur: tuple[float, float] = (math.radians(-90.0), math.radians(90.0))
    tibia: tuple[float, float] = (math.radians(-160.0), math.radians(0.0))

    def __post_init__(self) -> None:
        for name in ("coxa", "femur", "tibia"):
            lower, upper = getattr(self, name)
            _require(
                lower < upper, f"joint limits of {name}: lower {lower} must be < upper {upper}"
            )

    @property
    def lower(self) -> npt.NDArray[np.float64]:
        """Lower limits, shape (3,) [rad]."""
        return np.array([self.coxa[0], self.femur[0], self.tibia[0]])

    @property
    def upper(self) -> npt.NDArray[np.float64]:
        """Upper limits, shape (3,) [rad]."""
        return np.array([self.coxa[1], self.femur[1], self.tibia[1]])


@dataclass(frozen=True)
class LegMount:
    """Where a leg is attached to the body.

    Attributes:
        name: Short leg name, e.g. ``"LF"`` for left-front.
        position_in_body: Coxa joint position in the body frame, shape (3,) [m].
        yaw: Direction the leg points at rest, about the body z axis [rad].
    """

    name: str
    position_in_body: tuple[float, float, float]
    yaw: float


@dataclass(frozen=True)
class ServoGains:
    """Position servos as the thesis models them: stiff and heavily damped (thesis §3.3).

    Attributes:
        kp: Position gain [N m / rad].
        kv: Velocity (damping) gain of the actuator [N m s / rad].
        max_torque: Saturation torque [N m].
        armature: Reflected rotor inertia [kg m^2].
        joint_damping: Passive joint damping [N m s / rad].
        max_rate: Fastest the servos turn [rad/s]: standing up and sitting down stay
            under it (the joint targets' rates are measured against it).
    """

    kp: float = 60.0
    kv: float = 1.5
    max_torque: float = 6.0
    armature: float = 0.005
    joint_damping: float = 0.2
    max_rate: float = 4.0

    def __post_init__(self) -> None:
        require_positive(
            "servo", kp=self.kp, kv=self.kv, max_torque=self.max_torque, max_rate=self.max_rate
        )
        require_non_negative("servo", armature=self.armature, joint_damping=self.joint_damping)


@dataclass(frozen=True)
class CameraPlacement:
    """Where the depth camera sits on the body: the ``[camera]`` table of a robot's TOML.

    What the camera sees just ahead of the front feet depends on it: a robot whose legs are
    short must see the ground nearer its body (on a way down a staircase, the tread just past
    the edge) than a robot whose legs reach farther.

    Attributes:
        position_in_body: Optical centre in the body frame [m].
        pitch: The optical axis below the body's x axis [rad].
        roll: About the optical axis, the image's right side down [rad].
        yaw: The optical axis to the left of the body's x axis [rad].
    """

    position_in_body: tuple[float, float, float] = (0.13, 0.0, 0.08)
    pitch: float = math.radians(30.0)
    roll: float = 0.0
    yaw: float = 0.0

    def __post_init__(self) -> None:
        _require(
            len(self.position_in_body) == 3,
            f"camera position must be three numbers, got {self.position_in_body}",
        )
        _require(
            abs(self.pitch) < 0.5 * math.pi,
            f"camera pitch must lie within +-90 degrees, got {math.degrees(self.pitch):g}",
        )

    def optical_in_body(self) -> Pose:
        """The optical frame (x right, y down, z forward) in the body frame (x ahead, z up)."""
        from scipy.spatial.transform import Rotation

        from footfall.sensing.pose import Pose

        s, c = math.sin(self.pitch), math.cos(self.pitch)
        forward = np.array([c, 0.0, -s])
        right = np.array([0.0, -1.0, 0.0])
        down = np.cross(forward, right)
        level = Rotation.from_matrix(np.stack([right, down, forward], axis=1))
        # Yaw turns the camera about the body's z; roll turns the image about the optical z.
        rotation = Rotation.from_euler("z", self.yaw) * level * Rotation.from_euler("z", self.roll)
        return Pose(np.asarray(self.position_in_body, dtype=np.float64), rotation)


CAMERA_KEYS = ("position", "pitch_deg", "roll_deg", "yaw_deg")


def camera_placement_from_table(table: dict | None) -> CameraPlacement:
    """A :class:`CameraPlacement` from a ``[camera]`` table; the default for keys it lacks.

    Raises:
        ConfigError: An unknown key or a malformed value, named.
    """
    table = dict(table or {})
    unknown = sorted(set(table) - set(CAMERA_KEYS))
    if unknown:
        raise ConfigError(
            f"[camera] has no key {', '.join(unknown)}; it takes {', '.join(CAMERA_KEYS)}"
        )
    default = CameraPlacement()
    try:
        position = tuple(float(v) for v in table.get("position", default.position_in_body))
        pitch, roll, yaw = (
            math.radians(float(table[key])) if key in table else fallback
            for key, fallback in (
                ("pitch_deg", default.pitch),
                ("roll_deg", default.roll),
                ("yaw_deg", default.yaw),
            )
        )
    except (TypeError, ValueError) as exc:
        raise ConfigError(f"[camera] has a malformed value: {exc}") from exc
    if len(position) != 3 or not all(math.isfinite(v) for v in (*position, pitch, roll, yaw)):
        raise ConfigError(f"[camera] position must be three finite numbers, got {position}")
    return CameraPlacement(position, pitch, roll, yaw)  # type: ignore[arg-type]


@dataclass(frozen=True)
class HexapodSpec:
    """A hexapod's geometry, masses and servos.

    Attributes:
        name: Robot name.
        body_size: Body box length, width, height [m].
        body_mass: Body mass [kg], legs excluded.
        mounts: Six leg mounts, counter-clockwise from the front-left leg.
        coxa_length: Coxa axis to femur axis [m].
        femur_length: Femur axis to tibia axis [m].
        tibia_length: Tibia axis to the foot's contact point [m].
        segment_masses: Coxa, femur and tibia masses [kg].
        limits: Joint ranges.
        servo: Servo model.
        foot_radius: Radius of the spherical foot [m].
        foot_friction: Sliding friction coefficient of the foot.
        stance_radius: Horizontal distance from the coxa axis to the foot at rest [m].
        body_height: Nominal body height above the ground [m].
        max_step_height: Highest the foot may lift above the higher end of a swing [m]; the
            leg's workspace near its rest stance sets it.
        stride_length: Longest stride the legs allow [m]: the distance a foot travels over
            the ground in one swing, and the body's advance per gait cycle.
        camera: Where the depth camera sits on the body.
    """

    name: str
    body_size: tuple[float, float, float]
    body_mass: float
    mounts: tuple[LegMount, ...]
    coxa_length: float
    femur_length: float
    tibia_length: float
    segment_masses: tuple[float, float, float]
    limits: JointLimits = field(default_factory=JointLimits)
    servo: ServoGains = field(default_factory=ServoGains)
    foot_radius: float = 0.012
    foot_friction: float = 1.0
    stance_radius: float = 0.14
    body_height: float = 0.09
    max_step_height: float = 0.10
    stride_length: float = 0.15
    camera: CameraPlacement = field(default_factory=CameraPlacement)

    def __post_init__(self) -> None:
        for name, value in _numbers(self):
            _require(math.isfinite(value), f"{name} must be a finite number, got {value}")
        _require(len(self.mounts) == NUM_LEGS, f"a hexapod has 6 legs, got {len(self.mounts)}")
        names = [m.name for m in self.mounts]
        _require(len(set(names)) == NUM_LEGS, f"leg names must be unique, got {names}")
        require_positive(
            "robot",
            coxa_length=self.coxa_length,
            femur_length=self.femur_length,
            tibia_length=self.tibia_length,
            body_mass=self.body_mass,
            foot_radius=self.foot_radius,
            body_height=self.body_height,
            max_step_height=self.max_step_height,
            stride_length=self.stride_length,
            **{f"body_size[{k}]": s for k, s in enumerate(self.body_size)},
            **{f"segment_masses[{k}]": m for k, m in enumerate(self.segment_masses)},
        )
        _require(self.stance_radius > self.coxa_length, "stance_radius must exceed coxa_length")
        angles = np.unwrap(
            [math.atan2(m.position_in_body[1], m.position_in_body[0]) for m in self.mounts]
        )
        _require(
            bool(np.all(np.diff(angles) > 0)) and angles[-1] - angles[0] < 2 * math.pi,
            "legs must be listed counter-clockwise seen from above, starting at the front-left leg",
        )

    @property
    def leg_names(self) -> tuple[str, ...]:
        """Leg names in spec order."""
        return tuple(m.name for m in self.mounts)

    @property
    def mount_positions_in_body(self) -> npt.NDArray[np.float64]:
        """Coxa joint positions in the body frame, shape (6, 3) [m]."""
        return np.array([m.position_in_body for m in self.mounts], dtype=np.float64)

    @property
    def mount_yaws(self) -> npt.NDArray[np.float64]:
        """Leg mount yaw angles, shape (6,) [rad]."""
        return np.array([m.yaw for m in self.mounts], dtype=np.float64)

    @property
    def mass(self) -> float:
        """Total mass [kg]."""
        return self.body_mass + NUM_LEGS * sum(self.segment_masses)

    def rest_feet_in_body(self, body_height: float | None = None) -> npt.NDArray[np.float64]:
        """Rest (nominal) foot positions in the body frame, shape (6, 3) [m].

        Args:
            body_height: Height of the body frame above the ground [m]; the spec's nominal
                height when omitted.
        """
        height = self.body_height if body_height is None else body_height
        yaws = self.mount_yaws
        feet = self.mount_positions_in_body.copy()
        feet[:, 0] += self.stance_radius * np.cos(yaws)
        feet[:, 1] += self.stance_radius * np.sin(yaws)
        feet[:, 2] = -height
        return feet


def _numbers(value: object, name: str = "") -> list[tuple[str, float]]:
    """Every number in a spec, by its dotted name (dataclass fields and tuples)."""
    if isinstance(value, bool):
        return []
    if isinstance(value, int | float):
        return [(name, float(value))]
    if isinstance(value, tuple | list):
        return [n for k, v in enumerate(value) for n in _numbers(v, f"{name}[{k}]")]
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return [
            n
            for f in dataclasses.fields(value)
            for n in _numbers(getattr(value, f.name), f"{name}.{f.name}" if name else f.name)
        ]
    return []


def _pair_deg(table: dict, key: str, default: tuple[float, float]) -> tuple[float, float]:
    if key not in table:
        return default
    lower, upper = table[key]
    return (math.radians(lower), math.radians(upper))


def spec_from_dict(data: dict) -> HexapodSpec:
    """Build a :class:`HexapodSpec` from the parsed TOML layout (see ``robots/default.toml``).

    Raises:
        ConfigError: On a missing key or a value outside what is allowed.
    """
    try:
        body = data["body"]
        leg = data["leg"]
        limits_table = leg.get("limits_deg", {})
        defaults = JointLimits()
        limits = JointLimits(
            coxa=_pair_deg(limits_table, "coxa", defaults.coxa),
            femur=_pair_deg(limits_table, "femur", defaults.femur),
            tibia=_pair_deg(limits_table, "tibia", defaults.tibia),
        )
        mounts = tuple(
            LegMount(
                name=str(m["name"]),
                position_in_body=(float(m["x"]), float(m["y"]), float(m.get("z", 0.0))),
                yaw=math.radians(float(m["yaw_deg"])),
            )
            for m in data["mounts"]
        )
        stance = data.get("stance", {})
        foot = data.get("foot", {})
        return HexapodSpec(
            name=str(data.get("name", "robot")),
            body_size=tuple(float(v) for v in body["size"]),  # type: ignore[arg-type]
            body_mass=float(body["mass"]),
            mounts=mounts,
            coxa_length=float(leg["coxa_length"]),
            femur_length=float(leg["femur_length"]),
            tibia_length=float(leg["tibia_length"]),
            segment_masses=tuple(float(v) for v in leg["masses"]),  # type: ignore[arg-type]
            limits=limits,
            servo=ServoGains(**data.get("servo", {})),
            foot_radius=float(foot.get("radius", 0.012)),
            foot_friction=float(foot.get("friction", 1.0)),
            stance_radius=float(stance.get("radius", 0.14)),
            body_height=float(stance.get("body_height", 0.09)),
            max_step_height=float(stance.get("max_step_height", 0.10)),
            stride_length=float(stance.get("stride_length", 0.15)),
            camera=camera_placement_from_table(data.get("camera")),
        )
    except KeyError as exc:
        raise ConfigError(f"robot description is missing the key {exc}") from exc
    except (TypeError, ValueError, AttributeError) as exc:
        if isinstance(exc, ConfigError):
            raise
        raise ConfigError(f"robot description has a malformed entry: {exc}") from exc


def load_spec(name_or_path: str | Path) -> HexapodSpec:
    """Load a built-in robot (``"default"``, ``"phantomx"``) or a TOML file.

    Raises:
        ConfigError: When the name is unknown, the file is missing or malformed.
    """
    data = read_description(name_or_path, BUILTIN_ROBOTS)
    return spec_from_dict(data)
