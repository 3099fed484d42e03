"""An emulated Dynamixel bus on a pseudo-terminal: the servos, without the robot.

The host opens the pseudo-terminal's path as it would a U2D2 or USB2AX adapter
(``dynamixel-sdk``'s ``PortHandler`` does) and talks Protocol 1.0 or 2.0 to it; a thread on
the other end cuts the bytes into instruction packets and answers as the servos of
:mod:`footfall.hardware.emulated_servos` would: status packets with their errors, each after
the servo's return delay and the time its bytes take at the bus's baud rate (the byte
clock). The clock also counts what the bus carried, for its budget: bytes and wire time of
writes and of reads.
"""

from __future__ import annotations

import contextlib
import os
import select
import threading
import time
import tty
from dataclasses import dataclass
from pathlib import Path

from footfall.errors import ConfigError
from footfall.hardware.emulated_servos import EmulatedServo, EmulatedServos
from footfall.hardware.protocol import (
    ACTION,
    BROADCAST_ID,
    P1_CHECKSUM,
    P1_INSTRUCTION,
    P1_RANGE,
    P2_ACCESS,
    P2_CRC,
    P2_INSTRUCTION,
    PING,
    READ,
    REG_WRITE,
    SYNC_READ,
    SYNC_WRITE,
    WRITE,
    Instruction,
    PacketReader,
    status_packet,
)

_WRITES = (WRITE, SYNC_WRITE, REG_WRITE, ACTION)
# Where the servos' control tables end (AX-12A's at 50, X series' at 661).
TABLE_END = {1: 50, 2: 662}
# A packet whose bytes stop coming for this long is dropped, as a servo's receiver does [s].
QUIET_LINE_S = 0.02


@dataclass
class WireCounts:
    """What the bus carried, by the emulator's byte clock.

    Attributes:
        packets: Instruction and status packets.
        write_bytes: Bytes of write instructions and their status packets.
        read_bytes: Bytes of read and ping instructions and their status packets.
        write_seconds: Wire time of the writes, return delays included [s].
        read_seconds: Wire time of the reads, return delays included [s].
        errors: Status packets that reported an error, and instructions that arrived
            corrupted.
    """

    packets: int = 0
    write_bytes: int = 0
    read_bytes: int = 0
    write_seconds: float = 0.0
    read_seconds: float = 0.0
    errors: int = 0

    def copy(self) -> WireCounts:
        """A snapshot."""
        return WireCounts(**vars(self))

    def __sub__(self, other: WireCounts) -> WireCounts:
        return WireCounts(**{k: v - getattr(other, k) for k, v in vars(self).items()})


