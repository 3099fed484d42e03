"""Legs that clear the terrain: a foothold whose knee would stand in the mapped terrain.

A foothold can be a valid cell that the foot reaches and still be a bad one: the knee stands
out beyond the foot (a knee-up leg's tibia slants inwards), and while the body walks over a
standing foot the knee sweeps forwards or backwards over the terrain next to it. Beside a
ramp, a box or a step up the knee then runs into the slope, tips the robot over the feet that
stand and drags them along. The walking controller never sees the collision; the feet land
where the body's estimate no longer is. This module checks the leg's upper points (the knee
and the middle of the tibia) against the mapped terrain through the stance.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import numpy.typing as npt

from footfall.robot.kinematics import LegKinematics
from footfall.robot.planar import PlanarPose

# Points of the leg that must clear the terrain, as fractions of the way from the knee to
# the foot: the knee and the middle of the tibia (the lower half stands over the foothold's
# own edge margin).
TIBIA_FRACTIONS = (0.0, 0.5)


def midway(a: PlanarPose, b: PlanarPose) -> PlanarPose:
    """The pose halfway between two poses (heading by the shorter turn)."""
    turn = math.remainder(b.yaw - a.yaw, 2.0 * math.pi)
    return PlanarPose(0.5 * (a.x + b.x), 0.5 * (a.y + b.y), a.yaw + 0.5 * turn)


def legs_clear_heights(
    kinematics: LegKinematics,
    terrain_under: Callable[[npt.NDArray[np.float64]], npt.NDArray[np.float64]],
    leg: int,
    feet: npt.NDArray[np.float64],
    poses: tuple[PlanarPose, ...],
    heights: npt.NDArray[np.float64],
    clearance: float,
) -> npt.NDArray[np.bool_]:
    """At which body heights the leg's knee and tibia stay clear of the mapped terrain.

    Args:
        kinematics: The robot's leg kinematics.
        terrain_under: Highest mapped height within a link's radius of world points, shape
            (n, 2) -> (n,) [m]; ``-inf`` where unknown (an unknown cell does not refuse).
        leg: Leg index.
        feet: Foot centres in the world, shape (m, 3) [m].
        poses: Body poses the foot stands under.
        heights: Body heights in the world, shape (k,) [m].
        clearance: Least gap between a link's centre line and the terrain [m].

    Returns:
        Shape (m, k).
    """
    ok = np.ones((len(feet), len(heights)), dtype=bool)
    for pose in poses:
        in_body = np.repeat(pose.points_to_body(feet)[:, None, :], len(heights), axis=1)
        in_body[..., 2] -= heights
        knees = kinematics.knees_in_body(leg, in_body)
        for fraction in TIBIA_FRACTIONS:
            point = pose.points_to_world(knees + fraction * (in_body - knees))
            point[..., 2] += heights
            under = terrain_under(point[..., :2].reshape(-1, 2)).reshape(ok.shape)
            ok &= point[..., 2] >= under + clearance
    return ok
