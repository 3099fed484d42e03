"""CPU time and update latency per node: what each of footfall's nodes costs a robot.

A :class:`CpuMeter` times named calls: each node's ticks and the callbacks it subscribed
with (through :class:`MeteredBus`, the bus a node is given). CPU time is the calling
thread's (``time.thread_time``: other processes and threads do not count) and exclusive:
a node's callback that runs inside another node's tick (an in-process bus delivers a
message while it is published) is charged to the node it belongs to, not to the one that
published. Latency is the wall time of a node's outermost call, less the other nodes'
calls inside it: its whole update (a depth frame in, the scored map out). Calls on other
threads (a route planner's worker) are timed on theirs.
"""

from __future__ import annotations

import threading
import time
from collections import defaultdict
from collections.abc import Callable
from typing import Any

import numpy as np

from footfall.messages import Message


class CpuMeter:
    """CPU seconds and call latencies per node name."""

    def __init__(self) -> None:
        self.cpu_s: dict[str, float] = defaultdict(float)
        self.latency_s: dict[str, list[float]] = defaultdict(list)
        self._lock = threading.Lock()
        self._local = threading.local()

    def measure(self, node: str) -> _Span:
        """Charge what runs inside (``with``) to ``node``, less what nested nodes take."""
        return _Span(self, node)

    def _stack(self) -> list[list]:
        stack = getattr(self._local, "stack", None)
        if stack is None:
            stack = self._local.stack = []
        return stack

    def _charge(self, node: str, cpu_s: float, latency_s: float | None) -> None:
        with self._lock:
            self.cpu_s[node] += cpu_s
            if latency_s is not None:
                self.latency_s[node].append(latency_s)

    def wrap(self, node: str, function: Callable[..., Any]) -> Callable[..., Any]:
        """``function``, charged to ``node`` on every call."""

        def metered(*args: Any, **kwargs: Any) -> Any:
            with self.measure(node):
                return function(*args, **kwargs)

        return metered

    def report(self, walked_s: float) -> dict[str, dict[str, float]]:
        """What each node cost over ``walked_s`` seconds walked, the costliest first.

        Per node: CPU seconds, their share of one core (per second walked), calls, and the
        median and 95th percentile latency of a call [ms].
        """
        out = {}
        with self._lock:
            names = sorted(self.cpu_s, key=lambda n: -self.cpu_s[n])
            for name in names:
                latency = np.asarray(self.latency_s.get(name, []), dtype=np.float64) * 1e3
                median, p95 = np.percentile(latency, [50, 95]) if len(latency) else (0.0, 0.0)
                out[name] = {
                    "cpu_s": float(self.cpu_s[name]),
                    "cpu_share": float(self.cpu_s[name] / walked_s) if walked_s > 0 else 0.0,
                    "calls": len(latency),
                    "latency_median_ms": float(median),
                    "latency_p95_ms": float(p95),
                }
        return out


class _Span:
    """One timed call of a node (a context manager; plain slots, as it runs every tick)."""

    __slots__ = ("_frame", "_meter", "_node", "_outermost", "_stack")

    def __init__(self, meter: CpuMeter, node: str) -> None:
        self._meter, self._node = meter, node

    def __enter__(self) -> None:
        stack = self._stack = self._meter._stack()
        self._outermost = not any(frame[0] == self._node for frame in stack)
        # node, CPU at the start, nested nodes' CPU, wall at the start, nested nodes' wall
        self._frame = [self._node, time.thread_time(), 0.0, time.perf_counter(), 0.0]
        stack.append(self._frame)

    def __exit__(self, *exc: object) -> None:
        frame, stack = self._frame, self._stack
        stack.pop()
        spent = time.thread_time() - frame[1]
        took = time.perf_counter() - frame[3]
        latency = took - frame[4] if self._outermost else None
        self._meter._charge(self._node, spent - frame[2], latency)
        if stack:
            stack[-1][2] += spent
            stack[-1][4] += took


class MeteredBus:
    """A node's view of a bus: what it subscribes and serves is charged to it.

    Args:
        bus: The bus.
        meter: The meter.
        node: The node's name.
    """

    def __init__(self, bus: Any, meter: CpuMeter, node: str) -> None:
        self._bus = bus
        self._meter = meter
        self._node = node

    def subscribe(self, topic: str, callback: Callable[[Message], None], last: bool = False):
        """Subscribe, the callback charged to the node."""
        return self._bus.subscribe(topic, self._meter.wrap(self._node, callback), last=last)

    def serve(self, service: str, handler: Callable[[Message], Message]):
        """Serve, the handler charged to the node."""
        return self._bus.serve(service, self._meter.wrap(self._node, handler))

    def __getattr__(self, name: str) -> Any:
        """Everything else (publish, request, spin, last, stats) is the bus's own."""
        return getattr(self._bus, name)
