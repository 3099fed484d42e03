"""``footfall bench terrain``: every terrain over its difficulty range, in three modes.

The modes are planned (the full loop with route planning), straight (the same loop on the
straight line, the thesis' behaviour) and blind (the thesis' baseline). Each robot and gait
asked for (:mod:`footfall.reliability.variants`) walks the whole sweep; a row of the results
is one robot, gait, terrain, difficulty and mode over the seeds.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

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

# The modes: the full loop with route planning, the same on the straight line (the
# thesis' behaviour), and the blind baseline.
TERRAIN_MODES = ("planned", "straight", "blind")

# (robot, gait, settings, terrain, swept parameter, value, mode, seed, seconds)
Job = tuple[str, str, tuple, str, str, float, str, int, float]


def terrain_sweep(
    terrains: Sequence[str] | None = None,
) -> tuple[tuple[str, str, tuple[float, ...]], ...]:
    """What ``footfall bench terrain`` walks: ``(terrain, swept parameter, values)``.

    Every registered terrain that is benchmarked (or the named ones), in registration
    order; a terrain without a difficulty parameter is walked once, as ``("none", (0.0,))``.

    Raises:
        ConfigError: On a name the sweep does not hold.
    """
    from footfall.sim.terrains import TERRAINS

    sweep = []
    for name in TERRAINS:
        kind = TERRAINS.get(name)
        if kind.benchmarked:
            if kind.difficulty is not None and kind.sweep:
                sweep.append((name, kind.difficulty, tuple(kind.sweep)))
            else:
                sweep.append((name, "none", (0.0,)))
    if terrains is None:
        return tuple(sweep)
    known = {name for name, _, _ in sweep}
    unknown = [t for t in terrains if t not in known]
    if unknown:
        raise ConfigError(
            f"no terrain {', '.join(map(repr, unknown))} in the sweep; choose from "
            f"{', '.join(name for name, _, _ in sweep)}"
        )
    return tuple(entry for entry in sweep if entry[0] in terrains)


def terrain_modes(modes: Sequence[str] | None = None) -> tuple[str, ...]:
    """The named modes (all by default), in ``TERRAIN_MODES``' order.

    Raises:
        ConfigError: On a mode that is not one of them.
    """
    if modes is None:
        return TERRAIN_MODES
    unknown = [m for m in modes if m not in TERRAIN_MODES]
    if unknown or not modes:
        raise ConfigError(
            f"no mode {', '.join(map(repr, unknown)) or 'given'}; choose from "
            f"{', '.join(TERRAIN_MODES)}"
        )
    return tuple(m for m in TERRAIN_MODES if m in modes)


def _terrain_run(job: Job) -> dict[str, object]:
    """One walk of the sweep."""
    from footfall.sim.terrains import TERRAINS
    from footfall.sim.walk_metrics import WalkMetrics

    robot, gait, overrides, name, difficulty, value, mode, seed, seconds = job
    result = walk_variant(
        Variant(robot, gait, overrides),
        name,
        seed,
        seconds,
        difficulty=None if difficulty == "none" else value,
        blind=mode == "blind",
        straight=mode == "straight",
    )
    m = result.metrics
    assert isinstance(m, WalkMetrics)  # a simulated walk always walks
    invalid = m.footholds.invalid_footholds or 0
    safe = not m.fell and invalid == 0
    navigation = m.navigation
    no_route = navigation is not None and navigation.no_route
    if not TERRAINS.get(name).has_route:
        # Standing still with the reason: the navigator's "no route", or a freeze that
        # says why (the thesis' robot at a wall).
        success = safe and not m.reached_goal and (no_route or m.outcome.frozen)
    else:
        success = safe and m.reached_goal
    reason = (navigation.no_route_reason if navigation is not None else "") or (
        m.outcome.frozen_reason
    )

    def replan_ms(value: float | None) -> float:
        return float("nan") if value is None else float(value)

    estimator = {}
    if m.estimator is not None:  # footfall's own pose: its error per metre walked
        walked = max(m.gait.distance_m, 1e-9)
        estimator = {
            "estimator_drift_per_m": m.estimator["estimator_position_drift_m"] / walked,
            "estimator_heading_drift_deg_per_m": m.estimator["estimator_heading_drift_deg"]
            / walked,
        }
    return {
        **estimator,
        "success": success,
        "fell": m.fell,
        "invalid_footholds": invalid,
        "frozen": m.outcome.frozen,
        "foothold_region_jumps": m.robustness.foothold_region_jumps or 0,
        "no_route": no_route,
        "reason": reason,
        "tilt_max_deg": m.gait.tilt_max_deg,
        "mean_speed_mps": m.gait.mean_speed_mps,
        "stance_slip_max_m": m.gait.stance_slip_max_m,
        "sim_seconds": m.gait.sim_seconds,
        "wall_seconds": m.gait.wall_seconds,
        "replan_ms_median": replan_ms(navigation and navigation.replan_ms_median),
        "replan_ms_p95": replan_ms(navigation and navigation.replan_ms_p95),
    }


def impassable_reason(variant: Variant, terrain: str, difficulty: str, value: float) -> str:
    """Why no gait of the variant's robot can cross the terrain at this difficulty.

    :meth:`footfall.sim.terrain.Terrain.impassable_for` on the robot as the walks set it up
    (its settings applied); "" where one may.
    """
    from footfall.sim.walk_request import WalkRequest, prepare_walk

    job = prepare_walk(
        WalkRequest(
            terrain=terrain,
            robot=variant.robot,
            gait=variant.gait,
            difficulty=None if difficulty == "none" else value,
            overrides=variant.overrides,
        )
    )
    return job.terrain.impassable_for(job.spec)


def _walking_medians(outcomes: Sequence[dict]) -> dict[str, float]:
    """Medians over walks: the largest tilt, the mean speed and the largest stance slip.

    With footfall's own pose (``--pose estimator``) also its position and heading drift per
    metre walked.
    """

    def median(key: str) -> float:
        return float(np.median([o[key] for o in outcomes])) if outcomes else float("nan")

    medians = {
        "median_tilt_max_deg": median("tilt_max_deg"),
        "median_speed_mps": median("mean_speed_mps"),
        "median_stance_slip_max_m": median("stance_slip_max_m"),
    }
    for key in ("estimator_drift_per_m", "estimator_heading_drift_deg_per_m"):
        if outcomes and all(key in o for o in outcomes):
            medians[f"median_{key}"] = median(key)
    return medians


def run_terrain_benchmark(
    seeds: int,
    seconds: float = 150.0,
    on_run: Callable[[str], None] | None = None,
    jobs: int = 1,
    terrains: Sequence[str] | None = None,
    first_seed: int = 0,
    modes: Sequence[str] | None = None,
    robots: Sequence[str] | None = None,
    gaits: Sequence[str] | None = None,
    cluster: str | None = None,
    sets: Sequence[str] | None = None,
) -> dict[str, object]:
    """The terrain sweep in every mode (or ``modes``), ``seeds`` runs per configuration.

    Success = reached the goal, no fall, zero invalid footholds; on a terrain without a
    route (``Terrain.has_route`` False): stood still and said why, no fall, zero invalid.
    A row whose geometry no gait of its robot can cross (:func:`impassable_reason`) is
    walked and reported as ``impassable`` with the reason, and left out of the success rates.

    Args:
        seeds: Runs per terrain, difficulty and mode.
        seconds: Longest walk [s].
        on_run: Called with a label after each run (progress display).
        jobs: Walks simulated at once, each in its own process.
        terrains: Terrains of the sweep to walk (all by default).
        first_seed: The seeds run from this one up.
        modes: Modes to walk (all of ``TERRAIN_MODES`` by default); a mode not walked has
            no success rate.
        robots: Robots to walk (built-in names or TOML files; the default robot by default).
        gaits: Gaits each robot walks (tripod by default).
        sets: ``NAME=V1,V2,...`` settings (:mod:`footfall.sim.overrides`): the sweep is
            walked with every combination of their values.
        cluster: A Ray cluster's address (or ``"auto"``) to walk on instead of this
            machine's ``jobs`` processes (:func:`footfall.reliability.parallel.open_workers`).

    Returns:
        Per configuration (``results``: robot, gait, settings, terrain, difficulty, value,
        mode): ``impassable`` and ``impassable_reason``, runs, successes, falls, invalid
        footholds, frozen runs, runs without a route, the medians of the largest tilt, the
        speed and the largest stance slip, the reasons given, the failed seeds, wall time;
        overall ``planned_success_rate``, ``straight_success_rate`` and
        ``blind_success_rate`` over the rows not impassable, and ``impassable_rows``; the
        same, with the walking medians, per robot, gait and settings (``variants``); the
        names set (``settings``);
        and the route planner's replan times over the planned runs.
    """
    variants = parse_variants(robots, gaits, sets)
    sweep = terrain_sweep(terrains)
    chosen = terrain_modes(modes)
    configs = [
        (*variant, name, difficulty, value, mode)
        for variant in variants
        for name, difficulty, values in sweep
        for value in values
        for mode in chosen
    ]
    seed_range = range(first_seed, first_seed + seeds)
    work = [(*config, seed, seconds) for config in configs for seed in seed_range]
    several = len(variants) > 1

    def done(job: Job) -> None:
        if on_run is not None:
            robot, gait, overrides, name, difficulty, value, mode, seed, _ = job
            who = f"{Variant(robot, gait, overrides).label} " if several else ""
            on_run(f"{who}{name} {difficulty}={value:g} {mode} seed {seed}")

    with open_workers(jobs, cluster) as workers:
        runs = workers.run(_terrain_run, work, done)
    rows = []
    reasons: dict[tuple, str] = {}  # the modes of a terrain row share the verdict
    for config in configs:
        outcomes = [runs[(*config, seed, seconds)] for seed in seed_range]
        robot, gait, overrides, name, difficulty, value, mode = config
        if config[:-1] not in reasons:
            variant = Variant(robot, gait, overrides)
            reasons[config[:-1]] = impassable_reason(variant, name, difficulty, value)
        impassable = reasons[config[:-1]]
        rows.append(
            {
                **variant_row(Variant(robot, gait, overrides)),
                "terrain": name,
                "difficulty": difficulty,
                "value": value,
                "mode": mode,
                "impassable": bool(impassable),
                "impassable_reason": impassable,
                **tally(outcomes, seed_range),
                "no_route": sum(bool(o["no_route"]) for o in outcomes),
                **_walking_medians(outcomes),
                "reasons": sorted({str(o["reason"]) for o in outcomes if o["reason"]}),
                "wall_seconds": float(sum(o["wall_seconds"] for o in outcomes)),
            }
        )

    def rate(mode: str) -> float:
        mine = [r for r in rows if r["mode"] == mode and not r["impassable"]]
        runs_of_mode = sum(r["runs"] for r in mine)
        if not runs_of_mode:
            return float("nan")
        return sum(r["successes"] for r in mine) / runs_of_mode

    planned = [runs[job] for job in work if job[6] == "planned"]  # the job's mode
    of_variant: dict[Variant, list[dict]] = {v: [] for v in variants}
    for job in work:
        of_variant[Variant(*job[:3])].append(runs[job])
    medians = [o["replan_ms_median"] for o in planned if np.isfinite(o["replan_ms_median"])]
    p95s = [o["replan_ms_p95"] for o in planned if np.isfinite(o["replan_ms_p95"])]
    return {
        "seeds": seeds,
        "first_seed": first_seed,
        "robots": list(dict.fromkeys(v.robot for v in variants)),
        "gaits": list(dict.fromkeys(v.gait for v in variants)),
        "terrains": [name for name, _, _ in sweep],
        "modes": list(chosen),
        "results": rows,
        "impassable_rows": sum(r["impassable"] for r in rows),
        "settings": sorted({name for v in variants for name, _ in v.overrides}),
        "variants": [
            {**rates, **_walking_medians(of_variant[v])}
            for v, rates in zip(variants, variant_rates(rows, variants, chosen), strict=True)
        ],
        "planned_success_rate": rate("planned"),
        "straight_success_rate": rate("straight"),
        "blind_success_rate": rate("blind"),
        "replan_ms_median": float(np.median(medians)) if medians else float("nan"),
        "replan_ms_p95_max": float(np.max(p95s)) if p95s else float("nan"),
    }


def terrain_benchmark_runs(
    seeds: int,
    terrains: Sequence[str] | None = None,
    modes: Sequence[str] | None = None,
    variants: int = 1,
) -> int:
    """How many walks :func:`run_terrain_benchmark` makes for ``variants`` robot-gait pairs."""
    sweep = terrain_sweep(terrains)
    return variants * len(terrain_modes(modes)) * seeds * sum(len(v) for _, _, v in sweep)
