"""Nodes on a thread of their own, joined to the bus of the control thread.

A robot's control loop must not wait for its mapping: a depth frame takes tens of
milliseconds to fuse and score, several control periods, and a station's command that
arrives meanwhile would wait with it. :class:`NodeThread` runs nodes (the mapping node) on
a thread with a private in-process bus, as a separate process would run them:

- what the owner's bus carries on a topic the nodes subscribe to is queued for the thread
  and delivered there in the order it was published (across topics too);
- what the nodes publish reaches their own bus at once and the owner's bus when the owner
  calls :meth:`NodeThread.spin` (the control loop does at the start of each tick), on the
  owner's thread, in order;
- work handed over with :meth:`NodeThread.call` (a camera's render of the state it saved)
  runs there in turn with the messages;
- a topic (or a call's key) may keep at most a few waiting (``waiting``): a newer one then
  replaces the oldest, counted in ``dropped``, so a slow node takes the latest frames, not
  a backlog;
- an error in a node stops the thread and is raised again by the owner's next ``spin``.
"""

from __future__ import annotations

import threading
from collections import Counter, deque
from collections.abc import Callable, Mapping

from footfall.errors import FootfallError
from footfall.messages.codec import Message
from footfall.runtime.bus import Bus, Callback, Handler, InProcessBus

# Put last in the queue by close: the thread ends there.
_STOP = ("", ())


class NodeThreadError(FootfallError, RuntimeError):
    """A node on a node thread failed; the thread stopped."""


class _ThreadSide:
    """The bus the thread's nodes are given: subscriptions reach out to the owner's bus."""

    def __init__(self, owner: NodeThread) -> None:
        self._owner = owner
        self.inner = InProcessBus()

    def publish(self, topic: str, message: Message) -> None:
        self.inner.publish(topic, message)
        self._owner._outbox.append((topic, message))

    def subscribe(self, topic: str, callback: Callback, last: bool = False) -> None:
        self._owner._forward(topic)
        self.inner.subscribe(topic, callback, last)

    def serve(self, service: str, handler: Handler) -> None:
        raise NodeThreadError(f"a node on a node thread cannot serve {service!r}")

    def request(self, service: str, message: Message, timeout: float = 1.0) -> Message:
        raise NodeThreadError(f"a node on a node thread cannot request {service!r}")

    def spin(self, timeout: float = 0.0) -> int:
        return 0


class NodeThread:
    """A thread for nodes, fed from and publishing to ``outer`` (see the module).

    Build the nodes on :attr:`bus`, then :meth:`start`; :meth:`close` lets the thread finish
    what waits for it and stops it.

    Args:
        outer: The owner's bus.
        name: The thread's name.
        waiting: Per topic (or key of :meth:`call`), the most that may wait for the thread.

    Attributes:
        bus: The bus the thread's nodes subscribe and publish on.
        dropped: Per topic (or key), what a newer one replaced before the thread took it.
    """

    def __init__(self, outer: Bus, name: str, waiting: Mapping[str, int] | None = None) -> None:
        self.outer = outer
        self.name = name
        self.waiting = dict(waiting or {})
        self._side = _ThreadSide(self)
        self.bus: Bus = self._side
        self.dropped: Counter[str] = Counter()
        self._inbox: deque[tuple[str, Message]] = deque()
        self._outbox: deque[tuple[str, Message]] = deque()
        self._forwarded: set[str] = set()
        self._echo: str | None = None  # the topic of the message spin is publishing
        self._ready = threading.Condition()
        self._error: BaseException | None = None
        self._running = False
        self._thread = threading.Thread(target=self._run, name=name, daemon=True)

    def _forward(self, topic: str) -> None:
        if topic not in self._forwarded:
            self._forwarded.add(topic)
            self.outer.subscribe(topic, lambda message: self._queue(topic, message))

    def _queue(self, topic: str, message: Message) -> None:
        if topic == self._echo:
            self._echo = None  # the thread's own message coming back: its nodes have had it
            return
        self._put(topic, (topic, message))

    def call(self, key: str, function: Callable[..., object], *args: object) -> None:
        """Run ``function(*args)`` on the thread, in turn with the messages (a frame's work).

        ``key`` names the work for ``waiting`` and ``dropped``, as a topic names messages.
        """
        self._put(key, (function, args))

    def _put(self, key: str, item: tuple) -> None:
        with self._ready:
            limit = self.waiting.get(key)
            if limit is not None:
                same = [k for k, (name, _) in enumerate(self._inbox) if name == key]
                if len(same) >= limit:
                    del self._inbox[same[0]]
                    self.dropped[key] += 1
            self._inbox.append((key, item))
            self._ready.notify()

    def start(self) -> NodeThread:
        """Start delivering to the nodes."""
        self._thread.start()
        return self

    def _run(self) -> None:
        inner = self._side.inner
        while True:
            with self._ready:
                while not self._inbox:
                    self._ready.wait()
                _, item = self._inbox.popleft()
                self._running = True
            if item is _STOP:
                return
            try:
                if callable(item[0]):
                    item[0](*item[1])
                else:
                    inner.publish(*item)
            except BaseException as exc:  # raised again on the owner's thread
                self._error = exc
                return
            finally:
                with self._ready:
                    self._running = False

    @property
    def idle(self) -> bool:
        """Nothing waits for the thread and it is running nothing."""
        with self._ready:
            return not self._inbox and not self._running

    def spin(self) -> int:
        """Publish on the owner's bus what the nodes published; how many messages.

        Raises:
            NodeThreadError: A node failed on the thread (the error is its cause).
        """
        count = 0
        while self._outbox:
            topic, message = self._outbox.popleft()
            self._echo = topic if topic in self._forwarded else None
            try:
                self.outer.publish(topic, message)
            finally:
                self._echo = None
            count += 1
        if self._error is not None:
            error, self._error = self._error, None
            raise NodeThreadError(f"{self.name}: {error}") from error
        return count

    def close(self, timeout: float = 10.0) -> None:
        """Let the thread finish what waits for it, stop it, and wait for it [s]."""
        if self._thread.is_alive():
            self._put("", _STOP)
            self._thread.join(timeout)
