"""Control-tick schedulers: simulated time, and the wall clock for a real robot.

Both call ``tick(t)`` with the controller time of each tick, ``t = k / rate``, until the
duration is over or the tick returns True (stop). The simulated scheduler runs ticks back
to back (the backend's ``advance`` computes the time step). The wall-clock scheduler keeps
each tick on its deadline: it sleeps out the rest of the period, unless the backend's own
``advance`` is the real wait (hardware), and counts overruns, ticks that end after the next
one was due; an overrun skips the ticks it ran over rather than bursting to catch up.
A process that runs nodes until it is stopped (the robot, the station) catches SIGINT and
SIGTERM with :func:`stop_on_signals` and ends between two ticks, never in the middle of one.
"""

from __future__ import annotations

import signal
import socket
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass

from footfall.errors import ConfigError

Tick = Callable[[float], bool]


@contextmanager
def stop_on_signals() -> Iterator[Callable[[], bool]]:
    """While inside, SIGINT and SIGTERM only ask to stop; yields whether one has.

    Besides the Python handler, each signal's number arrives on a socket (the interpreter's
    wakeup fd, written by its C handler on whichever thread the signal lands): CPython
    3.11 can leave a Python handler unrun for a long while when the signal lands on a
    thread other than the main one (a network library's) while the main thread waits on a
    queue, and a robot that does not stop when told is not acceptable.
    """
    asked: list[int] = []
    wanted = (signal.SIGINT, signal.SIGTERM)
    previous = {s: signal.signal(s, lambda signum, frame: asked.append(signum)) for s in wanted}
    reader, writer = socket.socketpair()
    reader.setblocking(False)
    writer.setblocking(False)
    previous_fd = signal.set_wakeup_fd(writer.fileno(), warn_on_full_buffer=False)

    def stop() -> bool:
        if not asked:
            try:
                arrived = reader.recv(64)
            except BlockingIOError:
                arrived = b""
            asked.extend(s for s in arrived if s in wanted)
        return bool(asked)

    try:
        yield stop
    finally:
        signal.set_wakeup_fd(previous_fd)
        for s, handler in previous.items():
            signal.signal(s, handler)
        reader.close()
        writer.close()


def _check_rate(rate_hz: float) -> float:
    if not rate_hz > 0:
        raise ConfigError(f"control rate must be positive, got {rate_hz}")
    return 1.0 / rate_hz


class SimulatedScheduler:
    """Ticks in simulated time, as fast as they compute.

    Args:
        rate_hz: Tick rate [Hz].
    """

    def __init__(self, rate_hz: float) -> None:
        self.period = _check_rate(rate_hz)
        self.rate_hz = rate_hz
        self.ticks = 0

    def run(self, tick: Tick, seconds: float) -> None:
        """Run ticks for ``seconds`` of controller time [s]."""
        for k in range(round(seconds * self.rate_hz)):
            self.ticks += 1
            if tick(k * self.period):
                return


@dataclass
class OverrunStats:
    """How a wall-clock run kept its deadlines.

    Attributes:
        ticks: Ticks run.
        overruns: Ticks that ended after the next tick was due.
        skipped: Ticks not run because an overrun passed their deadline.
        max_late_s: Longest time a tick ended past its period [s].
    """

    ticks: int = 0
    overruns: int = 0
    skipped: int = 0
    max_late_s: float = 0.0


class WallClockScheduler:
    """Ticks on wall-clock deadlines.

    Args:
        rate_hz: Tick rate [Hz].
        backend_waits: The backend's ``advance`` is itself the real wait (a hardware
            driver): do not sleep on top of it.
        clock: Monotonic clock [s].
        sleep: Sleep function [s].
    """

    def __init__(
        self,
        rate_hz: float,
        backend_waits: bool = False,
        clock: Callable[[], float] = time.monotonic,
        sleep: Callable[[float], None] = time.sleep,
    ) -> None:
        self.period = _check_rate(rate_hz)
        self.rate_hz = rate_hz
        self.backend_waits = backend_waits
        self.clock = clock
        self.sleep = sleep
        self.stats = OverrunStats()

    def run(self, tick: Tick, seconds: float) -> None:
        """Run ticks for ``seconds`` of wall time [s]."""
        start = self.clock()
        total = round(seconds * self.rate_hz)
        k = 0
        while k < total:
            self.stats.ticks += 1
            if tick(k * self.period):
                return
            now = self.clock() - start
            next_due = (k + 1) * self.period
            late = now - next_due
            if late > 0:
                self.stats.overruns += 1
                self.stats.max_late_s = max(self.stats.max_late_s, late)
                behind = int(late // self.period)  # deadlines already passed
                self.stats.skipped += behind
                k += 1 + behind
                continue
            if not self.backend_waits:
                self.sleep(next_due - now)
            k += 1
