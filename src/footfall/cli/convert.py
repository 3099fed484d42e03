"""``footfall convert``: recorded data into the TUM RGB-D layout."""

from __future__ import annotations

import argparse
from pathlib import Path

from rich.console import Console

from footfall.cli.commands import summary
from footfall.cli.common import add_depth_camera_options


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """Add ``convert`` and its kinds."""
    p = subparsers.add_parser(
        "convert",
        help=summary("convert"),
        description=(
            "Convert recorded data into the TUM RGB-D layout `footfall map --tum` reads, or "
            "into an MCAP file of ROS 2 messages that `footfall replay` reads."
        ),
    )
    kinds = p.add_subparsers(dest="kind", metavar="KIND", required=True)
    redwood = kinds.add_parser(
        "redwood",
        help="a Redwood/Open3D sequence (depth/*.png in mm, trajectory.log)",
        description=(
            "Convert a Redwood sequence: depth PNGs in millimetres become TUM units (1/5000 m), "
            "trajectory.log camera-to-world matrices become groundtruth.txt, frames are "
            "stamped i / fps."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    redwood.add_argument("source", type=Path, help="the Redwood folder")
    redwood.add_argument(
        "destination", type=Path, help="output folder (TUM layout), or a .mcap file"
    )
    redwood.add_argument("--fps", type=float, default=30.0, help="frame rate for the timestamps")
    add_depth_camera_options(redwood, "for an MCAP file")
    redwood.set_defaults(handler=run_redwood)
    tum = kinds.add_parser(
        "tum",
        help="a TUM-layout sequence to an MCAP file (ROS 2 Image, CameraInfo, PoseStamped, TF)",
        description=(
            "Write a TUM-layout sequence as an MCAP file that footfall replay, Foxglove, rerun "
            "and ROS 2 tools read: depth as 16UC1 (when whole millimetres) or 32FC1, the "
            "camera's pose turned so the world's up axis is +z."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    tum.add_argument("source", type=Path, help="the TUM-layout folder")
    tum.add_argument("destination", type=Path, help="the .mcap file to write")
    tum.add_argument(
        "--up",
        type=float,
        nargs=3,
        metavar=("X", "Y", "Z"),
        default=(0.0, 0.0, 1.0),
        help="the recorded world's up axis",
    )
    tum.add_argument("--depth-scale", type=float, default=1.0 / 5000.0, help="metres per unit")
    add_depth_camera_options(tum, "")
    tum.set_defaults(handler=run_tum)


def run_redwood(args: argparse.Namespace, console: Console) -> int:
    """Convert a Redwood sequence, to the TUM layout or an MCAP file."""
    if args.destination.suffix.lower() == ".mcap":
        from footfall.recording.convert import redwood_to_mcap
        from footfall.sensing.noise import sensor_noise

        frames = redwood_to_mcap(
            args.source,
            args.destination,
            tuple(args.intrinsics),
            args.fps,
            sensor_noise(args.sensor),
        )
        console.print(f"Wrote {frames} frames as MCAP to {args.destination}")
        return 0
    from footfall.datasets.redwood import convert_redwood

    frames = convert_redwood(args.source, args.destination, args.fps)
    console.print(f"Wrote {frames} frames in the TUM layout to {args.destination}")
    return 0


def run_tum(args: argparse.Namespace, console: Console) -> int:
    """Convert a TUM-layout sequence to an MCAP file."""
    from footfall.recording.convert import tum_to_mcap
    from footfall.sensing.noise import sensor_noise

    frames = tum_to_mcap(
        args.source,
        args.destination,
        tuple(args.intrinsics),
        tuple(args.up),
        args.depth_scale,
        sensor_noise(args.sensor),
    )
    console.print(f"Wrote {frames} frames as MCAP to {args.destination}")
    return 0
