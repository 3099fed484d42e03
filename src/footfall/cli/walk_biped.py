"""``footfall walk-biped``: Archie walks a planned path in MuJoCo."""

from __future__ import annotations

import argparse
from pathlib import Path

from rich.console import Console

from footfall.cli.commands import summary
from footfall.cli.common import format_value, print_table, wrote

SUMMARY = (
    ("reached goal", "reached_goal", "{}"),
    ("fell", "fell", "{}"),
    ("collisions", "collisions", "{}"),
    ("ZMP margin (min)", "zmp_margin_min_m", "{:.4f} m"),
    ("footstep error (mean)", "footstep_error_mean_m", "{:.4f} m"),
    ("COM tracking error (max)", "com_tracking_error_max_m", "{:.4f} m"),
    ("footsteps", "footsteps", "{}"),
    ("plans", "plans", "{}"),
    ("no route", "no_route", "{}"),
    ("real-time factor", "realtime_factor", "{:.1f}x"),
)


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """Add ``walk-biped``."""
    p = subparsers.add_parser(
        "walk-biped",
        help=summary("walk-biped"),
        description=(
            "Simulate Archie in MuJoCo: a path around the obstacles, footsteps, a centre-of-mass "
            "pattern, joint angles from the legs' kinematics, a ZMP and attitude stabiliser. "
            "--case and --map bring their obstacles and goal and are planned once; --room SEED "
            "builds a random room the robot sees only through its head camera, looking and "
            "replanning as it goes. Writes metrics.json, top.png, balance.png and joints.png "
            "to --out."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    source = p.add_mutually_exclusive_group(required=True)
    source.add_argument("--case", type=int, choices=range(1, 12), metavar="1..11",
                        help="one of the dissertation's 11 test maps")  # fmt: skip
    source.add_argument("--map", type=Path, help="a JSON map file (see footfall.biped.maps)")
    source.add_argument("--room", type=int, metavar="SEED", help="a random room seen by camera")
    source.add_argument(
        "--kajita", action="store_true", help="Kajita's straight example: 0.3 m steps, 4 steps"
    )
    p.add_argument(
        "--goal", type=float, nargs=2, metavar=("X", "Y"), help="goal instead of the source's [m]"
    )
    p.add_argument("--robot", default="archie", help="biped spec: a built-in name or a TOML file")
    p.add_argument(
        "--out", type=Path, default=Path("footfall-out/walk-biped"), help="output folder"
    )
    p.set_defaults(handler=run)


def run(args: argparse.Namespace, console: Console) -> int:
    """Walk, write the outputs, print the summary."""
    from footfall.reports.biped_walk import run_walk_biped
    from footfall.sim.biped_run import WalkBipedRequest

    report = run_walk_biped(
        WalkBipedRequest(
            case=args.case,
            map=args.map,
            room=args.room,
            kajita=args.kajita,
            goal=tuple(args.goal) if args.goal is not None else None,
            spec=args.robot,
        )
    )
    paths = report.write(args.out)
    m = report.to_json()
    rows = [
        (label, format_value(m[key], fmt) if m[key] is not None else "n/a")
        for label, key, fmt in SUMMARY
    ]
    print_table(console, f"walk-biped: {m['name']}", rows)
    wrote(console, paths)
    return 0 if m["reached_goal"] else 1
