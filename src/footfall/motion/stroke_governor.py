"""The stroke governor: how much of the commanded twist the supporting feet allow.

Every supporting foot must stay within reach until it lifts off. Blind, that means within
its nominal stroke (plus a margin), which protects the legs at start-up and on command
changes; with mapped footholds, which may sit off their nominal places, within the leg's
workspace (checked by inverse kinematics where the foot will be at lift-off).
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from footfall.motion.gait import GaitConfig
from footfall.robot.kinematics import LegKinematics


class StrokeGovernor:
    """Largest fraction of the twist, in [0, 1], that keeps the supporting feet reached.

    Args:
        config: Gait parameters (stride, duty factor, stroke margin).
        kinematics: The legs' kinematics.
        rest_in_body: Rest foot positions, shape (6, 3) [m].
        reach_margin: Workspace margin for mapped footholds [m]; None governs by the
            nominal stroke (blind walking).
    """

    def __init__(
        self,
        config: GaitConfig,
        kinematics: LegKinematics,
        rest_in_body: npt.NDArray[np.float64],
        reach_margin: float | None,
    ) -> None:
        self.config = config
        self.kinematics = kinematics
        self.rest_in_body = rest_in_body
        self.reach_margin = reach_margin

    def scale(
        self,
        feet_in_body: npt.NDArray[np.float64],
        stance: npt.NDArray[np.bool_],
        velocity: tuple[float, float],
        yaw_rate: float,
        horizons: npt.NDArray[np.float64],
        rises: npt.NDArray[np.float64] | None = None,
    ) -> float:
        """The twist fraction every supporting foot allows until it lifts off.

        Args:
            feet_in_body: Foot positions in the body frame, shape (6, 3) [m].
            stance: Supporting legs, shape (6,).
            velocity: Body velocity in the body frame [m/s].
            yaw_rate: Body yaw rate [rad/s].
            horizons: Time until each leg lifts off, shape (6,) [s].
            rises: How far the body rises before each leg lifts off, shape (6,) [m]: the
                feet sink by as much in the body frame (mapped footholds only).
        """
        vx, vy = velocity
        feet = feet_in_body
        if rises is not None and self.reach_margin is not None:
            feet = feet.copy()
            feet[:, 2] -= rises
        # Body-frame velocity of a world-fixed point: -(v + omega x p).
        drift = np.stack([-vx + yaw_rate * feet[:, 1], -vy - yaw_rate * feet[:, 0]], axis=1)
        scale = 1.0
        drifts = drift * horizons[:, None]
        if self.reach_margin is not None:
            # Feet that stay reached over the whole drift need no bisection.
            after = feet.copy()
            after[:, :2] += drifts
            stance = stance & ~self.kinematics.reachable_all(after, self.reach_margin)
        for leg in np.flatnonzero(stance):
            u = drifts[leg]
            if float(u @ u) < 1e-12:
                continue
            if self.reach_margin is None:
                offset = feet[leg, :2] - self.rest_in_body[leg, :2]
                scale = min(scale, self.stroke_scale(offset, u))
            else:
                scale = min(scale, self.reach_scale(int(leg), feet[leg], u))
        return scale

    def stroke_scale(self, offset: npt.NDArray[np.float64], u: npt.NDArray[np.float64]) -> float:
        """Largest k in [0, 1] with |offset + k u| within the nominal stroke (plus margin)."""
        reach = 0.5 * self.config.stride * self.config.duty_factor + self.config.stroke_margin
        a, b, c = float(u @ u), float(offset @ u), float(offset @ offset) - reach**2
        if c > 0:
            return 1.0 if b < 0 else 0.0
        return min(1.0, (-b + math.sqrt(b * b - a * c)) / a)

    def reach_scale(
        self, leg: int, foot: npt.NDArray[np.float64], u: npt.NDArray[np.float64]
    ) -> float:
        """Largest k in [0, 1] keeping the foot reachable after drifting by k u (bisection)."""
        margin = self.reach_margin or 0.0

        def ok(k: float) -> bool:
            p = foot.copy()
            p[:2] += k * u
            return self.kinematics.reachable(leg, p, margin)

        if ok(1.0):
            return 1.0
        if not ok(0.0):
            # Already at the edge: allow motion that brings the foot back in.
            return 1.0 if ok(0.05) else 0.0
        low, high = 0.0, 1.0
        for _ in range(6):
            mid = 0.5 * (low + high)
            low, high = (mid, high) if ok(mid) else (low, mid)
        return low
