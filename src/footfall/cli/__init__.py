"""The ``footfall`` command line.

One module per subcommand, each parsing its options into a request, calling the library's
``run_*`` function (:mod:`footfall.reports`) and printing the report.
"""

from __future__ import annotations

import argparse

from rich.console import Console

from footfall.cli import (
    bench,
    convert,
    map,
    obstacles,
    plan,
    replay,
    robot,
    servo_bus,
    station,
    walk,
    walk_biped,
)
from footfall.errors import FootfallError

SUBCOMMANDS = (
    walk,
    map,
    replay,
    convert,
    bench,
    plan,
    obstacles,
    robot,
    servo_bus,
    station,
    walk_biped,
)


def build_parser() -> argparse.ArgumentParser:
    """The ``footfall`` argument parser."""
    parser = argparse.ArgumentParser(
        prog="footfall",
        description="Legged robots walking over uneven terrain, simulated and recorded.",
    )
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for module in SUBCOMMANDS:
        module.add_parser(subparsers)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``footfall`` console script."""
    args = build_parser().parse_args(argv)
    console = Console()
    try:
        return args.handler(args, console)
    except FootfallError as exc:
        console.print(f"[red]error:[/] {exc}")
        return 2
