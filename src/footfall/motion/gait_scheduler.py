"""The gait scheduler: which legs swing next and when a step ends (thesis §5.3).

Steps follow the gait's cycle of swing groups. The first step of a walk picks its group
from the walk direction: for the tripod, eqs. 5.15-5.16 (after which the two tripods
alternate, so a set held back by a refused step is never starved); for ripple and wave,
the group of the leg whose sextant holds the direction (§5.3.3). Stepping back to rest, the
next group in the cycle with a foot out of place swings.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import numpy.typing as npt

from footfall.motion.command_shaping import CommandShaper
from footfall.motion.gait import GaitConfig, active_sextant, tripod_swing_set
from footfall.robot.planar import PlanarPose


class GaitScheduler:
    """Step timing and the swing group sequence.

    Args:
        config: Gait parameters.
        rest_in_body: Rest foot positions, shape (6, 3) [m].
        mounts_in_body: Leg mount positions, shape (6, 3) [m].
        foot_radius: Height of a foot's centre over the ground when down [m].

    Attributes:
        group_index: Index of the group that swings (or swung last).
        start_of_walk: The next step starts a walk (its group comes from the direction).
        step_start: Start time of the step [s].
        step_duration: Duration of the step [s].
        steps_taken: Steps completed.
    """

    def __init__(
        self,
        config: GaitConfig,
        rest_in_body: npt.NDArray[np.float64],
        mounts_in_body: npt.NDArray[np.float64],
        foot_radius: float = 0.0,
    ) -> None:
        self.config = config
        self.foot_radius = foot_radius
        self.rest_in_body = rest_in_body
        self.mounts_in_body = mounts_in_body
        self.group_index = len(config.groups) - 1
        self.start_of_walk = True
        self.step_start = 0.0
        self.step_duration = config.rest_step_duration
        self.steps_taken = 0

    @property
    def n_groups(self) -> int:
        """Groups in the gait cycle."""
        return len(self.config.groups)

    def remaining(self, t: float) -> float:
        """Time left in the step at ``t`` [s]."""
        return max(self.step_start + self.step_duration - t, 0.0)

    def step_over(self, t: float) -> bool:
        """Whether the step has ended by ``t``."""
        return t >= self.step_start + self.step_duration - 1e-9

    def begin_step(self, t: float, shaper: CommandShaper) -> None:
        """Start a step at ``t``, timed for the twist (rest steps take their own time)."""
        self.step_duration = (
            self.config.step_duration(shaper.foot_speed(self.rest_in_body))
            if shaper.moving
            else self.config.rest_step_duration
        )
        self.step_start = t

    def rest_feet_in_world(self, pose: PlanarPose) -> npt.NDArray[np.float64]:
        """The rest stance under a body pose, feet on the plane z = 0, shape (6, 3) [m]."""
        feet = pose.points_to_world(self.rest_in_body)
        feet[:, 2] = self.foot_radius
        return feet

    def off_rest(
        self, feet_in_world: npt.NDArray[np.float64], pose: PlanarPose
    ) -> npt.NDArray[np.bool_]:
        """Which feet are off their rest positions under the body, shape (6,)."""
        offset = feet_in_world[:, :2] - self.rest_feet_in_world(pose)[:, :2]
        return np.hypot(offset[:, 0], offset[:, 1]) > self.config.rest_tolerance

    def nominal_targets(
        self,
        t: float,
        pose: PlanarPose,
        velocity: tuple[float, float],
        yaw_rate: float,
    ) -> npt.NDArray[np.float64]:
        """Touchdown targets in the world, shape (6, 3) [m].

        Each leg's rest position at the body pose predicted for the middle of its coming
        stance (the twist held), so that the stance stroke is centred on rest.
        """
        horizon = self.remaining(t) + 0.5 * (self.n_groups - 1) * self.step_duration
        return self.rest_feet_in_world(pose.moved(velocity, yaw_rate, horizon))

    def choose_group(
        self,
        shaper: CommandShaper,
        off_rest: npt.NDArray[np.bool_],
        feet_in_body: Callable[[], npt.NDArray[np.float64]],
    ) -> npt.NDArray[np.bool_]:
        """The legs that swing in the next step, shape (6,); none when nothing needs to.

        Args:
            shaper: The body twist.
            off_rest: Which feet are off their rest positions, shape (6,).
            feet_in_body: The foot positions in the body frame (asked only for a tripod's
                first step).
        """
        n = self.n_groups
        groups = self.config.groups
        swing = np.zeros(6, dtype=bool)
        if not shaper.moving:
            for k in range(1, n + 1):
                index = (self.group_index + k) % n
                if off_rest[list(groups[index])].any():
                    self.group_index = index
                    swing[list(groups[index])] = True
                    return swing
            return swing
        if self.start_of_walk and self.config.gait.by_sextant and shaper.walking:
            swing = tripod_swing_set(
                shaper.last_walk_direction, self.rest_in_body, feet_in_body(), self.mounts_in_body
            )
            self.group_index = 0 if swing[0] else 1
            self.start_of_walk = False
            return swing
        if self.start_of_walk and shaper.walking:
            xi = active_sextant(shaper.last_walk_direction, self.rest_in_body)
            self.group_index = next(i for i, g in enumerate(groups) if xi in g)
            self.start_of_walk = False
        else:
            self.group_index = (self.group_index + 1) % n
        swing[list(groups[self.group_index])] = True
        return swing

    def steps_until_swing(self, leg: int) -> int:
        """Steps from now until ``leg`` swings again (1 = the next step)."""
        n, groups = self.n_groups, self.config.groups
        for k in range(1, n + 1):
            if leg in groups[(self.group_index + k) % n]:
                return k
        return n

    def liftoff_horizons(self, t: float) -> npt.NDArray[np.float64]:
        """Time until each leg next lifts off, shape (6,) [s]."""
        remaining = self.remaining(t)
        return np.array(
            [remaining + (self.steps_until_swing(leg) - 1) * self.step_duration for leg in range(6)]
        )

    def support_after(self, swing: npt.NDArray[np.bool_]) -> npt.NDArray[np.bool_]:
        """Legs that support during the step after this one (all but the next group)."""
        if self.config.gait.by_sextant:
            return swing.copy()
        support = np.ones(6, dtype=bool)
        support[list(self.config.groups[(self.group_index + 1) % self.n_groups])] = False
        return support
