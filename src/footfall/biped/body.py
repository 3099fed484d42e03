"""Archie's body: the biped spec (TOML) and the closed-form kinematics of its legs.

Frames: the hip frame sits at the middle of the hip, x forward, y left, z up. Each leg
hangs from a hip joint ``hip_drop`` below it and ``hip_width / 2`` to the side, where the
hip yaw (z), roll (x) and pitch (y) axes meet; the thigh line runs ``hip_offset`` further
out (the DH offset d3), down ``thigh`` to the knee (y), ``shank`` to the ankle pitch (y),
``ankle_link`` to the ankle roll (x) and ``ankle_height`` to the sole. A foot pose is the
sole centre and the foot's orientation, in the hip frame or the world.

Joint order per leg, in the simulator's actuator order: hip yaw, hip roll, hip pitch,
knee, ankle pitch, ankle roll. Positive pitch rotates about +y, so a negative hip pitch
swings the leg forward and a positive knee bends the shank back.

The dissertation's relations (§4.4, eqs. 41-54) are the special cases of
:func:`leg_inverse` that they cover: a support leg with a straight knee and the trunk upright
(hip roll = -ankle roll, hip pitch = -ankle pitch), and a swing leg with its foot level;
``tests/test_biped_body.py`` checks both against :mod:`footfall.biped.archie`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import numpy.typing as npt

from footfall.checks import require_positive
from footfall.errors import ConfigError, UnreachableTargetError
from footfall.robots import read_description

JOINTS = ("hip_yaw", "hip_roll", "hip_pitch", "knee", "ankle_pitch", "ankle_roll")
SIDES = ("left", "right")
BUILTIN_BIPEDS = ("archie",)


@dataclass(frozen=True)
class ServoSpec:
    """Position servo settings."""

    kp: float
    kv: float
    joint_damping: float
    armature: float
    max_torque: float
    hip_yaw_max_torque: float


@dataclass(frozen=True)
class BipedSpec:
    """A biped's geometry, masses, servos and camera (see ``robots/archie.toml``).

    Lengths [m], masses [kg], angles [rad].
    """

    name: str
    ankle_height: float
    ankle_link: float
    shank: float
    thigh: float
    hip_offset: float
    hip_drop: float
    hip_width: float
    leg_masses: tuple[float, float, float, float]
    limits: dict[str, tuple[float, float]]
    pelvis_size: tuple[float, float, float]
    pelvis_mass: float
    torso_size: tuple[float, float, float]
    torso_mass: float
    torso_height: float
    foot_length: float
    foot_width: float
    foot_thickness: float
    foot_friction: float
    servo: ServoSpec
    hip_height: float
    step_height: float
    camera_position: tuple[float, float, float]
    camera_pitch: float

    def __post_init__(self) -> None:
        require_positive(
            "biped",
            ankle_height=self.ankle_height,
            ankle_link=self.ankle_link,
            shank=self.shank,
            thigh=self.thigh,
            hip_width=self.hip_width,
            pelvis_mass=self.pelvis_mass,
            torso_mass=self.torso_mass,
            foot_length=self.foot_length,
            foot_width=self.foot_width,
            foot_thickness=self.foot_thickness,
        )
        require_positive("biped", **{f"leg_mass_{k}": m for k, m in enumerate(self.leg_masses)})
        for joint in JOINTS:
            lower, upper = self.limits[joint]
            if not lower < upper:
                raise ConfigError(f"limits of {joint}: lower {lower} must be < upper {upper}")
        if not 0 < self.hip_height < self.leg_length + self.hip_drop:
            raise ConfigError(
                f"hip height {self.hip_height} m is beyond the legs' reach "
                f"{self.leg_length + self.hip_drop:.3f} m"
            )

    @property
    def leg_length(self) -> float:
        """Sole to hip joint with the leg straight [m]."""
        return self.ankle_height + self.ankle_link + self.shank + self.thigh

    @property
    def mass(self) -> float:
        """The whole robot's mass [kg]."""
        return self.pelvis_mass + self.torso_mass + 2 * sum(self.leg_masses)

    def side_sign(self, side: str) -> float:
        """+1 for the left leg, -1 for the right."""
        if side not in SIDES:
            raise ConfigError(f"side must be 'left' or 'right', got {side!r}")
        return 1.0 if side == "left" else -1.0

    def hip_joint(self, side: str) -> npt.NDArray[np.float64]:
        """Where a leg's hip axes meet, in the hip frame [m]."""
        return np.array([0.0, self.side_sign(side) * 0.5 * self.hip_width, -self.hip_drop])

    def stance_width(self) -> float:
        """Distance between the feet when both legs hang straight down [m]."""
        return self.hip_width + 2 * self.hip_offset


