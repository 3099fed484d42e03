"""Swing-foot trajectories: what a swing path is, and the registry of the kinds there are.

A swing path (:class:`SwingTrajectory`) runs in the world frame from lift-off to
touchdown, sampled by time since lift-off, and its target may be moved at any tick. The
kinds: the flow function of thesis §5.4.2 (:mod:`footfall.motion.flow_swing`), the
default, and the sixth-order polynomial arc of §5.4.1 (:mod:`footfall.motion.swing_polynomial`),
the baseline. ``GaitConfig.swing`` names one of :data:`SWINGS`; a new kind is one module
with a class that has ``plan(SwingPlan)``, and one line that registers it.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

import numpy as np
import numpy.typing as npt

from footfall.errors import ConfigError
from footfall.registry import Registry

if TYPE_CHECKING:
    from footfall.motion.gait import GaitConfig


def minimum_jerk(tau: float) -> float:
    """Minimum-jerk progress ``s`` in [0, 1] at normalised time ``tau`` in [0, 1].

    Velocity and acceleration are zero at both ends.
    """
    t = min(max(tau, 0.0), 1.0)
    return t * t * t * (10.0 + t * (-15.0 + 6.0 * t))


# A swing re-targeted in its last RETARGET_MIN_S gets that long, plus its remaining way
# at RETARGET_SPEED_MPS, before it lands, when the way is longer than RETARGET_WAIT_M: the
# step waits for it rather than dragging a foot over the ground to a target it could not
# reach in the air; a shorter way is carried in the time left [s], [m/s], [m].
RETARGET_MIN_S = 0.15
RETARGET_SPEED_MPS = 0.6
RETARGET_WAIT_M = 0.03


def time_to_land(ways_m: list[float], time_left_s: float) -> float | None:
    """How long a step must still last for late re-targeted feet to land [s].

    Args:
        ways_m: How far each re-targeted foot is from its new target [m].
        time_left_s: The time the step has left [s].

    Returns:
        The time from now, or None when the time left will do.
    """
    if time_left_s >= RETARGET_MIN_S:
        return None
    wait = max(
        (RETARGET_MIN_S + d / RETARGET_SPEED_MPS for d in ways_m if d > RETARGET_WAIT_M),
        default=0.0,
    )
    return wait if wait > time_left_s else None


class SwingTrajectory(Protocol):
    """A swing path in the world frame, re-targetable at any time."""

    duration: float

    @property
    def target(self) -> npt.NDArray[np.float64]:
        """Current touchdown target, shape (3,) [m]."""
        ...

    def position(self, t: float) -> npt.NDArray[np.float64]:
        """Foot position at ``t`` seconds after lift-off, shape (3,) [m]."""
        ...

    def retarget(self, target: npt.ArrayLike, t: float, duration: float | None = None) -> None:
        """Move the touchdown target at time ``t`` [s]; the path stays continuous.

        With ``duration`` the swing also ends at that time after lift-off [s] (a late
        re-target that needs longer than the swing has left).
        """
        ...

    @property
    def start(self) -> npt.NDArray[np.float64]:
        """Lift-off position, shape (3,) [m]."""
        ...

    def transform(
        self, rotation: npt.NDArray[np.float64], translation: npt.NDArray[np.float64]
    ) -> None:
        """Move the whole swing by a planar rigid transform (2x2 rotation, 2-vector) [m]."""
        ...


# A function giving the terrain height under horizontal points, shape (n, 2) -> (n,) [m].
TerrainFunction = Callable[[npt.NDArray[np.float64]], npt.NDArray[np.float64]]


@dataclass(frozen=True)
class SwingPlan:
    """What a swing is planned from.

    Attributes:
        start: Lift-off position in the world frame, shape (3,) [m].
        target: Touchdown target in the world frame, shape (3,) [m].
        duration: Swing duration [s].
        gait: The gait's settings (the flow parameters, the polynomial's apex).
        terrain: Height of the mapped terrain under horizontal points, or None (blind).
        clearance: Least height of the foot centre above that terrain [m].
    """

    start: npt.NDArray[np.float64]
    target: npt.NDArray[np.float64]
    duration: float
    gait: GaitConfig
    terrain: TerrainFunction | None = None
    clearance: float = 0.0


class SwingFactory(Protocol):
    """A registered kind of swing: a class (or any object) with ``plan``."""

    def plan(self, plan: SwingPlan) -> SwingTrajectory:
        """The swing path for ``plan``."""
        ...


class PolylineSwing:
    """Shared time-scaling of a swing along a polyline that is replaced on re-targeting.

    Progress along the path follows a minimum-jerk profile over the swing. When the path is
    replaced at time ``t``, the remaining progress ``1 - s(t)`` is mapped onto the new path,
    so the foot neither jumps nor stops.
    """

    def __init__(self, duration: float) -> None:
        if not duration > 0:
            raise ConfigError(f"swing duration must be positive, got {duration}")
        self.duration = duration
        self._path = np.zeros((1, 3))
        self._arclength = np.zeros(1)
        self._s_at_path_start = 0.0
        self._start = np.zeros(3)

    @property
    def start(self) -> npt.NDArray[np.float64]:
        """Lift-off position, shape (3,) [m]."""
        return self._start.copy()

    def transform(
        self, rotation: npt.NDArray[np.float64], translation: npt.NDArray[np.float64]
    ) -> None:
        """Move the whole swing by a planar rigid transform."""
        self._path[:, :2] = self._path[:, :2] @ np.asarray(rotation).T + translation
        self._start[:2] = np.asarray(rotation) @ self._start[:2] + translation

    def _set_path(self, path: npt.NDArray[np.float64], t: float) -> None:
        seg = np.linalg.norm(np.diff(path, axis=0), axis=1)
        self._path = path
        self._arclength = np.concatenate([[0.0], np.cumsum(seg)])
        self._s_at_path_start = minimum_jerk(t / self.duration)

    @property
    def target(self) -> npt.NDArray[np.float64]:
        """Current touchdown target, shape (3,) [m]."""
        return self._path[-1].copy()

    def position(self, t: float) -> npt.NDArray[np.float64]:
        """Foot position at ``t`` seconds after lift-off, shape (3,) [m]."""
        s = minimum_jerk(t / self.duration)
        s0 = self._s_at_path_start
        fraction = 1.0 if s0 >= 1.0 else (s - s0) / (1.0 - s0)
        length = self._arclength[-1]
        if length <= 0.0:
            return self._path[-1].copy()
        along = min(max(fraction, 0.0), 1.0) * length
        return np.array([np.interp(along, self._arclength, self._path[:, k]) for k in range(3)])


SWINGS: Registry[SwingFactory] = Registry("swing trajectory")

SWINGS.register("flow", "footfall.motion.flow_swing:FlowSwing")
SWINGS.register("polynomial", "footfall.motion.swing_polynomial:PolynomialArcSwing")
