"""The servo's side of Dynamixel Protocol 1.0 and 2.0: instruction packets in, status out.

The host's side is ROBOTIS' ``dynamixel-sdk``; this is what a servo does with the bytes
it hears, for the emulated bus (:mod:`footfall.hardware.emulator`).

Protocol 1.0: ``FF FF ID LEN INST PARAMS... CHECKSUM`` with ``LEN`` = parameters + 2 and
the checksum the low byte of the inverted sum of ``ID`` to the last parameter; a status
packet has the error byte where the instruction was. Protocol 2.0: ``FF FF FD 00 ID LEN_L
LEN_H INST PARAMS... CRC_L CRC_H`` with ``LEN`` = parameters + 3, byte stuffing (``FD``
after every ``FF FF FD`` from the instruction on) and a CRC-16 (polynomial 0x8005) over
everything before it; a status packet is instruction ``0x55`` then the error byte.
"""

from __future__ import annotations

from dataclasses import dataclass

BROADCAST_ID = 0xFE

PING, READ, WRITE, REG_WRITE, ACTION, RESET = 0x01, 0x02, 0x03, 0x04, 0x05, 0x06
REBOOT, STATUS, SYNC_READ, SYNC_WRITE, BULK_READ, BULK_WRITE = 0x08, 0x55, 0x82, 0x83, 0x92, 0x93

# Protocol 1.0 status error bits.
P1_VOLTAGE, P1_ANGLE, P1_OVERHEAT, P1_RANGE = 0x01, 0x02, 0x04, 0x08
P1_CHECKSUM, P1_OVERLOAD, P1_INSTRUCTION = 0x10, 0x20, 0x40
# Protocol 2.0 status error codes (low 7 bits) and the alert bit (a hardware error).
P2_RESULT_FAIL, P2_INSTRUCTION, P2_CRC, P2_RANGE = 0x01, 0x02, 0x03, 0x04
P2_LENGTH, P2_LIMIT, P2_ACCESS, P2_ALERT = 0x05, 0x06, 0x07, 0x80
# Protocol 2.0 hardware error status bits (address 70).
HW_VOLTAGE, HW_OVERHEAT, HW_ENCODER, HW_SHOCK, HW_OVERLOAD = 0x01, 0x04, 0x08, 0x10, 0x20

# What the error bits and codes mean, for messages.
P1_ERROR_TEXTS = (
    (0x01, "input voltage out of range"),
    (0x02, "goal outside its angle limits"),
    (0x04, "overheating"),
    (0x08, "a value out of range"),
    (0x10, "a corrupted instruction (checksum)"),
    (0x20, "overload"),
    (0x40, "an unknown instruction"),
)
P2_RESULT_TEXTS = {
    1: "a failed instruction",
    2: "an unknown instruction",
    3: "a corrupted instruction (CRC)",
    4: "a value out of range",
    5: "a wrong data length",
    6: "a value over its limit",
    7: "a write to a read-only register",
}
HARDWARE_ERROR_TEXTS = (
    (HW_VOLTAGE, "input voltage out of range"),
    (HW_OVERHEAT, "overheating"),
    (HW_ENCODER, "a motor encoder fault"),
    (HW_SHOCK, "an electrical shock"),
    (HW_OVERLOAD, "overload"),
)

_HEADER1 = b"\xff\xff"
_HEADER2 = b"\xff\xff\xfd\x00"


def checksum1(body: bytes) -> int:
    """Protocol 1.0 checksum of the bytes from ``ID`` to the last parameter."""
    return ~sum(body) & 0xFF


def _crc_table() -> list[int]:
    table = []
    for i in range(256):
        crc = i << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x8005) if crc & 0x8000 else crc << 1
        table.append(crc & 0xFFFF)
    return table


_CRC_TABLE = _crc_table()


def crc16(data: bytes) -> int:
    """Protocol 2.0 CRC-16 (polynomial 0x8005, initial 0, not reflected)."""
    crc = 0
    for byte in data:
        crc = ((crc << 8) ^ _CRC_TABLE[((crc >> 8) ^ byte) & 0xFF]) & 0xFFFF
    return crc


