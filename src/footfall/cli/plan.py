"""``footfall plan``: a biped's path, footsteps and centre-of-mass pattern around obstacles."""

from __future__ import annotations

import argparse
from pathlib import Path

from rich.console import Console

from footfall.cli.commands import summary
from footfall.cli.common import add_cloud_options, cloud_request, wrote


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """Add ``plan``."""
    p = subparsers.add_parser(
        "plan",
        help=summary("plan"),
        description=(
            "Plan the humanoid's walk (dissertation §6.3): a path around circular obstacles, "
            "footsteps along it and the Linear Inverted Pendulum pattern over them. Writes "
            "plan.json and plan.png to --out."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    source = p.add_mutually_exclusive_group(required=True)
    source.add_argument("--map", type=Path, help="a JSON map file (see footfall.biped.maps)")
    source.add_argument("--case", type=int, help="one of the dissertation's 11 test maps")
    source.add_argument(
        "--cloud", type=Path, help="a point cloud (.pcd, .ply, .npy): detect obstacles, then plan"
    )
    add_cloud_options(p)
    p.add_argument(
        "--start", type=float, nargs=2, metavar=("X", "Y"), help="start instead of the map's [m]"
    )
    p.add_argument(
        "--goal", type=float, nargs=2, metavar=("X", "Y"), help="goal instead of the map's [m]"
    )
    p.add_argument("--out", type=Path, default=Path("footfall-out/plan"), help="output folder")
    p.set_defaults(handler=run)


def run(args: argparse.Namespace, console: Console) -> int:
    """Plan, write the outputs, print a summary line."""
    from footfall.reports.biped import PlanRequest, run_plan

    report = run_plan(
        PlanRequest(
            map=args.map,
            case=args.case,
            cloud=cloud_request(args) if args.cloud is not None else None,
            start=tuple(args.start) if args.start is not None else None,
            goal=tuple(args.goal) if args.goal is not None else None,
        )
    )
    paths = report.write(args.out)
    plan = report.plan
    console.print(
        f"{report.plan_map.name}: path {plan.path.length:.2f} m, "
        f"{len(plan.path.waypoints) - 2} waypoints, "
        f"{len(plan.footsteps.positions)} footsteps, planned in {plan.plan_ms:.2f} ms, "
        f"{plan.collisions} collisions"
    )
    wrote(console, paths)
    return 0
