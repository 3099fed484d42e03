"""``footfall station``: the operator's base station in the browser."""

from __future__ import annotations

import argparse
import dataclasses

from rich.console import Console

from footfall.cli.commands import summary
from footfall.cli.robot import add_network_options, network_config


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """Add ``station``."""
    from footfall.runtime import DEFAULT_ENDPOINT

    p = subparsers.add_parser(
        "station",
        help=summary("station"),
        description=(
            "Connect to the robot's zenoh network and serve a page (viser) with its depth "
            "image, height and score maps, pose, gait status, log and link state, and the "
            "controls: mode (torque off / walking), direction, speed, body height, yaw rate, "
            "and a goal clicked on the ground, walked to along the route planner's routes on the "
            "robot's map. Commands repeat as a heartbeat."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    add_network_options(p, listen=[], connect=[DEFAULT_ENDPOINT])
    p.add_argument("--host", default="127.0.0.1", help="address the page is served on")
    p.add_argument("--port", type=int, default=8080, help="port of the page")
    p.add_argument("--seconds", type=float, default=None, help="stop after this long")
    p.add_argument(
        "--robot",
        default="default",
        help="the hexapod driven: a built-in robot or a robot description TOML file (its "
        "legs' span sizes the clearance of the routes to a clicked goal)",
    )
    p.add_argument(
        "--biped",
        action="store_true",
        help="the biped's station: capture and clear buttons, obstacles, path, footsteps and "
        "COM, and a clicked goal planned to (start_planning)",
    )
    p.add_argument(
        "--goal",
        nargs=2,
        type=float,
        metavar=("X", "Y"),
        help="a goal on the ground (map frame, m) sent as a click would, once the robot is "
        "heard: walked to along the routes (hexapod), planned to and walked (biped)",
    )
    p.set_defaults(handler=run)


def run(args: argparse.Namespace, console: Console) -> int:
    """Serve the station until Ctrl-C (or --seconds)."""
    from footfall.robot.spec import load_spec
    from footfall.runtime.scheduler import stop_on_signals
    from footfall.runtime.zenoh_bus import ZenohBus
    from footfall.station import Station

    # Ctrl-C or SIGTERM ends the run between two updates: an interrupt raised in the middle
    # of one could leave the page server or the session half-way and the process hanging.
    config = network_config(args)
    # Commands go on a connection of their own, never behind the station's other traffic.
    config = dataclasses.replace(config, command_session=bool(config.connect))
    with stop_on_signals() as stopped, ZenohBus(config) as bus:
        spec = None if args.biped else load_spec(args.robot)
        station = Station(bus, host=args.host, port=args.port, biped=args.biped, spec=spec)
        if args.goal is not None:
            station.pending_goal = (args.goal[0], args.goal[1])
        console.print(
            f"station for robot [bold]{args.name}[/] at http://{args.host}:{args.port}",
            highlight=False,
        )
        try:
            station.run(args.seconds, stop=stopped)
        finally:
            station.close()
    return 0
