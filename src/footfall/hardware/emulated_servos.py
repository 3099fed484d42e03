"""Emulated Dynamixel servos: control tables, and the joints they turn.

Each emulated servo keeps its model's control table (model number, id, return delay,
torque enable, goal position, moving speed or profile velocity, present position, speed,
load, voltage, temperature, the error state) and answers reads and writes as the real one
does. What it turns is a joint of a simulated robot: the simulator calls
:meth:`EmulatedServos.drive` every physics step for the position set-points and
:meth:`EmulatedServos.sense` after it, so that reads return where the joints are.

A servo moves as a Dynamixel does in position mode: its set-point runs toward the goal at
the moving speed (Protocol 2.0: the profile velocity), and the position controller feeds
that rate forward; a speed of 0 sets no limit, and the motor (the simulator's actuator)
goes as fast as it can. Faults make it misbehave as real ones
do: it stops answering, its status packets arrive corrupted, or it overheats (the error
bit set and, as the servo's shutdown setting does by default, its torque off).
"""

from __future__ import annotations

import threading

import numpy as np
import numpy.typing as npt

from footfall.hardware.config import HardwareConfig, JointServo
from footfall.hardware.protocol import (
    HW_OVERHEAT,
    HW_OVERLOAD,
    P1_OVERHEAT,
    P1_OVERLOAD,
    P1_RANGE,
    P2_ACCESS,
    P2_ALERT,
    P2_LIMIT,
)

ROOM_TEMPERATURE = 35  # what an emulated servo reports [deg C]
# The bit 10 of Protocol 1.0 present speed and load: turning or pushing clockwise.
P1_CLOCKWISE = 0x400


class EmulatedServo:
    """One servo's control table and state.

    Args:
        joint: The joint it turns, its id and model.
        index: Its joint's index in the robot (leg * 3 + joint).
        return_delay: Initial return delay time [s].
    """

    def __init__(self, joint: JointServo, index: int, return_delay: float) -> None:
        self.joint = joint
        self.model = joint.model
        self.index = index
        self.table = bytearray(self.model.table_size)
        self._writable = {
            a
            for r in self.model.registers.values()
            if r.writable
            for a in range(r.address, r.address + r.size)
        }
        self.answering = True  # False: a servo that stopped answering
        self.corrupt = False  # True: its status packets fail their checksum
        self.hardware_error = 0  # Protocol 2.0 hardware error bits
        self.temperature = ROOM_TEMPERATURE
        self.set("model_number", self.model.model_number)
        self.set("id", joint.servo_id)
        self.set("return_delay", round(return_delay / 2e-6))
        self.set("status_return_level", 2)
        self.set("temperature_limit", self.model.temperature_limit)
        if self.model.protocol == 1:
            self.set("ccw_angle_limit", self.model.position_steps - 1)
            self.set("shutdown", P1_OVERHEAT | P1_OVERLOAD)
        else:
            self.set("operating_mode", 3)  # position control
            self.set("max_position", self.model.position_steps - 1)
            self.set("shutdown", HW_OVERHEAT | HW_OVERLOAD)

    def get(self, name: str) -> int:
        """A register's value."""
        r = self.model.register(name)
        return int.from_bytes(self.table[r.address : r.address + r.size], "little", signed=r.signed)

    def set(self, name: str, value: int) -> None:
        """Set a register (the servo's own doing; no access check)."""
        r = self.model.register(name)
        self.table[r.address : r.address + r.size] = int(value).to_bytes(
            r.size, "little", signed=r.signed
        )

    @property
    def return_delay(self) -> float:
        """How long it waits before answering [s]."""
        return self.get("return_delay") * 2e-6

    @property
    def status_level(self) -> int:
        """0: answers pings only; 1: reads too; 2: every instruction to it."""
        return self.get("status_return_level")

    def error_byte(self) -> int:
        """The error field of its next status packet (its standing conditions)."""
        if self.model.protocol == 1:
            error = 0
            if self.temperature > self.get("temperature_limit"):
                error |= P1_OVERHEAT
            return error
        return P2_ALERT if self.hardware_error else 0

    def writable(self, address: int, size: int) -> bool:
        """Whether every byte from ``address`` on lies in a writable register."""
        return all(a in self._writable for a in range(address, address + size))


