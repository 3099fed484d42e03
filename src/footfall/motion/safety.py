"""The safety monitor: when the robot freezes, and when it may walk on.

A frozen robot stands with all feet down and holds its last targets. It freezes when a
target is out of a leg's reach, when a step finds no acceptable foothold, and when, asked
to move, its body has not advanced for two gait cycles (the way ahead has no foothold the
legs can reach). It tries again when the command changes materially, or, when a new map
might help (no foothold found), after ``MAP_FRAMES_BEFORE_RETRY`` new map frames.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from footfall.messages import WalkCommand
from footfall.planning.step_plan import NoFoothold

# A robot frozen for want of a foothold retries after this many new map frames.
MAP_FRAMES_BEFORE_RETRY = 5
# The body counts as stalled when it moved less than this in a step [m], while walking
# faster than STALL_SPEED [m/s].
STALL_DISTANCE = 0.005
STALL_SPEED = 1e-3


def materially_different(a: WalkCommand, b: WalkCommand) -> bool:
    """Whether a new command asks for something else, not just a steering wobble."""
    va, vb = np.array(a.velocity_in_body), np.array(b.velocity_in_body)
    return bool(
        np.hypot(*(va - vb)) > 0.02
        or abs(a.yaw_rate - b.yaw_rate) > 0.1
        or abs(a.body_height - b.body_height) > 0.005
    )


class SafetyMonitor:
    """Freeze reasons and the rules for resuming.

    Attributes:
        reason: Why the robot froze ("" when it is not frozen).
        leg: The leg the freeze concerns ("" when none).
        frozen_command: The command in force when it froze.
    """

    def __init__(self) -> None:
        self.reason = ""
        self.leg = ""
        self.frozen_command: WalkCommand | None = None
        self._frozen_version = -1
        self._stalled_steps = 0

    def freeze(
        self,
        reason: str,
        command: WalkCommand | None,
        map_version: int | None = None,
        leg: str = "",
    ) -> None:
        """Record a freeze; ``map_version`` is the map's version when a new map may help."""
        self.reason = reason
        self.leg = leg
        self.frozen_command = command
        self._frozen_version = map_version if map_version is not None else -1

    def resume(self) -> None:
        """Clear the freeze."""
        self.reason = ""
        self.leg = ""

    def may_resume(self, command: WalkCommand, map_version: int | None) -> bool:
        """Whether a frozen robot should try again: a changed command, or a fresh map."""
        if self.frozen_command is not None and materially_different(command, self.frozen_command):
            return True
        # Retry on a fresh map, a few frames on (a third of a second at 15 Hz).
        return (
            self._frozen_version >= 0
            and map_version is not None
            and map_version >= self._frozen_version + MAP_FRAMES_BEFORE_RETRY
        )

    def stalled(
        self,
        moved: float,
        speed: float,
        cycle_steps: int,
        detects: bool,
        nominal: npt.NDArray[np.float64],
        targets: npt.NDArray[np.float64],
        leg_names: tuple[str, ...],
    ) -> NoFoothold | None:
        """Count a finished step; the freeze reason once two gait cycles made no progress.

        Args:
            moved: How far the body moved in the step [m].
            speed: The shaped body speed [m/s].
            cycle_steps: Steps in a gait cycle.
            detects: Whether stalls count (footholds chosen on a map).
            nominal: The step's nominal targets, shape (6, 3) [m].
            targets: Its chosen targets, shape (6, 3) [m].
            leg_names: Leg names, for the reason.

        Returns:
            Why, naming the leg pulled back furthest from its nominal foothold; None while
            the body advances.
        """
        walking = speed > STALL_SPEED
        self._stalled_steps = self._stalled_steps + 1 if walking and moved < STALL_DISTANCE else 0
        if not detects or self._stalled_steps < 2 * cycle_steps:
            return None
        pulled = np.linalg.norm(targets[:, :2] - nominal[:, :2], axis=1)
        leg = leg_names[int(np.argmax(pulled))]
        self._stalled_steps = 0
        return NoFoothold(
            f"leg {leg}: blocked, no valid foothold it can reach ahead "
            f"(its nominal foothold is {pulled.max():.2f} m from the nearest acceptable cell; "
            f"the body has not advanced for two gait cycles)",
            leg,
        )
