"""An emulated radio link: a TCP proxy that shapes what passes through it.

This kernel's ``tc`` has no ``netem`` ("Specified qdisc kind is unknown"), so delay,
jitter and loss cannot come from the kernel here. :class:`ShapingProxy` stands between a
station and a robot (zenoh over TCP) and gives each direction of each connection:

- **bandwidth**: the bytes leave at the profile's rate (a token-free serialisation clock:
  each segment of ``MSS_BYTES`` takes ``8 * size / rate_bps`` seconds on the air);
- **delay and jitter**: each segment arrives its one-way delay after it left, plus a
  uniform jitter of up to ``jitter_s`` either way, never before the segment ahead of it
  (TCP delivers in order);
- **loss as TCP shows it**: a segment lost on the air is sent again, so the receiver sees
  it late and everything behind it waits (head-of-line blocking): with probability
  ``loss`` a segment arrives ``retransmit_s`` late, by default two round trips, the time a
  tail-loss probe or three duplicate acknowledgements take to bring it.

Queues are the proxy's own (a radio's buffer): what the sender writes faster than the rate
waits in order. Everything runs on one asyncio loop in a thread of its own.
"""

from __future__ import annotations

import asyncio
import contextlib
import dataclasses
import itertools
import os
import random
import shutil
import subprocess
import threading
from collections import deque
from dataclasses import dataclass, field

from footfall.errors import ConfigError

MSS_BYTES = 1448
READ_BYTES = 65536
_LINKS = itertools.count()


@dataclass(frozen=True)
class LinkProfile:
    """What a link does to the bytes crossing it, each way.

    Attributes:
        name: The profile's name.
        rate_bps: Bandwidth [bit/s].
        delay_s: One-way delay [s].
        jitter_s: Uniform jitter either side of the delay [s].
        loss: Share of segments lost on the air (each is retransmitted).
        retransmit_s: How late a lost segment arrives [s]; two round trips if None.
    """

    name: str
    rate_bps: float
    delay_s: float
    jitter_s: float = 0.0
    loss: float = 0.0
    retransmit_s: float | None = None

    def __post_init__(self) -> None:
        if not self.rate_bps > 0:
            raise ConfigError(f"link {self.name}: rate must be positive, got {self.rate_bps}")
        if self.delay_s < 0 or not 0 <= self.jitter_s <= self.delay_s:
            raise ConfigError(f"link {self.name}: need 0 <= jitter <= delay")
        if not 0 <= self.loss < 1:
            raise ConfigError(f"link {self.name}: loss must be in [0, 1), got {self.loss}")

    @property
    def stall_s(self) -> float:
        """How late a lost segment arrives [s]."""
        return self.retransmit_s if self.retransmit_s is not None else 4.0 * self.delay_s


PROFILES = {
    "good-wifi": LinkProfile("good-wifi", 50e6, 0.005, 0.0, 0.001),
    "poor-wifi": LinkProfile("poor-wifi", 10e6, 0.040, 0.010, 0.02),
}


@dataclass
class DirectionCounts:
    """What crossed one direction of the link.

    Attributes:
        bytes: Bytes delivered.
        segments: Segments delivered.
        lost: Segments lost and retransmitted.
        delays_s: Each segment's time from entering the proxy to leaving it [s].
    """

    bytes: int = 0
    segments: int = 0
    lost: int = 0
    delays_s: deque[float] = field(default_factory=lambda: deque(maxlen=100_000))


class _Direction:
    """One direction of one connection: the air's clock and the in-order delivery."""

    def __init__(self, profile: LinkProfile, counts: DirectionCounts, rng: random.Random):
        self.profile, self.counts, self.rng = profile, counts, rng
        self.air_free = 0.0  # when the air is free for the next segment (loop time)
        self.last_arrival = 0.0

    def schedule(self, now: float, size: int) -> float:
        """When a segment that entered at ``now`` arrives at the far end (loop time)."""
        p = self.profile
        leaves = max(now, self.air_free) + 8.0 * size / p.rate_bps
        self.air_free = leaves
        arrives = leaves + p.delay_s + self.rng.uniform(-p.jitter_s, p.jitter_s)
        if self.rng.random() < p.loss:
            arrives += p.stall_s
            self.counts.lost += 1
        self.last_arrival = max(arrives, self.last_arrival)
        return self.last_arrival


