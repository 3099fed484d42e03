"""The bus nodes talk over: publish/subscribe on topics, request/reply on services.

:class:`InProcessBus` runs every node of a graph in one process. It delivers a message at
once, to each subscriber in the order they subscribed, depth first (a subscriber that
publishes in its callback has that message delivered before the next subscriber of the
first), so a seeded run is repeatable to the bit. It keeps the last message of each topic:
a node that subscribes late may ask for it (``last=True``), as a late joiner gets the
current map. With ``check_encoding`` every message crosses as bytes (encoded and decoded),
which proves a graph runs unchanged over a transport between processes, and counts the
bytes per topic.
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

from footfall.errors import FootfallError
from footfall.messages.codec import Message, decode

Callback = Callable[[Message], None]
Handler = Callable[[Message], Message]


class ServiceError(FootfallError, RuntimeError):
    """A service request found no server, or its server failed."""


@dataclass
class TopicStats:
    """Traffic on one topic.

    Attributes:
        messages: Messages published.
        bytes: Bytes they encoded to (counted when the bus encodes).
    """

    messages: int = 0
    bytes: int = 0


class Bus(Protocol):
    """What a node needs from the transport."""

    def publish(self, topic: str, message: Message) -> None:
        """Send a message to every subscriber of ``topic``."""
        ...

    def subscribe(self, topic: str, callback: Callback, last: bool = False) -> None:
        """Call ``callback`` with each message on ``topic`` (first the latest, with ``last``)."""
        ...

    def serve(self, service: str, handler: Handler) -> None:
        """Answer requests to ``service`` with ``handler``."""
        ...

    def request(self, service: str, message: Message, timeout: float = 1.0) -> Message:
        """Ask ``service`` and wait for its reply [s]."""
        ...

    def spin(self, timeout: float = 0.0) -> int:
        """Deliver what has arrived from elsewhere; returns how much (0 in one process)."""
        ...


class InProcessBus:
    """A deterministic bus for the nodes of one process.

    Args:
        check_encoding: Deliver every message encoded and decoded again.
    """

    def __init__(self, check_encoding: bool = False) -> None:
        self.check_encoding = check_encoding
        self._subscribers: dict[str, list[Callback]] = defaultdict(list)
        self._services: dict[str, Handler] = {}
        self._last: dict[str, Message] = {}
        self._taps: list[Callable[[str, Message], None]] = []
        self.stats: dict[str, TopicStats] = defaultdict(TopicStats)

    def _carry(self, topic: str, message: Message) -> Message:
        if not self.check_encoding:
            return message
        data = message.encode()
        self.stats[topic].bytes += len(data)
        return decode(data)

    def publish(self, topic: str, message: Message) -> None:
        """Deliver ``message`` to the subscribers of ``topic`` now, in subscription order."""
        message = self._carry(topic, message)
        self.stats[topic].messages += 1
        self._last[topic] = message
        for tap in self._taps:
            tap(topic, message)
        for callback in tuple(self._subscribers.get(topic, ())):
            callback(message)

    def tap(self, callback: Callable[[str, Message], None]) -> None:
        """See every message published on any topic, before its subscribers (a recorder)."""
        self._taps.append(callback)

    def subscribe(self, topic: str, callback: Callback, last: bool = False) -> None:
        """Subscribe to ``topic``; with ``last``, get the latest message on it right away."""
        self._subscribers[topic].append(callback)
        if last and topic in self._last:
            callback(self._last[topic])

    def serve(self, service: str, handler: Handler) -> None:
        """Register the server of ``service`` (one per service)."""
        if service in self._services:
            raise ServiceError(f"service {service!r} already has a server")
        self._services[service] = handler

    def request(self, service: str, message: Message, timeout: float = 1.0) -> Message:
        """Call the server of ``service`` and return its reply."""
        handler = self._services.get(service)
        if handler is None:
            known = ", ".join(sorted(self._services)) or "none"
            raise ServiceError(f"no server for service {service!r} (served: {known})")
        return self._carry(service, handler(self._carry(service, message)))

    def spin(self, timeout: float = 0.0) -> int:
        """Nothing to do: in one process every message is delivered when published."""
        return 0

    def last(self, topic: str) -> Message | None:
        """The latest message published on ``topic``, if any."""
        return self._last.get(topic)
