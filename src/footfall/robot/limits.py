"""What a robot's legs reach: bounds from its geometry alone.

The height range a foot reaches at its rest place sets the slope a body takes level
(:mod:`footfall.motion.incline`). The other bounds say what no gait can do: a terrain row
of ``footfall bench terrain`` is declared impassable for a robot only by a rule that holds
for every gait and every planner, the true geometry of the terrain (its own parameters)
against these bounds. They are deliberately generous (a bound, not an estimate), so a
declared row is one that no walk could cross, never one the planner happens to fail.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from footfall.robot.kinematics import LegKinematics
from footfall.robot.spec import HexapodSpec

# Spacing of the points at which a leg's reach is sampled [m].
_SAMPLE_M = 0.002


def _runs(ok: npt.NDArray[np.bool_]) -> tuple[npt.NDArray[np.intp], npt.NDArray[np.intp]]:
    """The runs of True in a boolean array: their first and one-past-last indices."""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], ok.astype(np.int8), [0]])))
    return edges[0::2], edges[1::2]


def _line(point: npt.NDArray[np.float64], axis: int, offsets: npt.NDArray[np.float64]):
    """Points along a body axis through ``point``, at ``offsets`` from it [m]."""
    points = np.repeat(point[None], len(offsets), axis=0)
    points[:, axis] += offsets
    return points


def height_range(kinematics: LegKinematics, spec: HexapodSpec, margin: float) -> float:
    """The least, over the legs, of the height range a foot reaches at its rest place [m].

    The foot keeps its rest position in the ground plane and moves up and down from its
    rest height as far as the leg reaches, ``margin`` inside its workspace, without a gap.
    """
    rest = spec.rest_feet_in_body()
    span = kinematics.L2 + kinematics.L3
    offsets = np.arange(-span, span + spec.body_height, _SAMPLE_M)
    at_rest = int(np.argmin(np.abs(offsets)))
    ranges = []
    for leg in range(6):
        ok = np.asarray(kinematics.reachable(leg, _line(rest[leg], 2, offsets), margin))
        starts, ends = _runs(ok)
        around = (starts <= at_rest) & (at_rest < ends)
        if not around.any():
            return 0.0
        ranges.append(float(offsets[ends[around][0] - 1] - offsets[starts[around][0]]))
    return min(ranges)


def stroke_reach_m(spec: HexapodSpec) -> float:
    """The longest stretch along the body's x axis that one foot reaches [m].

    Over the legs, the longest run of reached foot positions on a line parallel to the body's
    x axis through the foot's rest position, at any height of the foot below its hip.
    """
    kinematics = LegKinematics(spec)
    span = kinematics.L1 + kinematics.L2 + kinematics.L3
    offsets = np.arange(-span, span, _SAMPLE_M)
    longest = 0
    rest = spec.rest_feet_in_body()
    for leg in range(6):
        for z in np.arange(-span, 0.0, 0.01):
            point = np.array([rest[leg, 0], rest[leg, 1], z])
            starts, ends = _runs(np.asarray(kinematics.reachable(leg, _line(point, 0, offsets))))
            if starts.size:
                longest = max(longest, int((ends - starts).max()))
    return longest * _SAMPLE_M


def longest_step_m(spec: HexapodSpec) -> float:
    """The farthest a foot can travel over the ground in one swing [m].

    The foot lifts off at one end of its leg's reach and lands at most at the other end,
    while the body moves on by at most as much again: the supporting feet, which hold the
    body, cannot travel farther than their own legs' reach (:func:`stroke_reach_m`).
    """
    return 2.0 * stroke_reach_m(spec)


def steepest_slope_rad(spec: HexapodSpec) -> float:
    """The steepest slope the feet hold on without sliding: the friction angle [rad]."""
    return math.atan(spec.foot_friction)
