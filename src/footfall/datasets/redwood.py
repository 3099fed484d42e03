"""Convert a Redwood / Open3D RGB-D sequence into the TUM layout.

Redwood keeps depth as 16-bit PNGs in millimetres and poses in ``trajectory.log``: per
frame a line ``i i i+1`` and then the 4x4 camera-to-world matrix, row by row. The TUM
layout wants depth as value / 5000 m, and ``t tx ty tz qx qy qz qw`` poses. Frames get
timestamps ``i / fps``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import numpy.typing as npt
from PIL import Image

from footfall.datasets.tum import load_depth_png
from footfall.errors import DatasetError
from footfall.sensing.pose import Pose

MILLIMETRE_TO_TUM = 5  # 1 mm = 5 TUM depth units (1/5000 m)


def read_trajectory_log(path: str | Path) -> list[npt.NDArray[np.float64]]:
    """Camera-to-world 4x4 matrices from a Redwood ``trajectory.log``.

    Raises:
        DatasetError: If the file is missing or a block is malformed.
    """
    p = Path(path)
    if not p.is_file():
        raise DatasetError(f"missing {p}")
    try:
        text = p.read_text()
    except UnicodeDecodeError as exc:
        raise DatasetError(f"{p}: not a text file ({exc})") from exc
    lines = [line.split() for line in text.splitlines() if line.strip()]
    if len(lines) % 5:
        raise DatasetError(f"{p}: {len(lines)} lines is not a whole number of 5-line blocks")
    matrices = []
    for block in range(len(lines) // 5):
        try:
            rows = [[float(v) for v in lines[5 * block + r]] for r in range(1, 5)]
        except ValueError as exc:
            raise DatasetError(f"{p}: block {block} holds a value that is not a number") from exc
        if any(len(r) != 4 for r in rows):
            raise DatasetError(f"{p}: block {block} is not a 4x4 matrix")
        matrices.append(np.array(rows))
    return matrices


def convert_redwood(source: str | Path, destination: str | Path, fps: float = 30.0) -> int:
    """Write a Redwood sequence (``depth/*.png`` in mm, ``trajectory.log``) in the TUM layout.

    Args:
        source: The Redwood folder.
        destination: Output folder (created).
        fps: Frame rate for the timestamps [Hz].

    Returns:
        Number of frames written.

    Raises:
        DatasetError: Missing files, or depth images and poses that do not pair up.
    """
    src, dst = Path(source), Path(destination)
    depth_files = sorted((src / "depth").glob("*.png"))
    if not depth_files:
        raise DatasetError(f"no depth/*.png in {src}")
    poses = read_trajectory_log(src / "trajectory.log")
    if len(poses) != len(depth_files):
        raise DatasetError(f"{src}: {len(depth_files)} depth images but {len(poses)} poses")
    (dst / "depth").mkdir(parents=True, exist_ok=True)
    depth_lines = [
        "# depth maps converted from Redwood millimetres to TUM units (1/5000 m)",
        "# timestamp filename",
    ]
    pose_lines = [
        "# camera-to-world poses from Redwood trajectory.log",
        "# timestamp tx ty tz qx qy qz qw",
    ]
    for index, (depth_file, matrix) in enumerate(zip(depth_files, poses, strict=True)):
        millimetres = load_depth_png(depth_file).astype(np.uint32)
        units = millimetres * MILLIMETRE_TO_TUM
        if units.max(initial=0) > np.iinfo(np.uint16).max:
            raise DatasetError(f"{depth_file}: depth beyond 13.1 m does not fit TUM's 16-bit units")
        name = f"depth/{index:05d}.png"
        Image.fromarray(units.astype(np.uint16)).save(dst / name)
        t = index / fps
        pose = Pose.from_matrix(matrix)
        x, y, z = pose.position
        qx, qy, qz, qw = pose.rotation.as_quat()
        depth_lines.append(f"{t:.6f} {name}")
        pose_lines.append(f"{t:.6f} {x:.9f} {y:.9f} {z:.9f} {qx:.9f} {qy:.9f} {qz:.9f} {qw:.9f}")
    (dst / "depth.txt").write_text("\n".join(depth_lines) + "\n")
    (dst / "groundtruth.txt").write_text("\n".join(pose_lines) + "\n")
    return len(depth_files)
