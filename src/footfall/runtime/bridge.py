"""A bridge between a process's in-process bus and the network bus.

The nodes of one process keep talking over their deterministic in-process bus; the bridge
forwards chosen topics out to the network (each at most at a chosen rate, so a 15 Hz map
need not cross a slow link in full) and chosen topics in from it. Incoming messages are
delivered on the caller's thread when the bridge spins. A topic goes one way only, so
nothing echoes back.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable, Mapping

from footfall.errors import ConfigError
from footfall.messages.codec import Message
from footfall.runtime.bus import Bus, InProcessBus

# A message this share of a period early still goes in its slot.
EARLY_SHARE = 0.1


class Bridge:
    """Forward topics between a local bus and a remote one.

    Args:
        local: The process's in-process bus.
        remote: The network bus (a :class:`~footfall.runtime.zenoh_bus.ZenohBus`).
        outgoing: Topics sent out, each with its largest rate [Hz] (None: every message).
        incoming: Topics taken in.
        clock: Wall clock for the rate limits [s].
    """

    def __init__(
        self,
        local: InProcessBus,
        remote: Bus,
        outgoing: Mapping[str, float | None],
        incoming: Iterable[str],
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        incoming = tuple(incoming)
        both = set(outgoing) & set(incoming)
        if both:
            raise ConfigError(f"topics cannot go both ways over a bridge: {sorted(both)}")
        self.local = local
        self.remote = remote
        self.clock = clock
        self.forwarded: dict[str, int] = dict.fromkeys(outgoing, 0)
        self.received: dict[str, int] = dict.fromkeys(incoming, 0)
        self._next: dict[str, float] = dict.fromkeys(outgoing, -float("inf"))
        for topic, rate in outgoing.items():
            if rate is not None and not rate > 0:
                raise ConfigError(f"bridge rate for {topic!r} must be positive, got {rate}")
            local.subscribe(topic, self._sender(topic, rate))
        for topic in incoming:
            remote.subscribe(topic, self._receiver(topic))

    def _sender(self, topic: str, rate: float | None) -> Callable[[Message], None]:
        def send(message: Message) -> None:
            if rate is not None:
                now, slot, period = self.clock(), self._next[topic], 1.0 / rate
                if now < slot - EARLY_SHARE * period:
                    return
                # The next slot follows this one's, not this message's arrival, so messages
                # that come more often than the rate go at the rate on average (the first
                # after a pause starts the slots afresh); one that comes at the rate, a
                # little early by the wall clock, still takes its slot.
                self._next[topic] = (now if now - slot > period else slot) + period
            self.remote.publish(topic, message)
            self.forwarded[topic] += 1

        return send

    def _receiver(self, topic: str) -> Callable[[Message], None]:
        def receive(message: Message) -> None:
            self.received[topic] += 1
            self.local.publish(topic, message)

        return receive

    def spin(self, timeout: float = 0.0) -> int:
        """Bring in what has arrived from the network; returns how many messages."""
        return self.remote.spin(timeout)
