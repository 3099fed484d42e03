"""Plain-NumPy reference of a height-map frame update.

Vectorised NumPy with no compiled code: the baseline the benchmarks measure the compiled
kernels against, and an independent oracle for the tests. It implements the ``latest``
rule: each cell touched by the frame takes the frame's highest point.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from footfall.sensing.camera import PinholeCamera
from footfall.sensing.pose import Pose


def integrate_depth_latest(
    heights: npt.NDArray[np.float64],
    known: npt.NDArray[np.bool_],
    origin: tuple[int, int],
    resolution: float,
    depth: npt.ArrayLike,
    camera: PinholeCamera,
    camera_pose: Pose,
    depth_scale: float | None = None,
) -> int:
    """Update a circular-buffer height map in place with one depth frame.

    Args:
        heights: Buffer of heights, shape (N, N) [m]; written where the frame has points.
        known: Buffer of known flags, shape (N, N); set where the frame has points.
        origin: Global cell index of the window's corner.
        resolution: Cell side [m].
        depth: Depth image.
        camera: Intrinsics.
        camera_pose: Optical frame's pose in the world.
        depth_scale: Metres per unit of integer depth.

    Returns:
        Number of points that landed in the window.
    """
    points, _ = camera.depth_to_points(depth, depth_scale)
    world = camera_pose.apply(points)
    n = heights.shape[0]
    cells = np.floor(world[:, :2] / resolution).astype(np.int64) - np.asarray(origin)
    inside = np.all((cells >= 0) & (cells < n), axis=1)
    cells, z = cells[inside], world[inside, 2]
    flat = np.mod(cells[:, 0] + origin[0], n) * n + np.mod(cells[:, 1] + origin[1], n)
    frame = np.full(n * n, -np.inf)
    np.maximum.at(frame, flat, z)
    touched = np.isfinite(frame)
    heights.ravel()[touched] = frame[touched]
    known.ravel()[touched] = True
    return int(inside.sum())
