"""``footfall bench terrain``, ``faults`` and ``soak``: the walking suites' options and tables."""

from __future__ import annotations

import argparse
import os
from collections.abc import Callable
from pathlib import Path

from rich.console import Console
from rich.table import Table

from footfall.cli.common import comma_list, count_progress, wrote


def add_walking_suites(kinds: argparse._SubParsersAction) -> None:
    """Add the terrain sweep, the fault benchmark and the soak to ``footfall bench``."""
    terrain = kinds.add_parser(
        "terrain",
        help="planned, straight and blind walking over a difficulty sweep",
        description=(
            "Walk every terrain over its difficulty range: stairs (rise 0.02-0.08 m), "
            "cobblestones (groove 0.01-0.06 m), the course, stepping stones (gap), gaps "
            "(width), boxes (height), ramps (slope), pits (depth), an obstacle field "
            "(density) and a dead end; in three modes: planned (the full loop with route "
            "planning), straight (the full loop on the straight line, the thesis' behaviour) "
            "and blind; --seeds runs each. Writes bench.json and bench.png to --out. "
            "Success = reached the goal, no fall, zero invalid footholds; on the dead end, "
            "stood still and said why. A row no gait of the robot can cross (its geometry "
            "against the robot's, e.g. trenches wider than a foot can step) is reported as "
            "impassable and left out of the success rates."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    terrain.add_argument(
        "--seeds", type=int, default=10, help="runs per terrain, difficulty and mode"
    )
    terrain.add_argument("--seconds", type=float, default=150.0, help="longest walk in seconds")
    terrain.add_argument(
        "--terrains",
        type=comma_list,
        default=None,
        metavar="NAME,NAME,...",
        help="terrains of the sweep to walk (default: all)",
    )
    terrain.add_argument(
        "--modes",
        type=comma_list,
        default=None,
        metavar="MODE,MODE,...",
        help="modes to walk: planned, straight, blind (default: all)",
    )
    terrain.add_argument("--first-seed", type=int, default=0, help="the seeds run from this one up")
    terrain.add_argument(
        "--jobs", type=int, default=1, help="walks simulated at once, one process each"
    )
    terrain.add_argument(
        "--out", type=Path, default=Path("footfall-out/bench-terrain"), help="output folder"
    )
    terrain.set_defaults(handler=run_terrain)
    faults = kinds.add_parser(
        "faults",
        help="walking through injected sensor and timing faults",
        description=(
            "Walk stairs, cobblestones and the course (planned, with the camera) with each "
            "fault class injected between the nodes (see footfall walk --faults), --seeds runs "
            "each, and survey the map's height error under SLAM noise without and with drift "
            "compensation; writes bench.json and bench.png to --out. Success = reached the "
            "goal, no fall, zero invalid footholds."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    faults.add_argument("--seeds", type=int, default=5, help="runs per fault class and terrain")
    faults.add_argument("--first-seed", type=int, default=0, help="the seeds run from this one up")
    faults.add_argument("--seconds", type=float, default=90.0, help="longest walk in seconds")
    faults.add_argument(
        "--survey-seconds",
        type=float,
        default=20.0,
        help="walking time of each map-error survey under SLAM noise",
    )
    faults.add_argument(
        "--faults",
        action="append",
        metavar="SPEC",
        help="walk this fault mix instead of the built-in classes (repeatable; as walk --faults)",
    )
    faults.add_argument(
        "--terrains",
        nargs="+",
        default=None,
        metavar="TERRAIN",
        help="terrains to walk (default: stairs cobblestones course)",
    )
    faults.add_argument(
        "--jobs",
        type=int,
        default=os.cpu_count() or 1,
        help="walks simulated at once, one process each",
    )
    faults.add_argument(
        "--out", type=Path, default=Path("footfall-out/bench-faults"), help="output folder"
    )
    faults.set_defaults(handler=run_faults)
    robots = (
        "robots to walk, each built-in (default, phantomx) or a robot TOML file; every one is "
        "a row dimension of bench.json and the chart"
    )
    gaits = "gaits every robot walks: tripod, ripple, wave"
    cluster = (
        "run every walk as a task on the Ray cluster at this address (HOST:PORT of its head) "
        "instead of --jobs processes here; auto: RAY_ADDRESS, the cluster last started on this "
        "machine, or a new local Ray instance (needs footfall[cluster] on every node)"
    )
    for suite in (terrain, faults):
        suite.add_argument(
            "--robot", type=comma_list, default=["default"], metavar="ROBOT,...", help=robots
        )
        suite.add_argument(
            "--gait", type=comma_list, default=["tripod"], metavar="GAIT,...", help=gaits
        )
        suite.add_argument(
            "--pose",
            type=comma_list,
            default=None,
            metavar="POSE,...",
            help="pose sources every variant walks with (sim, the simulator's truth; estimator, "
            "footfall's own from the legs and the IMU; each a row dimension, as --set "
            "walk.pose_source=...) [default: sim]",
        )
        suite.add_argument("--cluster", metavar="ADDRESS|auto", default=None, help=cluster)
        suite.add_argument(
            "--set",
            action="append",
            dest="sets",
            metavar="NAME=V1,V2,...",
            help="walk the suite with every combination of these settings (repeatable): a "
            "field of the robot, gait, scoring, mapping, planner, navigation or feedback "
            "configuration, e.g. scoring.threshold=0.4,0.5 or planner.footholds.search_radius=0.12",
        )
    soak = kinds.add_parser(
        "soak",
        help="a long run: memory and per-frame time over laps of a terrain",
        description=(
            "Walk laps of a terrain (planned, with the camera) for --minutes of wall time, "
            "sampling resident memory, per-frame mapping time, per-tick control time and live "
            "objects, and the time of a fixed reference workload (the machine's own speed "
            "drifts; the CPU times are also given as ratios to it); writes soak.json "
            "(samples, slopes per minute, growth from the first to the last ten minutes) and "
            "soak.png to --out."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    soak.add_argument("--minutes", type=float, default=60.0, help="wall-clock minutes to walk")
    soak.add_argument("--terrain", default="cobblestones", help="terrain to walk laps of")
    soak.add_argument("--sample-seconds", type=float, default=10.0, help="seconds between samples")
    soak.add_argument(
        "--out", type=Path, default=Path("footfall-out/bench-soak"), help="output folder"
    )
    soak.set_defaults(handler=run_soak)


def _walking(args: argparse.Namespace, on_run: Callable[[str], None]) -> dict[str, object]:
    """What both walking suites take from their common options: where and what to walk."""
    return {
        "jobs": args.jobs,
        "on_run": on_run,
        "first_seed": args.first_seed,
        "robots": args.robot,
        "gaits": args.gait,
        "cluster": args.cluster,
        "sets": _sets(args),
    }


def _sets(args: argparse.Namespace) -> list[str] | None:
    """The ``--set`` options, with ``--pose`` as the setting it stands for."""
    if args.pose is None:
        return args.sets
    return [*(args.sets or []), f"walk.pose_source={','.join(args.pose)}"]


def run_terrain(args: argparse.Namespace, console: Console) -> int:
    """Walk the terrain sweep and print the results table."""
    from footfall.reliability.terrain_bench import terrain_benchmark_runs
    from footfall.reliability.variants import parse_variants, variant_lines
    from footfall.reports.bench import run_terrain_bench

    variants = parse_variants(args.robot, args.gait, _sets(args))
    with count_progress(console, "walks") as progress:
        total = terrain_benchmark_runs(max(args.seeds, 0), args.terrains, args.modes, len(variants))
        task = progress.add_task("walking", total=total)
        report = run_terrain_bench(
            args.seeds,
            args.seconds,
            terrains=args.terrains,
            modes=args.modes,
            **_walking(args, lambda label: progress.update(task, advance=1, description=label)),
        )
    paths = report.write(args.out)
    bench = report.to_json()
    table = Table(title=f"terrain benchmark, {args.seeds} seeds")
    columns = "variant terrain difficulty mode success falls invalid frozen".split()
    for column in (*columns, "no route", "tilt (median)"):
        table.add_column(column)
    for r in bench["results"]:
        table.add_row(
            r["variant"],
            r["terrain"],
            f"{r['difficulty']} {r['value']:g}" if r["difficulty"] != "none" else "-",
            r["mode"],
            f"{r['successes']}/{r['runs']}" + (" impassable" if r["impassable"] else ""),
            str(r["falls"]),
            str(r["invalid_footholds"]),
            str(r["frozen"]),
            str(r["no_route"]),
            f"{r['median_tilt_max_deg']:.2f} deg",
        )
    console.print(table)
    console.print(
        f"success: planned {bench['planned_success_rate']:.0%}, straight "
        f"{bench['straight_success_rate']:.0%}, blind {bench['blind_success_rate']:.0%}; "
        f"route replans {bench['replan_ms_median']:.1f} ms median"
    )
    for line in variant_lines(bench):
        console.print(line)
    for reason in sorted({r["impassable_reason"] for r in bench["results"] if r["impassable"]}):
        console.print(f"impassable, left out of the success rates: {reason}")
    wrote(console, paths)
    return 0


def run_faults(args: argparse.Namespace, console: Console) -> int:
    """Walk every fault class and print the results table."""
    from footfall.reliability.faults_bench import (
        FAULT_CLASSES,
        FAULT_TERRAINS,
        fault_benchmark_runs,
        parse_fault_classes,
    )
    from footfall.reliability.variants import parse_variants, variant_lines
    from footfall.reports.bench import run_faults_bench

    faults = parse_fault_classes(args.faults) if args.faults else FAULT_CLASSES
    terrains = tuple(args.terrains) if args.terrains else FAULT_TERRAINS
    variants = parse_variants(args.robot, args.gait, _sets(args))
    with count_progress(console, "runs") as progress:
        task = progress.add_task(
            "walking", total=fault_benchmark_runs(max(args.seeds, 0), faults, terrains, variants)
        )
        report = run_faults_bench(
            args.seeds,
            args.seconds,
            faults=faults,
            terrains=terrains,
            survey_seconds=args.survey_seconds,
            **_walking(args, lambda label: progress.update(task, advance=1, description=label)),
        )
    paths = report.write(args.out)
    bench = report.to_json()
    table = Table(title=f"fault benchmark, {args.seeds} seeds")
    columns = ("variant", "fault", "terrain", "success", "falls", "invalid", "frozen")
    for column in (*columns, "recovered"):
        table.add_column(column)
    for r in bench["results"]:
        table.add_row(
            r["variant"],
            r["fault"],
            r["terrain"],
            f"{r['successes']}/{r['runs']}",
            str(r["falls"]),
            str(r["invalid_footholds"]),
            str(r["frozen"]),
            str(r["recovered"]),
        )
    console.print(table)
    rmse = bench["map_rmse"]
    console.print(
        f"success {bench['success_rate']:.0%}, falls {bench['falls']}, invalid footholds "
        f"{bench['invalid_footholds']}; map RMSE under SLAM noise "
        f"{1e3 * rmse['without_compensation_m']:.1f} mm without drift compensation, "
        f"{1e3 * rmse['with_compensation_m']:.1f} mm with"
    )
    for line in variant_lines(bench):
        console.print(line)
    wrote(console, paths)
    return 0


def run_soak(args: argparse.Namespace, console: Console) -> int:
    """Walk laps for the given time and print the trends."""
    from footfall.reliability.soak import QUANTITIES
    from footfall.reports.bench import run_soak_bench

    with count_progress(console) as progress:
        task = progress.add_task("soaking", total=args.minutes)
        report = run_soak_bench(
            args.minutes,
            terrain=args.terrain,
            sample_seconds=args.sample_seconds,
            on_sample=lambda s: progress.update(
                task,
                completed=s["wall_minutes"],
                description=f"lap {s['laps']}, {s['rss_mb']:.0f} MiB",
            ),
        )
    paths = report.write(args.out)
    figures = report.to_json()
    if figures.get("ended_early"):
        console.print(f"[red]The soak ended early:[/] {figures['ended_early']}")
    if "growth" in figures:
        table = Table(title=f"soak, {args.minutes:g} min, {figures['laps']} laps")
        for column in ("quantity", "first window", "last window", "growth", "slope / min"):
            table.add_column(column)
        for name in QUANTITIES:
            table.add_row(
                name,
                f"{figures['first_window_mean'][name]:.4g}",
                f"{figures['last_window_mean'][name]:.4g}",
                f"{figures['growth'][name]:+.2%}",
                f"{figures['slope_per_minute'][name]:+.3g}",
            )
        console.print(table)
    wrote(console, paths)
    return 0 if not figures.get("ended_early") else 1
