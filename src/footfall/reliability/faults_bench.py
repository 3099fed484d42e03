"""``footfall bench faults``: every fault class over stairs, cobblestones and the course.

Each run walks the planned robot (camera, map, footholds) to the terrain's goal with one
fault class injected between the nodes (:mod:`footfall.runtime.faults`). A run succeeds
when the robot reaches the goal without a fall and without an invalid foothold; a frozen
robot is safe but has not succeeded. A run *recovered* when the robot had to stop or
re-register on the way (it stood for a stale pose or map, froze, or the pose guard caught a
jump) and still reached the goal.

The same benchmark measures the map's height error under SLAM-like pose noise with and
without vertical drift compensation (the survey of ``footfall map --noise slam``).
"""

from __future__ import annotations

import math
import statistics
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

from footfall.errors import ConfigError
from footfall.reliability.parallel import open_workers
from footfall.reliability.variants import (
    Variant,
    parse_variants,
    tally,
    variant_rates,
    variant_row,
    walk_variant,
)
from footfall.runtime.fault_spec import FaultSpec

if TYPE_CHECKING:
    from footfall.sim.walk_settings import WalkResult

# The fault classes and the strength each is walked with.
FAULT_CLASSES: tuple[tuple[str, str], ...] = (
    ("none", ""),
    ("drop", "drop=0.3"),
    ("delay", "delay=0.2"),
    ("repeat", "repeat=0.1"),
    ("nan", "nan=0.05"),
    ("drift", "drift=slam"),
    ("jump", "jump=0.1:5@8"),
    ("pose_loss", "pose_loss=1.0@10"),
    ("overrun", "overrun=0.05"),
)
FAULT_TERRAINS = ("stairs", "cobblestones", "course")
# The map-error survey: terrains and walking time [s].
RMSE_TERRAINS = ("cobblestones", "course")
RMSE_SECONDS = 20.0

# (robot, gait, settings, fault label, fault spec, terrain, seed, seconds)
Job = tuple[str, str, tuple, str, str, str, int, float]
DEFAULT_VARIANT = Variant("default", "tripod")


def faulty_walk(
    terrain: str,
    spec: str,
    seed: int = 0,
    seconds: float = 90.0,
    variant: Variant = DEFAULT_VARIANT,
) -> WalkResult:
    """The planned robot walking ``terrain`` to its goal with the faults ``spec``."""
    return walk_variant(variant, terrain, seed, seconds, faults=spec)


def _walk(job: Job) -> dict[str, object]:
    """One walk of the benchmark."""
    from footfall.sim.walk_metrics import WalkMetrics

    robot, gait, overrides, _, spec, terrain, seed, seconds = job
    m = faulty_walk(terrain, spec, seed, seconds, Variant(robot, gait, overrides)).metrics
    assert isinstance(m, WalkMetrics)  # a simulated walk always walks
    r = m.robustness
    stopped = r.freezes + r.stale_stops
    caught = (r.pose_jumps_detected or 0) + (m.mapping.frames_inconsistent if m.mapping else 0)
    reached = m.reached_goal and not m.fell
    invalid = m.footholds.invalid_footholds or 0
    return {
        "success": reached and invalid == 0,
        "fell": m.fell,
        "invalid_footholds": invalid,
        "frozen": m.outcome.frozen,
        "foothold_region_jumps": m.robustness.foothold_region_jumps or 0,
        "recovered": reached and (stopped + caught) > 0,
        "wall_seconds": m.gait.wall_seconds,
    }


def _map_error(job: tuple[str, str, int, bool, float]) -> float:
    """Height RMSE of a SLAM-noise survey, ``(robot, terrain, seed, compensate, seconds)`` [m]."""
    from footfall.mapping.drift import DriftConfig
    from footfall.mapping.engine import HeightMapConfig
    from footfall.robot.spec import load_spec
    from footfall.sim.survey import MappingSettings, simulate_mapping

    robot, terrain, seed, compensate, seconds = job
    settings = MappingSettings(
        terrain=terrain,
        seconds=seconds,
        noise="slam",
        seed=seed,
        map=HeightMapConfig(drift=DriftConfig(enabled=compensate)),
    )
    return float(simulate_mapping(load_spec(robot), settings).metrics["height_rmse_m"])


def fault_benchmark_runs(
    seeds: int,
    faults: Sequence[tuple[str, str]],
    terrains: Sequence[str],
    variants: Sequence[Variant] = (DEFAULT_VARIANT,),
) -> int:
    """How many walks and surveys :func:`run_fault_benchmark` makes."""
    robots = len({v.robot for v in variants})
    return seeds * (len(variants) * len(faults) * len(terrains) + robots * 2 * len(RMSE_TERRAINS))


def parse_fault_classes(specs: Sequence[str]) -> tuple[tuple[str, str], ...]:
    """Fault mixes given on the command line, each labelled by its spec; checked now."""
    for spec in specs:
        FaultSpec.parse(spec)
    return tuple((spec or "none", spec) for spec in specs)