class EmulatedBus:
    """Servos answering on a pseudo-terminal.

    Args:
        servos: The servos and the joints they turn.
        link: A symbolic link to create to the pseudo-terminal (a stable name, like
            ``/dev/serial/by-id/...``), removed on close; None for none.
        pace: Answer no sooner than the byte clock allows (False answers at once).
    """

    def __init__(self, servos: EmulatedServos, link: Path | None = None, pace: bool = True):
        self.servos = servos
        self.config = servos.config
        self.protocol = self.config.protocol
        self.pace = pace
        self.counts = WireCounts()
        self._reader = PacketReader(self.protocol)
        self._master, self._slave = os.openpty()
        tty.setraw(self._slave)  # no echo or line editing before a client configures it
        self.path = os.ttyname(self._slave)
        self.link = link
        if link is not None:
            link = Path(link)
            if link.exists() and not link.is_symlink():
                os.close(self._master)
                os.close(self._slave)
                raise ConfigError(f"{link} exists and is not a link: choose another --link")
            if link.is_symlink():
                link.unlink()
            link.symlink_to(self.path)
        self._stop = threading.Event()
        self._wire_free = 0.0
        self._thread = threading.Thread(target=self._serve, name="servo-bus", daemon=True)
        self._thread.start()

    @property
    def port(self) -> str:
        """The path a host opens: the link, else the pseudo-terminal."""
        return str(self.link) if self.link is not None else self.path

    def close(self) -> None:
        """Stop answering and release the pseudo-terminal and the link."""
        self._stop.set()
        self._thread.join(timeout=2.0)
        self.close_port()
        with contextlib.suppress(OSError):
            os.close(self._slave)
        if self.link is not None and Path(self.link).is_symlink():
            Path(self.link).unlink()

    def close_port(self) -> None:
        """Hang up, as an adapter pulled from its socket: the host's reads and writes fail."""
        self._stop.set()
        with contextlib.suppress(OSError):
            os.close(self._master)

    def silence(self, servo_id: int) -> None:
        """A servo stops hearing and answering (a broken cable): it holds its last goal."""
        self.servos.by_id[servo_id].answering = False

    def corrupt(self, servo_id: int) -> None:
        """A servo's status packets arrive with a wrong checksum or CRC (noise on the line)."""
        self.servos.by_id[servo_id].corrupt = True

    def _serve(self) -> None:
        while not self._stop.is_set():
            try:
                ready, _, _ = select.select([self._master], [], [], QUIET_LINE_S)
                data = os.read(self._master, 4096) if ready else b""
            except OSError:
                return  # hung up
            arrived = time.perf_counter()
            if data:
                instructions = self._reader.feed(data)
            elif self._reader.pending:
                # The line went quiet in the middle of a packet: it was noise, not a packet.
                instructions = self._reader.resync()
            else:
                continue
            for instruction in instructions:
                try:
                    self._answer(instruction, arrived)
                except (IndexError, ValueError):  # parameters too short for the instruction
                    self.counts.errors += 1

    def _answer(self, instruction: Instruction, arrived: float) -> None:
        byte_time = self.config.byte_time
        writes = instruction.code in _WRITES
        self.counts.packets += 1
        self._count(writes, instruction.size, instruction.size * byte_time)
        clock = max(arrived, self._wire_free)
        for servo, packet in self._statuses(instruction):
            wire = servo.return_delay + len(packet) * byte_time
            clock += wire
            self.counts.packets += 1
            self._count(writes, len(packet), wire)
            if self.pace:
                wait = clock - time.perf_counter()
                if wait > 0:
                    time.sleep(wait)
            try:
                os.write(self._master, packet)
            except OSError:
                return
        self._wire_free = clock

    def _count(self, writes: bool, size: int, seconds: float) -> None:
        if writes:
            self.counts.write_bytes += size
            self.counts.write_seconds += seconds
        else:
            self.counts.read_bytes += size
            self.counts.read_seconds += seconds

    def _statuses(self, inst: Instruction) -> list[tuple[EmulatedServo, bytes]]:
        """The status packets an instruction draws, in the order the servos send them."""
        p1 = self.protocol == 1
        if inst.servo_id == BROADCAST_ID:
            if not inst.intact:
                self.counts.errors += 1
                return []
            if inst.code == SYNC_WRITE:
                self._sync_write(inst.params)
                return []
            if inst.code == SYNC_READ and not p1:
                return self._sync_read(inst.params)
            return []
        servo = self.servos.by_id.get(inst.servo_id)
        if servo is None or not servo.answering:
            return []
        if not inst.intact:
            self.counts.errors += 1
            return [self._status(servo, P1_CHECKSUM if p1 else P2_CRC)]
        params = inst.params
        if inst.code == PING:
            data = b"" if p1 else servo.table[0:2] + servo.table[6:7]
            return [self._status(servo, 0, bytes(data))]
        if inst.code == READ:
            if len(params) < (2 if p1 else 4):
                return [self._status(servo, P1_INSTRUCTION if p1 else P2_INSTRUCTION)]
            address, size = (params[0], params[1]) if p1 else _words(params, 2)
            if address + size > TABLE_END[self.protocol]:
                return [self._status(servo, P1_RANGE if p1 else P2_ACCESS)]
            if servo.status_level < 1:
                return []
            return [self._status(servo, 0, self.servos.read(servo, address, size))]
        if inst.code == WRITE:
            if len(params) < (1 if p1 else 2):
                return [self._status(servo, P1_INSTRUCTION if p1 else P2_INSTRUCTION)]
            address, data = (params[0], params[1:]) if p1 else (_words(params, 1)[0], params[2:])
            error = self.servos.write(servo, address, bytes(data))
            return [self._status(servo, error)] if servo.status_level >= 2 else []
        return [self._status(servo, P1_INSTRUCTION if p1 else P2_INSTRUCTION)]

    def _sync_write(self, params: bytes) -> None:
        p1 = self.protocol == 1
        address, size = (params[0], params[1]) if p1 else _words(params, 2)
        body = params[2:] if p1 else params[4:]
        for k in range(0, len(body) - size, size + 1):
            servo = self.servos.by_id.get(body[k])
            if servo is not None and servo.answering:
                if self.servos.write(servo, address, bytes(body[k + 1 : k + 1 + size])):
                    self.counts.errors += 1

    def _sync_read(self, params: bytes) -> list[tuple[EmulatedServo, bytes]]:
        address, size = _words(params, 2)
        if len(params) < 4 or address + size > TABLE_END[2]:
            self.counts.errors += 1
            return []
        statuses = []
        for servo_id in params[4:]:
            servo = self.servos.by_id.get(servo_id)
            if servo is not None and servo.answering:
                statuses.append(self._status(servo, 0, self.servos.read(servo, address, size)))
        return statuses

    def _status(self, servo: EmulatedServo, error: int, params: bytes = b"") -> tuple:
        error |= servo.error_byte()
        if error:
            self.counts.errors += 1
        packet = status_packet(self.protocol, servo.joint.servo_id, error, params)
        if servo.corrupt:
            packet = packet[:-1] + bytes([packet[-1] ^ 0x5A])
        return servo, packet


def _words(params: bytes, count: int) -> list[int]:
    """The first ``count`` little-endian 16-bit words of Protocol 2.0 parameters."""
    return [int.from_bytes(params[2 * k : 2 * k + 2], "little") for k in range(count)]
