"""The bus between processes and machines: eclipse-zenoh, the transport under ROS 2's rmw_zenoh.

A topic ``t`` of robot ``r`` is the key expression ``footfall/r/t``; a message travels as
its own byte encoding (:mod:`footfall.messages.codec`); a service is a zenoh queryable.

Zenoh hands samples over on its own threads; nodes are not thread-safe, so the bus queues
what arrives and delivers it on the caller's thread in :meth:`ZenohBus.spin` (as ROS
spins), in arrival order. A message that does not decode, or whose subscriber raises, is
dropped, counted in :attr:`ZenohBus.malformed` or :attr:`ZenohBus.failed` and logged on the
``log`` topic: a bad message never brings a node down.

With ``radio``, the map, depth and colour go packed for a radio link, within what the
link delivers (:mod:`footfall.runtime.link`); every bus unpacks and acknowledges what
arrives packed, so a subscriber sees the usual messages. Each topic's publisher has the
priority of :data:`~footfall.runtime.link.PRIORITIES`. A station's bus may send its
commands on a session of their own (``command_session``).

Safe defaults: only the endpoints asked for, loopback unless ``allow_remote`` says
otherwise, and no multicast scouting unless asked for. TLS and user/password
authentication come from a zenoh configuration file (JSON5), which the options here extend
(see ``docs/runtime.md``).
"""

from __future__ import annotations

import ipaddress
import json
import time
from collections import defaultdict
from dataclasses import dataclass, field
from pathlib import Path

import zenoh

from footfall.errors import ConfigError, MessageError
from footfall.messages import LogLine
from footfall.messages.codec import Message, decode
from footfall.messages.wire import LinkAck, WholeMapRequest
from footfall.runtime.bus import Callback, Handler, ServiceError, TopicStats
from footfall.runtime.link import BULK, COMMAND_TOPICS, PRIORITIES, LinkReceiver, LinkSender
from footfall.runtime.wake_queue import WakeQueue

KEY_PREFIX = "footfall"
# Batches zenoh's transmit queue holds for the small, latency-bound priorities (its
# default is 2 for every priority, at most 16); the bulk ones keep theirs, so no more
# image data waits in front of the link than before.
TX_QUEUE_BATCHES = {"real_time": 16, "interactive_high": 8, "interactive_low": 8}


def endpoint_host(endpoint: str) -> str:
    """The host of a zenoh endpoint such as ``tcp/127.0.0.1:7447`` or ``tls/[::1]:7447``.

    Raises:
        ConfigError: For an endpoint that is not ``protocol/host:port``.
    """
    _, sep, address = endpoint.partition("/")
    address = address.split("#", 1)[0]
    host, colon, port = address.rpartition(":")
    if not (sep and colon and host and port.isdigit()):
        raise ConfigError(f"endpoint {endpoint!r} is not protocol/host:port (tcp/127.0.0.1:7447)")
    return host.strip("[]")


def is_loopback(endpoint: str) -> bool:
    """Whether an endpoint's host is a loopback address (or ``localhost``)."""
    host = endpoint_host(endpoint)
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


@dataclass(frozen=True)
class ZenohConfig:
    """How a process joins the robot's zenoh network.

    Attributes:
        robot: Robot name: the key expressions are ``footfall/<robot>/<topic>``.
        listen: Endpoints to listen on, e.g. ``("tcp/127.0.0.1:7447",)``.
        connect: Endpoints to connect to.
        scouting: Discover peers by multicast (off by default).
        allow_remote: Allow listening on addresses other than loopback.
        config_file: A zenoh configuration file (JSON5) to start from: TLS certificates,
            user/password authentication, and anything else zenoh offers.
        radio: Send the map, depth and colour packed for a radio link, paced by the
            receivers' acknowledgements (``docs/runtime.md``).
        command_session: Send walk commands and the mode on a zenoh session of their own
            (a TCP connection to each ``connect`` endpoint): TCP delivers in order, so on
            a lossy radio a lost segment of this bus's other traffic (its
            acknowledgements) would hold the commands behind it until retransmitted. A
            station's choice; needs ``connect`` endpoints.
    """

    robot: str = "hexapod"
    listen: tuple[str, ...] = ()
    connect: tuple[str, ...] = ()
    scouting: bool = False
    allow_remote: bool = False
    config_file: Path | None = None
    radio: bool = False
    command_session: bool = False

    def __post_init__(self) -> None:
        if not self.robot or "/" in self.robot or any(c in self.robot for c in "*$#?"):
            raise ConfigError(f"robot name {self.robot!r} must be non-empty, without / * $ # ?")
        for endpoint in (*self.listen, *self.connect):
            endpoint_host(endpoint)
        remote = [e for e in self.listen if not is_loopback(e)]
        if remote and not self.allow_remote:
            raise ConfigError(
                f"listening on {', '.join(remote)} reaches beyond this machine; "
                "allow it explicitly (--listen-remote) or listen on 127.0.0.1"
            )
        if self.command_session and not self.connect:
            raise ConfigError("a session of its own for commands needs endpoints to connect to")
        if self.config_file is not None and not Path(self.config_file).is_file():
            raise ConfigError(f"zenoh configuration file {self.config_file} does not exist")

    def zenoh_config(self, listen: bool = True) -> zenoh.Config:
        """The zenoh configuration these settings describe (without listening, if not)."""
        config = (
            zenoh.Config.from_file(str(self.config_file))
            if self.config_file is not None
            else zenoh.Config()
        )
        config.insert_json5("mode", json.dumps("peer"))
        config.insert_json5("listen/endpoints", json.dumps(list(self.listen) if listen else []))
        config.insert_json5("connect/endpoints", json.dumps(list(self.connect)))
        config.insert_json5("scouting/multicast/enabled", json.dumps(self.scouting))
        config.insert_json5("adminspace/enabled", "true")  # for listening_locators()
        if self.config_file is None:
            # Room for bursts while the transmit thread waits for a core: with zenoh's two
            # batches per priority, a publisher that finds both taken waits 1 ms and then
            # drops (congestion control DROP), and on a busy machine three of five
            # commands sent back to back were lost that way.
            for priority, batches in TX_QUEUE_BATCHES.items():
                config.insert_json5(f"transport/link/tx/queue/size/{priority}", str(batches))
        return config


