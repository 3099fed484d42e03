"""A robot's servo bus, from the ``[hardware]`` table of its TOML description.

::

    [hardware]
    port = "/dev/ttyUSB0"       # the U2D2 / USB2AX adapter
    baud = 1000000
    protocol = 1                # 1: AX-12A, AX-18A, RX-64; 2: XL430, XM430
    model = "AX-12A"            # every servo's model, unless its leg says otherwise
    return_delay_us = 0         # written to every servo when the bus opens [us]

    [hardware.legs.LF]          # one table per leg, joints coxa, femur, tibia
    ids = [1, 2, 3]
    directions = [1, -1, 1]     # -1: the servo turns against footfall's angle
    zeros_deg = [0, 20, -80]    # footfall's angle at the servo's centre position
    # models = ["AX-12A", "AX-18A", "AX-18A"]
    # limits_deg = [[-50, 50], [-90, 80], [-150, 10]]   # narrower than the spec's

A leg without a table gets ids ``3 i + 1, 3 i + 2, 3 i + 3`` (legs in the spec's order),
directions 1 and zeros in the middle of the spec's joint ranges. Joint limits are the
spec's unless a leg narrows them; a limit the servo cannot reach is an error.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from footfall.errors import ConfigError
from footfall.hardware.models import DEFAULT_MODELS, ServoModel, servo_model
from footfall.robot.spec import BUILTIN_ROBOTS, HexapodSpec
from footfall.robots import read_description

JOINTS = ("coxa", "femur", "tibia")
# The baud rates the Dynamixel SDK's port handler accepts.
BAUD_RATES = (9600, 57600, 115200, 1000000, 2000000, 3000000, 4000000)


@dataclass(frozen=True)
class JointServo:
    """The servo that turns one joint.

    Attributes:
        leg: Leg name.
        joint: ``coxa``, ``femur`` or ``tibia``.
        servo_id: Its bus id.
        model: Its model.
        direction: 1 when its positions grow with footfall's angle, -1 when against.
        zero: footfall's angle at the servo's centre position [rad].
        lower: Lowest angle footfall sends [rad].
        upper: Highest angle footfall sends [rad].
    """

    leg: str
    joint: str
    servo_id: int
    model: ServoModel
    direction: int
    zero: float
    lower: float
    upper: float

    @property
    def name(self) -> str:
        """``"servo 5 (LM femur)"``, for messages."""
        return f"servo {self.servo_id} ({self.leg} {self.joint})"

    def steps(self, angle: float) -> int:
        """Goal position steps for a joint angle [rad]."""
        servo = self.direction * (angle - self.zero) * self.model.steps_per_rad
        return round(self.model.centre + servo)

    def angle(self, steps: int) -> float:
        """Joint angle [rad] at a position in steps."""
        return self.zero + self.direction * (steps - self.model.centre) / self.model.steps_per_rad


@dataclass(frozen=True)
class HardwareConfig:
    """The servo bus of one robot.

    Attributes:
        port: Serial device of the adapter.
        baud: Bits per second.
        protocol: 1 or 2.
        return_delay: How long a servo waits before it answers [s] (2 us steps).
        servos: The 18 joint servos, leg by leg in the spec's order, coxa first.
    """

    port: str
    baud: int
    protocol: int
    return_delay: float
    servos: tuple[JointServo, ...]

    def __post_init__(self) -> None:
        if self.protocol not in (1, 2):
            raise ConfigError(f"[hardware] protocol {self.protocol} is not 1 or 2")
        if self.baud not in BAUD_RATES:
            raise ConfigError(
                f"[hardware] baud {self.baud} is not one the Dynamixel SDK opens: "
                f"{', '.join(map(str, BAUD_RATES))}"
            )
        if not 0.0 <= self.return_delay <= 254 * 2e-6:
            raise ConfigError(f"[hardware] return_delay_us {self.return_delay * 1e6:g} ∉ [0, 508]")
        ids = [s.servo_id for s in self.servos]
        for servo in self.servos:
            if not 0 <= servo.servo_id <= 252:
                raise ConfigError(f"{servo.name}: ids run from 0 to 252")
            if ids.count(servo.servo_id) > 1:
                raise ConfigError(f"{servo.name}: id {servo.servo_id} is used twice")
            if servo.model.protocol != self.protocol:
                raise ConfigError(
                    f"{servo.name}: a {servo.model.name} speaks protocol {servo.model.protocol}, "
                    f"the bus protocol {self.protocol}"
                )

    @property
    def byte_time(self) -> float:
        """Time one byte takes on the wire (start, 8 data and stop bits) [s]."""
        return 10.0 / self.baud

    def by_id(self) -> dict[int, JointServo]:
        """The servos by bus id."""
        return {s.servo_id: s for s in self.servos}

    def lower(self) -> npt.NDArray[np.float64]:
        """Lowest joint angles, shape (6, 3) [rad]."""
        return np.array([s.lower for s in self.servos]).reshape(6, 3)

    def upper(self) -> npt.NDArray[np.float64]:
        """Highest joint angles, shape (6, 3) [rad]."""
        return np.array([s.upper for s in self.servos]).reshape(6, 3)


def _triple(table: dict, key: str, default: list, where: str) -> list:
    value = table.get(key, default)
    if not isinstance(value, list) or len(value) != 3:
        raise ConfigError(f"{where}.{key} needs three entries (coxa, femur, tibia)")
    return value


def hardware_from_dict(
    spec: HexapodSpec, data: dict | None, protocol: int | None = None, port: str | None = None
) -> HardwareConfig:
    """The servo bus of ``spec`` from its parsed ``[hardware]`` table.

    Args:
        spec: The robot (its legs and joint limits).
        data: The ``[hardware]`` table; None for a robot that has none (every default).
        protocol: The protocol to use when the table names none (``--servo-bus``).
        port: The serial port, overriding the table's.

    Raises:
        ConfigError: On a missing port, an unknown leg or model, a limit out of the servo's
            reach, a repeated id.
    """
    data = dict(data or {})
    try:
        protocol = int(data.get("protocol", protocol if protocol is not None else 1))
        model_name = str(data.get("model", DEFAULT_MODELS.get(protocol, "")))
        legs = data.get("legs", {})
        unknown = sorted(set(legs) - set(spec.leg_names))
        if unknown:
            raise ConfigError(
                f"[hardware.legs] names {', '.join(unknown)}; the robot's legs are "
                f"{', '.join(spec.leg_names)}"
            )
        spec_limits = list(zip(spec.limits.lower, spec.limits.upper, strict=True))
        servos = []
        for i, leg in enumerate(spec.leg_names):
            table = legs.get(leg, {})
            where = f"[hardware.legs.{leg}]"
            ids = _triple(table, "ids", [3 * i + 1, 3 * i + 2, 3 * i + 3], where)
            models = _triple(table, "models", [model_name] * 3, where)
            directions = _triple(table, "directions", [1, 1, 1], where)
            middles = [math.degrees(lo + hi) / 2.0 for lo, hi in spec_limits]
            zeros = _triple(table, "zeros_deg", middles, where)
            limits = table.get("limits_deg")
            for j, joint in enumerate(JOINTS):
                lower, upper = spec_limits[j]
                if limits is not None:
                    low_deg, high_deg = _triple(table, "limits_deg", [], where)[j]
                    lower = max(lower, math.radians(low_deg))
                    upper = min(upper, math.radians(high_deg))
                if int(directions[j]) not in (1, -1):
                    raise ConfigError(f"{where}.directions: {directions[j]} is not 1 or -1")
                servo = JointServo(
                    leg,
                    joint,
                    int(ids[j]),
                    servo_model(str(models[j])),
                    int(directions[j]),
                    math.radians(float(zeros[j])),
                    lower,
                    upper,
                )
                _check_reach(servo)
                servos.append(servo)
        return HardwareConfig(
            port=str(port if port is not None else data.get("port", "")),
            baud=int(data.get("baud", 1_000_000)),
            protocol=protocol,
            return_delay=float(data.get("return_delay_us", 0.0)) * 1e-6,
            servos=tuple(servos),
        )
    except (TypeError, ValueError) as exc:
        if isinstance(exc, ConfigError):
            raise
        raise ConfigError(f"[hardware] has a malformed entry: {exc}") from exc


def hardware_from_options(spec: HexapodSpec, options: dict[str, str]) -> HardwareConfig:
    """The servo bus a backend's options describe, taking out the keys it reads.

    ``robot`` (a built-in name or a TOML file whose ``[hardware]`` table to use),
    ``protocol`` (1 or 2, when the table names none), ``port`` (overrides the table's).

    Raises:
        ConfigError: On a malformed table or protocol.
    """
    table = None
    if "robot" in options:
        table = read_description(options.pop("robot"), BUILTIN_ROBOTS).get("hardware")
    protocol = options.pop("protocol", "")
    if protocol not in ("", "1", "2"):
        raise ConfigError(f"Dynamixel protocol {protocol!r} is not 1 or 2")
    return hardware_from_dict(
        spec, table, protocol=int(protocol) if protocol else None, port=options.pop("port", None)
    )


def _check_reach(servo: JointServo) -> None:
    if servo.lower >= servo.upper:
        raise ConfigError(f"{servo.name}: its limits leave no range")
    for angle in (servo.lower, servo.upper):
        steps = servo.steps(angle)
        if not 0 <= steps < servo.model.position_steps:
            raise ConfigError(
                f"{servo.name}: the limit {math.degrees(angle):.1f} deg is outside what a "
                f"{servo.model.name} turns to (step {steps}); change its zero or its limits"
            )
