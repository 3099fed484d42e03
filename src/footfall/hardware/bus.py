"""A Dynamixel bus seen from the host: the port, the servos on it, what they last said.

:class:`DynamixelBus` wraps ROBOTIS' ``dynamixel-sdk`` (its ``PortHandler``, packet
handlers and sync write group): it finds and checks the servos, writes goals in one sync
write, reads back on the :class:`~footfall.hardware.schedule.ReadSchedule`, and turns a
servo's error bits, missing or corrupted status packets and a failing port into
:class:`~footfall.errors.BackendError` naming the servo and the cause.
"""

from __future__ import annotations

import math
import termios

import numpy as np
import numpy.typing as npt

from footfall.errors import BackendError, ConfigError
from footfall.hardware.config import HardwareConfig, JointServo
from footfall.hardware.protocol import (
    HARDWARE_ERROR_TEXTS,
    P1_ERROR_TEXTS,
    P2_ALERT,
    P2_RESULT_TEXTS,
)
from footfall.hardware.schedule import ReadSchedule

# What a failing port raises: pyserial's SerialException is an OSError; flushing a
# pseudo-terminal (or adapter) that hung up raises termios' own error.
PORT_ERRORS = (OSError, termios.error)
# A servo that misses this many status packets in a row has stopped answering.
MISSES_ALLOWED = 2


