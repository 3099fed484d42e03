"""``footfall replay``: a recording through the mapping and scoring nodes."""

from __future__ import annotations

import argparse
from pathlib import Path

from rich.console import Console

from footfall.cli.commands import summary
from footfall.cli.common import add_camera_pose_options, format_value, print_table, wrote


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """Add ``replay``."""
    from footfall.sensing.noise import SENSORS

    p = subparsers.add_parser(
        "replay",
        help=summary("replay"),
        description=(
            "Play a recording's depth images and camera poses through the same mapping and "
            "scoring nodes as a live run: footfall's own MCAP recordings, ROS 2 bags (sqlite3 "
            "or MCAP) and ROS 1 bags. Depth as 16UC1 (mm) or 32FC1 (m); the pose from a "
            "PoseStamped or Odometry topic of the depth camera's optical frame in a z-up world, "
            "or from TF. Writes what `footfall map` writes: map.npz, heightmap.png, "
            "scoremap.png and metrics.json."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    p.add_argument("file", type=Path, help="the recording (.mcap, a ROS 2 bag folder, a .bag)")
    pace = p.add_mutually_exclusive_group()
    pace.add_argument("--rate", type=float, default=1.0, help="playback speed (1 = as recorded)")
    pace.add_argument("--fast", action="store_true", help="play as fast as the mapping goes")
    p.add_argument("--depth-topic", default=None, help="depth image topic (default: the one)")
    p.add_argument("--info-topic", default=None, help="its CameraInfo topic (default: beside it)")
    pose = p.add_mutually_exclusive_group()
    pose.add_argument("--pose-topic", default=None, help="PoseStamped/Odometry camera pose topic")
    pose.add_argument(
        "--tf-frames",
        nargs=2,
        metavar=("WORLD", "CAMERA"),
        default=None,
        help="look the camera's pose up in TF from WORLD to CAMERA (its optical frame)",
    )
    add_camera_pose_options(p, "a fixed camera, for a recording with no pose")
    p.add_argument(
        "--pose",
        choices=("recorded", "odometry"),
        default="recorded",
        help="the camera's poses: the recording's (topic, TF or a fixed camera), or tracked "
        "from its depth images (footfall odometry; the first frame over the floor it sees, or "
        "at --camera-height and --camera-pitch-deg; needs footfall[odometry])",
    )
    p.add_argument(
        "--sensor",
        choices=tuple(SENSORS),
        default="kinect",
        help="the depth sensor's noise model, for recordings that do not carry one",
    )
    p.add_argument(
        "--fusion",
        choices=("latest", "max", "variance"),
        default=None,
        help="per-cell fusion rule (default: the recording's, else variance)",
    )
    p.add_argument("--rerun", type=Path, default=None, metavar="FILE.rrd", help="also log to rerun")
    p.add_argument("--rerun-spawn", action="store_true", help="open a rerun viewer on the replay")
    p.add_argument("--out", type=Path, default=Path("footfall-out/replay"), help="output folder")
    p.set_defaults(handler=run)


def run(args: argparse.Namespace, console: Console) -> int:
    """Replay, write the map outputs, print the metrics."""
    from footfall.recording.replay_request import ReplayRequest
    from footfall.reports.replay import run_replay

    request = ReplayRequest(
        path=args.file,
        rate=args.rate,
        fast=args.fast,
        depth_topic=args.depth_topic,
        info_topic=args.info_topic,
        pose_topic=args.pose_topic,
        tf_frames=tuple(args.tf_frames) if args.tf_frames else None,
        sensor=args.sensor,
        fusion=args.fusion,
        camera_height=args.camera_height,
        camera_pitch_deg=args.camera_pitch_deg,
        camera_roll_deg=args.camera_roll_deg,
        pose=args.pose,
    )
    console.print(f"Replaying {args.file}" + ("" if args.fast else f" at {args.rate:g}x"))
    report = run_replay(request, rerun=args.rerun, rerun_spawn=args.rerun_spawn)
    paths = report.write(args.out)
    rows = [
        (key, format_value(value))
        for key, value in report.to_json().items()
        if isinstance(value, float | int | str)
    ]
    print_table(console, "replay summary", rows)
    wrote(console, paths)
    return 0
