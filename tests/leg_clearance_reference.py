"""The leg checks of the foothold planner in NumPy, as they were before they were compiled.

The reference the compiled checks (:mod:`footfall.planning.clearance_kernels`) answer as:
whole arrays at a time, in the same order of operations.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from footfall.planning.leg_clearance import (
    SWING_END_RADIUS_M,
    SWING_SAMPLES,
    TIBIA_FRACTIONS,
    MapTerrain,
)
from footfall.robot.kinematics import LegKinematics
from footfall.robot.planar import PlanarPose, inclined_to_level, level_to_inclined


def terrain_under(terrain: MapTerrain, xy: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    """The highest known height at each point shifted by each offset; -inf where none [m]."""
    n = terrain.heights.shape[0]
    best = np.full(len(xy), -np.inf)
    for dx, dy in terrain.offsets:
        i = np.floor((xy[:, 0] + dx - terrain.origin_x) / terrain.resolution)
        j = np.floor((xy[:, 1] + dy - terrain.origin_y) / terrain.resolution)
        inside = (i >= 0) & (i < n) & (j >= 0) & (j < n)
        value = np.full(len(xy), np.nan)
        value[inside] = terrain.heights[i[inside].astype(int), j[inside].astype(int)]
        best = np.where(value > best, value, best)
    return best


def to_body(pose: PlanarPose, points, heights, incline: float = 0.0):
    """World points in the body frame at each body height, shape (..., k, 3) [m]."""
    in_body = np.repeat(pose.points_to_body(points)[..., None, :], len(heights), axis=-2)
    in_body[..., 2] -= heights
    return level_to_inclined(in_body, incline)


def reach_heights(kinematics: LegKinematics, leg, points, poses, heights, margin, inclines):
    ok = np.ones((*np.shape(points)[:-1], len(heights)), dtype=bool)
    for pose, incline in zip(poses, inclines, strict=True):
        ok &= kinematics.reachable(leg, to_body(pose, points, heights, incline), margin)
    return ok


def legs_clear_heights(kinematics, terrain, leg, feet, poses, heights, clearance, inclines):
    ok = np.ones((len(feet), len(heights)), dtype=bool)
    for pose, incline in zip(poses, inclines, strict=True):
        in_body = to_body(pose, feet, heights, incline)
        knees = kinematics.knees_in_body(leg, in_body)
        for fraction in TIBIA_FRACTIONS:
            level = inclined_to_level(knees + fraction * (in_body - knees), incline)
            point = pose.points_to_world(level)
            point[..., 2] += heights
            under = terrain_under(terrain, point[..., :2].reshape(-1, 2)).reshape(ok.shape)
            ok &= point[..., 2] >= under + clearance
    return ok


def swing_reach_heights(kinematics, terrain, leg, start, ends, poses, heights, lift, inclines):
    fraction = np.linspace(0.0, 1.0, SWING_SAMPLES)
    way = ends[:, None, :] - start
    points = start + fraction[None, :, None] * way
    length = np.linalg.norm(way[..., :2], axis=2)
    far = (fraction * length > SWING_END_RADIUS_M) & (
        (1.0 - fraction) * length > SWING_END_RADIUS_M
    )
    need = terrain_under(terrain, points[..., :2].reshape(-1, 2)).reshape(far.shape) + lift
    lifted = far & np.isfinite(need) & (need > points[..., 2])
    ok = np.ones((len(ends), len(heights)), dtype=bool)
    if not lifted.any():
        return ok
    over = points[lifted]
    over[:, 2] = need[lifted]
    reached = np.zeros((len(over), len(heights)), dtype=bool)
    for pose, incline in zip(poses, inclines, strict=True):
        reached |= reach_heights(kinematics, leg, over, (pose,), heights, 0.0, (incline,))
    np.logical_and.at(ok, np.nonzero(lifted)[0], reached)
    return ok
