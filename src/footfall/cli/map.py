"""``footfall map``: a height map and score map, in simulation or from a recorded sequence."""

from __future__ import annotations

import argparse
from pathlib import Path

from rich.console import Console

from footfall.cli.commands import summary
from footfall.cli.common import (
    add_camera_pose_options,
    add_depth_camera_options,
    add_recording_options,
    format_value,
    key_values,
    print_table,
    sim_progress,
    wrote,
)


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """Add ``map``."""
    from footfall.sim.terrains import TERRAINS

    p = subparsers.add_parser(
        "map",
        help=summary("map"),
        description=(
            "Walk the simulated hexapod across a terrain while its depth camera builds the "
            "rolling height map, or map a recorded TUM-layout sequence (--tum). Writes "
            "heightmap.png, scoremap.png, metrics.json and map.npz to --out."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    p.add_argument(
        "--terrain", choices=TERRAINS.names(), default="course", help="terrain to walk and map"
    )
    p.add_argument("--seconds", type=float, default=20.0, help="walking time in seconds")
    p.add_argument(
        "--noise",
        choices=("none", "slam"),
        default="none",
        help="pose estimate: true, or SLAM-like drift and jitter",
    )
    p.add_argument("--seed", type=int, default=0, help="seed of the terrain and the pose noise")
    p.add_argument(
        "--image-size",
        type=int,
        nargs=2,
        metavar=("W", "H"),
        default=(640, 480),
        help="depth image size in pixels",
    )
    p.add_argument(
        "--fusion",
        choices=("latest", "max", "variance"),
        default=None,
        help="per-cell fusion rule (default: latest in simulation; variance, the sensor's "
        "noise averaged down over frames, for a recording)",
    )
    p.add_argument(
        "--drift-compensation",
        action="store_true",
        help="register every frame vertically against the map before fusing it (takes out "
        "a drifting pose's height error; see footfall bench faults)",
    )
    p.add_argument(
        "--max-cell-spread",
        type=float,
        default=None,
        help="height range in m within one cell in one frame, beyond its slope and the "
        "sensor's noise, above which the cell straddles an edge (default: the score's)",
    )
    p.add_argument(
        "--tum",
        type=Path,
        default=None,
        help="map this TUM-layout sequence instead of simulating; with --camera-height, also "
        "one depth PNG or a folder of them taken from that pose",
    )
    p.add_argument(
        "--realsense",
        type=Path,
        default=None,
        metavar="FILE",
        help="map this RealSense recording (.bag or .db3, played by librealsense; needs "
        "footfall[realsense]) with --trajectory, or from a fixed camera pose",
    )
    p.add_argument(
        "--trajectory",
        type=Path,
        default=None,
        metavar="FILE",
        help="the camera's poses for --realsense: TUM format (t tx ty tz qx qy qz qw, the "
        "optical frame in the world, t on the recording's clock)",
    )
    p.add_argument(
        "--realsense-option",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="librealsense's depth filters for --realsense: decimation=2, spatial=1, "
        "temporal=1, hole_filling=1 (repeatable)",
    )
    add_depth_camera_options(p, "with --tum")
    add_camera_pose_options(p, "with --tum or --realsense, for frames without a trajectory")
    p.add_argument(
        "--up",
        type=float,
        nargs=3,
        metavar=("X", "Y", "Z"),
        default=(0.0, 0.0, 1.0),
        help="the recorded world's up axis (with --tum or --trajectory); TUM and Redwood "
        "worlds are not z-up",
    )
    p.add_argument(
        "--depth-scale", type=float, default=1.0 / 5000.0, help="metres per depth unit (with --tum)"
    )
    p.add_argument(
        "--pose",
        choices=("recorded", "odometry"),
        default="recorded",
        help="the camera's poses for --tum: its groundtruth.txt, or tracked from its own depth "
        "images (footfall odometry; the first frame placed over the floor it sees, or by "
        "--camera-height and --camera-pitch-deg; needs footfall[odometry])",
    )
    add_recording_options(p)
    p.add_argument("--out", type=Path, default=Path("footfall-out/map"), help="output folder")
    p.set_defaults(handler=run)


def run(args: argparse.Namespace, console: Console) -> int:
    """Map, write the outputs, print the metrics."""
    from footfall.reports.map import MapRequest, run_map

    request = MapRequest(
        terrain=args.terrain,
        seconds=args.seconds,
        noise=args.noise,
        seed=args.seed,
        image_size=tuple(args.image_size),
        fusion=args.fusion,
        max_cell_spread=args.max_cell_spread,
        drift_compensation=args.drift_compensation,
        tum=args.tum,
        intrinsics=tuple(args.intrinsics),
        up=tuple(args.up),
        depth_scale=args.depth_scale,
        sensor=args.sensor,
        camera_height=args.camera_height,
        camera_pitch_deg=args.camera_pitch_deg,
        camera_roll_deg=args.camera_roll_deg,
        record=args.record,
        rerun=args.rerun,
        rerun_spawn=args.rerun_spawn,
        realsense=args.realsense,
        trajectory=args.trajectory,
        realsense_options=key_values("--realsense-option", args.realsense_option),
        pose=args.pose,
    )
    if args.tum is not None or args.realsense is not None:
        console.print(f"Mapping recorded sequence {args.tum or args.realsense}")
        report = run_map(request)
    else:
        width, height = args.image_size
        console.print(
            f"Mapping [bold]{args.terrain}[/] terrain for {args.seconds:g} s "
            f"({width}x{height} depth, pose noise: {args.noise})"
        )
        with sim_progress(console) as progress:
            task = progress.add_task("map", total=args.seconds)
            report = run_map(request, on_tick=lambda t: progress.update(task, completed=t))
    paths = report.write(args.out)
    rows = [
        (key, format_value(value))
        for key, value in report.to_json().items()
        if isinstance(value, float | int | str)
    ]
    print_table(console, "map summary", rows)
    wrote(console, paths)
    return 0
