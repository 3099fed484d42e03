"""Exact depth images of a room with boxes in it, ray-cast from a known camera pose.

The room is the inside of an axis-aligned box (world z up, floor at z = 0); solid boxes stand
on its floor and hang on its walls. A pixel's depth is where its ray first meets a box face
or the room's walls, along the optical axis (z of the camera's optical frame).
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from footfall.sensing.camera import PinholeCamera
from footfall.sensing.pose import Pose

# The room's inside [m]: x from -1 to 5, y from -2.5 to 2.5, z from 0 to 3.
ROOM = (np.array([-1.0, -2.5, 0.0]), np.array([5.0, 2.5, 3.0]))
# Solid boxes (lower corner, upper corner) [m].
BOXES = (
    (np.array([2.0, -0.8, 0.0]), np.array([2.6, -0.2, 0.5])),
    (np.array([3.0, 0.4, 0.0]), np.array([3.4, 1.3, 0.9])),
    (np.array([1.5, 1.0, 0.0]), np.array([1.8, 1.3, 1.4])),
    (np.array([4.6, -1.5, 1.0]), np.array([5.0, -0.5, 1.6])),
    (np.array([3.5, -2.5, 0.5]), np.array([4.2, -2.1, 0.8])),
)
CAMERA = PinholeCamera(250.0, 250.0, 159.5, 119.5, 320, 240)


def looking(position: npt.ArrayLike, yaw_rad: float, pitch_rad: float) -> Pose:
    """A camera at ``position`` looking along heading ``yaw_rad``, ``pitch_rad`` down."""
    from scipy.spatial.transform import Rotation

    # Optical frame: z forward, x right, y down; from a body frame x forward, z up.
    optical_in_body = Rotation.from_matrix([[0, 0, 1], [-1, 0, 0], [0, -1, 0]])
    body = Rotation.from_euler("ZY", [yaw_rad, pitch_rad])
    return Pose(np.asarray(position, dtype=np.float64), body * optical_in_body)


def render(
    camera_in_world: Pose, camera: PinholeCamera = CAMERA, boxes: tuple = BOXES
) -> npt.NDArray[np.float64]:
    """Depth along the optical axis [m], shape (height, width), of the room with ``boxes``."""
    u, v = np.meshgrid(np.arange(camera.width), np.arange(camera.height))
    rays = np.stack(
        [(u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy, np.ones(u.shape)], axis=-1
    ).reshape(-1, 3)
    d = camera_in_world.rotation.apply(rays)  # z of each ray in the camera is 1: t is depth
    o = camera_in_world.position
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = 1.0 / d
        low, high = ROOM
        exits = np.where(d > 0, (high - o) * inv, (low - o) * inv)
        exits[~np.isfinite(exits)] = np.inf
        depth = exits.min(axis=1)
        for lo, hi in boxes:
            t0, t1 = (lo - o) * inv, (hi - o) * inv
            near = np.nanmax(np.minimum(t0, t1), axis=1)
            far = np.nanmin(np.maximum(t0, t1), axis=1)
            hit = (near <= far) & (near > 0)
            depth = np.where(hit & (near < depth), near, depth)
    return depth.reshape(camera.height, camera.width)
