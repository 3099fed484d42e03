"""``footfall robot``: the simulated hexapod as a robot on the network."""

from __future__ import annotations

import argparse
import dataclasses
import math
from pathlib import Path

from rich.console import Console

from footfall.cli.commands import summary
from footfall.cli.common import add_recording_options, key_values, wrote
from footfall.errors import ConfigError


def add_network_options(p: argparse.ArgumentParser, listen: list[str], connect: list[str]) -> None:
    """The options of joining the zenoh network."""
    p.add_argument(
        "--listen",
        action="append",
        metavar="ENDPOINT",
        help=f"zenoh endpoint to listen on (repeatable; default {', '.join(listen) or 'none'})",
    )
    p.add_argument(
        "--connect",
        action="append",
        metavar="ENDPOINT",
        help=f"zenoh endpoint to connect to (repeatable; default {', '.join(connect) or 'none'})",
    )
    p.add_argument("--name", default="hexapod", help="robot name in the key expressions")
    p.add_argument(
        "--listen-remote",
        action="store_true",
        help="allow listening on addresses other than loopback (reachable from other machines)",
    )
    p.add_argument(
        "--scouting", action="store_true", help="discover peers by multicast (off by default)"
    )
    p.add_argument(
        "--zenoh-config",
        type=Path,
        help="zenoh configuration file (JSON5): TLS certificates, user/password authentication",
    )
    p.set_defaults(default_listen=listen, default_connect=connect)


