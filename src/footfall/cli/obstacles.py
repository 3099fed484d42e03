"""``footfall obstacles``: obstacles in a point cloud."""

from __future__ import annotations

import argparse
from pathlib import Path

from rich.console import Console

from footfall.cli.commands import summary
from footfall.cli.common import add_cloud_options, cloud_request, wrote


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """Add ``obstacles``."""
    p = subparsers.add_parser(
        "obstacles",
        help=summary("obstacles"),
        description=(
            "Detect obstacles in a point cloud (dissertation §6.3.1): pass-through filter, voxel "
            "grid, ground removal, Euclidean clustering, principal-axes boxes and circles "
            "(along the obstacle's medial line where a box's would cover free floor). Writes "
            "obstacles.json and obstacles.png (top view) to --out."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    p.add_argument("--cloud", type=Path, required=True, help="point cloud file (.pcd, .ply, .npy)")
    add_cloud_options(p)
    p.add_argument("--out", type=Path, default=Path("footfall-out/obstacles"), help="output folder")
    p.set_defaults(handler=run)


def run(args: argparse.Namespace, console: Console) -> int:
    """Detect, write the outputs, print a summary line."""
    from footfall.reports.biped import run_obstacles

    report = run_obstacles(cloud_request(args))
    paths = report.write(args.out)
    summary = report.to_json()
    ground = summary["ground_plane"]
    console.print(
        f"ground: {ground['inlier_fraction']:.0%} of the points, "
        f"{ground['angle_to_up_deg']:.1f} deg from the expected up axis"
        + (
            f"; camera {summary['camera']['height_m']:.2f} m above it, looking "
            f"{summary['camera']['pitch_deg']:.1f} deg down"
            if "camera" in summary
            else ""
        )
    )
    console.print(
        f"{len(summary['clusters'])} obstacles from {summary['points_in']} points "
        f"({summary['points_after_voxel']} after the voxel grid) in {summary['detect_ms']:.0f} ms"
    )
    wrote(console, paths)
    return 0
