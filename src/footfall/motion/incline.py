"""The body's incline on slopes and stairs: level where the legs take the ground level.

A hexapod whose feet span a long stance stands, on stairs, with its front feet a step or
two above its hind ones. A level body then needs the rise between them out of its legs'
height range, and a short-legged robot runs out of it: the front legs can no longer lift a
foot over the next riser from a body low enough for the hind feet (the PhantomX on 6 cm
stairs). Inclining the body along the ground gives the rise back to the legs, as OpenSHC
does on inclines.

The wanted incline follows the slope of the ground under the feet along the heading (of
the least-squares plane through the supporting feet's and the swinging legs' nominal
footholds' ground). Ground the legs take level leaves the body level: up to
:func:`level_slope_limit`, the slope at which the rise between the front and the hind feet
takes a share of the legs' height range about their rest stance; from there a growing share
of the slope, all of it from ``FULL_RATIO`` times that slope on (continuous, so an estimate
near the limit cannot flip the body), at most ``GaitConfig.incline_limit``.

Pitch here is the IMU's: about the body's y axis, positive nose down. Going up a slope the
body's incline is negative.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from footfall.robot.kinematics import LegKinematics
from footfall.robot.limits import height_range
from footfall.robot.planar import PlanarPose
from footfall.robot.spec import HexapodSpec

# From this multiple of the level slope limit on the body takes the whole slope.
FULL_RATIO = 1.5
# Ground points must spread this far along the heading to give a slope [m].
MIN_SLOPE_SPREAD_M = 0.05


def level_slope_limit(
    kinematics: LegKinematics, spec: HexapodSpec, share: float, margin: float
) -> float:
    """Steepest slope the body takes level [rad].

    At this slope the rise between the front and the hind feet at rest takes ``share`` of
    the legs' height range ``margin`` inside their workspace (:func:`height_range`).
    """
    rest = spec.rest_feet_in_body()
    length = float(rest[:, 0].max() - rest[:, 0].min())
    if length <= 0.0:
        return 0.0
    return math.atan(share * height_range(kinematics, spec, margin) / length)


def ground_slope(ground_in_world: npt.NDArray[np.float64], pose: PlanarPose) -> float | None:
    """The slope along the body's heading of the plane fitted to ground points [rad].

    A least-squares plane over the points (rising across the heading too, where they
    spread across it); positive where the ground rises ahead. None with fewer than two
    points or points spread less than ``MIN_SLOPE_SPREAD_M`` along the heading.

    Args:
        ground_in_world: Ground points, shape (n, 3) [m]; rows with NaN are left out.
        pose: The body's pose (its heading).
    """
    points = ground_in_world[np.all(np.isfinite(ground_in_world), axis=1)]
    if len(points) < 2:
        return None
    local = pose.points_to_body(points)
    if np.ptp(local[:, 0]) < MIN_SLOPE_SPREAD_M:
        return None
    centred = local - local.mean(axis=0)
    fit, *_ = np.linalg.lstsq(centred[:, :2], centred[:, 2], rcond=None)
    return math.atan(float(fit[0]))


def wanted_pitch(slope: float | None, level_limit: float, limit: float) -> float:
    """The body pitch a ground slope asks for [rad], positive nose down.

    Args:
        slope: The ground's slope along the heading, rising ahead positive [rad]; None for
            no estimate (the body levels).
        level_limit: Steepest slope the body takes level [rad].
        limit: The steepest incline allowed [rad].
    """
    if slope is None or limit <= 0.0:
        return 0.0
    steep = abs(slope)
    band = (FULL_RATIO - 1.0) * level_limit
    share = 1.0 if band <= 0.0 else min(max((steep - level_limit) / band, 0.0), 1.0)
    return -math.copysign(min(steep * share, limit), slope)
