"""Ground the map assumes without seeing it, and the frames that confirm or erase it.

The camera never sees under or beside the standing robot, where its first steps land; the
robot knows that ground from its feet (:meth:`HeightMap.assume_ground
<footfall.mapping.height_map.HeightMap.assume_ground>`). A depth frame whose point falls in
an assumed cell confirms it; one that sees through it (its reading along the ray through
the cell's centre lies beyond it, as past a pit's rim near the start) erases it.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from footfall.mapping.layers import CellLayers
from footfall.mapping.window import MapWindow
from footfall.sensing.camera import PinholeCamera
from footfall.sensing.pose import Pose

# An assumed cell is contradicted when the camera's reading through its centre lies this
# much beyond it, plus three standard deviations of the camera's noise there [m].
SEE_THROUGH_M = 0.02


def check_assumed(
    layers: CellLayers,
    window: MapWindow,
    hit: npt.NDArray[np.int64],
    depth: npt.ArrayLike,
    camera: PinholeCamera,
    camera_pose: Pose,
    depth_scale: float | None,
) -> None:
    """Confirm the assumed cells a frame hits; erase those it sees through.

    Args:
        layers: The map's layers (``assumed`` and ``known`` change).
        window: The map's window.
        hit: Flat buffer indices of the cells the frame's points fell in.
        depth: The frame's depth image.
        camera: Its intrinsics and noise.
        camera_pose: Its optical frame in the world.
        depth_scale: Metres per unit of integer depth.
    """
    layers.assumed.flat[hit] = False
    i, j = np.nonzero(layers.assumed)
    if not len(i):
        return
    global_cell = window.global_cell(np.column_stack([i, j]))
    centre = np.column_stack([window.centre_of(global_cell), layers.heights[i, j]])
    in_camera = camera_pose.rotation.inv().apply(centre - camera_pose.position)
    z = in_camera[:, 2]
    ahead = z > camera.min_range
    u = np.full(len(z), -1, dtype=np.int64)
    v = np.full(len(z), -1, dtype=np.int64)
    u[ahead] = np.round(camera.fx * in_camera[ahead, 0] / z[ahead] + camera.cx)
    v[ahead] = np.round(camera.fy * in_camera[ahead, 1] / z[ahead] + camera.cy)
    seen = ahead & (u >= 0) & (u < camera.width) & (v >= 0) & (v < camera.height)
    if not seen.any():
        return
    d = camera.depth_in_metres(depth, depth_scale)
    reading = d[v[seen], u[seen]].astype(np.float64) * camera.scale_for(d, depth_scale)
    valid = np.isfinite(reading) & (reading > camera.min_range) & (reading <= camera.max_range)
    sigma = camera.noise.sigma_m(z[seen])  # elementwise on the ranges
    beyond = valid & (reading > z[seen] + SEE_THROUGH_M + 3.0 * sigma)
    gone_i, gone_j = i[seen][beyond], j[seen][beyond]
    layers.known[gone_i, gone_j] = False
    layers.assumed[gone_i, gone_j] = False
