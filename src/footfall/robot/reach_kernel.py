"""Compiled reach test (numba): whether legs reach foot positions within their joint limits.

The foothold planner, the stroke governor and the body's height and incline ask it tens of
thousands of times a walk, mostly for one to a few dozen points at a time, where NumPy's
per-call cost of some twenty array operations outweighed the arithmetic fifty times over.
The test is :meth:`footfall.robot.kinematics.LegKinematics.reachable`'s, point by point:
the foot within the leg's reach (``margin`` inside it) and each joint of the knee-up
solution ``margin / L3`` inside its limits.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

# Columns of the per-leg geometry array: the mount in the body frame and its yaw's cosine
# and sine.
MOUNT_X, MOUNT_Y, MOUNT_Z, COS_YAW, SIN_YAW = range(5)


@njit(cache=True, nogil=True)
def reaches(x, y, z, k, geometry, lengths, lower, upper, margin):
    """Whether leg ``k`` reaches the foot position ``(x, y, z)`` in the body frame [m]."""
    l1, l2, l3 = lengths[0], lengths[1], lengths[2]
    slack = margin / l3
    px = x - geometry[k, MOUNT_X]
    py = y - geometry[k, MOUNT_Y]
    z = z - geometry[k, MOUNT_Z]
    c, s = geometry[k, COS_YAW], geometry[k, SIN_YAW]
    lx = c * px + s * py
    ly = -s * px + c * py
    r = math.hypot(lx, ly) - l1
    reach = math.hypot(r, z)
    if not (abs(l2 - l3) + margin <= reach and reach <= l2 + l3 - margin):
        return False
    cos_knee = (r * r + z * z - l2 * l2 - l3 * l3) / (2.0 * l2 * l3)
    t3 = -math.acos(min(max(cos_knee, -1.0), 1.0))
    t2 = math.atan2(z, r) - math.atan2(l3 * math.sin(t3), l2 + l3 * math.cos(t3))
    t2 = (t2 + math.pi) % (2.0 * math.pi) - math.pi
    t1 = math.atan2(ly, lx)
    return (
        lower[0] + slack <= t1 <= upper[0] - slack
        and lower[1] + slack <= t2 <= upper[1] - slack
        and lower[2] + slack <= t3 <= upper[2] - slack
    )


@njit(cache=True, nogil=True)
def reached(points, leg, geometry, lengths, lower, upper, margin, out):
    """Fill ``out`` with whether each foot position is reached.

    Args:
        points: Foot positions in the body frame, shape (n, 3) [m].
        leg: The leg of every point; -1 when the points cycle through the six legs
            (point ``i`` is leg ``i % 6``'s).
        geometry: Per-leg mount and yaw, shape (6, 5) (columns above).
        lengths: Coxa, femur and tibia lengths, shape (3,) [m].
        lower: Lower joint limits, shape (3,) [rad].
        upper: Upper joint limits, shape (3,) [rad].
        margin: Workspace margin [m].
        out: Result, shape (n,).
    """
    for i in range(points.shape[0]):
        k = i % 6 if leg < 0 else leg
        out[i] = reaches(
            points[i, 0], points[i, 1], points[i, 2], k, geometry, lengths, lower, upper, margin
        )


def leg_geometry(mounts_in_body: np.ndarray, yaws: np.ndarray) -> np.ndarray:
    """The per-leg geometry array :func:`reached` reads, shape (6, 5)."""
    geometry = np.empty((len(yaws), 5))
    geometry[:, MOUNT_X : MOUNT_Z + 1] = mounts_in_body
    geometry[:, COS_YAW] = np.cos(yaws)
    geometry[:, SIN_YAW] = np.sin(yaws)
    return geometry
