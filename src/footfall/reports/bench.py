"""The benchmarks of ``footfall bench``: mapping speed, and walking over a terrain sweep."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from footfall.errors import ConfigError
from footfall.reports import write_json


@dataclass(frozen=True)
class BenchReport:
    """A benchmark's figures.

    Attributes:
        suite: ``"mapping"``, ``"terrain"``, ``"faults"`` or ``"soak"``.
        figures: The ``bench.json`` content.
    """

    suite: str
    figures: dict[str, object] = field(default_factory=dict)

    def to_json(self) -> dict[str, object]:
        """The ``bench.json`` content."""
        return dict(self.figures)

    def write(self, out: Path) -> list[Path]:
        """Write ``bench.json`` (``soak.json`` for a soak) and its figure to ``out``."""
        out.mkdir(parents=True, exist_ok=True)
        paths = [out / ("soak.json" if self.suite == "soak" else "bench.json")]
        write_json(paths[0], self.to_json())
        if self.suite == "terrain":
            from footfall.plots import plot_terrain_benchmark

            paths.append(out / "bench.png")
            plot_terrain_benchmark(self.figures, paths[1])
        elif self.suite == "faults":
            from footfall.reliability.plots import plot_fault_benchmark

            paths.append(out / "bench.png")
            plot_fault_benchmark(self.figures, paths[1])
        elif self.suite == "soak":
            from footfall.reliability.plots import plot_soak

            paths.append(out / "soak.png")
            plot_soak(self.figures, paths[1])
        return paths


def run_mapping_bench(repeats: int = 30) -> BenchReport:
    """Time the map update and the scoring against their NumPy baselines."""
    from footfall.benchmarking import run_mapping_benchmark

    if repeats < 1:
        raise ConfigError(f"--repeats must be at least 1, got {repeats}")
    return BenchReport("mapping", dict(run_mapping_benchmark(repeats=repeats)))


def run_terrain_bench(
    seeds: int,
    seconds: float,
    jobs: int = 1,
    on_run: Callable[[str], None] | None = None,
    terrains: Sequence[str] | None = None,
    first_seed: int = 0,
    modes: Sequence[str] | None = None,
    robots: Sequence[str] | None = None,
    gaits: Sequence[str] | None = None,
    cluster: str | None = None,
    sets: Sequence[str] | None = None,
) -> BenchReport:
    """Planned, straight and blind walking over the terrain sweep (``run_terrain_benchmark``)."""
    from footfall.reliability.terrain_bench import run_terrain_benchmark

    if seeds < 1:
        raise ConfigError(f"--seeds must be at least 1, got {seeds}")
    return BenchReport(
        "terrain",
        run_terrain_benchmark(
            seeds,
            seconds,
            on_run=on_run,
            jobs=jobs,
            terrains=terrains,
            first_seed=first_seed,
            modes=modes,
            robots=robots,
            gaits=gaits,
            cluster=cluster,
            sets=sets,
        ),
    )


def run_faults_bench(
    seeds: int,
    seconds: float,
    faults: Sequence[tuple[str, str]] | None = None,
    terrains: Sequence[str] | None = None,
    jobs: int = 1,
    on_run: Callable[[str], None] | None = None,
    survey_seconds: float = 20.0,
    first_seed: int = 0,
    robots: Sequence[str] | None = None,
    gaits: Sequence[str] | None = None,
    cluster: str | None = None,
    sets: Sequence[str] | None = None,
) -> BenchReport:
    """Every fault class on every terrain (see ``run_fault_benchmark``)."""
    from footfall.reliability.faults_bench import (
        FAULT_CLASSES,
        FAULT_TERRAINS,
        run_fault_benchmark,
    )

    figures = run_fault_benchmark(
        seeds,
        seconds,
        faults=faults or FAULT_CLASSES,
        terrains=terrains or FAULT_TERRAINS,
        jobs=jobs,
        on_run=on_run,
        survey_seconds=survey_seconds,
        first_seed=first_seed,
        robots=robots,
        gaits=gaits,
        cluster=cluster,
        sets=sets,
    )
    return BenchReport("faults", figures)


def run_soak_bench(
    minutes: float,
    terrain: str = "cobblestones",
    sample_seconds: float = 10.0,
    on_sample: Callable[[dict[str, float]], None] | None = None,
) -> BenchReport:
    """Laps of a terrain for ``minutes`` of wall time (see ``run_soak``)."""
    from footfall.reliability.soak import run_soak

    return BenchReport("soak", run_soak(minutes, terrain, sample_seconds, on_sample=on_sample))
