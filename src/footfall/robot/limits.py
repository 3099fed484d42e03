"""What no gait of a robot can do: bounds from its geometry alone, for impassable terrain.

A terrain row of ``footfall bench terrain`` is declared impassable for a robot only by a
rule that holds for every gait and every planner: the true geometry of the terrain (its
own parameters) against these bounds, which come from the robot's description. They are
deliberately generous (a bound, not an estimate), so a declared row is one that no walk
could cross, never one the planner happens to fail.
"""

from __future__ import annotations

import math

import numpy as np

from footfall.robot.kinematics import LegKinematics
from footfall.robot.spec import HexapodSpec

# Spacing of the points at which a leg's reach is sampled [m].
_SAMPLE_M = 0.002


def stroke_reach_m(spec: HexapodSpec) -> float:
    """The longest stretch along the body's x axis that one foot reaches [m].

    Over the legs, the longest run of reached foot positions on a line parallel to the body's
    x axis through the foot's rest position, at any height of the foot below its hip.
    """
    kinematics = LegKinematics(spec)
    span = kinematics.L1 + kinematics.L2 + kinematics.L3
    longest = 0.0
    rest = spec.rest_feet_in_body()
    for leg in range(6):
        for z in np.arange(-span, 0.0, 0.01):
            points = np.repeat(rest[leg][None], int(2 * span / _SAMPLE_M), axis=0)
            points[:, 0] = rest[leg, 0] + np.arange(len(points)) * _SAMPLE_M - span
            points[:, 2] = z
            ok = np.asarray(kinematics.reachable(leg, points))
            if ok.any():
                longest = max(longest, _longest_run(ok) * _SAMPLE_M)
    return longest


def _longest_run(ok: np.ndarray) -> int:
    """The length of the longest run of True in a boolean array."""
    padded = np.concatenate([[False], ok, [False]]).astype(np.int8)
    edges = np.flatnonzero(np.diff(padded))
    return int((edges[1::2] - edges[0::2]).max()) if edges.size else 0


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
