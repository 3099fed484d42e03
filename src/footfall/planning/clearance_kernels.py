"""Compiled leg checks of the foothold planner (numba): reach, swing way and leg clearance.

For every candidate foothold the planner asks at which body heights the leg reaches it
from each pose of the step, can lift its foot over the terrain on the way to it, and keeps
its knee and tibia clear of the terrain while it stands there
(:mod:`footfall.planning.leg_clearance` says what each check means). Each kernel computes,
point by point, what the NumPy form of :mod:`~footfall.planning.leg_clearance` computed on
arrays, in the same order of operations, and skips what an earlier check already refused:
``out`` comes in holding the heights still open and leaves holding those that pass.

Poses are rows ``(x, y, yaw, pitch)``: the body's planar pose in the world [m, rad] and its
incline [rad] (:func:`~footfall.robot.planar.level_to_inclined`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from footfall.planning.plan_kernels import highest_at
from footfall.robot.reach_kernel import reaches


@njit(cache=True, nogil=True)
def _turns(poses):
    """Each pose's heading and pitch as cosines and sines, rows ``(cy, sy, cp, sp)``."""
    out = np.empty((poses.shape[0], 4))
    for p in range(poses.shape[0]):
        out[p, 0], out[p, 1] = math.cos(poses[p, 2]), math.sin(poses[p, 2])
        out[p, 2], out[p, 3] = math.cos(poses[p, 3]), math.sin(poses[p, 3])
    return out


@njit(cache=True, nogil=True)
def _to_body(px, py, pz, pose, turn, height):
    """A world point in the body frame of ``pose`` with its origin at ``height`` [m].

    ``turn``: the pose's row of :func:`_turns`.
    """
    c, s = turn[0], turn[1]
    dx, dy = px - pose[0], py - pose[1]
    x = c * dx + s * dy
    y = -s * dx + c * dy
    z = pz - height
    if pose[3] == 0.0:
        return x, y, z
    cp, sp = turn[2], turn[3]
    return cp * x - sp * z, y, sp * x + cp * z


@njit(cache=True, nogil=True)
def reach_heights(points, poses, heights, leg, geometry, lengths, lower, upper, margin, out):
    """Clear ``out[i, k]`` where the leg misses point ``i`` from a pose at height ``k``.

    Args:
        points: World points, shape (m, 3) [m].
        poses: Shape (p, 4), rows as in the module docstring.
        heights: Body heights in the world, shape (k,) [m].
        leg: Leg index.
        geometry: Per-leg mount and yaw (:func:`~footfall.robot.reach_kernel.leg_geometry`).
        lengths: Coxa, femur and tibia lengths, shape (3,) [m].
        lower: Lower joint limits, shape (3,) [rad].
        upper: Upper joint limits, shape (3,) [rad].
        margin: Workspace margin [m].
        out: Shape (m, k), updated in place.
    """
    turns = _turns(poses)
    for i in range(points.shape[0]):
        px, py, pz = points[i, 0], points[i, 1], points[i, 2]
        for k in range(heights.shape[0]):
            for p in range(poses.shape[0]):
                if not out[i, k]:
                    break
                x, y, z = _to_body(px, py, pz, poses[p], turns[p], heights[k])
                if not reaches(x, y, z, leg, geometry, lengths, lower, upper, margin):
                    out[i, k] = False


