"""What one step's foothold plan is checked at and what it gives: poses, plan or the reason.

:class:`~footfall.planning.terrain_planner.TerrainPlanner` plans a step's footholds at the
body poses of :class:`StepPoses` and answers with a :class:`FootholdPlan` or, when no
foothold serves, :class:`NoFoothold` with the reason.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from footfall.robot.planar import PlanarPose


@dataclass(frozen=True)
class StepPoses:
    """Planned body poses that one step's footholds are checked at.

    Attributes:
        now: The body now.
        touchdown: The body when the swinging legs touch down.
        liftoff: The body when the swinging legs lift off again.
        stable: Poses at which the body centre must lie inside the support polygon of the
            legs that support after touchdown.
        incline_now: The body's pitch now [rad] (:mod:`footfall.motion.incline`).
        incline_step: Its pitch at touchdown and on to lift-off [rad].
    """

    now: PlanarPose
    touchdown: PlanarPose
    liftoff: PlanarPose
    stable: tuple[PlanarPose, ...]
    incline_now: float = 0.0
    incline_step: float = 0.0


@dataclass(frozen=True)
class NoFoothold:
    """Why a step has no footholds.

    Attributes:
        reason: What failed, naming the leg where one leg failed.
        leg: That leg's name, or "" when the reason concerns no single leg.
    """

    reason: str
    leg: str = ""

    def __str__(self) -> str:
        return self.reason


@dataclass(frozen=True)
class FootholdPlan:
    """Footholds for the swinging legs of one step.

    Attributes:
        targets: Foot-centre targets in the world, shape (6, 3) [m]; rows of legs that do
            not swing are their current positions.
        nominal: The nominal targets the search started from, shape (6, 3) [m].
        adjusted: Which swinging legs were moved off their nominal cell, shape (6,).
        body_z: The body heights in the world, ascending, at which every leg reaches its
            foot: supporting feet now and at touchdown, the chosen footholds from the body
            now (it may stop at any time), at touchdown and at lift-off [m].
    """

    targets: npt.NDArray[np.float64]
    nominal: npt.NDArray[np.float64]
    adjusted: npt.NDArray[np.bool_]
    body_z: npt.NDArray[np.float64]
