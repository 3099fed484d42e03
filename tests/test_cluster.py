"""Benchmarks on a Ray cluster: a real head node and a worker node started on this machine.

Ray binds its nodes to the machine's own address (it replaces 127.0.0.1 on purpose); the
traffic stays on this machine. Each node offers one CPU, so the walks spread over both.
"""

import json
import os
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from footfall.cli import main
from footfall.reliability.cluster import local_cluster
from test_zenoh_bus import free_port

BIN = Path(sys.executable).parent
# A small sweep: two single-layout terrains, two modes, one seed: 4 walks.
SWEEP = ["bench", "terrain", "--terrains", "course,dead_end", "--modes", "planned,blind"]
SWEEP += ["--seeds", "1", "--seconds", "2"]
# Ray's task for a walk of the terrain sweep names its worker process after the function.
WALK_PROCESS = "ray::_terrain_run"


@pytest.fixture(scope="module")
def ray_cluster() -> Iterator[str]:
    """``HOST:PORT`` of a Ray cluster: a head and a worker node, one CPU each."""
    with local_cluster(nodes=2, cpus_per_node=1) as address:
        yield address


def _without_wall_times(bench: object) -> object:
    """``bench.json`` without what the wall clock measures (wall seconds, replan times)."""
    if isinstance(bench, dict):
        return {
            key: _without_wall_times(value)
            for key, value in bench.items()
            if "wall" not in key and not key.startswith("replan_ms")
        }
    if isinstance(bench, list):
        return [_without_wall_times(value) for value in bench]
    return bench


def _same(a: Path, b: Path) -> bool:
    """Whether two ``bench.json`` files agree outside wall times (NaN equal to NaN)."""
    load = [_without_wall_times(json.loads(p.read_text())) for p in (a, b)]
    return json.dumps(load[0], sort_keys=True) == json.dumps(load[1], sort_keys=True)


def _walk_processes() -> list[int]:
    """Process ids of Ray workers walking a task of the terrain sweep now."""
    pids = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                title = (entry / "cmdline").read_bytes().split(b"\0")[0].decode()
            except OSError:
                continue
            if title.startswith(WALK_PROCESS):
                pids.append(int(entry.name))
    return pids


@pytest.fixture(scope="module")
def local_sweep(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """The sweep's ``bench.json`` with ``--jobs 2`` on this machine."""
    out = tmp_path_factory.mktemp("local")
    assert main([*SWEEP, "--jobs", "2", "--out", str(out)]) == 0
    return out / "bench.json"


def test_a_sweep_on_the_cluster_gives_the_bench_json_of_local_processes(
    ray_cluster, local_sweep, tmp_path, monkeypatch
):
    """Every walk a Ray task: the same rows and figures as `--jobs 2`, outside wall times;
    `--cluster auto` finds the cluster through RAY_ADDRESS."""
    monkeypatch.setenv("RAY_ADDRESS", ray_cluster)
    assert main([*SWEEP, "--cluster", "auto", "--out", str(tmp_path)]) == 0
    bench = json.loads((tmp_path / "bench.json").read_text())
    assert [r["runs"] for r in bench["results"]] == [1, 1, 1, 1]
    assert _same(tmp_path / "bench.json", local_sweep)


def test_a_walk_lost_with_its_worker_is_walked_again(ray_cluster, local_sweep, tmp_path):
    """Killing a Ray worker in the middle of a walk loses no walk: the sweep (its own process,
    as a user runs it) finishes with every row, and the figures of a clean run."""
    sweep = subprocess.Popen(
        [str(BIN / "footfall"), *SWEEP, "--cluster", ray_cluster, "--out", str(tmp_path)],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    killed = None
    deadline = time.monotonic() + 120.0
    while killed is None and sweep.poll() is None and time.monotonic() < deadline:
        walking = _walk_processes()
        if walking:
            time.sleep(0.5)  # into the walk
            try:
                os.kill(walking[0], signal.SIGKILL)
                killed = walking[0]
            except ProcessLookupError:
                pass
        time.sleep(0.1)
    out, _ = sweep.communicate(timeout=300)
    assert killed is not None, f"no walk was seen running on the cluster:\n{out}"
    assert sweep.returncode == 0, out
    bench = json.loads((tmp_path / "bench.json").read_text())
    assert [r["runs"] for r in bench["results"]] == [1, 1, 1, 1]
    assert _same(tmp_path / "bench.json", local_sweep)


def test_a_cluster_that_does_not_answer_is_named(tmp_path, capsys):
    """An address where no cluster listens fails at once, naming the address."""
    address = f"127.0.0.1:{free_port()}"
    assert main([*SWEEP, "--cluster", address, "--out", str(tmp_path)]) == 2
    assert address in capsys.readouterr().out
    assert not (tmp_path / "bench.json").exists()
