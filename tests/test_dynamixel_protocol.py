"""The emulated servos' side of Dynamixel Protocol 1.0 and 2.0 against ROBOTIS' SDK."""

from __future__ import annotations

import itertools

import dynamixel_sdk as sdk
import pytest
from hypothesis import given
from hypothesis import strategies as st

from footfall.hardware.protocol import (
    PacketReader,
    crc16,
    status_packet,
    stuff,
    unstuff,
)


class RecordingPort:
    """The part of a PortHandler the SDK's txPacket uses, keeping what it writes."""

    def __init__(self) -> None:
        self.is_using = False
        self.written = b""

    def clearPort(self) -> None:  # noqa: N802 (the SDK's name)
        """Nothing to clear."""

    def writePort(self, packet) -> int:  # noqa: N802
        """Keep the bytes."""
        self.written += bytes(packet)
        return len(packet)


def sdk_instruction(protocol: int, servo_id: int, code: int, params: bytes) -> bytes:
    """The bytes the SDK puts on the wire for an instruction."""
    port = RecordingPort()
    if protocol == 1:
        packet = [0] * (6 + len(params))
        packet[2], packet[3], packet[4] = servo_id, len(params) + 2, code
        packet[5 : 5 + len(params)] = params
        assert sdk.Protocol1PacketHandler().txPacket(port, packet) == sdk.COMM_SUCCESS
    else:
        packet = [0] * (10 + len(params))
        length = len(params) + 3
        packet[4], packet[5], packet[6], packet[7] = servo_id, length & 0xFF, length >> 8, code
        packet[8 : 8 + len(params)] = params
        assert sdk.Protocol2PacketHandler().txPacket(port, packet) == sdk.COMM_SUCCESS
    return port.written


ids = st.integers(0, 0xFD)
params = st.binary(max_size=40)
# dynamixel-sdk 4.1 drops the stuffed copy of a packet it sends (addStuffing's result is
# not kept), so it cannot send FF FF FD in parameters; footfall's goals, speeds and ids
# never hold it. Stuffing is checked on status packets, which the SDK unstuffs.
unstuffed_params = params.filter(lambda b: b"\xff\xff\xfd" not in b)


@given(st.binary(max_size=300))
def test_crc_is_the_sdks(data: bytes) -> None:
    """The servo's CRC-16 is the one the SDK computes."""
    assert crc16(data) == sdk.Protocol2PacketHandler().updateCRC(0, list(data), len(data))


@given(st.binary(max_size=100).map(lambda b: b.replace(b"\xff", b"\xff\xff")))
def test_stuffing_round_trips(body: bytes) -> None:
    """Unstuffing undoes stuffing, and a stuffed body holds no bare FF FF FD."""
    stuffed = stuff(body)
    assert unstuff(stuffed) == body
    assert b"\xff\xff\xfd\xfd" in stuffed or b"\xff\xff\xfd" not in stuffed


@pytest.mark.parametrize("protocol", [1, 2])
@given(
    packets=st.lists(
        st.tuples(ids, st.integers(1, 0x93), unstuffed_params), min_size=1, max_size=5
    ),
    garbage=st.binary(max_size=8).filter(lambda b: b"\xff" not in b),
    cuts=st.lists(st.integers(0, 400), max_size=6),
)
def test_reader_cuts_sdk_packets_from_any_chunks(protocol, packets, garbage, cuts) -> None:
    """Instruction packets the SDK builds come out whole, however the bytes arrive."""
    stream = garbage + b"".join(sdk_instruction(protocol, *p) for p in packets)
    reader = PacketReader(protocol)
    heard = []
    edges = sorted({0, len(stream), *(c for c in cuts if c < len(stream))})
    for start, end in itertools.pairwise(edges):
        heard += reader.feed(stream[start:end])
    assert [(h.servo_id, h.code, h.params) for h in heard] == [
        (i, c, bytes(p)) for i, c, p in packets
    ]
    assert all(h.intact for h in heard)
    assert sum(h.size for h in heard) == len(stream) - len(garbage)


@pytest.mark.parametrize("protocol", [1, 2])
@given(servo_id=ids, params=unstuffed_params, flip=st.integers(0, 10_000))
def test_a_corrupted_byte_fails_the_check(protocol, servo_id, params, flip) -> None:
    """A packet with one byte changed after the header is heard as not intact (or not at all)."""
    packet = bytearray(sdk_instruction(protocol, servo_id, 0x03, params))
    header = 4 if protocol == 1 else 7  # keep the header and length so a packet is cut
    k = header + flip % (len(packet) - header)
    packet[k] ^= 0x01
    heard = PacketReader(protocol).feed(bytes(packet))
    assert not heard or not heard[0].intact or heard[0].params != bytes(params)


@pytest.mark.parametrize("protocol", [1, 2])
@given(servo_id=st.integers(0, 0xFC), error=st.integers(0, 0x7F), params=params)
def test_status_packets_are_what_the_sdk_reads(protocol, servo_id, error, params) -> None:
    """A status packet decodes in the SDK's receiver with its id, error and parameters."""
    packet = status_packet(protocol, servo_id, error, params)

    class Replay:
        is_using = True
        data = packet

        def readPort(self, length):  # noqa: N802 (the SDK's names)
            out, self.data = self.data[:length], self.data[length:]
            return out

        def isPacketTimeout(self):  # noqa: N802
            return not self.data

    handler = sdk.Protocol1PacketHandler() if protocol == 1 else sdk.Protocol2PacketHandler()
    extra = () if protocol == 1 else (False,)  # not a fast sync read
    received, result = handler.rxPacket(Replay(), *extra)
    assert result == sdk.COMM_SUCCESS
    if protocol == 1:
        assert (received[2], received[4], bytes(received[5:-1])) == (servo_id, error, params)
    else:
        assert (received[4], received[8]) == (servo_id, error)
        length = received[5] | received[6] << 8  # instruction, error, parameters, CRC
        assert bytes(received[9 : 9 + length - 4]) == params
