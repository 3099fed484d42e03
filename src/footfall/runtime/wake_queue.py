"""A queue that a loop waits on with a timeout, and that a signal cannot leave it stuck in.

The main loops of footfall's processes (robot, biped robot, station) wait for messages with
a timeout and check between waits whether SIGINT or SIGTERM asked them to stop. Waiting in
``queue.SimpleQueue.get(timeout=...)``, a biped robot process on CPython 3.11 was seen to
stay in that call for good once the SIGINT handler had run on the waiting thread: it never
checked again, and did not stop (about one run in six, on a loaded machine). Here every
put also writes a byte to a socket, and the wait is a ``select`` on it, which the
interpreter resumes with the time left after a signal's handler runs.
"""

from __future__ import annotations

import queue
import select
import socket
import time
from typing import Generic, TypeVar

T = TypeVar("T")


class WakeQueue(Generic[T]):
    """Items put from any thread, taken on one, with a wait that signals cannot hang."""

    def __init__(self) -> None:
        self._items: queue.SimpleQueue[T] = queue.SimpleQueue()
        self._reader, self._writer = socket.socketpair()
        self._reader.setblocking(False)
        self._writer.setblocking(False)

    def put(self, item: T) -> None:
        """Add an item and wake the waiting thread (any thread may put)."""
        self._items.put(item)
        try:
            self._writer.send(b"\0")
        except OSError:  # full (the taker drains it before it waits) or closed
            pass

    def get_nowait(self) -> T | None:
        """The oldest item, or None if there is none."""
        try:
            return self._items.get_nowait()
        except queue.Empty:
            return None

    def get(self, timeout: float) -> T | None:
        """The oldest item, waiting up to ``timeout`` [s] for one; None if none came."""
        item = self.get_nowait()
        if item is not None or timeout <= 0:
            return item
        deadline = time.monotonic() + timeout
        while True:
            try:
                while self._reader.recv(4096):
                    pass
            except OSError:  # drained (or closed)
                pass
            # A put after the drain is found below or wakes the select; a byte whose item
            # was taken already wakes it for nothing, and the wait goes on.
            item = self.get_nowait()
            remaining = deadline - time.monotonic()
            if item is not None or remaining <= 0:
                return item
            select.select([self._reader], [], [], remaining)

    def close(self) -> None:
        """Release the wake-up socket; puts after this are kept but wake nobody."""
        self._reader.close()
        self._writer.close()
