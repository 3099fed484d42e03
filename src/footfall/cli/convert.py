"""``footfall convert``: recorded data into the TUM RGB-D layout."""

from __future__ import annotations

import argparse
from pathlib import Path

from rich.console import Console


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """Add ``convert`` and its kinds."""
    p = subparsers.add_parser(
        "convert",
        help="convert recorded data into the TUM RGB-D layout",
        description="Convert recorded data into the TUM RGB-D layout `footfall map --tum` reads.",
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
    redwood.add_argument("destination", type=Path, help="output folder (TUM layout)")
    redwood.add_argument("--fps", type=float, default=30.0, help="frame rate for the timestamps")
    redwood.set_defaults(handler=run_redwood)


def run_redwood(args: argparse.Namespace, console: Console) -> int:
    """Convert a Redwood sequence."""
    from footfall.datasets.redwood import convert_redwood

    frames = convert_redwood(args.source, args.destination, args.fps)
    console.print(f"Wrote {frames} frames in the TUM layout to {args.destination}")
    return 0
