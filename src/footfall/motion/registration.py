"""How far the map may have slid under the feet: the controller's pose corrections.

The controller's world is re-registered on every pose estimate (:meth:`WalkController.
correct_pose`); between estimates it moves as odometry says. A cell the camera mapped a few
seconds ago sits where the estimate of that time put it. When the estimate drifts, the
corrections since then move the feet's world against the map by about their sum: a
drifting SLAM estimate that the controller follows shows here as a steady run of
corrections the same way, where jitter and odometry's small bias cancel or stay small. The
largest such sum over the time a cell stays in use bounds how far the map may lie off.
"""

from __future__ import annotations

import math
from collections import deque


class RegistrationDrift:
    """The largest net pose correction over a recent time window.

    Args:
        horizon_s: The window: how long a mapped cell stays in use [s].
    """

    def __init__(self, horizon_s: float) -> None:
        self.horizon_s = horizon_s
        self._total = (0.0, 0.0)  # sum of the corrections so far [m]
        self._history: deque[tuple[float, float, float]] = deque()  # (t, total x, total y)
        self._started = False
        self.largest_m = 0.0  # the largest error so far [m]

    def add(self, t: float, dx: float, dy: float) -> None:
        """A correction of the body's position by ``(dx, dy)`` [m] at time ``t`` [s].

        The first correction registers the controller's world on the estimate's and moves
        nothing against the map (the map is the estimate's from its first frame); a
        non-finite one is ignored.
        """
        if not self._started:
            self._started = True
            self._history.append((t, *self._total))
            return
        if not (math.isfinite(dx) and math.isfinite(dy)):
            return
        x, y = self._total[0] + dx, self._total[1] + dy
        self._total = (x, y)
        self._history.append((t, x, y))
        while len(self._history) > 1 and self._history[1][0] <= t - self.horizon_s:
            self._history.popleft()
        self.largest_m = max(self.largest_m, self.error_m)

    @property
    def error_m(self) -> float:
        """The largest distance the corrections moved the body's world within the window [m]."""
        x, y = self._total
        return max((math.hypot(x - hx, y - hy) for _, hx, hy in self._history), default=0.0)
