"""``footfall servo-bus``: emulated servos and a camera for a dry run of ``robot --hardware``."""

from __future__ import annotations

import argparse
from pathlib import Path

from rich.console import Console

from footfall.cli.commands import summary
from footfall.cli.robot import add_network_options, network_config

SENSOR_ENDPOINT = "tcp/127.0.0.1:7448"


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """Add ``servo-bus``."""
    from footfall.robot.spec import BUILTIN_ROBOTS
    from footfall.sim.terrains import TERRAINS

    p = subparsers.add_parser(
        "servo-bus",
        help=summary("servo-bus"),
        description=(
            "Emulated Dynamixel servos turning the MuJoCo robot's joints answer on a "
            "pseudo-terminal that --link names, at the wall clock's pace; the robot's depth "
            "and colour images and their poses go out on zenoh under --name. Then run "
            "'footfall robot --hardware ROBOT.toml --port LINK --camera network --pose "
            "network' and drive it from a station. The servos power up limp."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    p.add_argument("--sim", choices=TERRAINS.names(), default="stairs", help="terrain")
    p.add_argument("--seed", type=int, default=0, help="seed of the terrain")
    p.add_argument(
        "--link", type=Path, required=True, help="symbolic link to create to the pseudo-terminal"
    )
    p.add_argument(
        "--robot",
        default="default",
        help=f"built-in robot ({', '.join(BUILTIN_ROBOTS)}) or a TOML file with [hardware]",
    )
    p.add_argument(
        "--protocol",
        type=int,
        choices=(1, 2),
        help="Dynamixel protocol when the robot's [hardware] table names none (default 1)",
    )
    p.add_argument("--seconds", type=float, default=600.0, help="longest run in seconds")
    add_network_options(p, listen=[SENSOR_ENDPOINT], connect=[])
    p.set_defaults(handler=run, name="hexapod-sim")


def run(args: argparse.Namespace, console: Console) -> int:
    """Serve until Ctrl-C or --seconds."""
    from footfall.hardware.config import hardware_from_dict
    from footfall.hardware.dry_run import serve_servo_bus
    from footfall.robot.spec import BUILTIN_ROBOTS, spec_from_dict
    from footfall.robots import read_description
    from footfall.runtime.scheduler import stop_on_signals
    from footfall.runtime.zenoh_bus import ZenohBus
    from footfall.sim.terrains import make_terrain

    description = read_description(args.robot, BUILTIN_ROBOTS)
    spec = spec_from_dict(description)
    config = hardware_from_dict(spec, description.get("hardware"), args.protocol, port="")
    terrain = make_terrain(args.sim, seed=args.seed)
    with stop_on_signals() as stop, ZenohBus(network_config(args)) as network:

        def ready(bus) -> None:
            where = ", ".join(network.listening_locators()) or "nowhere (connecting only)"
            console.print(
                f"servo bus on {bus.port} (-> {bus.path}): protocol {config.protocol}, "
                f"{config.baud} baud, {len(config.servos)} servos, limp; camera on "
                f"{network.prefix}/depth, color, pose, listening on {where}",
                highlight=False,
            )

        report = serve_servo_bus(
            spec, config, terrain, network, args.link, args.seconds, stop, on_ready=ready
        )
    console.print(
        f"served {report.sim_seconds:.1f} s: {report.packets} packets, {report.errors} "
        f"errors, {report.frames} images; body {report.body_height_m:.3f} m above the ground"
    )
    return 0
