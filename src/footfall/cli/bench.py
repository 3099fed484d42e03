"""``footfall bench``: the mapping speed benchmark and the terrain sweep."""

from __future__ import annotations

import argparse
from pathlib import Path

from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn
from rich.table import Table

from footfall.cli.common import wrote


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """Add ``bench`` and its suites."""
    p = subparsers.add_parser(
        "bench",
        help="measure footfall's speed",
        description="Measure footfall's speed against baselines timed in the same run.",
    )
    kinds = p.add_subparsers(dest="suite", metavar="SUITE", required=True)
    mapping = kinds.add_parser(
        "mapping",
        help="depth frame -> map update, and scoring, against plain NumPy",
        description=(
            "Time one 640x480 depth frame -> points -> map update and the scoring of a "
            "256x256 map, against plain-NumPy baselines; writes bench.json to --out."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    mapping.add_argument("--repeats", type=int, default=30, help="timed repetitions per figure")
    mapping.add_argument(
        "--out", type=Path, default=Path("footfall-out/bench"), help="output folder"
    )
    mapping.set_defaults(handler=run_mapping)
    terrain = kinds.add_parser(
        "terrain",
        help="planned against blind walking over a difficulty sweep",
        description=(
            "Walk stairs (rise 0.02-0.08 m), cobblestones (groove 0.01-0.06 m) and the course, "
            "planned and blind, --seeds runs each; writes bench.json and bench.png to --out. "
            "Success = reached the goal, no fall, zero invalid footholds."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    terrain.add_argument(
        "--seeds", type=int, default=10, help="runs per terrain, difficulty and mode"
    )
    terrain.add_argument("--seconds", type=float, default=90.0, help="longest walk in seconds")
    terrain.add_argument(
        "--jobs", type=int, default=1, help="walks simulated at once, one process each"
    )
    terrain.add_argument(
        "--out", type=Path, default=Path("footfall-out/bench-terrain"), help="output folder"
    )
    terrain.set_defaults(handler=run_terrain)


def run_mapping(args: argparse.Namespace, console: Console) -> int:
    """Time the mapping and print the figures."""
    from footfall.reports.bench import run_mapping_bench

    report = run_mapping_bench(repeats=args.repeats)
    paths = report.write(args.out)
    table = Table(title="mapping benchmark (one core)")
    table.add_column("figure")
    table.add_column("value", justify="right")
    for key, value in report.to_json().items():
        table.add_row(key, f"{value:,.3f}" if isinstance(value, float) else str(value))
    console.print(table)
    wrote(console, paths)
    return 0


def run_terrain(args: argparse.Namespace, console: Console) -> int:
    """Walk the terrain sweep and print the results table."""
    from footfall.benchmarking import terrain_benchmark_runs
    from footfall.reports.bench import run_terrain_bench

    with Progress(
        TextColumn("{task.description}"),
        BarColumn(),
        TextColumn("{task.completed}/{task.total} walks"),
        TimeRemainingColumn(),
        console=console,
    ) as progress:
        task = progress.add_task("walking", total=terrain_benchmark_runs(max(args.seeds, 0)))
        report = run_terrain_bench(
            args.seeds,
            args.seconds,
            jobs=args.jobs,
            on_run=lambda label: progress.update(task, advance=1, description=label),
        )
    paths = report.write(args.out)
    bench = report.to_json()
    table = Table(title=f"terrain benchmark, {args.seeds} seeds")
    for column in (
        "terrain",
        "difficulty",
        "mode",
        "success",
        "falls",
        "invalid",
        "frozen",
        "tilt (median)",
    ):
        table.add_column(column)
    for r in bench["results"]:
        table.add_row(
            r["terrain"],
            f"{r['difficulty']} {r['value']:g}" if r["difficulty"] != "none" else "-",
            r["mode"],
            f"{r['successes']}/{r['runs']}",
            str(r["falls"]),
            str(r["invalid_footholds"]),
            str(r["frozen"]),
            f"{r['median_tilt_max_deg']:.2f} deg",
        )
    console.print(table)
    planned, blind = bench["planned_success_rate"], bench["blind_success_rate"]
    console.print(f"planned success {planned:.0%}, blind {blind:.0%}")
    wrote(console, paths)
    return 0
