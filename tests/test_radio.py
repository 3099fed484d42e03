"""The emulated radio link delivers the profile it claims: rate, delay, jitter, loss."""

from __future__ import annotations

import socket
import struct
import threading
import time

import numpy as np
import pytest

from footfall.errors import ConfigError
from footfall.runtime.radio import PROFILES, LinkProfile, ShapingProxy


class Sink:
    """A TCP server that reads everything and notes when each byte count arrived."""

    def __init__(self) -> None:
        self.server = socket.create_server(("127.0.0.1", 0))
        self.port = self.server.getsockname()[1]
        self.arrivals: list[tuple[float, bytes]] = []
        self.thread = threading.Thread(target=self._serve, daemon=True)
        self.thread.start()

    def _serve(self) -> None:
        conn, _ = self.server.accept()
        with conn:
            while data := conn.recv(65536):
                self.arrivals.append((time.monotonic(), data))

    def received(self) -> bytes:
        """Everything that arrived, in order."""
        return b"".join(d for _, d in self.arrivals)


def test_bulk_data_crosses_at_the_profiles_rate():
    """2 MB written at once through a 10 Mbit/s link take 1.6 s to arrive, not less."""
    sink = Sink()
    profile = LinkProfile("rate", 10e6, 0.0)
    with ShapingProxy(profile, ("127.0.0.1", sink.port)) as proxy:
        with socket.create_connection(("127.0.0.1", proxy.port)) as client:
            payload = bytes(range(256)) * 8192  # 2 MiB
            start = time.monotonic()
            client.sendall(payload)
            while len(sink.received()) < len(payload) and time.monotonic() - start < 10:
                time.sleep(0.01)
    took = sink.arrivals[-1][0] - start
    assert sink.received() == payload
    expected = 8 * len(payload) / profile.rate_bps
    assert expected * 0.95 < took < expected * 1.15, took


def test_small_messages_arrive_after_the_delay_with_the_jitter_and_losses_of_poor_wifi():
    """Single-segment messages over "poor Wi-Fi" (40 ms +- 10 ms, 2 % loss) arrive after
    30-50 ms, about 2 % of the segments late by a retransmission, in the order sent."""
    sink = Sink()
    profile = PROFILES["poor-wifi"]
    sent: list[float] = []
    with ShapingProxy(profile, ("127.0.0.1", sink.port), seed=3) as proxy:
        with socket.create_connection(("127.0.0.1", proxy.port)) as client:
            for k in range(1000):
                sent.append(time.monotonic())
                client.sendall(struct.pack("<I", k) + bytes(96))
                time.sleep(0.004)
            time.sleep(0.5)
        lost, segments = proxy.up.lost, proxy.up.segments
    data = sink.received()
    assert len(data) == 100 * 1000
    # Each message's arrival: the first chunk holding its first byte.
    arrival, at = [], 0
    for t, chunk in sink.arrivals:
        while at < 100 * 1000 and len(arrival) * 100 < at + len(chunk):
            arrival.append(t)
        at += len(chunk)
    order = [struct.unpack_from("<I", data, 100 * k)[0] for k in range(1000)]
    assert order == list(range(1000))
    latency = np.asarray(arrival[:1000]) - np.asarray(sent)
    assert segments == 1000 and 5 <= lost <= 40  # 2 % of 1000, binomial bounds
    assert 0.029 < np.min(latency) and 0.037 < np.median(latency) < 0.05
    assert np.max(latency) > profile.delay_s + profile.stall_s * 0.9
    # A loss holds up the messages behind it (in-order delivery), so more arrive late.
    late = latency > profile.delay_s + profile.jitter_s + 0.005
    assert np.mean(late) > lost / segments


def test_a_cut_link_holds_everything_until_it_returns():
    """Out of range, nothing arrives; back in range, what was held arrives, in order."""
    sink = Sink()
    with ShapingProxy(PROFILES["good-wifi"], ("127.0.0.1", sink.port)) as proxy:
        with socket.create_connection(("127.0.0.1", proxy.port)) as client:
            client.sendall(b"before")
            time.sleep(0.2)
            proxy.cut_link()
            client.sendall(b"during")
            time.sleep(0.5)
            assert sink.received() == b"before"
            proxy.restore_link()
            time.sleep(0.2)
    assert sink.received() == b"beforeduring"


def test_an_impossible_profile_is_refused():
    """A jitter beyond the delay, or a loss of every segment, is refused by name."""
    with pytest.raises(ConfigError, match="jitter"):
        LinkProfile("bad", 1e6, 0.01, jitter_s=0.02)
    with pytest.raises(ConfigError, match="loss"):
        LinkProfile("bad", 1e6, 0.01, loss=1.0)
