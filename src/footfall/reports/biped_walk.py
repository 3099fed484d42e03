"""``footfall walk-biped`` and ``footfall bench biped``: reports of Archie's walks."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from footfall.biped.maps import TEST_CASES
from footfall.errors import ConfigError
from footfall.reliability.parallel import open_workers
from footfall.reports import write_json
from footfall.sim.biped_run import BipedWalk, WalkBipedRequest, walk_biped


@dataclass
class BipedWalkReport:
    """A walk and its figures."""

    walk: BipedWalk

    def to_json(self) -> dict[str, object]:
        """The ``metrics.json`` content."""
        return self.walk.metrics()

    def write(self, out: Path) -> list[Path]:
        """``metrics.json``, ``top.png``, ``balance.png``, ``joints.png``."""
        from footfall.plots_biped import plot_biped_balance, plot_biped_joints, plot_biped_top

        out.mkdir(parents=True, exist_ok=True)
        return [
            write_json(out / "metrics.json", self.to_json()),
            plot_biped_top(self.walk, out / "top.png"),
            plot_biped_balance(self.walk, out / "balance.png"),
            plot_biped_joints(self.walk, out / "joints.png"),
        ]


def run_walk_biped(request: WalkBipedRequest) -> BipedWalkReport:
    """Walk what the request asks for."""
    return BipedWalkReport(walk_biped(request))


def _one(job: tuple[str, int]) -> dict[str, object]:
    kind, number = job
    request = WalkBipedRequest(case=number) if kind == "case" else WalkBipedRequest(room=number)
    m = walk_biped(request).metrics()
    return {"kind": kind, "number": number, **m}


@dataclass
class BipedBenchReport:
    """Every dissertation map and ``seeds`` rooms."""

    runs: list[dict[str, object]]
    seeds: int

    def to_json(self) -> dict[str, object]:
        """The ``bench.json`` content: per run metrics and totals per kind."""
        summary = {}
        for kind in ("case", "room"):
            rows = [r for r in self.runs if r["kind"] == kind]
            summary[kind] = {
                "runs": len(rows),
                "reached_goal": sum(bool(r["reached_goal"]) for r in rows),
                "falls": sum(bool(r["fell"]) for r in rows),
                "collisions": sum(int(r["collisions"]) for r in rows),
                "success_rate": (
                    sum(bool(r["reached_goal"]) for r in rows) / len(rows) if rows else None
                ),
            }
        return {"seeds": self.seeds, "summary": summary, "runs": self.runs}

    def write(self, out: Path) -> list[Path]:
        """``bench.json``."""
        out.mkdir(parents=True, exist_ok=True)
        return [write_json(out / "bench.json", self.to_json())]


def run_biped_bench(
    seeds: int,
    first_seed: int = 0,
    jobs: int = 1,
    cases: tuple[int, ...] = TEST_CASES,
    on_run: Callable[[str], None] | None = None,
    cluster: str | None = None,
) -> BipedBenchReport:
    """Walk the dissertation's maps and ``seeds`` random rooms.

    The walks run in ``jobs`` processes, or as tasks on the Ray ``cluster`` at that address
    (:func:`footfall.reliability.parallel.open_workers`).

    Raises:
        ConfigError: A negative seed count or fewer than one job.
    """
    if seeds < 0 or jobs < 1:
        raise ConfigError(f"--seeds must be >= 0 and --jobs >= 1, got {seeds}, {jobs}")
    work = [("case", n) for n in cases] + [("room", first_seed + k) for k in range(seeds)]

    def done(job: tuple[str, int]) -> None:
        if on_run:
            on_run(f"{job[0]} {job[1]}")

    with open_workers(jobs, cluster) as workers:
        rows = workers.run(_one, work, done)
    runs = [rows[job] for job in work]
    return BipedBenchReport(runs, seeds)
