"""The feet of one step in the air: their swing paths, re-targeted as the footholds move."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from footfall.motion.gait import GaitConfig
from footfall.motion.swing import SWINGS, SwingPlan, SwingTrajectory, TerrainFunction, time_to_land

# Time step of the finite difference that gives the swing foot's velocity [s].
VELOCITY_PROBE_DT = 1e-3


class SwingFeet:
    """The swinging legs of the step under way and their paths in the world frame.

    Attributes:
        swings: Each swinging leg's path, by leg index.
        swinging: Which legs swing, shape (6,).
    """

    def __init__(self) -> None:
        self.swings: dict[int, SwingTrajectory] = {}
        self.swinging = np.zeros(6, dtype=bool)

    def lift(
        self,
        swing: npt.NDArray[np.bool_],
        starts: npt.NDArray[np.float64],
        targets: npt.NDArray[np.float64],
        duration: float,
        config: GaitConfig,
        terrain: TerrainFunction | None,
        clearance: float,
    ) -> None:
        """Start a step: plan the path (of ``config.swing``'s kind) of every swinging leg.

        Args:
            swing: Which legs swing, shape (6,).
            starts: Lift-off points in the world, shape (6, 3) [m].
            targets: Touchdown targets in the world, shape (6, 3) [m].
            duration: Step duration [s].
            config: The gait (swing kind and its parameters).
            terrain: Mapped terrain height under points, or None (blind).
            clearance: Least height of the foot centre above that terrain [m].
        """
        kind = SWINGS.get(config.swing)
        self.swinging = swing
        self.swings = {
            int(leg): kind.plan(
                SwingPlan(starts[leg], targets[leg], duration, config, terrain, clearance)
            )
            for leg in np.flatnonzero(swing)
        }

    def clear(self) -> None:
        """No leg swings (the feet landed, or were re-anchored)."""
        self.swings = {}
        self.swinging[:] = False

    def transform(self, rotation: npt.NDArray[np.float64], translation: npt.NDArray[np.float64]):
        """Move every path by a planar rigid transform (2x2 rotation, 2-vector) [m]."""
        for swing in self.swings.values():
            swing.transform(rotation, translation)

    def follow(
        self,
        targets: npt.NDArray[np.float64],
        local_t: float,
        remaining: float,
        tolerance: float,
    ) -> tuple[dict[int, npt.NDArray[np.float64]], npt.NDArray[np.float64], float | None]:
        """Re-target the paths whose foothold moved, and sample every path at ``local_t``.

        A foot re-targeted late may need longer than the step has left: the whole group
        then lands together, when the farthest foot can (:func:`time_to_land`).

        Args:
            targets: Current footholds, shape (6, 3) [m].
            local_t: Time since lift-off [s].
            remaining: Time the step has left [s].
            tolerance: A target that moved less than this is kept [m].

        Returns:
            Each swinging foot's position [m]; the velocities of all feet (zero for
            stance), shape (6, 3) [m/s]; and the step's new duration, or None if unchanged.
        """
        moved = {
            leg: targets[leg]
            for leg, swing in self.swings.items()
            if np.linalg.norm(targets[leg] - swing.target) > tolerance
        }
        ways = [
            float(np.linalg.norm(goal - self.swings[leg].position(local_t)))
            for leg, goal in moved.items()
        ]
        wait = time_to_land(ways, remaining)
        duration = None if wait is None else local_t + wait
        for leg, swing in self.swings.items():
            if leg in moved or wait is not None:
                swing.retarget(moved.get(leg, swing.target), local_t, duration)
        positions = {}
        velocity = np.zeros((6, 3))
        for leg, swing in self.swings.items():
            positions[leg] = swing.position(local_t)
            ahead = swing.position(local_t + VELOCITY_PROBE_DT)
            velocity[leg] = (ahead - positions[leg]) / VELOCITY_PROBE_DT
        return positions, velocity, duration
