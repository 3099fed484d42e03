"""What the navigator does about a walker frozen for want of footholds: look, or block.

A walker that stays frozen (counted across its retries on fresh maps) for
``blocked_after_s`` is stuck. When the frozen leg's place has not been seen (the camera
looks ahead, and a route that turns close beside the edge of what it has seen puts feet
where it never looked), the robot first turns on the spot to face that place, once per
place. Otherwise the ground ahead is kept out of routes for ``blocked_for_s``: the route
was blocked there.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from footfall.messages import GaitState, GaitStatus, MapUpdate, WalkCommand
from footfall.planning.navigation import NavigationConfig
from footfall.robot.planar import PlanarPose

# A foot's place counts as unseen when less than this share of the cells around it is known.
UNSEEN_SHARE = 0.5
# A look is done when the body faces the place within this [rad], or after this long [s].
LOOK_DONE_RAD = math.radians(10.0)
LOOK_TIMEOUT_S = 10.0
# A walker that froze and has not moved farther than this since is still stuck there [m].
STUCK_RADIUS_M = 0.1
# A place within this of one already looked at is not looked at again [m].
LOOKED_RADIUS_M = 0.1


@dataclass(frozen=True)
class BlockedDisc:
    """Ground kept out of routes for a while.

    Attributes:
        x_m: Centre x in the world [m].
        y_m: Centre y in the world [m].
        radius_m: Radius [m].
        until_s: Kept out until this time [s].
    """

    x_m: float
    y_m: float
    radius_m: float
    until_s: float


@dataclass(frozen=True)
class Look:
    """A turn on the spot to face a place the map has not seen.

    Attributes:
        yaw_rad: Heading that faces the place [rad].
        until_s: Given up at this time [s].
    """

    yaw_rad: float
    until_s: float


class StuckWatch:
    """Tells a stuck walker from a walking one, and decides to look or to block.

    Args:
        config: The navigation settings (when stuck, what to block, how to turn).
        leg_names: The robot's legs, in the spec's order.
        rest_feet_in_body: Rest foot positions in the body frame, shape (6, 2) [m].
        log: Called with ``(t, level, text)`` to say what it did.
    """

    def __init__(
        self,
        config: NavigationConfig,
        leg_names: tuple[str, ...],
        rest_feet_in_body: np.ndarray,
        log: Callable[[float, str, str], None],
    ) -> None:
        self.config = config
        self.leg_names = leg_names
        self.rest_feet_in_body = rest_feet_in_body
        self.log = log
        self.blocked: list[BlockedDisc] = []
        self.blocked_count = 0
        self.looks = 0
        self.look: Look | None = None
        self.looked: list[tuple[float, float]] = []
        self._frozen_since: float | None = None
        self._frozen_at: tuple[float, float] | None = None
        self._handled = False  # this freeze has had its look or its block

    def _walked_on(self) -> None:
        """The next freeze starts the count afresh."""
        self._frozen_since, self._frozen_at, self._handled = None, None, False

    def blocked_discs(self, t: float) -> tuple[tuple[float, float, float], ...]:
        """The discs ``(x, y, radius)`` kept out of routes at time ``t`` [m]."""
        return tuple((b.x_m, b.y_m, b.radius_m) for b in self.blocked if b.until_s > t)

    def watch(
        self,
        t: float,
        status: GaitStatus,
        last_command: WalkCommand | None,
        update: MapUpdate | None,
    ) -> bool:
        """Look at the walker's status at time ``t`` [s].

        Returns:
            True when it blocked ground (a route must be planned afresh).
        """
        pose = status.body_pose
        if self._frozen_at is not None and (
            math.hypot(pose.x - self._frozen_at[0], pose.y - self._frozen_at[1]) > STUCK_RADIUS_M
        ):
            self._walked_on()
        if status.state is not GaitState.FROZEN:
            return False
        if self._frozen_since is None:
            # Counted from the first freeze here: a walker that retries on each fresh map
            # and freezes again at once is as stuck as one that stays frozen.
            self._frozen_since, self._frozen_at = t, (pose.x, pose.y)
        if self._handled or t - self._frozen_since < self.config.blocked_after_s:
            return False
        self._handled = True
        place = self._unseen_place(status, update)
        if place is not None:
            self.looked.append(place)
            yaw = math.atan2(place[1] - pose.y, place[0] - pose.x)
            self.look = Look(yaw, t + LOOK_TIMEOUT_S)
            self.looks += 1
            self.log(
                t,
                "info",
                f"leg {status.frozen_leg} has not seen where it steps ({place[0]:.2f}, "
                f"{place[1]:.2f}) m; turning to look",
            )
            return False
        heading = pose.yaw
        if last_command is not None and last_command.speed > 0:
            heading += math.atan2(last_command.direction[1], last_command.direction[0])
        ahead = self.config.blocked_ahead_m
        x, y = pose.x + ahead * math.cos(heading), pose.y + ahead * math.sin(heading)
        disc = BlockedDisc(x, y, self.config.blocked_radius_m, t + self.config.blocked_for_s)
        self.blocked = [b for b in [*self.blocked, disc] if b.until_s > t]
        self.blocked_count += 1
        self.log(
            t, "info", f"route blocked at ({x:.2f}, {y:.2f}) m ({status.frozen_reason}); replanning"
        )
        return True

    def _unseen_place(
        self, status: GaitStatus, update: MapUpdate | None
    ) -> tuple[float, float] | None:
        """Where the frozen leg steps at rest, if the map has not seen it and no look has."""
        if update is None or status.frozen_leg not in self.leg_names:
            return None
        foot = self.rest_feet_in_body[self.leg_names.index(status.frozen_leg)]
        x, y = (float(v) for v in status.body_pose.points_to_world(foot))
        if any(math.hypot(x - a, y - b) < LOOKED_RADIUS_M for a, b in self.looked):
            return None
        known = np.asarray(update.known, dtype=bool)
        res = update.resolution
        half = max(1, round(self.config.traversability.support_radius_m / res))
        i = math.floor((x - update.origin[0]) / res)
        j = math.floor((y - update.origin[1]) / res)
        n = known.shape[0]
        around = known[
            max(i - half, 0) : min(i + half + 1, n), max(j - half, 0) : min(j + half + 1, n)
        ]
        seen = float(around.mean()) if around.size else 0.0
        return (x, y) if seen < UNSEEN_SHARE else None

    def looking(
        self, t: float, pose: PlanarPose, base: WalkCommand
    ) -> tuple[WalkCommand | None, bool]:
        """The turn on the spot of a look under way at time ``t`` [s].

        Returns:
            The command, or None when no look is under way; and whether a look just ended
            (a route must be planned on what it showed).
        """
        if self.look is None:
            return None, False
        error = math.atan2(
            math.sin(self.look.yaw_rad - pose.yaw), math.cos(self.look.yaw_rad - pose.yaw)
        )
        if abs(error) < LOOK_DONE_RAD or t > self.look.until_s:
            self.look = None
            # Stuck here again after the look: the count starts afresh, and ends in a block.
            self._walked_on()
            return None, True
        rate = self.config.max_yaw_rate
        yaw_rate = float(np.clip(self.config.yaw_gain * error, -rate, rate))
        command = WalkCommand(speed=0.0, body_height=base.body_height, yaw_rate=yaw_rate, stamp=t)
        return command, False
