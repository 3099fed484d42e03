"""Legs that clear the terrain: a foothold whose knee would stand in the mapped terrain.

A foothold can be a valid cell that the foot reaches and still be a bad one: the knee stands
out beyond the foot (a knee-up leg's tibia slants inwards), and while the body walks over a
standing foot the knee sweeps forwards or backwards over the terrain next to it. Beside a
ramp, a box or a step up the knee then runs into the slope, tips the robot over the feet that
stand and drags them along. The walking controller never sees the collision; the feet land
where the body's estimate no longer is. This module checks the leg's upper points (the knee
and the middle of the tibia) against the mapped terrain through the stance, and the foot's
way to its foothold: a short leg folds up as its foot passes beside the hip and cannot lift
it over a riser there from a body standing too low.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import numpy.typing as npt

from footfall.robot.kinematics import LegKinematics
from footfall.robot.planar import PlanarPose, inclined_to_level, level_to_inclined

# Points of the leg that must clear the terrain, as fractions of the way from the knee to
# the foot: the knee and the middle of the tibia (the lower half stands over the foothold's
# own edge margin).
TIBIA_FRACTIONS = (0.0, 0.5)
# A swing's way is checked at this many points (a centimetre apart on a long step); within
# SWING_END_RADIUS_M of either end the path stands over the footholds themselves and is not
# checked (as the swing paths do) [m].
SWING_SAMPLES = 24
SWING_END_RADIUS_M = 0.03


def _inclines(poses: tuple[PlanarPose, ...], inclines: tuple[float, ...] | None) -> tuple:
    """The body's pitch at each pose [rad]: ``inclines``, or level throughout."""
    if inclines is None:
        return (0.0,) * len(poses)
    if len(inclines) != len(poses):
        raise ValueError(f"{len(poses)} poses need as many inclines, got {len(inclines)}")
    return tuple(inclines)


