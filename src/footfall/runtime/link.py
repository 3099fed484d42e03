"""The radio link's two ends: what the robot sends when, and what the station makes of it.

**Priorities.** Each topic has a zenoh priority (:data:`PRIORITIES`): commands, the mode and
the link's own acknowledgements travel at ``REAL_TIME`` (batched: a mode and a command sent
together share a TCP segment, and on TCP every segment the station's side loses holds up
what follows it), the robot's status, state, pose and log at ``INTERACTIVE_HIGH``,
``express`` (sent at once). The map,
depth and colour travel at ``DATA_LOW``. Zenoh keeps a queue per priority and empties the
higher ones first, so a command never waits behind an image in the sender's queues. Every
publisher uses congestion control ``DROP``: a control loop must never block on a slow link.

**Bulk topics** (map, depth, colour) go through :class:`LinkSender`: one message waits per
topic and a newer one replaces it (the replaced one is counted as dropped: newest kept).
While a receiver acknowledges what it gets (a footfall bus does, :class:`LinkAck`), the
sender keeps the bytes in flight (sent, not yet acknowledged) within a window of what the
link delivered in the last second times the round trip, the acknowledgements' interval
and ``TARGET_DELAY_S``: a slow
link gets fewer images rather than older ones, and the queues in front of the commands
(zenoh's, the kernel's, the radio's) stay short. Without acknowledgements (a plain
subscriber) every message goes at once. The map goes first, then depth, then colour.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections import defaultdict, deque
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from footfall.messages import ColorImage, DepthFrame, MapUpdate, Message
from footfall.messages.wire import LinkAck, PackedColor, PackedDepth, PackedMap, WholeMapRequest
from footfall.runtime.wire import (
    MapPacker,
    MapUnpacker,
    pack_color,
    pack_depth,
    unpack_color,
    unpack_depth,
)

# Topic -> (zenoh priority name, express). Topics not named travel at DATA.
PRIORITIES: dict[str, tuple[str, bool]] = {
    "command": ("REAL_TIME", False),
    "mode": ("REAL_TIME", False),
    LinkAck.TOPIC: ("REAL_TIME", False),
    WholeMapRequest.TOPIC: ("REAL_TIME", False),
    "status": ("INTERACTIVE_HIGH", True),
    "servo": ("INTERACTIVE_HIGH", True),
    "state": ("INTERACTIVE_HIGH", True),
    "pose": ("INTERACTIVE_HIGH", True),
    "log": ("INTERACTIVE_HIGH", True),
    "touchdown": ("INTERACTIVE_LOW", False),
    "effector_targets": ("INTERACTIVE_LOW", False),
    "joint_targets": ("INTERACTIVE_LOW", False),
    "map": ("DATA_LOW", False),
    "depth": ("DATA_LOW", False),
    "color": ("DATA_LOW", False),
}
# What a station commands: on a radio it goes on a connection of its own (``ZenohConfig.
# command_session``), never behind a lost segment of the station's acknowledgements.
COMMAND_TOPICS = ("command", "mode")
# Bulk topics, most wanted first, with the message each packs.
BULK: dict[str, type[Message]] = {"map": MapUpdate, "depth": DepthFrame, "color": ColorImage}
# A message unacknowledged this long no longer counts as in flight (lost) [s].
ACK_WAIT_S = 1.0
# Flow control holds while a receiver acknowledged within this [s]: zenoh's lease, after
# which a station that went silent is gone. Through a shorter outage the robot keeps to
# the smallest window, so what waits on the link when it returns is little.
ACKING_RECENTLY_S = 10.0
# Queueing the window allows on top of the round trip [s].
TARGET_DELAY_S = 0.1
# The window never closes below this [bytes].
MIN_WINDOW_BYTES = 32_000
# A receiver acknowledges at most this often [s].
ACK_EVERY_S = 0.1
# A receiver asks for a whole map at most this often [s].
WHOLE_REQUEST_EVERY_S = 0.5


@dataclass
class LinkCounts:
    """What the sending end did, per bulk topic.

    Attributes:
        sent: Messages sent.
        sent_bytes: Their bytes on the wire.
        dropped: Messages replaced by a newer one before they could go (newest kept).
        wholes: Whole maps sent.
        acknowledged: Messages a receiver acknowledged.
    """

    sent: dict[str, int] = field(default_factory=lambda: defaultdict(int))
    sent_bytes: dict[str, int] = field(default_factory=lambda: defaultdict(int))
    dropped: dict[str, int] = field(default_factory=lambda: defaultdict(int))
    wholes: int = 0
    acknowledged: int = 0

    def to_json(self) -> dict:
        """The counts as ``metrics.json`` holds them."""
        return {
            "sent": dict(self.sent),
            "sent_bytes": dict(self.sent_bytes),
            "dropped": dict(self.dropped),
            "wholes": self.wholes,
            "acknowledged": self.acknowledged,
        }


class LinkSender:
    """The robot's end: bulk messages packed, newest kept, within what the link delivers.

    Args:
        put: Sends a packed message's bytes on a topic.
        clock: Wall clock (``time.time``: acknowledgements carry it) [s].
    """

    def __init__(self, put: Callable[[str, bytes], None], clock=time.time) -> None:
        self.put = put
        self.clock = clock
        self.maps = MapPacker(clock=clock)
        self.counts = LinkCounts()
        self._waiting: dict[str, tuple[Message, float]] = {}  # topic -> (message, offered)
        self._in_flight: dict[int, tuple[float, int]] = {}  # link sequence -> (sent, bytes)
        self._acked: deque[tuple[float, int]] = deque()  # (when, bytes) in the last second
        self._round_trip_s = math.inf
        self._last_ack = -math.inf
        self._sequence = 0

    def offer(self, topic: str, message: Message) -> None:
        """Queue the newest message of a bulk topic and send what the link has room for."""
        if topic in self._waiting:
            self.counts.dropped[topic] += 1
        self._waiting[topic] = (message, self.clock())
        self.flush()

    @property
    def flow_controlled(self) -> bool:
        """Whether a receiver acknowledges (else every message goes at once)."""
        return self.clock() - self._last_ack < ACKING_RECENTLY_S

    def window_bytes(self) -> float:
        """The bytes the link may hold in flight now."""
        now = self.clock()
        while self._acked and now - self._acked[0][0] > 1.0:
            self._acked.popleft()
        rate = sum(n for _, n in self._acked)  # bytes per second delivered
        round_trip = self._round_trip_s if math.isfinite(self._round_trip_s) else 0.0
        delay = TARGET_DELAY_S + ACK_EVERY_S + round_trip  # acknowledgements come in batches
        return max(MIN_WINDOW_BYTES, rate * delay)

    def in_flight_bytes(self) -> int:
        """Bytes sent and not yet acknowledged (nor given up on)."""
        now = self.clock()
        for seq in [s for s, (t, _) in self._in_flight.items() if now - t > ACK_WAIT_S]:
            del self._in_flight[seq]
        return sum(n for _, n in self._in_flight.values())

    def flush(self) -> None:
        """Send waiting messages, most wanted first, while the window has room."""
        for topic in BULK:
            if topic not in self._waiting:
                continue
            if self.flow_controlled and self.in_flight_bytes() >= self.window_bytes():
                return
            self._send(topic, *self._waiting.pop(topic))

    def _send(self, topic: str, message: Message, offered: float) -> None:
        self._sequence += 1
        now = self.clock()
        if isinstance(message, MapUpdate):
            packed = self.maps.pack(message)
            self.counts.wholes += packed.base == 0
        elif isinstance(message, DepthFrame):
            packed = pack_depth(message)
        else:
            packed = pack_color(message)
        stamped = dataclasses.replace(packed, link_sequence=self._sequence, offered_at=offered)
        data = stamped.encode()
        self._in_flight[self._sequence] = (now, len(data))
        self.counts.sent[topic] += 1
        self.counts.sent_bytes[topic] += len(data)
        self.put(topic, data)

    def acknowledged(self, ack: LinkAck) -> None:
        """A receiver got messages: they leave the flight, their bytes count as delivered."""
        now = self.clock()
        sequences = ack.link_sequences.tolist()
        self._last_ack = now
        for sequence in sequences:
            sent = self._in_flight.pop(sequence, None)
            if sent is None:
                continue
            self.counts.acknowledged += 1
            self._acked.append((now, sent[1]))
            round_trip = now - sent[0]
            # The smallest recent round trip: the link's own, without its queues.
            self._round_trip_s = min(round_trip, 0.9 * self._round_trip_s + 0.1 * round_trip)
        if sequences:
            # Packed messages travel in order (one priority, one connection): one not
            # acknowledged before the last that was never arrived (dropped on the way, or
            # sent before the receiver subscribed) and must not hold the window.
            last = max(sequences)
            for lost in [s for s in self._in_flight if s < last]:
                del self._in_flight[lost]
        self.flush()

    def whole_map_wanted(self, request: WholeMapRequest) -> None:
        """A receiver asked for a whole map: the next map goes whole."""
        self.maps.want_whole = True


class LinkReceiver:
    """The station's end: packed messages back to what they stand for, acknowledged.

    Args:
        reply: Publishes an acknowledgement or a whole-map request back to the sender.
        receiver: This end's name in what it sends back.
        clock: Wall clock [s].

    Attributes:
        waiting_for_whole: Map changes received while no whole map was at hand.
        latency_s: Per bulk topic, each message's age on arrival: from when the robot
            offered it to the link [s] (meaningful when both ends share a clock).
        offered_at: Per bulk topic, when the robot offered the last message that arrived
            (``time.time()``) [s].
    """

    def __init__(self, reply: Callable[[str, Message], None], receiver: str, clock=time.time):
        self.reply = reply
        self.receiver = receiver
        self.clock = clock
        self.maps = MapUnpacker()
        self.waiting_for_whole = 0
        self.latency_s: dict[str, deque[float]] = defaultdict(lambda: deque(maxlen=1000))
        self.offered_at: dict[str, float] = {}
        self._asked = -math.inf
        self._unacknowledged: list[int] = []
        self._received_at = 0.0
        self._acked_at = -math.inf

    def acknowledge(self) -> None:
        """Acknowledge what arrived, if there is any, at most every ``ACK_EVERY_S``.

        Few acknowledgements keep the station's side of the link quiet: on TCP every
        segment lost there holds up the commands behind it.
        """
        now = self.clock()
        if self._unacknowledged and now - self._acked_at >= ACK_EVERY_S:
            sequences = np.asarray(self._unacknowledged, np.int64)
            self.reply(LinkAck.TOPIC, LinkAck(sequences, self._received_at, self.receiver))
            self._unacknowledged.clear()
            self._acked_at = now

    def unpack(self, topic: str, message: Message) -> Message | None:
        """What a packed message stands for; any other message as it is.

        Returns None for changes to a whole map not at hand (one is asked for).
        """
        if not isinstance(message, (PackedMap, PackedDepth, PackedColor)):
            return message
        now = self.clock()
        self._unacknowledged.append(message.link_sequence)
        self._received_at = now
        self.latency_s[topic].append(now - message.offered_at)
        self.offered_at[topic] = message.offered_at
        if isinstance(message, PackedDepth):
            return unpack_depth(message)
        if isinstance(message, PackedColor):
            return unpack_color(message)
        update = self.maps.unpack(message)
        if update is None:
            self.waiting_for_whole += 1
            if now - self._asked >= WHOLE_REQUEST_EVERY_S:
                self._asked = now
                self.reply(WholeMapRequest.TOPIC, WholeMapRequest(now, self.receiver))
        return update