def load_biped_spec(name_or_path: str | Path = "archie") -> BipedSpec:
    """Read a biped spec: a built-in name or a TOML file.

    Raises:
        ConfigError: When the file is missing, not TOML, or lacks a key (named).
    """
    d = read_description(name_or_path, BUILTIN_BIPEDS)
    try:
        leg, body, foot, servo, stance, cam = (
            d[k] for k in ("leg", "body", "foot", "servo", "stance", "camera")
        )
        limits = {j: (math.radians(v[0]), math.radians(v[1])) for j, v in leg["limits_deg"].items()}
        missing = set(JOINTS) - set(limits)
        if missing:
            raise ConfigError(f"biped spec lacks joint limits for {', '.join(sorted(missing))}")
        return BipedSpec(
            name=str(d.get("name", Path(name_or_path).stem)),
            ankle_height=float(leg["ankle_height"]),
            ankle_link=float(leg["ankle_link"]),
            shank=float(leg["shank"]),
            thigh=float(leg["thigh"]),
            hip_offset=float(leg["hip_offset"]),
            hip_drop=float(leg["hip_drop"]),
            hip_width=float(leg["hip_width"]),
            leg_masses=tuple(float(m) for m in leg["masses"]),
            limits=limits,
            pelvis_size=tuple(float(v) for v in body["pelvis_size"]),
            pelvis_mass=float(body["pelvis_mass"]),
            torso_size=tuple(float(v) for v in body["torso_size"]),
            torso_mass=float(body["torso_mass"]),
            torso_height=float(body["torso_height"]),
            foot_length=float(foot["length"]),
            foot_width=float(foot["width"]),
            foot_thickness=float(foot["thickness"]),
            foot_friction=float(foot["friction"]),
            servo=ServoSpec(**{k: float(v) for k, v in servo.items()}),
            hip_height=float(stance["hip_height"]),
            step_height=float(stance["step_height"]),
            camera_position=tuple(float(v) for v in cam["position"]),
            camera_pitch=math.radians(float(cam["pitch_deg"])),
        )
    except KeyError as exc:
        raise ConfigError(f"biped spec {name_or_path} lacks the key {exc}") from exc
    except (TypeError, ValueError) as exc:
        raise ConfigError(f"biped spec {name_or_path} has a malformed entry: {exc}") from exc


def rot_x(a: float) -> npt.NDArray[np.float64]:
    """Rotation about x by ``a`` [rad]."""
    c, s = math.cos(a), math.sin(a)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def rot_y(a: float) -> npt.NDArray[np.float64]:
    """Rotation about y by ``a`` [rad]."""
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def rot_z(a: float) -> npt.NDArray[np.float64]:
    """Rotation about z by ``a`` [rad]."""
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def mean_heading(a: float, b: float) -> float:
    """The heading halfway between two headings [rad]."""
    return math.atan2(math.sin(a) + math.sin(b), math.cos(a) + math.cos(b))


