"""Walks as tasks on a Ray cluster: the benchmarks' ``--cluster ADDRESS|auto``.

Every job of a batch becomes one Ray task that needs one CPU. The task is footfall's own
function, sent by reference (its module and name): a node needs footfall installed (with the
same Python and Ray as the machine that starts the sweep) and nothing else; no code travels
with the tasks. A task whose worker process or node dies is run again, up to ``RETRIES``
times; a walk that raises an error is not, and its error is raised here as the walk raised
it. Results come back as tasks finish.
"""

from __future__ import annotations

import logging
import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from types import ModuleType, TracebackType
from typing import TypeVar

from footfall.errors import ClusterError, ConfigError

T = TypeVar("T")
R = TypeVar("R")

# Runs of a task lost with its worker or node before the sweep gives up on it.
RETRIES = 3
# How long to wait for a cluster's address to accept a connection [s].
CONNECT_TIMEOUT_S = 10.0
# ``--cluster auto``: RAY_ADDRESS, else the cluster last started on this machine, else a new
# local Ray instance.
AUTO = "auto"


def _import_ray() -> ModuleType:
    """Ray, or a clear error saying how to install it."""
    # Under `uv run`, Ray would copy the working directory to every node and start its
    # workers through `uv run` there; footfall's tasks need only footfall installed on the
    # nodes. RAY_ENABLE_UV_RUN_RUNTIME_ENV=1 in the environment asks Ray for its way.
    os.environ.setdefault("RAY_ENABLE_UV_RUN_RUNTIME_ENV", "0")
    try:
        import ray
    except ImportError as exc:
        raise ConfigError(
            "--cluster needs Ray: install footfall's cluster extra (pip install "
            "'footfall[cluster]') here and on every node of the cluster"
        ) from exc
    return ray


def _host_port(address: str) -> tuple[str, int] | None:
    """``(host, port)`` of a ``HOST:PORT`` address (IPv6 hosts in brackets), else None."""
    host, colon, port = address.rpartition(":")
    if not colon or not port.isdigit() or not host:
        return None
    return host.strip("[]"), int(port)


def check_reachable(address: str, timeout_s: float = CONNECT_TIMEOUT_S) -> None:
    """Fail fast where nothing listens at a cluster's ``HOST:PORT`` (Ray itself retries long).

    Raises:
        ClusterError: Naming the address and what the connection said.
    """
    host_port = _host_port(address)
    if host_port is None:
        return
    try:
        with socket.create_connection(host_port, timeout=timeout_s):
            pass
    except OSError as exc:
        raise ClusterError(
            f"no Ray cluster answers at {address} ({exc.strerror or exc}); start one with "
            f"`ray start --head` there, or give --cluster auto"
        ) from exc


class RayCluster:
    """A connection to a Ray cluster for the length of a ``with`` block.

    Where Ray is already connected in this process (a caller's own ``ray.init``), the
    cluster is used as it is and left connected.

    Args:
        address: ``HOST:PORT`` of the cluster's head, ``ray://HOST:PORT`` (Ray's client,
            which needs ``ray[client]``), or ``"auto"``.

    Raises:
        ConfigError: Ray is not installed, or the address is empty.
    """

    def __init__(self, address: str) -> None:
        if not address.strip():
            raise ConfigError("--cluster names no address; give HOST:PORT or auto")
        self.address = address.strip()
        self._ray = _import_ray()
        self._connected_here = False

    def __enter__(self) -> RayCluster:
        ray = self._ray
        if ray.is_initialized():
            return self
        auto = self.address == AUTO
        if not auto:
            check_reachable(self.address)
        try:
            ray.init(
                address=None if auto else self.address,
                include_dashboard=False,
                log_to_driver=False,
                logging_level=logging.WARNING,
            )
        except (ConnectionError, TimeoutError) as exc:
            raise ClusterError(f"cannot join the Ray cluster at {self.address}: {exc}") from exc
        self._connected_here = True
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        if self._connected_here:
            # Disconnecting cancels the tasks still queued (their owner is gone); a local
            # instance that ``auto`` started stops.
            self._ray.shutdown()
            self._connected_here = False

    def run(
        self, function: Callable[[T], R], jobs: Sequence[T], on_done: Callable[[T], None]
    ) -> dict[T, R]:
        """``function`` of every job as a task, by job; ``on_done(job)`` as each finishes.

        Raises:
            ClusterError: A task lost more than ``RETRIES`` times with its worker or node.
            FootfallError: As the walk raised it (Ray's error subclasses the walk's).
        """
        ray = self._ray
        task = ray.remote(num_cpus=1, max_retries=RETRIES, retry_exceptions=False)(function)
        jobs_of = {task.remote(job): job for job in jobs}
        pending = list(jobs_of)
        results: dict[T, R] = {}
        while pending:
            done, pending = ray.wait(pending, num_returns=1)
            for ref in done:
                job = jobs_of[ref]
                try:
                    results[job] = ray.get(ref)
                except ray.exceptions.RayTaskError:
                    raise
                except ray.exceptions.RayError as exc:
                    raise ClusterError(
                        f"the cluster lost the walk {job!r} {RETRIES + 1} times: {exc}"
                    ) from exc
                on_done(job)
        return results


