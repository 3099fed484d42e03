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
from collections.abc import Callable, Iterator
from contextlib import contextmanager
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

    @contextmanager
    def measure(self, node: str) -> Iterator[None]:
        """Charge what runs inside to ``node`` (less what nested nodes take)."""
        stack = getattr(self._local, "stack", None)
        if stack is None:
            stack = self._local.stack = []
        outermost = not any(frame[0] == node for frame in stack)
        frame = [node, time.thread_time(), 0.0, time.perf_counter(), 0.0]
        stack.append(frame)
        try:
            yield
        finally:
            stack.pop()
            spent = time.thread_time() - frame[1]
            took = time.perf_counter() - frame[3]
            with self._lock:
                self.cpu_s[node] += spent - frame[2]
                if outermost:
                    self.latency_s[node].append(took - frame[4])
            if stack:
                stack[-1][2] += spent
                stack[-1][4] += took

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
