"""Where a benchmark's walks run: here, in processes on this machine, or on a Ray cluster.

A benchmark opens its workers once (:func:`open_workers`) and hands them batches of jobs
(:meth:`Workers.run`); every job is a hashable tuple that says all a walk needs, so the
outcome of a job is the same wherever it runs. Results come back as walks finish, and the
caller's ``on_done`` hears of each (the progress bar).
"""

from __future__ import annotations

import multiprocessing
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from contextlib import contextmanager
from typing import Protocol, TypeVar

from footfall.errors import ConfigError

T = TypeVar("T")
R = TypeVar("R")


class Workers(Protocol):
    """Runs a function of every job of a batch."""

    def run(
        self, function: Callable[[T], R], jobs: Sequence[T], on_done: Callable[[T], None]
    ) -> dict[T, R]:
        """``function`` of every job, by job; ``on_done(job)`` as each finishes."""
        ...


class InProcess:
    """Every job in this process, one after another (``--jobs 1``)."""

    def run(
        self, function: Callable[[T], R], jobs: Sequence[T], on_done: Callable[[T], None]
    ) -> dict[T, R]:
        """``function`` of every job, in order."""
        results: dict[T, R] = {}
        for job in jobs:
            results[job] = function(job)
            on_done(job)
        return results


class LocalProcesses:
    """Jobs spread over processes of this machine (``--jobs N``), one job at a time each.

    Args:
        pool: The process pool (closed by whoever opened it).
    """

    def __init__(self, pool: ProcessPoolExecutor) -> None:
        self._pool = pool

    def run(
        self, function: Callable[[T], R], jobs: Sequence[T], on_done: Callable[[T], None]
    ) -> dict[T, R]:
        """``function`` of every job, in completion order."""
        results: dict[T, R] = {}
        futures = {self._pool.submit(function, job): job for job in jobs}
        for future in as_completed(futures):
            results[futures[future]] = future.result()
            on_done(futures[future])
        return results


@contextmanager
def open_workers(jobs: int = 1, cluster: str | None = None) -> Iterator[Workers]:
    """The workers of a benchmark, open for the ``with`` block.

    Args:
        jobs: Processes on this machine (this process alone for 1); unused with a cluster.
        cluster: A Ray cluster's address, or ``"auto"`` (``RAY_ADDRESS``, the cluster last
            started on this machine, or a new local instance); None to stay on this machine.

    Raises:
        ConfigError: Fewer than one job.
        ClusterError: The cluster cannot be reached (see
            :class:`footfall.reliability.cluster.RayCluster`).
    """
    if cluster is not None:
        from footfall.reliability.cluster import RayCluster

        with RayCluster(cluster) as ray_cluster:
            yield ray_cluster
        return
    if jobs < 1:
        raise ConfigError(f"--jobs must be at least 1, got {jobs}")
    if jobs == 1:
        yield InProcess()
        return
    # Spawned, not forked: a fork of a process holding rendering contexts and thread pools
    # can deadlock.
    context = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(max_workers=jobs, mp_context=context) as pool:
        yield LocalProcesses(pool)