def leg_forward(
    spec: BipedSpec, side: str, q: npt.ArrayLike
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """Sole centre and foot orientation in the hip frame from a leg's six joint angles.

    Args:
        spec: The biped.
        side: ``"left"`` or ``"right"``.
        q: Hip yaw, hip roll, hip pitch, knee, ankle pitch, ankle roll [rad].

    Returns:
        ``(sole_in_hip, rotation_foot_to_hip)``: shape (3,) [m] and (3, 3).
    """
    yaw, roll, pitch, knee, ankle_pitch, ankle_roll = (float(v) for v in q)
    s = spec.side_sign(side)
    r = rot_z(yaw) @ rot_x(roll) @ rot_y(pitch)
    p = spec.hip_joint(side) + r @ np.array([0.0, s * spec.hip_offset, -spec.thigh])
    r = r @ rot_y(knee)
    p = p + r @ np.array([0.0, 0.0, -spec.shank])
    r = r @ rot_y(ankle_pitch)
    p = p + r @ np.array([0.0, 0.0, -spec.ankle_link])
    r = r @ rot_x(ankle_roll)
    return p + r @ np.array([0.0, 0.0, -spec.ankle_height]), r


def leg_inverse(
    spec: BipedSpec,
    side: str,
    sole_in_hip: npt.ArrayLike,
    rotation_foot_to_hip: npt.ArrayLike | None = None,
) -> npt.NDArray[np.float64]:
    """A leg's six joint angles that put its sole at a pose in the hip frame (closed form).

    The ankle roll axis is found first (the leg below the hip roll lies in one plane once
    the foot's roll is known), then the knee and ankle pitch by the cosine law, then the
    hip's yaw, roll and pitch from the remaining rotation. The knee bends backwards
    (positive), as Archie's does.

    Args:
        spec: The biped.
        side: ``"left"`` or ``"right"``.
        sole_in_hip: Target sole centre in the hip frame, shape (3,) [m].
        rotation_foot_to_hip: Target foot orientation, shape (3, 3); level and straight
            ahead when None.

    Returns:
        Hip yaw, hip roll, hip pitch, knee, ankle pitch, ankle roll [rad].

    Raises:
        UnreachableTargetError: When the sole is beyond the stretched leg or too close.
    """
    s = spec.side_sign(side)
    target = np.asarray(sole_in_hip, dtype=np.float64)
    r_foot = np.eye(3) if rotation_foot_to_hip is None else np.asarray(rotation_foot_to_hip)
    ankle_roll_axis = target + r_foot @ np.array([0.0, 0.0, spec.ankle_height])
    v = r_foot.T @ (spec.hip_joint(side) - ankle_roll_axis)  # ankle roll -> hip, foot frame
    w_y = -s * spec.hip_offset
    across = v[1] ** 2 + v[2] ** 2 - w_y**2
    if across <= 0:
        raise UnreachableTargetError(side, "the sole is inside the hip offset", float("nan"))
    w_z = math.sqrt(across)
    ankle_roll = math.atan2(v[1], v[2]) - math.atan2(w_y, w_z)
    # Sagittal plane of the rotated leg: ankle pitch axis -> hip, a 2-link chain.
    fx, fz = v[0], w_z - spec.ankle_link
    r2 = fx * fx + fz * fz
    a2, a3 = spec.shank, spec.thigh
    cos_knee = (r2 - a2 * a2 - a3 * a3) / (2 * a2 * a3)
    if cos_knee > 1.0 + 1e-9 or cos_knee < -1.0:
        reach = math.sqrt(r2)
        raise UnreachableTargetError(
            side,
            f"ankle {reach:.3f} m from the hip, the leg reaches {a2 + a3:.3f} m",
            reach - (a2 + a3),
        )
    knee = math.acos(min(1.0, cos_knee))
    ankle_pitch = -(math.atan2(fx, fz) - math.atan2(-a3 * math.sin(knee), a2 + a3 * math.cos(knee)))
    # Hip: Rz(yaw) Rx(roll) Ry(pitch) = R_foot Rx(-ankle_roll) Ry(-(knee + ankle_pitch)).
    m = r_foot @ rot_x(-ankle_roll) @ rot_y(-(knee + ankle_pitch))
    roll = math.asin(float(np.clip(m[2, 1], -1.0, 1.0)))
    yaw = math.atan2(-m[0, 1], m[1, 1])
    pitch = math.atan2(-m[2, 0], m[2, 2])
    return np.array([yaw, roll, pitch, knee, ankle_pitch, ankle_roll])
