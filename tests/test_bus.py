"""The in-process bus: ordered, depth-first delivery, late joiners, services, encoding."""

from __future__ import annotations

import pytest

from footfall.messages import LogLine, ModeCommand, WalkCommand
from footfall.runtime.bus import InProcessBus, ServiceError


def test_delivery_is_in_subscription_order_and_depth_first():
    """Subscribers get a message in the order they subscribed; one published from a
    callback is delivered in full before the next subscriber of the first."""
    bus = InProcessBus()
    seen = []
    bus.subscribe(
        "a", lambda m: (seen.append(("first", m.text)), bus.publish("b", LogLine(0, "", "", "b")))
    )
    bus.subscribe("b", lambda m: seen.append(("b", m.text)))
    bus.subscribe("a", lambda m: seen.append(("second", m.text)))
    bus.publish("a", LogLine(0.0, "n", "info", "a"))
    assert seen == [("first", "a"), ("b", "b"), ("second", "a")]


def test_a_late_subscriber_may_take_the_last_message():
    """With last=True a new subscriber gets the latest message at once; without, nothing."""
    bus = InProcessBus()
    bus.publish("cmd", WalkCommand(speed=0.1))
    bus.publish("cmd", WalkCommand(speed=0.2))
    got, ignored = [], []
    bus.subscribe("cmd", got.append, last=True)
    bus.subscribe("cmd", ignored.append)
    assert [m.speed for m in got] == [0.2]
    assert ignored == []


def test_services_answer_and_missing_ones_are_named():
    """A request reaches its server; a request to no server names what is served."""
    bus = InProcessBus()
    bus.serve("echo", lambda m: m)
    assert bus.request("echo", ModeCommand()) == ModeCommand()
    with pytest.raises(ServiceError, match="echo"):
        bus.request("nothing", ModeCommand())
    with pytest.raises(ServiceError, match="already"):
        bus.serve("echo", lambda m: m)


def test_checked_encoding_delivers_equal_messages_and_counts_bytes():
    """With check_encoding the subscriber gets a decoded copy, and the bytes are counted."""
    bus = InProcessBus(check_encoding=True)
    got = []
    bus.subscribe("cmd", got.append)
    command = WalkCommand(speed=0.3, yaw_rate=0.1)
    bus.publish("cmd", command)
    assert got == [command] and got[0] is not command
    assert bus.stats["cmd"].messages == 1
    assert bus.stats["cmd"].bytes == len(command.encode())