def run_fault_benchmark(
    seeds: int,
    seconds: float = 90.0,
    faults: Sequence[tuple[str, str]] = FAULT_CLASSES,
    terrains: Sequence[str] = FAULT_TERRAINS,
    jobs: int = 1,
    on_run: Callable[[str], None] | None = None,
    survey_seconds: float = RMSE_SECONDS,
    first_seed: int = 0,
    robots: Sequence[str] | None = None,
    gaits: Sequence[str] | None = None,
    cluster: str | None = None,
    sets: Sequence[str] | None = None,
) -> dict[str, object]:
    """Walk every fault class on every terrain ``seeds`` times, and survey the map error.

    Each survey walks ``survey_seconds`` under SLAM noise, without and with compensation.
    The seeds are ``first_seed`` to ``first_seed + seeds - 1``. Every robot in ``robots``
    walks every gait in ``gaits`` (the default robot's tripod by default) with every
    combination of the ``sets`` (``NAME=V1,V2,...``, :mod:`footfall.sim.overrides`); each
    robot is surveyed (as configured). The walks run in ``jobs`` processes, or as tasks on
    the Ray ``cluster`` at that address (:func:`footfall.reliability.parallel.open_workers`).

    Returns:
        ``results`` rows (``robot``, ``gait``, ``settings``, ``fault``, ``spec``,
        ``terrain``, ``runs``, ``successes``, ``falls``, ``invalid_footholds``, ``frozen``,
        ``recovered``, ``failed_seeds``, ``wall_seconds``), totals ``falls``,
        ``invalid_footholds`` and ``success_rate``, the same per robot, gait and settings
        (``variants``), and ``map_rmse`` with the surveys' mean height RMSE without and with
        drift compensation.
    """
    if seeds < 1:
        raise ConfigError(f"--seeds must be at least 1, got {seeds}")
    from footfall.sim.terrains import TERRAINS

    for terrain in terrains:
        TERRAINS.check(terrain)  # an unknown name is an error that lists the known ones
    for _, spec in faults:
        FaultSpec.parse(spec)
    variants = parse_variants(robots, gaits, sets)
    surveyed = list(dict.fromkeys(v.robot for v in variants))

    def progress(job: object) -> None:
        if on_run is not None:
            assert isinstance(job, tuple)
            # A walk: robot, gait, settings, fault, spec, terrain, seed; a survey: robot,
            # terrain, seed.
            walk = len(job) == 8
            shown = job[3:7] if walk else job[1:4]
            who = (Variant(*job[:3]).label,) if walk else job[:1]
            parts = (*who, *shown) if len(variants) > 1 else shown
            on_run(" ".join(str(part) for part in parts))

    seed_range = range(first_seed, first_seed + seeds)
    walks: list[Job] = [
        (*variant, label, spec, terrain, seed, seconds)
        for variant in variants
        for label, spec in faults
        for terrain in terrains
        for seed in seed_range
    ]
    if not (math.isfinite(survey_seconds) and survey_seconds > 0):
        raise ConfigError(f"--survey-seconds must be positive, got {survey_seconds}")
    surveys = [
        (robot, terrain, seed, compensate, survey_seconds)
        for robot in surveyed
        for terrain in RMSE_TERRAINS
        for seed in seed_range
        for compensate in (False, True)
    ]
    with open_workers(jobs, cluster) as workers:
        outcomes = workers.run(_walk, walks, progress)
        errors = workers.run(_map_error, surveys, progress)
    rows = []
    for variant in variants:
        for label, spec in faults:
            for terrain in terrains:
                key = (*variant, label, spec, terrain)
                runs = [outcomes[(*key, seed, seconds)] for seed in seed_range]
                rows.append(_row(key, runs, seed_range))
    total_runs = sum(r["runs"] for r in rows)
    per_survey = [
        {
            "robot": r,
            "terrain": t,
            "seed": s,
            "compensated": c,
            "height_rmse_m": errors[(r, t, s, c, d)],
        }
        for r, t, s, c, d in surveys
    ]
    return {
        "seeds": seeds,
        "first_seed": first_seed,
        "seconds": seconds,
        "robots": surveyed,
        "gaits": list(dict.fromkeys(v.gait for v in variants)),
        "settings": sorted({name for v in variants for name, _ in v.overrides}),
        "results": rows,
        "variants": variant_rates(rows, variants, ()),
        "falls": sum(r["falls"] for r in rows),
        "invalid_footholds": sum(r["invalid_footholds"] for r in rows),
        "success_rate": sum(r["successes"] for r in rows) / max(total_runs, 1),
        "map_rmse": {
            "noise": "slam",
            "survey_seconds": survey_seconds,
            "without_compensation_m": statistics.fmean(
                e["height_rmse_m"] for e in per_survey if not e["compensated"]
            ),
            "with_compensation_m": statistics.fmean(
                e["height_rmse_m"] for e in per_survey if e["compensated"]
            ),
            "surveys": per_survey,
        },
    }


def _row(key: tuple, runs: Sequence[dict], seed_range: range) -> dict[str, object]:
    """One ``results`` row: a robot, gait, fault and terrain over the seeds."""
    robot, gait, overrides, label, spec, terrain = key
    return {
        **variant_row(Variant(robot, gait, overrides)),
        "fault": label,
        "spec": spec,
        "terrain": terrain,
        **tally(runs, seed_range),
        "recovered": sum(bool(r["recovered"]) for r in runs),
        "wall_seconds": float(sum(float(r["wall_seconds"]) for r in runs)),
    }
