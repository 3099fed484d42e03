"""The terrain's truth, for judging a walk.

Which cells a foot may really use, and a walk's touchdowns and swing clearances against it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from footfall.control_loop import WalkLog
from footfall.scoring.walkability import ScoreConfig, edge_cells, score_heights
from footfall.sim.terrain import Terrain


class TrueScores:
    """The ground-truth terrain scored on a grid: which cells a foot may really use.

    Each cell takes the highest point of the true terrain inside it, and a cell whose
    points span more height than the score's ``max_cell_spread`` beyond what its slope
    explains is invalid: the rules the mapper and the scorer apply to the points that fall
    in a cell, so this is the score map a perfect camera would give. The terrain is sampled
    at ``SAMPLES`` fractions of each cell along each axis, its near side included and its
    far side a hair inside (a cell holds ``[x0, x0 + res)``, as the mapper bins points):
    an edge that crosses a cell a millimetre from its side puts a sliver of the higher
    level in that cell, which a camera's points show and samples inside the cell alone
    would miss. (Sampling the cell centre only would leave a cell whose centre lies on an
    edge, as 6 cm grooves between 16 cm stones put every edge, to floating-point rounding.)
    """

    SAMPLES = (0.0, 0.25, 0.5, 0.75, 1.0 - 1e-4)

    def __init__(
        self, terrain: Terrain, resolution: float, score: ScoreConfig, extent: tuple[float, ...]
    ) -> None:
        x0, x1, y0, y1 = extent
        self.origin = (x0, y0)
        self.resolution = resolution
        k = len(self.SAMPLES)
        inner = np.asarray(self.SAMPLES) * resolution
        xs = x0 + np.arange(round((x1 - x0) / resolution))[:, None] * resolution + inner
        ys = y0 + np.arange(round((y1 - y0) / resolution))[:, None] * resolution + inner
        heights = terrain.height(xs.ravel()[:, None], ys.ravel()[None, :])
        cells = heights.reshape(len(xs), k, len(ys), k)
        top = cells.max(axis=(1, 3))
        self.slope, _, self.score, self.valid = score_heights(top, resolution, score)
        spread = top - cells.min(axis=(1, 3))
        self.valid &= ~edge_cells(spread, self.slope, resolution, score)

    def valid_at(self, xy: npt.ArrayLike) -> bool:
        """Whether the true terrain is walkable at a world point (off the grid: flat, valid)."""
        i, j = (int(v) for v in np.floor((np.asarray(xy) - self.origin) / self.resolution))
        if 0 <= i < self.valid.shape[0] and 0 <= j < self.valid.shape[1]:
            return bool(self.valid[i, j])
        return True


def touchdown_feet(log: WalkLog, min_step: float = 0.02) -> list[tuple[int, int]]:
    """(tick, leg) of every touchdown in the log that moved the foot at least ``min_step``.

    A foot put back where it lifted off is not a new foothold.
    """
    swinging = log.array("swinging").astype(np.int8)
    feet = log.array("feet_commanded_in_world")
    out = []
    for leg in range(swinging.shape[1]):
        lifts = np.flatnonzero(np.diff(swinging[:, leg]) == 1) + 1
        for k in np.flatnonzero(np.diff(swinging[:, leg]) == -1) + 1:
            earlier = lifts[lifts < k]
            if (
                earlier.size
                and np.hypot(*(feet[k, leg, :2] - feet[earlier[-1] - 1, leg, :2])) >= min_step
            ):
                out.append((int(k), leg))
    return sorted(out)


@dataclass(frozen=True)
class FootholdMetrics:
    """The footholds of a walk against the terrain's truth.

    Attributes:
        touchdowns: Touchdowns that moved the foot at least 2 cm.
        invalid_footholds: Touchdowns on cells the true terrain scores invalid; None when
            the robot cannot say where its feet are (no truth can judge it).
        min_clearance_m: Least height of a swinging foot's underside above the true
            terrain [m] (NaN without a swing); None when the feet are not known.
    """

    touchdowns: int
    invalid_footholds: int | None
    min_clearance_m: float | None

    @classmethod
    def unjudged(cls, log: WalkLog) -> FootholdMetrics:
        """The touchdowns of a robot that does not know where its feet are."""
        return cls(len(touchdown_feet(log)), None, None)


def foothold_metrics(
    log: WalkLog, terrain: Terrain, truth: TrueScores, foot_radius: float
) -> FootholdMetrics:
    """Invalid touchdowns (on cells the true terrain scores invalid) and swing clearance."""
    feet = log.array("feet_in_world")
    invalid = 0
    settle = 3  # ticks after touchdown, once the foot rests
    for tick, leg in touchdown_feet(log):
        k = min(tick + settle, len(feet) - 1)
        invalid += not truth.valid_at(feet[k, leg, :2])
    swinging = log.array("swinging")
    clearance = np.inf
    r = foot_radius
    for leg in range(6):
        s = swinging[:, leg].astype(np.int8)
        starts = np.flatnonzero(np.diff(s) == 1) + 1
        ends = np.flatnonzero(np.diff(s) == -1) + 1
        for a in starts:
            later = ends[ends > a]
            if not later.size:
                continue
            path = feet[a : later[0], leg]
            away = (np.linalg.norm(path[:, :2] - path[0, :2], axis=1) > 0.03) & (
                np.linalg.norm(
                    path[:, :2] - feet[min(later[0] + settle, len(feet) - 1), leg, :2], axis=1
                )
                > 0.03
            )
            if not away.any():
                continue
            p = path[away]
            under = np.max(
                [
                    terrain.height(p[:, 0] + dx, p[:, 1] + dy)
                    for dx, dy in ((0, 0), (r, 0), (-r, 0), (0, r), (0, -r))
                ],
                axis=0,
            )
            clearance = min(clearance, float(np.min(p[:, 2] - r - under)))
    return FootholdMetrics(
        touchdowns=len(touchdown_feet(log)),
        invalid_footholds=invalid,
        min_clearance_m=clearance if np.isfinite(clearance) else float("nan"),
    )


def judge_footholds(
    log: WalkLog,
    terrain: Terrain,
    resolution: float,
    score: ScoreConfig,
    foot_radius: float,
    goal: npt.NDArray[np.float64],
) -> FootholdMetrics:
    """A walk's footholds against the terrain's truth.

    The truth is scored at the map's ``resolution`` [m] on the map's grid, over where the
    feet went and the ``goal``. Unjudged when the robot does not know where its feet are.
    """
    feet = log.array("feet_in_world")[..., :2].reshape(-1, 2)
    if not np.isfinite(feet).all():
        return FootholdMetrics.unjudged(log)
    low = np.minimum(feet.min(axis=0), goal) - 0.5
    high = np.maximum(feet.max(axis=0), goal) + 0.5
    # On the map's grid: global cells [k res, (k + 1) res), as the mapper bins points.
    low = np.floor(np.minimum(low, (-1.0, -1.5)) / resolution) * resolution
    high = np.ceil(np.maximum(high, (float(goal[0]) + 1.0, 1.5)) / resolution) * resolution
    extent = (float(low[0]), float(high[0]), float(low[1]), float(high[1]))
    truth = TrueScores(terrain, resolution, score, extent)
    return foothold_metrics(log, terrain, truth, foot_radius)
