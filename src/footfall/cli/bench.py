"""``footfall bench``: the mapping speed, the walking suites and the biped's benchmark."""

from __future__ import annotations

import argparse
from pathlib import Path

from rich.console import Console
from rich.table import Table

from footfall.cli.bench_walks import add_walking_suites
from footfall.cli.commands import summary
from footfall.cli.common import count_progress, wrote


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """Add ``bench`` and its suites."""
    p = subparsers.add_parser(
        "bench",
        help=summary("bench"),
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
    add_walking_suites(kinds)
    biped = kinds.add_parser(
        "biped",
        help="Archie on the dissertation's 11 maps and random rooms",
        description=(
            "Walk the biped on the 11 test maps of the dissertation (§6.3.2) and on --seeds "
            "random rooms seen through its head camera; writes bench.json (per run: reached "
            "goal, fall, collisions, ZMP margin, footstep and COM errors; totals per kind)."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    biped.add_argument("--seeds", type=int, default=5, help="random rooms to walk")
    biped.add_argument("--first-seed", type=int, default=0, help="the rooms' seeds start here")
    biped.add_argument("--jobs", type=int, default=1, help="walks run in parallel")
    biped.add_argument(
        "--cluster",
        metavar="ADDRESS|auto",
        default=None,
        help="run every walk as a task on this Ray cluster instead of --jobs processes here",
    )
    biped.add_argument(
        "--out", type=Path, default=Path("footfall-out/bench-biped"), help="output folder"
    )
    biped.set_defaults(handler=run_biped)


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


def run_biped(args: argparse.Namespace, console: Console) -> int:
    """Walk the biped's maps and rooms and print the table."""
    from footfall.biped.maps import TEST_CASES
    from footfall.reports.biped_walk import run_biped_bench

    with count_progress(console, "walks") as progress:
        task = progress.add_task("walking", total=len(TEST_CASES) + max(args.seeds, 0))
        report = run_biped_bench(
            args.seeds,
            first_seed=args.first_seed,
            jobs=args.jobs,
            cluster=args.cluster,
            on_run=lambda label: progress.update(task, advance=1, description=label),
        )
    paths = report.write(args.out)
    bench = report.to_json()
    table = Table(title=f"biped benchmark: 11 maps, {args.seeds} rooms")
    for column in ("run", "goal", "fell", "collisions", "ZMP margin", "footstep error"):
        table.add_column(column)
    for r in bench["runs"]:
        margin, error = r["zmp_margin_min_m"], r["footstep_error_mean_m"]
        table.add_row(
            r["name"],
            "yes" if r["reached_goal"] else "no",
            "yes" if r["fell"] else "no",
            str(r["collisions"]),
            "n/a" if margin is None else f"{100 * margin:.1f} cm",
            "n/a" if error is None else f"{100 * error:.1f} cm",
        )
    console.print(table)
    for kind, s in bench["summary"].items():
        console.print(
            f"{kind}s: {s['reached_goal']}/{s['runs']} reached the goal, {s['falls']} falls, "
            f"{s['collisions']} collisions"
        )
    wrote(console, paths)
    return 0
