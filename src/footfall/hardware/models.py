"""Dynamixel servo models: their protocol, control-table addresses and units.

From ROBOTIS' e-Manuals: AX-12A, AX-18A and RX-64 speak Protocol 1.0 (a 300 degree
position range in 1024 steps, moving speed in 0.111 rpm steps, no sync read); XL430-W250
and XM430-W350 speak Protocol 2.0 (4096 steps a turn, profile velocity in 0.229 rpm steps,
sync read). Dynamixel positions grow counter-clockwise seen from the horn.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from footfall.errors import ConfigError

RPM = 2.0 * math.pi / 60.0  # [rad/s] per rpm


@dataclass(frozen=True)
class Register:
    """One entry of a control table.

    Attributes:
        address: Its first byte.
        size: Bytes (1, 2 or 4, little-endian).
        signed: Two's complement (Protocol 2.0 velocities and currents).
        writable: Whether a host may write it.
    """

    address: int
    size: int
    signed: bool = False
    writable: bool = False


@dataclass(frozen=True)
class ServoModel:
    """What footfall needs to know of one Dynamixel model.

    Attributes:
        name: Model name as ROBOTIS writes it.
        protocol: 1 or 2.
        model_number: What the servo reports at address 0.
        position_steps: Raw steps over ``position_range`` (1024 or 4096).
        position_range: Angle the steps span [rad].
        speed_step: One step of moving speed or profile velocity [rad/s].
        speed_steps: The largest moving speed or profile velocity a host may write (0 is
            no limit: the motor's top speed).
        no_load_speed: Top speed at the nominal voltage [rad/s].
        stall_torque: At the nominal voltage [N m].
        load_step: One step of present load, as a fraction of the stall torque.
        nominal_voltage: [V].
        temperature_limit: Default shutdown temperature [deg C].
        registers: Named entries of the control table.
    """

    name: str
    protocol: int
    model_number: int
    position_steps: int
    position_range: float
    speed_step: float
    speed_steps: int
    no_load_speed: float
    stall_torque: float
    load_step: float
    nominal_voltage: float
    temperature_limit: int
    registers: dict[str, Register]

    @property
    def steps_per_rad(self) -> float:
        """Position steps per radian."""
        return self.position_steps / self.position_range

    @property
    def centre(self) -> int:
        """The step at the middle of the range (the servo's zero)."""
        return self.position_steps // 2

    def register(self, name: str) -> Register:
        """The register ``name``."""
        return self.registers[name]

    @property
    def table_size(self) -> int:
        """Bytes of the control table footfall emulates."""
        return max(r.address + r.size for r in self.registers.values())


def _protocol1_table(extra: dict[str, Register] | None = None) -> dict[str, Register]:
    w = {"writable": True}
    table = {
        "model_number": Register(0, 2),
        "firmware": Register(2, 1),
        "id": Register(3, 1, **w),
        "baud_rate": Register(4, 1, **w),
        "return_delay": Register(5, 1, **w),  # [2 us]
        "cw_angle_limit": Register(6, 2, **w),
        "ccw_angle_limit": Register(8, 2, **w),
        "temperature_limit": Register(11, 1, **w),
        "min_voltage": Register(12, 1, **w),
        "max_voltage": Register(13, 1, **w),
        "max_torque": Register(14, 2, **w),
        "status_return_level": Register(16, 1, **w),
        "alarm_led": Register(17, 1, **w),
        "shutdown": Register(18, 1, **w),
        "torque_enable": Register(24, 1, **w),
        "led": Register(25, 1, **w),
        "goal_position": Register(30, 2, **w),
        "moving_speed": Register(32, 2, **w),
        "torque_limit": Register(34, 2, **w),
        "present_position": Register(36, 2),
        "present_speed": Register(38, 2),
        "present_load": Register(40, 2),
        "present_voltage": Register(42, 1),  # [0.1 V]
        "present_temperature": Register(43, 1),  # [deg C]
        "moving": Register(46, 1),
        "lock": Register(47, 1, **w),
        "punch": Register(48, 2, **w),
    }
    return table | (extra or {})


def _protocol2_table() -> dict[str, Register]:
    w = {"writable": True}
    return {
        "model_number": Register(0, 2),
        "firmware": Register(6, 1),
        "id": Register(7, 1, **w),
        "baud_rate": Register(8, 1, **w),
        "return_delay": Register(9, 1, **w),  # [2 us]
        "operating_mode": Register(11, 1, **w),
        "temperature_limit": Register(31, 1, **w),
        "max_voltage": Register(32, 2, **w),
        "min_voltage": Register(34, 2, **w),
        "max_position": Register(48, 4, **w),
        "min_position": Register(52, 4, **w),
        "shutdown": Register(63, 1, **w),
        "torque_enable": Register(64, 1, **w),
        "led": Register(65, 1, **w),
        "status_return_level": Register(68, 1, **w),
        "hardware_error": Register(70, 1),
        "profile_acceleration": Register(108, 4, **w),
        "profile_velocity": Register(112, 4, **w),
        "goal_position": Register(116, 4, **w),
        "moving": Register(122, 1),
        "present_load": Register(126, 2, signed=True),  # current or load, by model
        "present_speed": Register(128, 4, signed=True),
        "present_position": Register(132, 4, signed=True),
        "present_voltage": Register(144, 2),  # [0.1 V]
        "present_temperature": Register(146, 1),  # [deg C]
    }


_P1_RANGE = math.radians(300.0)
MODELS: dict[str, ServoModel] = {
    m.name: m
    for m in (
        ServoModel(
            "AX-12A", 1, 12, 1024, _P1_RANGE, 0.111 * RPM, 1023, 59 * RPM, 1.5, 0.001, 12.0, 70,
            _protocol1_table(),
        ),
        ServoModel(
            "AX-18A", 1, 18, 1024, _P1_RANGE, 0.111 * RPM, 1023, 97 * RPM, 1.8, 0.001, 12.0, 75,
            _protocol1_table(),
        ),
        ServoModel(
            "RX-64", 1, 64, 1024, _P1_RANGE, 0.111 * RPM, 1023, 64 * RPM, 6.4, 0.001, 18.0, 80,
            _protocol1_table(),
        ),
        ServoModel(
            "XL430-W250", 2, 1060, 4096, 2 * math.pi, 0.229 * RPM, 32767, 57 * RPM, 1.5, 0.001,
            12.0, 72, _protocol2_table(),
        ),
        ServoModel(
            # Present current in 2.69 mA steps; its stall current is 2.3 A.
            "XM430-W350", 2, 1020, 4096, 2 * math.pi, 0.229 * RPM, 32767, 46 * RPM, 4.1,
            0.00269 / 2.3, 12.0, 80, _protocol2_table(),
        ),
    )
}  # fmt: skip

# The model a protocol's emulated bus gives every joint when the robot names none.
DEFAULT_MODELS = {1: "AX-12A", 2: "XM430-W350"}


def servo_model(name: str) -> ServoModel:
    """The model called ``name``.

    Raises:
        ConfigError: For a model footfall does not know, listing the known ones.
    """
    try:
        return MODELS[name]
    except KeyError:
        raise ConfigError(
            f"servo model {name!r} is not one footfall knows; choose from {', '.join(MODELS)}"
        ) from None
