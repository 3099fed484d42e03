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

The checks run compiled, point by point (:mod:`footfall.planning.clearance_kernels`): the
planner asks them for every candidate foothold at every body height it tries.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
import numpy.typing as npt

from footfall.robot.kinematics import LegKinematics
from footfall.robot.planar import PlanarPose

# Points of the leg that must clear the terrain, as fractions of the way from the knee to
# the foot: the knee and the middle of the tibia (the lower half stands over the foothold's
# own edge margin).
TIBIA_FRACTIONS = np.array([0.0, 0.5])
# A swing's way is checked at this many points (a centimetre apart on a long step); within
# SWING_END_RADIUS_M of either end the path stands over the footholds themselves and is not
# checked (as the swing paths do) [m].
SWING_SAMPLES = 24
SWING_END_RADIUS_M = 0.03
_SWING_FRACTIONS = np.linspace(0.0, 1.0, SWING_SAMPLES)


class MapTerrain(NamedTuple):
    """The mapped terrain as the checks sample it: the highest height around a point.

    Attributes:
        offsets: Shifts sampled around each point (a link's or a foot's radius), shape
            (k, 2) [m].
        heights: The map window's heights, shape (N, N), NaN where unknown [m].
        origin_x: World x of the corner of cell ``[0, 0]`` [m].
        origin_y: World y of that corner [m].
        resolution: Cell side [m].
    """

    offsets: npt.NDArray[np.float64]
    heights: npt.NDArray[np.float64]
    origin_x: float
    origin_y: float
    resolution: float


class FootholdChecks(NamedTuple):
    """What a step's footholds are checked against (:func:`foothold_heights`).

    Attributes:
        reach_poses: Poses the leg must reach the foothold from, rows of :func:`pose_rows`.
        reach_margin: Workspace margin of that reach [m].
        swing_poses: Poses the foot may be lifted over the terrain from.
        lift: Least height of the foot's centre above the terrain on its way [m].
        stance_poses: Poses the leg stands under, its knee and tibia clear of the terrain.
        clearance: Least gap between a link's centre line and the terrain [m].
    """

    reach_poses: npt.NDArray[np.float64]
    reach_margin: float
    swing_poses: npt.NDArray[np.float64]
    lift: float
    stance_poses: npt.NDArray[np.float64]
    clearance: float


def pose_rows(
    poses: tuple[PlanarPose, ...], inclines: tuple[float, ...] | None = None
) -> npt.NDArray[np.float64]:
    """Poses as the compiled checks read them: rows ``(x, y, yaw, pitch)``, shape (p, 4).

    ``inclines``: the body's pitch at each pose [rad]; level when None.
    """
    if inclines is None:
        inclines = (0.0,) * len(poses)
    if len(inclines) != len(poses):
        raise ValueError(f"{len(poses)} poses need as many inclines, got {len(inclines)}")
    return np.array([(p.x, p.y, p.yaw, a) for p, a in zip(poses, inclines, strict=True)])


def midway(a: PlanarPose, b: PlanarPose) -> PlanarPose:
    """The pose halfway between two poses (heading by the shorter turn)."""
    turn = math.remainder(b.yaw - a.yaw, 2.0 * math.pi)
    return PlanarPose(0.5 * (a.x + b.x), 0.5 * (a.y + b.y), a.yaw + 0.5 * turn)


def _points(points: npt.ArrayLike) -> npt.NDArray[np.float64]:
    return np.ascontiguousarray(np.asarray(points, dtype=np.float64).reshape(-1, 3))


def _heights(heights: npt.ArrayLike) -> npt.NDArray[np.float64]:
    return np.ascontiguousarray(heights, dtype=np.float64)


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
    from footfall.planning import clearance_kernels  # numba, loaded when first asked

    flat, h = _points(points), _heights(heights)
    out = np.ones((len(flat), len(h)), dtype=bool)
    clearance_kernels.reach_heights(
        flat, pose_rows(poses, inclines), h, int(leg), *kinematics.reach_arrays, margin, out
    )
    return out.reshape(*np.shape(points)[:-1], len(h))


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


def foothold_heights(
    kinematics: LegKinematics,
    terrain: MapTerrain,
    leg: int,
    centres: npt.NDArray[np.float64],
    start: npt.NDArray[np.float64],
    heights: npt.NDArray[np.float64],
    checks: FootholdChecks,
) -> npt.NDArray[np.bool_]:
    """At which body heights the leg reaches, swings to and stands on each foothold centre.

    The leg reaches the centre from every reach pose; it can lift its foot over the terrain
    on the way (beyond ``SWING_END_RADIUS_M`` of either end, as the swing path does, every
    point of the straight way where that lifts the foot above the line is reached from one
    of the swing poses); and its knee and the middle of its tibia keep ``clearance`` above
    the terrain from every stance pose. Each check runs only on the heights the ones
    before left open (:mod:`footfall.planning.clearance_kernels`).

    Args:
        kinematics: The robot's leg kinematics.
        terrain: The map, sampled within a link's radius of each point (an unknown cell
            does not refuse).
        leg: Leg index.
        centres: Candidate foot centres in the world, shape (m, 3) [m].
        start: Where the foot lifts off, shape (3,) [m].
        heights: Body heights in the world, shape (k,) [m].
        checks: The step's poses and margins.

    Returns:
        Shape (m, k).
    """
    from footfall.planning import clearance_kernels  # numba, loaded when first asked

    points, h = _points(centres), _heights(heights)
    out = np.ones((len(points), len(h)), dtype=bool)
    geometry = kinematics.reach_arrays
    clearance_kernels.reach_heights(
        points, checks.reach_poses, h, int(leg), *geometry, checks.reach_margin, out
    )
    clearance_kernels.swing_reach_heights(
        np.ascontiguousarray(start, dtype=np.float64),
        points,
        checks.swing_poses,
        h,
        checks.lift,
        _SWING_FRACTIONS,
        SWING_END_RADIUS_M,
        terrain,
        int(leg),
        *geometry,
        out,
    )
    clearance_kernels.legs_clear_heights(
        points,
        checks.stance_poses,
        h,
        TIBIA_FRACTIONS,
        checks.clearance,
        terrain,
        np.ascontiguousarray(kinematics.mounts_in_body[leg]),
        geometry[1],
        out,
    )
    return out