@dataclass
class _Counts:
    malformed: dict[str, int] = field(default_factory=lambda: defaultdict(int))
    failed: dict[str, int] = field(default_factory=lambda: defaultdict(int))


class ZenohBus:
    """A :class:`~footfall.runtime.bus.Bus` over a zenoh session.

    Args:
        config: Network settings.
    """

    def __init__(self, config: ZenohConfig | None = None) -> None:
        self.config = config or ZenohConfig()
        self.prefix = f"{KEY_PREFIX}/{self.config.robot}"
        self.session = zenoh.open(self.config.zenoh_config())
        self.command_session = (
            zenoh.open(self.config.zenoh_config(listen=False))
            if self.config.command_session
            else None
        )
        self.stats: dict[str, TopicStats] = defaultdict(TopicStats)
        self.received: dict[str, TopicStats] = defaultdict(TopicStats)
        self._counts = _Counts()
        self._inbox: WakeQueue[tuple] = WakeQueue()
        self._publishers: dict[str, zenoh.Publisher] = {}
        self._subscribers: dict[str, list[Callback]] = defaultdict(list)
        self._zenoh_subscribers: dict[str, zenoh.Subscriber] = {}
        self._services: dict[str, Handler] = {}
        self._queryables: list[zenoh.Queryable] = []
        self._last: dict[str, Message] = {}
        self.link_receiver = LinkReceiver(self.publish, receiver=str(self.session.zid()))
        self.link_sender: LinkSender | None = None
        if self.config.radio:
            self.link_sender = sender = LinkSender(self._put)
            self.subscribe(LinkAck.TOPIC, sender.acknowledged)
            self.subscribe(WholeMapRequest.TOPIC, sender.whole_map_wanted)

    # Keys ----------------------------------------------------------------------------------
    def key(self, topic: str) -> str:
        """The key expression of a topic."""
        return f"{self.prefix}/{topic}"

    @property
    def malformed(self) -> dict[str, int]:
        """Messages dropped per topic because they did not decode."""
        return dict(self._counts.malformed)

    @property
    def failed(self) -> dict[str, int]:
        """Messages dropped per topic because a subscriber raised on them."""
        return dict(self._counts.failed)

    # Publish / subscribe ---------------------------------------------------------------------
    def publish(self, topic: str, message: Message) -> None:
        """Send ``message`` on ``topic`` (to this process's subscribers too).

        On a radio bus a map, depth image or colour image waits its turn on the link
        (:class:`~footfall.runtime.link.LinkSender`) and goes packed.
        """
        self._last[topic] = message
        bulk = BULK.get(topic)
        if self.link_sender is not None and bulk is not None and isinstance(message, bulk):
            self.link_sender.offer(topic, message)
        else:
            self._put(topic, message.encode())

    def _put(self, topic: str, data: bytes) -> None:
        publisher = self._publishers.get(topic)
        if publisher is None:
            priority, express = PRIORITIES.get(topic, ("DATA", False))
            session = self.session
            if self.command_session is not None and topic in COMMAND_TOPICS:
                session = self.command_session
            publisher = self._publishers[topic] = session.declare_publisher(
                self.key(topic),
                priority=getattr(zenoh.Priority, priority),
                congestion_control=zenoh.CongestionControl.DROP,
                express=express,
            )
        stats = self.stats[topic]
        stats.messages += 1
        stats.bytes += len(data)
        publisher.put(data)

    def publish_bytes(self, topic: str, data: bytes) -> None:
        """Send raw bytes on ``topic`` (for tests of what a node does with bad input)."""
        self.session.put(self.key(topic), data)

    def subscribe(self, topic: str, callback: Callback, last: bool = False) -> None:
        """Call ``callback`` (from :meth:`spin`) with each message on ``topic``.

        With ``last``, the latest message this process published on it comes first.
        """
        self._subscribers[topic].append(callback)
        if topic not in self._zenoh_subscribers:
            inbox = self._inbox

            def arrived(sample: zenoh.Sample, topic: str = topic) -> None:
                inbox.put(("topic", topic, sample.payload.to_bytes()))

            self._zenoh_subscribers[topic] = self.session.declare_subscriber(
                self.key(topic), arrived
            )
        if last and topic in self._last:
            self._call(topic, callback, self._last[topic])

    def _call(self, topic: str, callback: Callback, message: Message) -> None:
        try:
            callback(message)
        except Exception as exc:  # a bad message must not bring the node down
            self._counts.failed[topic] += 1
            self._log("error", f"{topic}: subscriber failed on a {type(message).__name__}: {exc}")

    def _log(self, level: str, text: str) -> None:
        try:
            self.publish(LogLine.TOPIC, LogLine(time.time(), "bus", level, text))
        except Exception:  # the log itself must never fail the bus
            return

    def spin(self, timeout: float = 0.0) -> int:
        """Deliver what has arrived, on this thread; wait up to ``timeout`` [s] for the first.

        Returns:
            How many messages and requests were handled.
        """
        handled = 0
        item = self._inbox.get(timeout)
        while item is not None:
            self._handle(item)
            handled += 1
            item = self._inbox.get_nowait()
        self.link_receiver.acknowledge()
        if self.link_sender is not None:
            self.link_sender.flush()
        return handled

    def _handle(self, item: tuple) -> None:
        kind, name, payload = item
        if kind == "query":
            self._answer(name, payload)
            return
        received = self.received[name]
        received.messages += 1
        received.bytes += len(payload)
        try:
            message = self.link_receiver.unpack(name, decode(payload))
        except MessageError as exc:
            self._counts.malformed[name] += 1
            self._log("warning", f"{name}: dropped a malformed message ({exc})")
            return
        if message is None:  # changes to a map not at hand: a whole one was asked for
            return
        for callback in tuple(self._subscribers.get(name, ())):
            self._call(name, callback, message)

    # Services --------------------------------------------------------------------------------
    def serve(self, service: str, handler: Handler) -> None:
        """Answer requests to ``service`` (from :meth:`spin`) with ``handler``."""
        if service in self._services:
            raise ServiceError(f"service {service!r} already has a server")
        self._services[service] = handler
        inbox = self._inbox

        def asked(query: zenoh.Query, service: str = service) -> None:
            inbox.put(("query", service, query))

        self._queryables.append(self.session.declare_queryable(self.key(service), asked))

    def _answer(self, service: str, query: zenoh.Query) -> None:
        try:
            request = decode(query.payload.to_bytes() if query.payload is not None else b"")
            reply = self._services[service](request)
            query.reply(query.key_expr, reply.encode())
        except Exception as exc:
            self._counts.failed[service] += 1
            query.reply_err(str(exc).encode())
        finally:
            query.drop()

    def request(self, service: str, message: Message, timeout: float = 1.0) -> Message:
        """Ask ``service`` and wait for its reply (a server in this process answers at once).

        Raises:
            ServiceError: No server answered within ``timeout``, or it answered an error.
        """
        local = self._services.get(service)
        if local is not None:
            return local(message)
        replies = self.session.get(self.key(service), payload=message.encode(), timeout=timeout)
        for reply in replies:
            if reply.ok is not None:
                return decode(reply.ok.payload.to_bytes())
            raise ServiceError(
                f"{service}: {reply.err.payload.to_bytes().decode(errors='replace')}"
            )
        raise ServiceError(f"no server answered {service!r} within {timeout:g} s")

    # The session -----------------------------------------------------------------------------
    def listening_locators(self) -> list[str]:
        """The locators this session listens on (from zenoh's admin space)."""
        zid = str(self.session.zid())
        for reply in self.session.get(f"@/{zid}/**", timeout=2.0):
            if reply.ok is not None and str(reply.ok.key_expr).count("/") == 2:
                return list(json.loads(reply.ok.payload.to_bytes()).get("locators", []))
        return []

    def close(self) -> None:
        """Close the session (and the one for commands)."""
        if self.command_session is not None:
            self.command_session.close()
        self.session.close()
        self._inbox.close()

    def __enter__(self) -> ZenohBus:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
