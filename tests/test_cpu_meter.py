"""The per-node CPU meter: exclusive CPU time, latencies, callbacks charged to their node."""

from __future__ import annotations

import threading
import time

import pytest

from footfall.messages import Trigger
from footfall.runtime.bus import InProcessBus
from footfall.runtime.cpu_meter import CpuMeter, MeteredBus


def _spin(seconds: float) -> None:
    """Burn this thread's CPU for ``seconds``."""
    end = time.thread_time() + seconds
    while time.thread_time() < end:
        pass


def test_a_node_called_inside_another_is_charged_to_itself():
    """A publishes while it works and B's callback runs inside A's call (an in-process bus):
    each is charged its own CPU and latency, not the other's."""
    meter = CpuMeter()
    bus = InProcessBus()

    def b(_message) -> None:
        _spin(0.03)
        time.sleep(0.3)  # waiting costs B latency, and no one CPU

    MeteredBus(bus, meter, "b").subscribe("topic", b)
    with meter.measure("a"):
        _spin(0.02)
        bus.publish("topic", Trigger())
    assert meter.cpu_s["a"] == pytest.approx(0.02, abs=0.008)
    assert meter.cpu_s["b"] == pytest.approx(0.03, abs=0.008)
    report = meter.report(walked_s=1.0)
    assert report["b"]["calls"] == report["a"]["calls"] == 1
    assert report["b"]["latency_median_ms"] >= 330
    assert 20 <= report["a"]["latency_median_ms"] < 250  # B's wait is not A's
    assert report["b"]["cpu_share"] == pytest.approx(meter.cpu_s["b"])
    assert list(report) == ["b", "a"]  # the costliest first


def test_a_node_that_calls_itself_counts_one_call():
    """A node re-entered by its own message is one call, its time counted once."""
    meter = CpuMeter()
    with meter.measure("a"):
        _spin(0.01)
        with meter.measure("a"):
            _spin(0.01)
    assert meter.report(1.0)["a"]["calls"] == 1
    assert meter.cpu_s["a"] == pytest.approx(0.02, abs=0.008)


def test_other_threads_keep_their_own_time_and_nesting():
    """A worker thread's node is timed on its thread; sleeping costs no CPU."""
    meter = CpuMeter()
    worker = threading.Thread(target=meter.wrap("planner", lambda: _spin(0.02)))
    with meter.measure("control"):
        worker.start()
        time.sleep(0.05)
        worker.join()
    assert meter.cpu_s["planner"] == pytest.approx(0.02, abs=0.01)
    assert meter.cpu_s["control"] < 0.01
    assert meter.report(1.0)["control"]["latency_median_ms"] >= 50


def test_a_metered_bus_is_the_bus_for_everything_else():
    """Publishing, the last message and the rest go to the bus itself."""
    bus = InProcessBus()
    view = MeteredBus(bus, CpuMeter(), "node")
    view.publish("topic", Trigger(2.0))
    assert view.last("topic") == Trigger(2.0)