class ShapingProxy:
    """A TCP proxy on 127.0.0.1 that shapes both directions by a :class:`LinkProfile`.

    Args:
        profile: What the link does.
        target: ``(host, port)`` it connects each client to.
        seed: Seeds the jitter and the losses.

    Attributes:
        port: Where it listens (after :meth:`start`).
        up: What crossed from the clients to the target.
        down: What crossed from the target to the clients.
    """

    def __init__(self, profile: LinkProfile, target: tuple[str, int], seed: int = 0) -> None:
        self.profile, self.target = profile, target
        self.rng = random.Random(seed)
        self.up, self.down = DirectionCounts(), DirectionCounts()
        self.port = 0
        self.cut = False
        self._loop = asyncio.new_event_loop()
        self._thread = threading.Thread(target=self._loop.run_forever, daemon=True)
        self._server: asyncio.base_events.Server | None = None
        self._writers: set[asyncio.StreamWriter] = set()

    def start(self) -> ShapingProxy:
        """Listen and shape until :meth:`stop`."""
        self._thread.start()
        future = asyncio.run_coroutine_threadsafe(self._listen(), self._loop)
        self.port = future.result(timeout=5.0)
        return self

    async def _listen(self) -> int:
        self._server = await asyncio.start_server(self._accept, "127.0.0.1", 0)
        return self._server.sockets[0].getsockname()[1]

    async def _accept(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        try:
            far_reader, far_writer = await asyncio.open_connection(*self.target)
        except OSError:
            writer.close()
            return
        self._writers |= {writer, far_writer}
        up = _Direction(self.profile, self.up, self.rng)
        down = _Direction(self.profile, self.down, self.rng)
        await asyncio.gather(
            self._pump(reader, far_writer, up), self._pump(far_reader, writer, down)
        )

    async def _pump(
        self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter, way: _Direction
    ) -> None:
        loop = self._loop
        queue: asyncio.Queue[tuple[float, float, bytes] | None] = asyncio.Queue()

        async def deliver() -> None:
            while (item := await queue.get()) is not None:
                entered, arrives, segment = item
                wait = arrives - loop.time()
                if wait > 0:
                    await asyncio.sleep(wait)
                while self.cut:
                    await asyncio.sleep(0.005)
                writer.write(segment)
                way.counts.bytes += len(segment)
                way.counts.segments += 1
                way.counts.delays_s.append(loop.time() - entered)
                await writer.drain()
            writer.close()

        delivering = asyncio.ensure_future(deliver())
        try:
            while data := await reader.read(READ_BYTES):
                now = loop.time()
                for at in range(0, len(data), MSS_BYTES):
                    segment = data[at : at + MSS_BYTES]
                    queue.put_nowait((now, way.schedule(now, len(segment)), segment))
        except (ConnectionError, OSError):
            pass
        finally:
            queue.put_nowait(None)
            with contextlib.suppress(ConnectionError, OSError):
                await delivering

    def cut_link(self) -> None:
        """Hold everything on the air, both ways, until :meth:`restore_link`.

        Out of range: the connections stay open, as TCP's do through a short outage.
        """
        self.cut = True

    def restore_link(self) -> None:
        """Deliver again, what was held first."""
        self.cut = False

    def stop(self) -> None:
        """Close everything and end the proxy's thread."""

        async def close() -> None:
            for writer in self._writers:
                writer.close()
            if self._server is not None:
                self._server.close()

        with contextlib.suppress(Exception):
            asyncio.run_coroutine_threadsafe(close(), self._loop).result(timeout=5.0)
        self._loop.call_soon_threadsafe(self._loop.stop)
        self._thread.join(timeout=5.0)

    def __enter__(self) -> ShapingProxy:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()


class NamespaceError(RuntimeError):
    """The emulated link's network namespace could not be made (no privileges, no tools)."""


def _run(*command: str) -> None:
    done = subprocess.run(command, capture_output=True, text=True, check=False)
    if done.returncode != 0:
        raise NamespaceError(f"{' '.join(command)}: {done.stderr.strip() or done.returncode}")


class EmulatedLink:
    """A robot in a network namespace of its own, its station across an emulated radio.

    The namespace and a veth pair are made here and removed on exit. Both ends of the pair
    shape their outgoing packets to the profile's rate with ``tc``'s ``tbf`` (a real
    bottleneck: a full queue drops packets and TCP backs off); a :class:`ShapingProxy`
    on the station's side adds the delay, the jitter and the losses. The robot listens on
    :attr:`robot_endpoint` inside the namespace (run it with :meth:`inside`); the station
    connects to :attr:`station_endpoint`.

    Args:
        profile: What the link does.
        port: The robot's zenoh port inside the namespace.
        seed: Seeds the proxy's jitter and losses.

    Raises:
        NamespaceError: From ``__enter__``, when the namespace cannot be made.
    """

    def __init__(self, profile: LinkProfile, port: int = 7447, seed: int = 0) -> None:
        tag = f"{os.getpid() % 100000}{next(_LINKS)}"
        self.profile, self.port, self.seed = profile, port, seed
        self.namespace = f"ffradio{tag}"
        self.robot_device, self.station_device = f"ffr{tag}", f"ffs{tag}"
        subnet = random.Random(tag).randrange(0, 250)
        self.station_address, self.robot_address = f"10.213.{subnet}.1", f"10.213.{subnet}.2"
        self.proxy: ShapingProxy | None = None

    @property
    def robot_endpoint(self) -> str:
        """Where the robot listens, inside its namespace."""
        return f"tcp/{self.robot_address}:{self.port}"

    @property
    def station_endpoint(self) -> str:
        """Where the station connects: the radio's near end."""
        assert self.proxy is not None, "the link is not up"
        return f"tcp/127.0.0.1:{self.proxy.port}"

    def inside(self, command: list[str]) -> list[str]:
        """A command that runs in the robot's namespace."""
        return ["ip", "netns", "exec", self.namespace, *command]

    def __enter__(self) -> EmulatedLink:
        if shutil.which("ip") is None or shutil.which("tc") is None:
            raise NamespaceError("the emulated link needs iproute2's ip and tc")
        rate = f"{self.profile.rate_bps / 1e3:.0f}kbit"
        burst = f"{max(16_000, int(self.profile.rate_bps / 8 / 250))}"
        ns, robot, station = self.namespace, self.robot_device, self.station_device
        _run("ip", "netns", "add", ns)
        try:
            _run("ip", "link", "add", station, "type", "veth", "peer", "name", robot)
            _run("ip", "link", "set", robot, "netns", ns)
            _run("ip", "addr", "add", f"{self.station_address}/30", "dev", station)
            _run("ip", "link", "set", station, "up")
            inside = ("ip", "netns", "exec", ns)
            _run(*inside, "ip", "addr", "add", f"{self.robot_address}/30", "dev", robot)
            _run(*inside, "ip", "link", "set", robot, "up")
            _run(*inside, "ip", "link", "set", "lo", "up")
            tbf = ("root", "tbf", "rate", rate, "burst", burst, "latency", "50ms")
            _run("tc", "qdisc", "add", "dev", station, *tbf)
            _run(*inside, "tc", "qdisc", "add", "dev", robot, *tbf)
        except NamespaceError:
            self._remove()
            raise
        unshaped = dataclasses.replace(self.profile, rate_bps=1e11)  # tbf shapes the rate
        self.proxy = ShapingProxy(unshaped, (self.robot_address, self.port), self.seed).start()
        return self

    def _remove(self) -> None:
        subprocess.run(["ip", "link", "del", self.station_device], capture_output=True)
        subprocess.run(["ip", "netns", "del", self.namespace], capture_output=True)

    def __exit__(self, *exc: object) -> None:
        if self.proxy is not None:
            self.proxy.stop()
        self._remove()