@njit(cache=True, nogil=True)
def swing_reach_heights(
    start,
    ends,
    poses,
    heights,
    lift,
    fractions,
    end_radius,
    terrain,
    leg,
    geometry,
    lengths,
    lower,
    upper,
    out,
):
    """Clear ``out[i, k]`` where the leg cannot lift its foot over the terrain to end ``i``.

    Along the straight line from ``start`` to each end, sampled at ``fractions`` of the
    way, every sample farther than ``end_radius`` from both ends where the terrain under it
    (plus ``lift``) is above the line must be reached, with no margin, from one of
    ``poses``. ``terrain`` is ``(offsets, heights, origin_x, origin_y, resolution)`` as
    :func:`~footfall.planning.plan_kernels.highest_at` reads it.
    """
    offsets, grid, origin_x, origin_y, resolution = terrain
    turns = _turns(poses)
    n = fractions.shape[0]
    for i in range(ends.shape[0]):
        wx, wy, wz = ends[i, 0] - start[0], ends[i, 1] - start[1], ends[i, 2] - start[2]
        length = math.sqrt(wx * wx + wy * wy)
        for j in range(n):
            f = fractions[j]
            if not (f * length > end_radius and (1.0 - f) * length > end_radius):
                continue
            px, py, pz = start[0] + f * wx, start[1] + f * wy, start[2] + f * wz
            need = highest_at(px, py, offsets, grid, origin_x, origin_y, resolution) + lift
            if not (math.isfinite(need) and need > pz):
                continue
            for k in range(heights.shape[0]):
                if not out[i, k]:
                    continue
                reached = False
                for p in range(poses.shape[0]):
                    x, y, z = _to_body(px, py, need, poses[p], turns[p], heights[k])
                    if reaches(x, y, z, leg, geometry, lengths, lower, upper, 0.0):
                        reached = True
                        break
                out[i, k] = reached


@njit(cache=True, nogil=True)
def legs_clear_heights(feet, poses, heights, fractions, clearance, terrain, mount, lengths, out):
    """Clear ``out[i, k]`` where the leg's knee or tibia comes within ``clearance`` of the terrain.

    The leg stands on foot ``i`` from each of ``poses`` at body height ``k``; its points at
    ``fractions`` of the way from the knee to the foot (the knee-up branch, a foot out of
    reach putting the knee where the stretched or folded leg pointing at it has it) keep
    ``clearance`` above the highest terrain within a link's radius. ``mount``: the leg's
    mount in the body frame [m]; ``terrain`` as for :func:`swing_reach_heights`.
    """
    offsets, grid, origin_x, origin_y, resolution = terrain
    l1, l2, l3 = lengths[0], lengths[1], lengths[2]
    turns = _turns(poses)
    for p in range(poses.shape[0]):
        pose, turn = poses[p], turns[p]
        c, s = turn[0], turn[1]
        back = -pose[3]
        cb, sb = math.cos(back), math.sin(back)
        for i in range(feet.shape[0]):
            for k in range(heights.shape[0]):
                if not out[i, k]:
                    continue
                x, y, z = _to_body(feet[i, 0], feet[i, 1], feet[i, 2], pose, turn, heights[k])
                # The knee (LegKinematics.knees_in_body, point by point).
                qx, qy, qz = x - mount[0], y - mount[1], z - mount[2]
                d = math.hypot(qx, qy)
                r = d - l1
                cos_knee = (r * r + qz * qz - l2 * l2 - l3 * l3) / (2.0 * l2 * l3)
                t3 = -math.acos(min(max(cos_knee, -1.0), 1.0))
                t2 = math.atan2(qz, r) - math.atan2(l3 * math.sin(t3), l2 + l3 * math.cos(t3))
                t2 = (t2 + math.pi) % (2.0 * math.pi) - math.pi
                out_factor = (l1 + l2 * math.cos(t2)) / max(d, 1e-9)
                kx = qx * out_factor + mount[0]
                ky = qy * out_factor + mount[1]
                kz = l2 * math.sin(t2) + mount[2]
                for fraction in fractions:
                    lx = kx + fraction * (x - kx)
                    ly = ky + fraction * (y - ky)
                    lz = kz + fraction * (z - kz)
                    if back != 0.0:
                        lx, lz = cb * lx - sb * lz, sb * lx + cb * lz
                    wx = c * lx - s * ly + pose[0]
                    wy = s * lx + c * ly + pose[1]
                    wz = lz + heights[k]
                    under = highest_at(wx, wy, offsets, grid, origin_x, origin_y, resolution)
                    if not wz >= under + clearance:
                        out[i, k] = False
                        break