def network_config(args: argparse.Namespace):
    """The zenoh settings the network options describe."""
    from footfall.runtime.zenoh_bus import ZenohConfig

    return ZenohConfig(
        robot=args.name,
        listen=tuple(args.listen if args.listen is not None else args.default_listen),
        connect=tuple(args.connect if args.connect is not None else args.default_connect),
        scouting=args.scouting,
        allow_remote=args.listen_remote,
        config_file=args.zenoh_config,
    )


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """Add ``robot``."""
    from footfall.backends.registry import BACKENDS
    from footfall.nodes.sources import CAMERAS, POSES
    from footfall.runtime import DEFAULT_ENDPOINT
    from footfall.sim.terrains import TERRAINS

    p = subparsers.add_parser(
        "robot",
        help=summary("robot"),
        description=(
            "Run the hexapod's nodes (camera, pose, mapping, movement, servo) on a robot "
            "backend (the MuJoCo robot by default), paced to the wall clock, and bridge them "
            "to a zenoh network: images, map, pose, state, status and log go out; walk "
            "commands and the mode come in. Starts in torque-off; stands still when the "
            "commands stop for 0.5 s. Ends on Ctrl-C, after --seconds, after a fall or at the "
            "goal (--stop-at-goal), and writes metrics.json, walk.png and footholds.png to "
            "--out."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    p.add_argument("--sim", choices=TERRAINS.names(), default="stairs", help="terrain to stand on")
    p.add_argument("--seed", type=int, default=0, help="seed of the terrain")
    p.add_argument(
        "--backend",
        choices=BACKENDS.names(),
        default="sim",
        help="the robot's driver: sim (MuJoCo), mock (joints that follow their targets), or "
        "one you registered",
    )
    p.add_argument(
        "--backend-option",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="a setting for the backend (a serial port, a baud rate); repeatable",
    )
    p.add_argument(
        "--camera",
        choices=(*CAMERAS.names(), "none"),
        help="the depth camera; none walks blind (no map, nominal footholds) [default: sim; "
        "network with --hardware]",
    )
    p.add_argument(
        "--pose",
        choices=POSES.names(),
        help="the pose source placing the images [default: sim; network with --hardware]",
    )
    hardware = p.add_argument_group("a real robot's servos")
    hardware.add_argument(
        "--hardware",
        type=Path,
        metavar="ROBOT",
        help="run on the robot's Dynamixel servos (the dynamixel backend; ROBOT a built-in name or "
        "a TOML file with its [hardware] table), with the camera and pose from the network "
        "(footfall servo-bus in a dry run, or your camera's process)",
    )
    hardware.add_argument("--port", help="the servo bus's serial port (overrides [hardware] port)")
    hardware.add_argument(
        "--realsense-file",
        type=Path,
        metavar="FILE",
        help="the camera is this RealSense recording (.bag, .db3), played at its own pace "
        "(--camera realsense; needs footfall[realsense])",
    )
    hardware.add_argument(
        "--realsense-serial",
        metavar="SERIAL",
        help="the camera is the RealSense with this serial number (--camera realsense; the "
        "only one connected when --camera realsense names none)",
    )
    for kind, example in (("camera", "a device's serial number"), ("pose", "a map file")):
        p.add_argument(
            f"--{kind}-option",
            action="append",
            default=[],
            metavar="KEY=VALUE",
            help=f"a setting for the {kind} source ({example}); repeatable",
        )
    p.add_argument("--seconds", type=float, default=600.0, help="longest run in seconds")
    p.add_argument("--stop-at-goal", action="store_true", help="end the run at the goal")
    p.add_argument(
        "--foxglove",
        type=int,
        metavar="PORT",
        help="serve the robot live to Foxglove over its WebSocket protocol on this port "
        "(on 127.0.0.1; with --listen-remote on every address): open a Foxglove WebSocket "
        "connection to ws://127.0.0.1:PORT (needs footfall[foxglove])",
    )
    p.add_argument(
        "--full-precision",
        action="store_true",
        help="send the map, depth and colour as the robot holds them (a wired network) "
        "rather than packed for a radio link and paced by the station's acknowledgements",
    )
    p.add_argument(
        "--rate",
        action="append",
        default=[],
        metavar="TOPIC=HZ",
        help="largest rate a topic is sent out at (HZ 'all' for every message); repeatable",
    )
    biped = p.add_argument_group("biped: its vision and planning node, and Archie in a room")
    biped.add_argument(
        "--biped",
        action="store_true",
        help="serve the biped's services (start_capture, stop_capture, start_planning, "
        "new_map, clear) instead of simulating the hexapod",
    )
    source = biped.add_mutually_exclusive_group()
    source.add_argument(
        "--room",
        type=int,
        metavar="SEED",
        help="Archie walks in MuJoCo in this seeded room, seeing through its head camera: a "
        "goal planned to is walked while the station sends mode walking",
    )
    source.add_argument("--case", type=int, help="what the capture sees: a dissertation map")
    source.add_argument("--map", type=Path, help="what the capture sees: a map file")
    source.add_argument("--cloud", type=Path, help="what the capture sees: a point cloud")
    add_network_options(p, listen=[DEFAULT_ENDPOINT], connect=[])
    add_recording_options(p)
    p.add_argument("--out", type=Path, default=Path("footfall-out/robot"), help="output folder")
    p.set_defaults(handler=run)


def _ready(console: Console, args: argparse.Namespace, what: str):
    """Say where the robot listens, once its network bus is open."""

    def ready(bus) -> None:
        where = ", ".join(bus.listening_locators()) or "nowhere (connecting only)"
        console.print(
            f"robot [bold]{args.name}[/] ({what}): listening on {where}; keys {bus.prefix}/*",
            highlight=False,
        )

    return ready


def _foxglove(args: argparse.Namespace) -> tuple[str, int] | None:
    """Where --foxglove serves: loopback unless --listen-remote."""
    if args.foxglove is None:
        return None
    if not 0 < args.foxglove < 65536:
        raise ConfigError(f"--foxglove {args.foxglove}: a port is 1 to 65535")
    return ("0.0.0.0" if args.listen_remote else "127.0.0.1", args.foxglove)


def _robot_network(args: argparse.Namespace):
    """The robot's zenoh settings: packed for a radio link unless --full-precision."""
    return dataclasses.replace(network_config(args), radio=not args.full_precision)


def _rates(items: list[str]) -> dict[str, float | None]:
    from footfall.sim.robot import OUTGOING

    rates: dict[str, float | None] = {}
    for item in items:
        topic, _, value = item.partition("=")
        if topic not in OUTGOING or not value:
            raise ConfigError(f"--rate {item!r}: use TOPIC=HZ, TOPIC one of {', '.join(OUTGOING)}")
        try:
            rates[topic] = None if value == "all" else float(value)
        except ValueError as exc:
            raise ConfigError(f"--rate {item!r}: {value!r} is not a rate in Hz or 'all'") from exc
    return rates


def run(args: argparse.Namespace, console: Console) -> int:
    """Run the robot until it is stopped; write its record."""
    from footfall.reports.robot import BipedRequest, RobotRequest, run_biped, run_robot_report
    from footfall.sim.walk_request import WalkRequest

    if args.biped:
        request = BipedRequest(
            case=args.case,
            map=args.map,
            cloud=args.cloud,
            room=args.room,
            network=_robot_network(args),
            seconds=args.seconds,
        )
        what = "biped planning" if args.room is None else "Archie walking in MuJoCo"
        served = run_biped(request, on_ready=_ready(console, args, what))
        console.print(f"served {', '.join(served['services'])} on {served['map']}")
        if "state" in served:
            console.print(
                f"Archie {served['state']}: {served['footsteps']} footsteps, "
                f"{served['collisions']} collisions, COM at "
                f"({served['com'][0]:.2f}, {served['com'][1]:.2f}) m"
            )
        return 0
    if any(v is not None for v in (args.case, args.map, args.cloud, args.room)):
        raise ConfigError("--case, --map, --cloud and --room go with --biped")
    backend, backend_options = args.backend, key_values("--backend-option", args.backend_option)
    camera, pose, robot, terrain = args.camera or "sim", args.pose or "sim", "default", args.sim
    if args.hardware is not None:
        backend, robot, terrain = "dynamixel", str(args.hardware), "flat"
        camera, pose = args.camera or "network", args.pose or "network"
        backend_options = {"robot": robot, **backend_options}
        if args.port is not None:
            backend_options["port"] = args.port
    elif args.port is not None:
        raise ConfigError("--port goes with --hardware")
    camera_options = key_values("--camera-option", args.camera_option)
    if args.realsense_file is not None or args.realsense_serial is not None:
        if args.camera not in (None, "realsense"):
            raise ConfigError("--realsense-file and --realsense-serial are the realsense camera")
        if args.realsense_file is not None and args.realsense_serial is not None:
            raise ConfigError("give --realsense-file or --realsense-serial, not both")
        camera = "realsense"
        if args.realsense_file is not None:
            camera_options["file"] = str(args.realsense_file)
        else:
            camera_options["serial"] = args.realsense_serial
    if camera == "realsense":
        # The robot's TOML places the camera on the body ([camera]).
        camera_options.setdefault("robot", robot)
    request = RobotRequest(
        walk=WalkRequest(
            terrain=terrain,
            seed=args.seed,
            seconds=args.seconds,
            robot=robot,
            record=args.record,
            rerun=args.rerun,
            rerun_spawn=args.rerun_spawn,
            backend=backend,
            backend_options=backend_options,
            camera_options=camera_options,
            pose_options=key_values("--pose-option", args.pose_option),
            camera=None if camera == "none" else camera,
            pose=pose,
        ),
        network=_robot_network(args),
        seconds=args.seconds,
        stop_at_goal=args.stop_at_goal,
        rates=_rates(args.rate),
        foxglove=_foxglove(args),
    )
    if request.foxglove is not None:
        host, port = request.foxglove
        console.print(f"Foxglove: open a WebSocket connection to ws://{host}:{port}")
    world = f"servos of {args.hardware}" if args.hardware else f"on {args.sim}"
    where = f"{backend} hexapod {world}; torque off until mode=walking"
    ready = _ready(console, args, where)
    report = run_robot_report(request, on_ready=ready)
    metrics = report.to_json()
    # A robot that does not know where its feet are is not judged by the terrain's truth.
    invalid = metrics.get("invalid_footholds", "not judged")
    distance = metrics["distance_m"]
    travelled = f"{distance:.2f} m" if math.isfinite(distance) else "not measured"
    console.print(
        f"ran {metrics['sim_seconds']:.1f} s: distance {travelled}, "
        f"reached goal {metrics['reached_goal']}, fell {metrics['fell']}, "
        f"invalid footholds {invalid}"
    )
    wrote(console, report.write(args.out))
    return 0
