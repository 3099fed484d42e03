"""The zenoh bus: real sessions on loopback, between two processes; TLS; safe defaults."""

from __future__ import annotations

import datetime
import ipaddress
import json
import os
import signal
import socket
import subprocess
import sys
import textwrap
import threading
import time

import pytest

from footfall.errors import ConfigError
from footfall.messages import LogLine, ModeCommand, WalkCommand
from footfall.runtime.zenoh_bus import ZenohBus, ZenohConfig, is_loopback
from processes import read_until


def free_port() -> int:
    """A TCP port on loopback nobody listens on now."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def spin_until(bus: ZenohBus, done, seconds: float = 5.0) -> None:
    """Spin ``bus`` until ``done()`` or the time is up."""
    end = time.monotonic() + seconds
    while not done() and time.monotonic() < end:
        bus.spin(0.05)


ECHO = textwrap.dedent(
    """
    import sys, time
    from footfall.messages import LogLine, WalkCommand
    from footfall.runtime.zenoh_bus import ZenohBus, ZenohConfig
    bus = ZenohBus(ZenohConfig(robot="echo", listen=(sys.argv[1],)))
    seen = []
    def echo(message):
        seen.append(message)
        bus.publish("log", LogLine(message.stamp, "echo", "info", f"speed {message.speed}"))
    bus.subscribe("command", echo)
    bus.serve("count", lambda request: LogLine(0.0, "echo", "info", str(len(seen))))
    print("ready", flush=True)
    end = time.monotonic() + 20.0
    while time.monotonic() < end and len(seen) < 5:
        bus.spin(0.05)
    end = time.monotonic() + 2.0
    while time.monotonic() < end:
        bus.spin(0.05)
    bus.close()
    """
)


def test_two_processes_exchange_messages_and_services_over_loopback():
    """A process that echoes commands as log lines, over a real zenoh session on loopback:
    every command arrives, in order, and its service answers across the processes."""
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    echo = subprocess.Popen(
        [sys.executable, "-c", ECHO, endpoint], stdout=subprocess.PIPE, text=True
    )
    try:
        assert read_until(echo, "ready", 60.0).strip() == "ready"
        with ZenohBus(ZenohConfig(robot="echo", connect=(endpoint,))) as bus:
            lines: list[LogLine] = []
            bus.subscribe("log", lines.append)
            time.sleep(0.5)  # the session links up
            for k in range(5):
                bus.publish("command", WalkCommand(speed=0.01 * k, stamp=float(k)))
            spin_until(bus, lambda: len(lines) >= 5)
            assert [line.text for line in lines] == [f"speed {0.01 * k}" for k in range(5)]
            assert [line.stamp for line in lines] == [0.0, 1.0, 2.0, 3.0, 4.0]
            answer = bus.request("count", ModeCommand(), timeout=3.0)
            assert isinstance(answer, LogLine) and answer.text == "5"
    finally:
        echo.wait(timeout=30)
    assert echo.returncode == 0


def test_malformed_bytes_are_dropped_counted_and_logged():
    """Bytes that are not a message reach no subscriber: they are counted and logged."""
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    with (
        ZenohBus(ZenohConfig(listen=(endpoint,))) as sender,
        ZenohBus(ZenohConfig(connect=(endpoint,))) as receiver,
    ):
        got, logs = [], []
        receiver.subscribe("command", got.append)
        receiver.subscribe("log", logs.append)
        time.sleep(0.5)
        sender.publish_bytes("command", b"not a message")
        sender.publish_bytes("command", WalkCommand(speed=0.1).encode()[:-2])
        sender.publish("command", WalkCommand(speed=0.2))
        spin_until(receiver, lambda: got and len(logs) >= 2)
        assert [m.speed for m in got] == [0.2]
        assert receiver.malformed == {"command": 2}
        assert all("malformed" in line.text for line in logs)


def test_a_subscriber_that_raises_does_not_stop_the_bus():
    """A callback that fails is counted; the next message is delivered as usual."""
    with ZenohBus(ZenohConfig(listen=(f"tcp/127.0.0.1:{free_port()}",))) as bus:
        got = []

        def fragile(message):
            if message.speed > 0.15:
                raise RuntimeError("too fast for this test")
            got.append(message)

        bus.subscribe("command", fragile)
        for speed in (0.1, 0.2, 0.1):
            bus.publish("command", WalkCommand(speed=speed))
        spin_until(bus, lambda: len(got) >= 2)
        assert len(got) == 2 and bus.failed == {"command": 1}


def test_nothing_listens_beyond_loopback_unless_asked():
    """The session listens on exactly the loopback endpoint it was given, and listening
    elsewhere needs an explicit permission."""
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    with ZenohBus(ZenohConfig(listen=(endpoint,))) as bus:
        locators = bus.listening_locators()
        assert locators == [endpoint]
        assert all(is_loopback(loc) for loc in locators)
    with ZenohBus(ZenohConfig()) as quiet:  # no endpoint: listens nowhere
        assert quiet.listening_locators() == []
    with pytest.raises(ConfigError, match="beyond this machine"):
        ZenohConfig(listen=("tcp/0.0.0.0:7447",))
    with pytest.raises(ConfigError, match="protocol/host:port"):
        ZenohConfig(connect=("127.0.0.1",))
    assert ZenohConfig(listen=("tcp/0.0.0.0:7447",), allow_remote=True).allow_remote


def _certificates(folder):
    """A CA and a leaf certificate for localhost / 127.0.0.1 signed by it (PEM files)."""
    from cryptography import x509
    from cryptography.hazmat.primitives import hashes, serialization
    from cryptography.hazmat.primitives.asymmetric import ec
    from cryptography.x509.oid import NameOID

    now = datetime.datetime.now(datetime.UTC)
    ca_key = ec.generate_private_key(ec.SECP256R1())
    ca_name = x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, "footfall test CA")])
    ca = (
        x509.CertificateBuilder()
        .subject_name(ca_name)
        .issuer_name(ca_name)
        .public_key(ca_key.public_key())
        .serial_number(x509.random_serial_number())
        .not_valid_before(now - datetime.timedelta(minutes=5))
        .not_valid_after(now + datetime.timedelta(days=1))
        .add_extension(x509.BasicConstraints(ca=True, path_length=None), critical=True)
        .sign(ca_key, hashes.SHA256())
    )
    key = ec.generate_private_key(ec.SECP256R1())
    leaf = (
        x509.CertificateBuilder()
        .subject_name(x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, "localhost")]))
        .issuer_name(ca_name)
        .public_key(key.public_key())
        .serial_number(x509.random_serial_number())
        .not_valid_before(now - datetime.timedelta(minutes=5))
        .not_valid_after(now + datetime.timedelta(days=1))
        .add_extension(
            x509.SubjectAlternativeName(
                [x509.DNSName("localhost"), x509.IPAddress(ipaddress.ip_address("127.0.0.1"))]
            ),
            critical=False,
        )
        .add_extension(x509.BasicConstraints(ca=False, path_length=None), critical=True)
        .sign(ca_key, hashes.SHA256())
    )
    pem = serialization.Encoding.PEM
    paths = {name: folder / f"{name}.pem" for name in ("ca", "cert", "key")}
    paths["ca"].write_bytes(ca.public_bytes(pem))
    paths["cert"].write_bytes(leaf.public_bytes(pem))
    paths["key"].write_bytes(
        key.private_bytes(pem, serialization.PrivateFormat.PKCS8, serialization.NoEncryption())
    )
    return paths


def test_tls_from_a_configuration_file(tmp_path):
    """With TLS switched on from a zenoh configuration file (a CA and a leaf certificate
    made here), messages cross a tls/ endpoint on loopback."""
    certs = _certificates(tmp_path)
    server_config = tmp_path / "server.json5"
    server_config.write_text(
        json.dumps(
            {
                "transport": {
                    "link": {
                        "tls": {
                            "listen_certificate": str(certs["cert"]),
                            "listen_private_key": str(certs["key"]),
                            "root_ca_certificate": str(certs["ca"]),
                        }
                    }
                }
            }
        )
    )
    client_config = tmp_path / "client.json5"
    client_config.write_text(
        json.dumps({"transport": {"link": {"tls": {"root_ca_certificate": str(certs["ca"])}}}})
    )
    endpoint = f"tls/localhost:{free_port()}"
    with (
        ZenohBus(ZenohConfig(listen=(endpoint,), config_file=server_config)) as server,
        ZenohBus(ZenohConfig(connect=(endpoint,), config_file=client_config)) as client,
    ):
        got = []
        server.subscribe("command", got.append)
        end = time.monotonic() + 10.0
        while not got and time.monotonic() < end:
            client.publish("command", WalkCommand(speed=0.1))
            server.spin(0.2)
        assert got and got[0].speed == 0.1
        assert server.listening_locators() == [endpoint]


def test_a_station_may_send_its_commands_on_a_connection_of_their_own():
    """With ``command_session`` the station joins the robot twice: its commands and mode
    arrive over the second session (a TCP connection of its own), the rest over the first.
    It needs endpoints to connect to."""
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    with ZenohBus(ZenohConfig(listen=(endpoint,))) as robot:
        station = ZenohBus(ZenohConfig(connect=(endpoint,), command_session=True))
        try:
            assert station.command_session is not None
            commands, logs = [], []
            robot.subscribe("command", commands.append)
            robot.subscribe("mode", commands.append)
            robot.subscribe("log", logs.append)
            spin_until(robot, lambda: len(robot.session.info.peers_zid()) == 2)
            peers = {str(z) for z in robot.session.info.peers_zid()}
            assert peers == {str(station.session.zid()), str(station.command_session.zid())}
            end = time.monotonic() + 5.0
            while len(commands) < 2 or not logs:
                assert time.monotonic() < end, "nothing arrived"
                station.publish("command", WalkCommand(speed=0.2))
                station.publish("mode", ModeCommand())
                station.publish("log", LogLine(0.0, "station", "info", "hello"))
                robot.spin(0.1)
            assert station.stats["command"].messages >= 1
        finally:
            station.close()
    with pytest.raises(ConfigError, match="connect"):
        ZenohConfig(listen=(endpoint,), command_session=True)


def test_a_sigint_landing_on_a_network_thread_stops_the_loop():
    """A process loop waiting on the bus stops on SIGINT whichever thread the kernel hands
    the signal to (here a zenoh thread: the main thread blocks it while the loop runs), and
    leaves the handlers as it found them."""
    from footfall.runtime.scheduler import stop_on_signals

    before = signal.getsignal(signal.SIGINT)
    with stop_on_signals() as stop, ZenohBus(ZenohConfig()) as bus:
        signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
        try:
            threading.Timer(0.2, subprocess.run, (["kill", "-INT", str(os.getpid())],)).start()
            start = time.monotonic()
            while not stop() and time.monotonic() - start < 5.0:
                bus.spin(0.05)
            assert stop() and time.monotonic() - start < 2.0
        finally:
            signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})
    assert signal.getsignal(signal.SIGINT) is before
    assert signal.set_wakeup_fd(-1) == -1  # no wakeup socket left behind


def test_the_session_leaves_room_for_bursts_of_small_messages(tmp_path):
    """Commands, the mode, status and logs get more of zenoh's transmit batches than its
    default two: a burst published while the transmit thread waits for a core is queued,
    not dropped after zenoh's 1 ms wait. A user's own zenoh configuration file is kept
    as written."""
    ours = ZenohConfig().zenoh_config()
    for priority in ("real_time", "interactive_high", "interactive_low"):
        assert int(ours.get_json(f"transport/link/tx/queue/size/{priority}")) >= 8
    assert int(ours.get_json("transport/link/tx/queue/size/data_low")) == 2  # bulk: as zenoh's
    own = tmp_path / "zenoh.json5"
    own.write_text("{ transport: { link: { tx: { queue: { size: { real_time: 3 } } } } } }")
    theirs = ZenohConfig(config_file=own).zenoh_config()
    assert int(theirs.get_json("transport/link/tx/queue/size/real_time")) == 3
