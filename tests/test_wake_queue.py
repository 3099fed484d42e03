"""The queue the network bus's loop waits on: woken by puts, never held by a signal."""

from __future__ import annotations

import os
import signal
import threading
import time

from hypothesis import given, settings
from hypothesis import strategies as st

from footfall.runtime.wake_queue import WakeQueue


@given(st.lists(st.integers(), max_size=300))
@settings(max_examples=30, deadline=None)
def test_items_put_from_another_thread_come_out_in_order(items):
    """Whatever one thread puts, the other takes, in the order put, and then none."""
    inbox: WakeQueue[int] = WakeQueue()
    putter = threading.Thread(target=lambda: [inbox.put(i) for i in items])
    putter.start()
    taken = []
    while len(taken) < len(items):
        item = inbox.get(1.0)
        assert item is not None, f"waited 1 s with {len(items) - len(taken)} items to come"
        taken.append(item)
    putter.join()
    assert taken == items
    assert inbox.get_nowait() is None
    inbox.close()


def test_a_put_wakes_the_wait_and_an_empty_wait_lasts_its_timeout():
    """A wait of 5 s ends as soon as an item is put; with nothing put, it ends after its
    timeout with None."""
    inbox: WakeQueue[str] = WakeQueue()
    threading.Timer(0.2, inbox.put, args=("map",)).start()
    start = time.monotonic()
    assert inbox.get(5.0) == "map"
    assert time.monotonic() - start < 2.0
    start = time.monotonic()
    assert inbox.get(0.3) is None
    assert 0.25 <= time.monotonic() - start < 2.0
    inbox.close()


def test_a_signal_handled_during_the_wait_does_not_hold_it():
    """SIGUSR2 lands while the loop waits; its handler runs and the wait still ends by its
    timeout, so the loop checks again whether it was asked to stop."""
    inbox: WakeQueue[str] = WakeQueue()
    seen: list[int] = []
    previous = signal.signal(signal.SIGUSR2, lambda signum, frame: seen.append(signum))
    try:
        threading.Timer(0.1, os.kill, args=(os.getpid(), signal.SIGUSR2)).start()
        start = time.monotonic()
        assert inbox.get(0.5) is None
        elapsed = time.monotonic() - start
    finally:
        signal.signal(signal.SIGUSR2, previous)
        inbox.close()
    assert seen == [signal.SIGUSR2]
    assert 0.45 <= elapsed < 2.0
