"""The thesis' baseline swing: a sixth-order polynomial arc per axis (§5.4.1)."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from footfall.errors import ConfigError
from footfall.motion.swing import SwingPlan


def polynomial_arc_coefficients(
    q_start: npt.ArrayLike, q_mid: npt.ArrayLike, q_end: npt.ArrayLike, t_end: float
) -> npt.NDArray[np.float64]:
    """Coefficients ``a0..a6`` of the sixth-order arc through three points (thesis eq. 5.22).

    The arc starts at rest (``a1 = a2 = 0``), passes ``q_mid`` at ``t_end / 2`` and ends at
    ``q_end`` at ``t_end``.

    Returns:
        Shape (7, 3): one column per coordinate.
    """
    qi = np.asarray(q_start, dtype=np.float64)
    dm = np.asarray(q_mid, dtype=np.float64) - qi
    df = np.asarray(q_end, dtype=np.float64) - qi
    tf = float(t_end)
    return np.stack(
        [
            qi,
            np.zeros_like(qi),
            np.zeros_like(qi),
            2.0 / tf**3 * (32.0 * dm - 11.0 * df),
            -3.0 / tf**4 * (64.0 * dm - 27.0 * df),
            3.0 / tf**5 * (64.0 * dm - 30.0 * df),
            -32.0 / tf**6 * (2.0 * dm - df),
        ]
    )


class PolynomialArcSwing:
    """The thesis' baseline swing: one sixth-order polynomial per axis (eqs. 5.21-5.22).

    The mid point lies half way between start and target, ``apex_height`` above the higher
    of the two. Re-targeting recomputes the arc from the current point as if it were a new
    lift-off, which makes the foot rise again (the defect of Fig. 5.12); it is kept as the
    baseline the flow function is compared with.

    Args:
        start: Lift-off position in the world frame, shape (3,) [m].
        target: Touchdown target, shape (3,) [m].
        duration: Swing duration [s].
        apex_height: Height of the mid point above the higher end [m].
    """

    def __init__(
        self, start: npt.ArrayLike, target: npt.ArrayLike, duration: float, apex_height: float
    ) -> None:
        if not duration > 0:
            raise ConfigError(f"swing duration must be positive, got {duration}")
        self.duration = duration
        self.apex_height = apex_height
        self._t0 = 0.0
        self._start = np.asarray(start, dtype=np.float64).copy()
        self._fit(self._start, np.asarray(target, dtype=np.float64), 0.0)

    @classmethod
    def plan(cls, plan: SwingPlan) -> PolynomialArcSwing:
        """The arc of ``plan``, its apex the gait's ``polynomial_apex``."""
        return cls(plan.start, plan.target, plan.duration, plan.gait.polynomial_apex)

    @property
    def start(self) -> npt.NDArray[np.float64]:
        """Lift-off position, shape (3,) [m]."""
        return self._start.copy()

    def transform(
        self, rotation: npt.NDArray[np.float64], translation: npt.NDArray[np.float64]
    ) -> None:
        """Move the whole swing by a planar rigid transform."""
        r = np.asarray(rotation)
        self._coefficients[:, :2] = self._coefficients[:, :2] @ r.T
        self._coefficients[0, :2] += translation
        self._target[:2] = r @ self._target[:2] + translation
        self._start[:2] = r @ self._start[:2] + translation

    def _fit(
        self, start: npt.NDArray[np.float64], target: npt.NDArray[np.float64], t0: float
    ) -> None:
        mid = 0.5 * (start + target)
        mid[2] = max(start[2], target[2]) + self.apex_height
        self._t0 = t0
        self._target = target.copy()
        self._coefficients = polynomial_arc_coefficients(start, mid, target, self.duration - t0)

    @property
    def target(self) -> npt.NDArray[np.float64]:
        """Current touchdown target, shape (3,) [m]."""
        return self._target.copy()

    def position(self, t: float) -> npt.NDArray[np.float64]:
        """Foot position at ``t`` seconds after lift-off, shape (3,) [m]."""
        tau = min(max(t, self._t0), self.duration) - self._t0
        powers = tau ** np.arange(7)
        return powers @ self._coefficients

    def retarget(self, target: npt.ArrayLike, t: float, duration: float | None = None) -> None:
        """Refit the arc from the position at ``t`` to the new target."""
        here = self.position(t)
        if duration is not None:
            self.duration = duration
        if t >= self.duration:
            self._fit(
                np.asarray(target, dtype=np.float64), np.asarray(target, dtype=np.float64), 0.0
            )
            return
        self._fit(here, np.asarray(target, dtype=np.float64), t)