class DynamixelBus:
    """The servos of one bus, through ``dynamixel-sdk``.

    Args:
        config: The bus and its servos.
        control_period: The control loop's period, for the read schedule [s].

    Attributes:
        positions: Joint angles as last read, shape (18,) [rad].
        velocities: Joint rates as last read [rad/s].
        loads: Servo loads as last read, fractions of their stall torque.
        voltages: Supply voltages as last read [V] (NaN before the first read).
        temperatures: Temperatures as last read [deg C].
        over_speed: Goals sent faster than their servo's no-load speed.
        fault: Why the bus cannot go on, or "".

    Raises:
        BackendError: When the port does not open, a servo does not answer or is another
            model than the configuration says.
    """

    def __init__(self, config: HardwareConfig, control_period: float = 0.01) -> None:
        try:
            import dynamixel_sdk as sdk
        except ImportError as exc:
            raise ConfigError(
                "the Dynamixel bus needs ROBOTIS' dynamixel-sdk: install footfall[hardware]"
            ) from exc

        self._sdk = sdk
        self.config = config
        self.schedule = ReadSchedule.fitting(config, control_period)
        self.port = sdk.PortHandler(config.port)
        try:
            opened = self.port.openPort() and self.port.setBaudRate(config.baud)
        except PORT_ERRORS as exc:
            raise BackendError(f"servo bus port {config.port!r} does not open: {exc}") from exc
        if not opened:
            raise BackendError(f"servo bus port {config.port!r} does not open")
        self.packets = sdk.PacketHandler(float(config.protocol))
        self.servos = config.servos
        n = len(self.servos)
        self.positions = np.zeros(n)
        self.velocities = np.zeros(n)
        self.loads = np.zeros(n)
        self.voltages = np.full(n, np.nan)
        self.temperatures = np.full(n, np.nan)
        self.over_speed = 0
        self.fault = ""
        self._misses = np.zeros(n, dtype=int)
        self._index = {s.servo_id: i for i, s in enumerate(self.servos)}
        self._next = 0
        self._start()

    def _start(self) -> None:
        """Find every servo, check its model, set its return delay; read where it is."""
        missing = []
        for servo in self.servos:
            number, result, _ = self._call(self.packets.ping, servo.servo_id)
            if result != self._sdk.COMM_SUCCESS:
                missing.append(servo.name)
            elif number != servo.model.model_number:
                raise BackendError(
                    f"{servo.name} is model number {number}, not a {servo.model.name} "
                    f"({servo.model.model_number}); check [hardware] in the robot's TOML"
                )
        if missing:
            raise BackendError(f"no answer from {', '.join(missing)} on {self.config.port}")
        delay = round(self.config.return_delay / 2e-6)
        for servo in self.servos:
            if self.read(servo, "return_delay") != delay:
                self.write(servo, "return_delay", delay)
            if servo.model.protocol == 2 and self.read(servo, "operating_mode") != 3:
                self.write(servo, "torque_enable", 0)
                self.write(servo, "operating_mode", 3)  # position control
        self.poll_all()

    def _call(self, function, *args):
        """An SDK call; a failing port becomes a BackendError."""
        try:
            return function(self.port, *args)
        except PORT_ERRORS as exc:
            self.fault = f"servo bus port {self.config.port} failed: {exc}"
            raise BackendError(self.fault) from exc

    def read(self, servo: JointServo, name: str) -> int:
        """A register of one servo."""
        r = servo.model.register(name)
        read = {1: self.packets.read1ByteTxRx, 2: self.packets.read2ByteTxRx}
        value, result, error = self._call(
            read.get(r.size, self.packets.read4ByteTxRx), servo.servo_id, r.address
        )
        self._check(servo, result, error)
        return value

    def write(self, servo: JointServo, name: str, value: int) -> None:
        """Write a register of one servo."""
        r = servo.model.register(name)
        write = {1: self.packets.write1ByteTxRx, 2: self.packets.write2ByteTxRx}
        result, error = self._call(
            write.get(r.size, self.packets.write4ByteTxRx), servo.servo_id, r.address, value
        )
        self._check(servo, result, error)

    def torque_enabled(self) -> list[bool]:
        """Each servo's torque as it says (a round trip to every servo)."""
        return [bool(self.read(s, "torque_enable")) for s in self.servos]

    def close(self) -> None:
        """Release the port."""
        if self.port.is_open:
            self.port.closePort()

    def send(self, goal: npt.NDArray[np.float64], speed: npt.NDArray[np.float64]) -> None:
        """Goal angles [rad] and speeds [rad/s], shape (18,), in one sync write."""
        data = []
        for servo, angle, rate in zip(self.servos, goal, speed, strict=True):
            model = servo.model
            steps = int(np.clip(servo.steps(float(angle)), 0, model.position_steps - 1))
            speed_steps = max(1, math.ceil(rate / model.speed_step))
            if speed_steps > model.speed_steps:
                speed_steps = 0  # faster than a speed can say: no limit
            if rate > model.no_load_speed:
                self.over_speed += 1
            if model.protocol == 1:
                data.append(steps.to_bytes(2, "little") + speed_steps.to_bytes(2, "little"))
            else:
                data.append(speed_steps.to_bytes(4, "little") + steps.to_bytes(4, "little"))
        first = "goal_position" if self.config.protocol == 1 else "profile_velocity"
        self.sync_write(first, data)

    def sync_write(self, register: str, values: list) -> None:
        """One value (or a block of bytes from ``register`` on) per servo, by sync write."""
        r = self.servos[0].model.register(register)
        size = len(values[0]) if isinstance(values[0], bytes) else r.size
        group = self._sdk.GroupSyncWrite(self.port, self.packets, r.address, size)
        for servo, value in zip(self.servos, values, strict=True):
            data = value if isinstance(value, bytes) else int(value).to_bytes(size, "little")
            group.addParam(servo.servo_id, list(data))
        result = self._call(lambda _port: group.txPacket())
        if result != self._sdk.COMM_SUCCESS:
            self.fault = f"servo bus port {self.config.port}: the sync write failed ({result})"
            raise BackendError(self.fault)

    def poll_all(self) -> None:
        """Read every servo once, a servo that missed its answer once more."""
        if self.config.protocol == 2 and not self._sync_read_motion():
            self._sync_read_motion()
        for i in range(len(self.servos)):
            if not self._read_state(i):
                self._read_state(i)

    def poll(self) -> None:
        """This tick's reads: some servos' state block (Protocol 1.0) or all (2.0)."""
        n = len(self.servos)
        chosen = [(self._next + k) % n for k in range(self.schedule.reads)]
        self._next = (self._next + self.schedule.reads) % n
        if self.config.protocol == 2:
            self._sync_read_motion()
        for i in chosen:
            self._read_state(i)

    def _read_state(self, i: int) -> bool:
        """One servo's state block; False when it did not answer.

        Protocol 1.0: position, speed, load, voltage, temperature; 2.0: voltage, temperature.
        """
        servo = self.servos[i]
        if servo.model.protocol == 1:
            data, result, error = self._call(self.packets.readTxRx, servo.servo_id, 36, 8)
            if not self._check(servo, result, error):
                return False
            self._decode_p1(i, bytes(data))
            return True
        data, result, error = self._call(self.packets.readTxRx, servo.servo_id, 144, 3)
        if not self._check(servo, result, error):
            return False
        self.voltages[i] = int.from_bytes(bytes(data[0:2]), "little") / 10.0
        self.temperatures[i] = data[2]
        return True

    def _sync_read_motion(self) -> bool:
        """Every servo's load, speed and position (addresses 126-135) in one sync read.

        The SDK's sync read group drops the status packets' error bytes, so the packets are
        sent and received one by one with its packet handler: a servo's hardware alert
        shows on the tick it happens. False when a servo did not answer (those after it
        are not heard then).
        """
        ids = [s.servo_id for s in self.servos]
        result = self._call(self.packets.syncReadTx, 126, 10, ids, len(ids), False)
        if result != self._sdk.COMM_SUCCESS:
            self.fault = f"servo bus port {self.config.port}: the sync read failed ({result})"
            raise BackendError(self.fault)
        for i, servo in enumerate(self.servos):
            data, result, error = self._call(self.packets.readRx, servo.servo_id, 10)
            if not self._check(servo, result, error):
                return False  # the servos after it wait for its status packet
            model = servo.model
            raw = bytes(data)
            load = int.from_bytes(raw[0:2], "little", signed=True)
            speed = int.from_bytes(raw[2:6], "little", signed=True)
            steps = int.from_bytes(raw[6:10], "little", signed=True)
            self.positions[i] = servo.angle(steps)
            self.velocities[i] = servo.direction * speed * model.speed_step
            self.loads[i] = servo.direction * load * model.load_step
        return True

    def _decode_p1(self, i: int, raw: bytes) -> None:
        servo = self.servos[i]
        model = servo.model
        steps = int.from_bytes(raw[0:2], "little")
        speed, load = (int.from_bytes(raw[k : k + 2], "little") for k in (2, 4))
        self.positions[i] = servo.angle(steps)
        self.velocities[i] = servo.direction * _p1_value(speed) * model.speed_step
        self.loads[i] = servo.direction * _p1_value(load) * model.load_step
        self.voltages[i] = raw[6] / 10.0
        self.temperatures[i] = raw[7]

    def _check(self, servo: JointServo, result: int, error: int) -> bool:
        """True for a good status packet; raises on a servo that cannot go on."""
        i = self._index[servo.servo_id]
        if result != self._sdk.COMM_SUCCESS:
            self._misses[i] += 1
            if self._misses[i] >= MISSES_ALLOWED:
                what = "corrupted" if result == self._sdk.COMM_RX_CORRUPT else "no"
                self.fault = (
                    f"{servo.name}: {what} status packets {self._misses[i]} times in a row "
                    f"({self.packets.getTxRxResult(result) or result})"
                )
                raise BackendError(self.fault)
            return False
        self._misses[i] = 0
        if error:
            self.fault = f"{servo.name}: {self._describe(servo, error)}"
            raise BackendError(self.fault)
        return True

    def _describe(self, servo: JointServo, error: int) -> str:
        if servo.model.protocol == 1:
            causes = [text for bit, text in P1_ERROR_TEXTS if error & bit]
        else:
            causes = [P2_RESULT_TEXTS[error & 0x7F]] if error & 0x7F in P2_RESULT_TEXTS else []
            if error & P2_ALERT:
                bits, _, _ = self._call(self.packets.read1ByteTxRx, servo.servo_id, 70)
                causes += [text for bit, text in HARDWARE_ERROR_TEXTS if bits & bit]
                causes = causes or ["a hardware alert"]
        return " and ".join(causes) + f" (error byte 0x{error:02x})"


def _p1_value(raw: int) -> int:
    """Protocol 1.0 speed or load: magnitude in bits 0-9, bit 10 clockwise (negative)."""
    return -(raw & 0x3FF) if raw & 0x400 else raw & 0x3FF