class EmulatedServos:
    """The servos on an emulated bus, and the joints of the robot they turn.

    Args:
        config: The bus: protocol, the servos and their joints.
    """

    def __init__(self, config: HardwareConfig) -> None:
        self.config = config
        self.servos = [
            EmulatedServo(s, i, config.return_delay) for i, s in enumerate(config.servos)
        ]
        self.by_id = {s.joint.servo_id: s for s in self.servos}
        n = len(self.servos)
        self.lock = threading.Lock()
        self.goal = np.zeros(n)  # [rad], footfall's angles
        self.speed_limit = np.full(n, np.inf)  # [rad/s]
        self.torque = np.zeros(n, dtype=bool)
        self.setpoint = np.zeros(n)  # [rad]
        self.setpoint_rate = np.zeros(n)  # [rad/s]
        self.position = np.zeros(n)  # [rad]
        self.velocity = np.zeros(n)  # [rad/s]
        self.effort = np.zeros(n)  # [N m]

    def start(self, positions: npt.ArrayLike, torque: bool) -> None:
        """Power on at joint angles ``positions`` (shape (18,)): goals where the joints are."""
        with self.lock:
            self.position[:] = np.asarray(positions, dtype=float).ravel()
            self.setpoint[:] = self.position
            self.goal[:] = self.position
            self.torque[:] = torque
            for s in self.servos:
                s.set("goal_position", s.joint.steps(self.position[s.index]))
                s.set("torque_enable", int(torque))
                self._refresh(s)

    def drive(self, dt: float) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
        """Move the set-points toward their goals for ``dt`` seconds [s].

        Returns:
            Set-points [rad] and their rates [rad/s], shape (18,) each; the caller's position
            controller tracks them (its torque off where :attr:`torque` is False).
        """
        with self.lock:
            step = np.clip(self.goal - self.setpoint, -self.speed_limit * dt, self.speed_limit * dt)
            self.setpoint += step
            self.setpoint_rate = step / dt if dt > 0 else np.zeros_like(step)
            self.setpoint[~self.torque] = self.position[~self.torque]
            return self.setpoint.copy(), self.setpoint_rate.copy()

    def sense(self, positions: npt.ArrayLike, velocities: npt.ArrayLike, efforts: npt.ArrayLike):
        """Where the joints are [rad], how fast [rad/s] and the servos' torques [N m]."""
        with self.lock:
            self.position[:] = np.ravel(positions)
            self.velocity[:] = np.ravel(velocities)
            self.effort[:] = np.ravel(efforts)

    def overheat(self, servo_id: int) -> None:
        """Make a servo overheat: its error bit set and, by its shutdown setting, torque off."""
        with self.lock:
            s = self.by_id[servo_id]
            s.temperature = s.get("temperature_limit") + 5
            s.hardware_error |= HW_OVERHEAT
            if s.model.protocol == 2:
                s.set("hardware_error", s.hardware_error)
            s.set("torque_enable", 0)
            self.torque[s.index] = False

    def read(self, servo: EmulatedServo, address: int, size: int) -> bytes:
        """The bytes of its table from ``address`` (present values refreshed).

        Registers footfall does not emulate read as zeros.
        """
        with self.lock:
            self._refresh(servo)
            return bytes(servo.table[address : address + size]).ljust(size, b"\0")

    def write(self, servo: EmulatedServo, address: int, data: bytes) -> int:
        """Write bytes into its table; the error of the status packet (0 when accepted)."""
        protocol = servo.model.protocol
        if address + len(data) > len(servo.table) or not servo.writable(address, len(data)):
            return P1_RANGE if protocol == 1 else P2_ACCESS
        with self.lock:
            old = bytes(servo.table)
            servo.table[address : address + len(data)] = data
            goal = servo.get("goal_position")
            low, high = 0, servo.model.position_steps - 1
            if protocol == 2:
                low, high = servo.get("min_position"), servo.get("max_position")
            if not low <= goal <= high:
                servo.table[:] = old
                return P1_RANGE if protocol == 1 else P2_LIMIT
            torque_before = self.torque[servo.index]
            on = servo.get("torque_enable") != 0 and not servo.hardware_error
            self.torque[servo.index] = on
            if on and not torque_before:
                # The profile starts where the horn is.
                self.setpoint[servo.index] = self.position[servo.index]
            self.goal[servo.index] = servo.joint.angle(goal)
            speed = servo.get("moving_speed" if protocol == 1 else "profile_velocity")
            if protocol == 1:
                speed &= 0x3FF
            # 0 sets no profile: the joint moves as fast as its motor (the simulator) can.
            self.speed_limit[servo.index] = speed * servo.model.speed_step if speed else np.inf
        return 0

    def _refresh(self, s: EmulatedServo) -> None:
        """Present position, speed, load, voltage and temperature from the joint."""
        i, model, joint = s.index, s.model, s.joint
        steps = joint.steps(self.position[i])
        s.set("present_position", int(np.clip(steps, 0, model.position_steps - 1)))
        speed = joint.direction * self.velocity[i] / model.speed_step
        load = joint.direction * self.effort[i] / model.stall_torque / model.load_step
        if model.protocol == 1:
            s.set("present_speed", _p1_signed(speed))
            s.set("present_load", _p1_signed(load))
            s.set("present_voltage", round(model.nominal_voltage * 10))
        else:
            s.set("present_speed", round(speed))
            s.set("present_load", int(np.clip(round(load), -32768, 32767)))
            s.set("present_voltage", round(model.nominal_voltage * 10))
        s.set("present_temperature", s.temperature)
        s.set("moving", int(abs(self.goal[i] - self.setpoint[i]) > 1.0 / model.steps_per_rad))


def _p1_signed(value: float) -> int:
    """Protocol 1.0's magnitude-and-direction encoding (bit 10: clockwise)."""
    magnitude = min(1023, round(abs(value)))
    return magnitude | (P1_CLOCKWISE if value < 0 else 0)
