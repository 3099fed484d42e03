"""What the subcommands share: progress bars, metric tables, name lists, point-cloud options."""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn
from rich.table import Table


def sim_progress(console: Console) -> Progress:
    """A progress bar over simulated seconds."""
    return Progress(
        TextColumn("simulating"),
        BarColumn(),
        TextColumn("{task.completed:.1f}/{task.total:.0f} s"),
        TimeRemainingColumn(),
        console=console,
        transient=True,
    )


def count_progress(console: Console, unit: str = "") -> Progress:
    """A progress bar with a label, counting ``unit`` (or only the time left)."""
    count = [TextColumn(f"{{task.completed}}/{{task.total}} {unit}")] if unit else []
    return Progress(
        TextColumn("{task.description}"),
        BarColumn(),
        *count,
        TimeRemainingColumn(),
        console=console,
    )


def comma_list(text: str) -> list[str]:
    """``A,B,...`` as names, blanks dropped."""
    return [t.strip() for t in text.split(",") if t.strip()]


def key_values(option: str, items: list[str]) -> dict[str, str]:
    """``KEY=VALUE`` items of a repeatable option as a dict.

    Raises:
        ConfigError: An item without a key or an ``=``, naming the option.
    """
    from footfall.errors import ConfigError

    options = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not key or not sep:
            raise ConfigError(f"{option} {item!r}: use KEY=VALUE")
        options[key] = value
    return options


def format_value(value: object, fmt: str | None = None) -> str:
    """A metric for a table: NaN as n/a, else with ``fmt`` (floats to 4 digits by default)."""
    if isinstance(value, float) and math.isnan(value):
        return "n/a"
    if fmt is not None:
        return fmt.format(value)
    return f"{value:.4g}" if isinstance(value, float) else str(value)


def print_table(console: Console, title: str, rows: list[tuple[str, str]]) -> None:
    """A two-column table of labels and values."""
    table = Table(title=title)
    table.add_column("metric")
    table.add_column("value", justify="right")
    for label, value in rows:
        table.add_row(label, value)
    console.print(table)


def wrote(console: Console, paths: list[Path]) -> None:
    """Say which files were written."""
    names = [str(p) for p in paths]
    listed = names[0] if len(names) == 1 else ", ".join(names[:-1]) + " and " + names[-1]
    console.print(f"Wrote {listed}", soft_wrap=True)  # a path broken over lines cannot be pasted


def add_cloud_options(p: argparse.ArgumentParser) -> None:
    """Options of a point cloud's obstacle detection."""
    p.add_argument(
        "--frame",
        choices=("camera", "map"),
        default="camera",
        help="frame the cloud's points are in: the optical camera frame (x right, y down, "
        "z forward) or a z-up map frame",
    )
    p.add_argument(
        "--ground",
        choices=("ransac", "plane", "cones"),
        default="ransac",
        help="ground removal: the floor RANSAC finds near the expected up axis, a known plane "
        "(the camera's height and pitch, or --ground-plane), or Manduchi's inverted cones",
    )
    add_camera_pose_options(p, "")
    p.add_argument(
        "--ground-plane",
        type=float,
        nargs=4,
        metavar=("A", "B", "C", "D"),
        default=None,
        help="the floor a x + b y + c z + d = 0 in the camera frame (m)",
    )
    p.add_argument(
        "--camera-height-range",
        type=float,
        nargs=2,
        metavar=("MIN", "MAX"),
        default=(0.1, 3.0),
        help="with no pose given, the heights (m) the camera may stand over its floor: the "
        "ground is the lowest large level plane this far below it",
    )
    p.add_argument(
        "--voxel-size", type=float, default=0.02, help="voxel grid side in m (0: every point)"
    )
    p.add_argument(
        "--max-obstacle-height",
        type=float,
        default=2.0,
        help="points higher than this above the floor (m) are overhead: a ceiling, a lamp",
    )
    p.add_argument(
        "--cluster-tolerance", type=float, default=0.30, help="Euclidean clustering radius in m"
    )
    p.add_argument("--min-cluster-size", type=int, default=5, help="smallest obstacle in points")


def cloud_request(args: argparse.Namespace):
    """The cloud request the cloud options describe."""
    from footfall.reports.biped import CloudRequest

    return CloudRequest(
        cloud=args.cloud,
        frame=args.frame,
        ground=args.ground,
        camera_height=args.camera_height,
        camera_pitch_deg=args.camera_pitch_deg,
        camera_roll_deg=args.camera_roll_deg,
        ground_plane=None if args.ground_plane is None else tuple(args.ground_plane),
        camera_height_range=tuple(args.camera_height_range),
        voxel_size=args.voxel_size,
        max_obstacle_height=args.max_obstacle_height,
        cluster_tolerance=args.cluster_tolerance,
        min_cluster_size=args.min_cluster_size,
    )


def add_recording_options(p: argparse.ArgumentParser) -> None:
    """Options that record a run: MCAP for ROS tools and replay, rerun for a person."""
    p.add_argument(
        "--record",
        type=Path,
        default=None,
        metavar="FILE.mcap",
        help="record every bus message to an MCAP file (ROS 2 types, CDR; footfall replay)",
    )
    p.add_argument(
        "--rerun",
        type=Path,
        default=None,
        metavar="FILE.rrd",
        help="log the run for the rerun viewer (needs footfall[viz])",
    )
    p.add_argument(
        "--rerun-spawn", action="store_true", help="open a rerun viewer on the run as it goes"
    )


def add_camera_pose_options(p: argparse.ArgumentParser, when: str) -> None:
    """``--camera-height``, ``--camera-pitch-deg``, ``--camera-roll-deg``: a camera over a floor.

    Args:
        p: The parser.
        when: When they apply, appended to the help (e.g. "for frames without a pose").
    """
    suffix = f" ({when})" if when else ""
    p.add_argument(
        "--camera-height",
        type=float,
        default=None,
        help=f"camera height above the floor in m{suffix}",
    )
    p.add_argument(
        "--camera-pitch-deg",
        type=float,
        default=None,
        help=f"how far the camera looks down, in degrees (positive: down){suffix}",
    )
    p.add_argument(
        "--camera-roll-deg",
        type=float,
        default=None,
        help=f"how far the camera's right side dips, in degrees{suffix}",
    )


def add_depth_camera_options(p: argparse.ArgumentParser, when: str) -> None:
    """``--intrinsics`` and ``--sensor``: a recording's depth camera and its noise model."""
    from footfall.sensing.noise import SENSORS

    suffix = f" ({when})" if when else ""
    p.add_argument(
        "--intrinsics",
        type=float,
        nargs=4,
        metavar=("FX", "FY", "CX", "CY"),
        default=(525.0, 525.0, 319.5, 239.5),
        help=f"depth camera intrinsics in pixels{suffix}",
    )
    p.add_argument(
        "--sensor",
        choices=tuple(SENSORS),
        default="kinect",
        help=f"the depth sensor's class, for its noise model{suffix}",
    )
