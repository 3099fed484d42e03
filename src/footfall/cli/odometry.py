"""``footfall odometry``: a depth sequence's camera path from its own images."""

from __future__ import annotations

import argparse
from pathlib import Path

from rich.console import Console

from footfall.cli.commands import summary
from footfall.cli.common import wrote


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """Add ``odometry``."""
    p = subparsers.add_parser(
        "odometry",
        help=summary("odometry"),
        description=(
            "Track the camera of a TUM-layout depth sequence (depth.txt, depth/*.png) from "
            "its depth images alone: each frame is registered (VGICP, small_gicp) against a "
            "map of the frames before it. Writes trajectory.tum (camera-to-world, one line "
            "per depth frame) and metrics.json (CPU ms per frame; with groundtruth.txt, the "
            "ATE after SE(3) alignment and the drift per metre) to --out. A track that is "
            "lost exits 2 and says where, writing no trajectory. Needs footfall[odometry]."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    p.add_argument("sequence", type=Path, help="the TUM-layout folder")
    p.add_argument(
        "--intrinsics",
        type=float,
        nargs=4,
        metavar=("FX", "FY", "CX", "CY"),
        required=True,
        help="depth camera intrinsics in pixels",
    )
    p.add_argument("--depth-scale", type=float, default=1.0 / 5000.0, help="metres per depth unit")
    p.add_argument("--stride", type=int, default=2, help="use every n-th pixel row and column")
    p.add_argument("--max-frames", type=int, default=None, help="track only the first frames")
    p.add_argument("--threads", type=int, default=1, help="threads the registration may use")
    p.add_argument("--out", type=Path, default=Path("footfall-out/odometry"), help="output folder")
    p.set_defaults(handler=run)


def run(args: argparse.Namespace, console: Console) -> int:
    """Track, write and print the figures."""
    from footfall.odometry.registration import OdometryConfig
    from footfall.reports.odometry import OdometryRequest, run_odometry

    request = OdometryRequest(
        args.sequence,
        tuple(args.intrinsics),
        args.depth_scale,
        OdometryConfig(stride_px=args.stride, threads=args.threads),
        args.max_frames,
    )
    report = run_odometry(request)
    metrics = report.to_json()
    console.print(
        f"{metrics['registered']}/{metrics['frames']} frames registered, "
        f"{metrics['cpu_ms_per_frame']:.1f} ms CPU per frame"
    )
    if report.errors is not None:
        drift = metrics["rpe_per_m"]
        console.print(
            f"ATE {report.errors.ate_rmse_m * 1000:.1f} mm RMSE over "
            f"{report.errors.reference_length_m:.2f} m"
            + ("" if drift is None else f", drift {100 * drift:.2f} % per metre")
        )
    wrote(console, report.write(args.out))
    return 0