def to_body(
    pose: PlanarPose,
    points: npt.NDArray[np.float64],
    heights: npt.NDArray[np.float64],
    incline: float = 0.0,
) -> npt.NDArray[np.float64]:
    """World points in the body frame at each body height, shape (..., k, 3) [m].

    The body stands at ``pose`` with its origin at each of ``heights`` (world z) and
    pitched by ``incline`` [rad] (:func:`~footfall.robot.planar.level_to_inclined`).
    """
    in_body = np.repeat(pose.points_to_body(points)[..., None, :], len(heights), axis=-2)
    in_body[..., 2] -= heights
    return level_to_inclined(in_body, incline)


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
    inclines: tuple[float, ...] | None = None,
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
        inclines: The body's pitch at each pose [rad]; level when None.

    Returns:
        Shape (m, k).
    """
    ok = np.ones((len(feet), len(heights)), dtype=bool)
    for pose, incline in zip(poses, _inclines(poses, inclines), strict=True):
        in_body = to_body(pose, feet, heights, incline)
        knees = kinematics.knees_in_body(leg, in_body)
        for fraction in TIBIA_FRACTIONS:
            level = inclined_to_level(knees + fraction * (in_body - knees), incline)
            point = pose.points_to_world(level)
            point[..., 2] += heights
            under = terrain_under(point[..., :2].reshape(-1, 2)).reshape(ok.shape)
            ok &= point[..., 2] >= under + clearance
    return ok


def reach_heights(
    kinematics: LegKinematics,
    leg: int,
    points: npt.NDArray[np.float64],
    poses: tuple[PlanarPose, ...],
    heights: npt.NDArray[np.float64],
    margin: float = 0.0,
    inclines: tuple[float, ...] | None = None,
) -> npt.NDArray[np.bool_]:
    """At which body heights the leg reaches world points from every pose.

    Args:
        kinematics: The robot's leg kinematics.
        leg: Leg index.
        points: World point, shape (3,), or several, shape (..., 3) [m].
        poses: Body poses.
        heights: Body heights in the world, shape (k,) [m].
        margin: Workspace margin [m].
        inclines: The body's pitch at each pose [rad]; level when None.

    Returns:
        Shape (k,) for one point, else (..., k).
    """
    ok = np.ones((*np.shape(points)[:-1], len(heights)), dtype=bool)
    for pose, incline in zip(poses, _inclines(poses, inclines), strict=True):
        ok &= kinematics.reachable(leg, to_body(pose, points, heights, incline), margin)
    return ok


def stance_heights(
    kin: LegKinematics,
    feet: npt.NDArray[np.float64],
    stance: npt.NDArray[np.bool_],
    poses: tuple[PlanarPose, PlanarPose],
    heights: npt.NDArray[np.float64],
    reach_margin: float,
    inclines: tuple[float, float] = (0.0, 0.0),
) -> npt.NDArray[np.bool_]:
    """Body heights at which every supporting foot stays reached from now until touchdown.

    Only the pose now is binding when no height serves both (the stroke governor then slows
    the body down so the feet stay reached), and then without a margin.

    Args:
        kin: The legs' kinematics.
        feet: Every foot's position, world frame, shape (6, 3) [m].
        stance: Which feet support the body.
        poses: The body now and at touchdown.
        heights: Body heights to test, shape (H,) [m].
        reach_margin: The planner's; the feet keep half of it, as the stroke governor does [m].
        inclines: The body's pitch now and at touchdown [rad].
    """
    legs = np.flatnonzero(stance)
    ok = np.zeros(len(heights), dtype=bool)
    for count, margin in ((2, 0.5 * reach_margin), (1, 0.0)):
        ok = np.ones(len(heights), dtype=bool)
        pose_set, pitches = poses[:count], inclines[:count]
        for leg in legs:
            ok &= reach_heights(kin, int(leg), feet[leg], pose_set, heights, margin, pitches)
        if ok.any():
            break
    return ok


def swing_reach_heights(
    kinematics: LegKinematics,
    terrain_under: Callable[[npt.NDArray[np.float64]], npt.NDArray[np.float64]],
    leg: int,
    start: npt.NDArray[np.float64],
    ends: npt.NDArray[np.float64],
    poses: tuple[PlanarPose, ...],
    heights: npt.NDArray[np.float64],
    lift: float,
    inclines: tuple[float, ...] | None = None,
) -> npt.NDArray[np.bool_]:
    """At which body heights the leg can lift its foot over the terrain to each end.

    The swing path clears the mapped terrain on its way (beyond ``SWING_END_RADIUS_M`` of
    either end, as the path does): at every point of the way where that lifts the foot
    above the straight line between its ends, the leg must reach the foot from one of the
    poses (the body now or at touchdown).

    Args:
        kinematics: The robot's leg kinematics.
        terrain_under: As for :func:`legs_clear_heights`.
        leg: Leg index.
        start: Where the foot lifts off, shape (3,) [m].
        ends: Candidate foot centres, shape (m, 3) [m].
        poses: Body poses the foot may be lifted from.
        heights: Body heights in the world, shape (k,) [m].
        lift: Least height of the foot's centre above the terrain on the way [m].
        inclines: The body's pitch at each pose [rad]; level when None.

    Returns:
        Shape (m, k).
    """
    fraction = np.linspace(0.0, 1.0, SWING_SAMPLES)
    way = ends[:, None, :] - start
    points = start + fraction[None, :, None] * way  # (m, n, 3): the straight line
    length = np.linalg.norm(way[..., :2], axis=2)
    far = (fraction * length > SWING_END_RADIUS_M) & (
        (1.0 - fraction) * length > SWING_END_RADIUS_M
    )
    need = terrain_under(points[..., :2].reshape(-1, 2)).reshape(far.shape) + lift
    lifted = far & np.isfinite(need) & (need > points[..., 2])
    ok = np.ones((len(ends), len(heights)), dtype=bool)
    if not lifted.any():
        return ok
    over = points[lifted]
    over[:, 2] = need[lifted]
    reached = np.zeros((len(over), len(heights)), dtype=bool)
    for pose, incline in zip(poses, _inclines(poses, inclines), strict=True):
        reached |= reach_heights(kinematics, leg, over, (pose,), heights, 0.0, (incline,))
    np.logical_and.at(ok, np.nonzero(lifted)[0], reached)
    return ok