def _signal_groups(groups: Sequence[int], signum: int) -> bool:
    """Send ``signum`` to every process group; whether any group still had a process."""
    alive = False
    for group in groups:
        try:
            os.killpg(group, signum)
            alive = True
        except ProcessLookupError:
            pass
    return alive


@contextmanager
def local_cluster(nodes: int = 2, cpus_per_node: int = 1) -> Iterator[str]:
    """A Ray cluster of ``nodes`` nodes on this machine for the ``with`` block: its address.

    A head and ``nodes - 1`` worker nodes, each started by ``ray start`` as on separate
    machines, each offering ``cpus_per_node`` CPUs: a sweep on it goes through everything a
    real cluster does (the tests and ``benchmarks/bench_cluster.py`` use it). Ray binds the
    nodes to the machine's own address; nothing leaves the machine. On leaving, every process
    the nodes started is stopped and their files removed.

    Raises:
        ClusterError: A node that does not start (with what ``ray start`` said).
    """
    _import_ray()
    ray_cli = Path(sys.executable).parent / "ray"
    # Short: Ray's socket paths under it must stay within 107 bytes.
    temp = Path(tempfile.mkdtemp(prefix="ray", dir="/tmp"))
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    env = {**os.environ, "RAY_ENABLE_UV_RUN_RUNTIME_ENV": "0", "RAY_USAGE_STATS_ENABLED": "0"}
    groups: list[int] = []

    def start(*args: str) -> None:
        # A session of its own: the daemons it leaves behind share its process group.
        p = subprocess.Popen(
            [str(ray_cli), "start", *args, "--num-cpus", str(cpus_per_node)],
            env=env,
            start_new_session=True,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
        )
        groups.append(p.pid)
        out, _ = p.communicate(timeout=120)
        if p.returncode != 0:
            raise ClusterError(f"ray start {' '.join(args)} failed:\n{out}")

    try:
        start("--head", "--port", str(port), "--include-dashboard", "false", f"--temp-dir={temp}")
        for _ in range(nodes - 1):
            start("--address", f"127.0.0.1:{port}")
        yield f"127.0.0.1:{port}"
    finally:
        for signum in (signal.SIGTERM, signal.SIGKILL):
            _signal_groups(groups, signum)
            deadline = time.monotonic() + 3.0  # Ray's raylet lingers on SIGTERM
            while _signal_groups(groups, 0) and time.monotonic() < deadline:
                time.sleep(0.2)
        shutil.rmtree(temp, ignore_errors=True)
        # `ray start --head` leaves its address for `auto` to find; it names a cluster gone.
        latest = Path(tempfile.gettempdir()) / "ray" / "ray_current_cluster"
        if latest.exists() and latest.read_text().strip().endswith(f":{port}"):
            latest.unlink()