def stuff(body: bytes) -> bytes:
    """Protocol 2.0 byte stuffing: ``FD`` added after every ``FF FF FD``."""
    return body.replace(b"\xff\xff\xfd", b"\xff\xff\xfd\xfd")


def unstuff(body: bytes) -> bytes:
    """Undo :func:`stuff`."""
    return body.replace(b"\xff\xff\xfd\xfd", b"\xff\xff\xfd")


@dataclass(frozen=True)
class Instruction:
    """One instruction packet as a servo hears it.

    Attributes:
        servo_id: Addressee (``BROADCAST_ID`` for all).
        code: The instruction (``READ``, ``SYNC_WRITE``...).
        params: Its parameters (unstuffed).
        intact: Whether its checksum or CRC was right.
        size: Bytes it took on the wire.
    """

    servo_id: int
    code: int
    params: bytes
    intact: bool
    size: int


def status_packet(protocol: int, servo_id: int, error: int, params: bytes = b"") -> bytes:
    """A servo's status packet."""
    if protocol == 1:
        body = bytes([servo_id, len(params) + 2, error]) + params
        return _HEADER1 + body + bytes([checksum1(body)])
    inner = stuff(bytes([STATUS, error]) + params)
    packet = _HEADER2 + bytes([servo_id]) + (len(inner) + 2).to_bytes(2, "little") + inner
    return packet + crc16(packet).to_bytes(2, "little")


class PacketReader:
    """Cuts a byte stream into instruction packets, as a servo's receiver does.

    Bytes before a header are dropped; a packet whose length runs past what has arrived
    waits for more. A packet with a wrong checksum is returned with ``intact`` False.

    Args:
        protocol: 1 or 2.
    """

    def __init__(self, protocol: int) -> None:
        if protocol not in (1, 2):
            raise ValueError(f"Dynamixel protocol {protocol} is not 1 or 2")
        self.protocol = protocol
        self._buffer = bytearray()
        self.dropped = 0  # bytes thrown away before a header

    @property
    def pending(self) -> int:
        """Bytes held for a packet not yet complete."""
        return len(self._buffer)

    def resync(self) -> list[Instruction]:
        """Give up on the packet being received: drop its first byte and look again.

        For a line gone quiet mid-packet, as after noise that looked like a header.
        """
        if self._buffer:
            self.dropped += 1
            del self._buffer[0]
        return self.feed(b"")

    def feed(self, data: bytes) -> list[Instruction]:
        """Add received bytes; the packets now complete."""
        self._buffer += data
        packets = []
        while (packet := self._next()) is not None:
            packets.append(packet)
        return packets

    def _next(self) -> Instruction | None:
        header = _HEADER1 if self.protocol == 1 else _HEADER2
        start = self._buffer.find(header)
        if start < 0:
            keep = len(header) - 1  # a header may be arriving
            if len(self._buffer) > keep:
                self.dropped += len(self._buffer) - keep
                del self._buffer[: len(self._buffer) - keep]
            return None
        if start:
            self.dropped += start
            del self._buffer[:start]
        return self._next1() if self.protocol == 1 else self._next2()

    def _next1(self) -> Instruction | None:
        buf = self._buffer
        if len(buf) < 4:
            return None
        if buf[2] == 0xFF:  # a third FF: the header starts one byte on
            self.dropped += 1
            del buf[0]
            return None if len(buf) < 4 else self._next1()
        total = buf[3] + 4
        if buf[3] < 2:
            self.dropped += 2
            del buf[:2]
            return None
        if len(buf) < total:
            return None
        packet = bytes(buf[:total])
        del buf[:total]
        intact = checksum1(packet[2:-1]) == packet[-1]
        return Instruction(packet[2], packet[4], packet[5:-1], intact, total)

    def _next2(self) -> Instruction | None:
        buf = self._buffer
        if len(buf) < 7:
            return None
        length = int.from_bytes(buf[5:7], "little")
        total = length + 7
        if length < 3:
            self.dropped += 4
            del buf[:4]
            return None
        if len(buf) < total:
            return None
        packet = bytes(buf[:total])
        del buf[:total]
        intact = crc16(packet[:-2]) == int.from_bytes(packet[-2:], "little")
        body = unstuff(packet[7:-2])
        return Instruction(packet[4], body[0], body[1:], intact, total)
