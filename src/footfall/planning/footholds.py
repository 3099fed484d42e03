"""Foothold search (thesis §6.3): the nearest valid, reachable, stable cell to a nominal one.

The thesis grows square rings around the nominal cell and notes that this is inexact for
large radii. Here the candidate offsets are precomputed once and sorted by true distance,
so the first acceptable candidate is the nearest; candidates at the same distance are
tried best score first.

A candidate is acceptable when its cell is valid in the score map (known, kernel window
known, score below threshold), the leg can reach it at the planned body pose, and the
centre of mass stays inside the support polygon with a margin (§6.2.3). The foot height
is the mapped height of the chosen cell (§6.4).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np
import numpy.typing as npt

from footfall.checks import require_non_negative
from footfall.errors import ConfigError
from footfall.planning.plan_kernels import polygon_margin
from footfall.planning.regions import Regions, steppable_regions
from footfall.robot.scale import RobotScale
from footfall.scoring.walkability import ScoreMap

# The widest search, in cells of the map searched.
MAX_SEARCH_CELLS = 500
# The centre of mass keeps this far inside the support polygon on the default robot [m].
STABILITY_MARGIN_M = 0.02


@dataclass(frozen=True)
class FootholdConfig:
    """Search settings.

    Attributes:
        search_radius: Farthest a foothold may move from its nominal position [m].
        stability_margin: Least distance from the centre of mass to the edge of the support
            polygon [m]; None takes 2 cm on the default robot, scaled to the robot's span
            (:meth:`for_robot`).
        edge_margin_cells: A candidate should also have every cell within this many cells
            valid: room for the foot's radius, tracking error and a map edge that is a cell
            off (a riser seen face-on lends its height to the cell before it).
        min_edge_margin_cells: Where no candidate within the radius has the full margin
            (stones smaller than the margin leaves room on), the margin shrinks one cell at
            a time down to this.
        region_hysteresis: A re-planned foothold leaves the region of the one planned
            before only for a cell at least this much nearer its nominal position [m]: an
            edge that came a cell nearer does not flip the foot across it. Off (0) by
            default: a foot held in its region follows the map, and where the controller's
            world has come off the robot (a body that slid on its feet, which odometry does
            not see) it was held on the rim of a small region it had planned to stand in
            the middle of.
    """

    search_radius: float = 0.16
    stability_margin: float | None = None
    edge_margin_cells: int = 2
    min_edge_margin_cells: int = 0
    region_hysteresis: float = 0.0

    def __post_init__(self) -> None:
        require_non_negative(
            "foothold",
            search_radius=self.search_radius,
            region_hysteresis=self.region_hysteresis,
        )
        if self.stability_margin is not None:
            require_non_negative("foothold", stability_margin=self.stability_margin)
        if not 0 <= self.min_edge_margin_cells <= self.edge_margin_cells:
            raise ConfigError("edge margins need 0 <= min_edge_margin_cells <= edge_margin_cells")

    def for_robot(self, scale: RobotScale) -> FootholdConfig:
        """This config with the robot's stability margin filled in where unset."""
        if self.stability_margin is not None:
            return self
        return replace(self, stability_margin=STABILITY_MARGIN_M * scale.span)


def sorted_offsets(radius_cells: float) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.float64]]:
    """Cell offsets within a radius, nearest first.

    Returns:
        Offsets, shape (k, 2), and their distances [cells], shape (k,), ascending.
    """
    r = int(np.floor(radius_cells))
    di, dj = np.meshgrid(np.arange(-r, r + 1), np.arange(-r, r + 1), indexing="ij")
    offsets = np.stack([di.ravel(), dj.ravel()], axis=1)
    distance = np.hypot(offsets[:, 0], offsets[:, 1])
    keep = distance <= radius_cells + 1e-9
    order = np.argsort(distance[keep], kind="stable")
    return offsets[keep][order], distance[keep][order]


def point_in_polygon_margin(point: npt.ArrayLike, polygon: npt.ArrayLike) -> float:
    """Signed distance from a point to the edges of a convex polygon [m].

    Positive inside (the distance to the nearest edge), negative outside. The polygon's
    vertices may come in any order; their convex hull is used (compiled:
    :func:`footfall.planning.plan_kernels.polygon_margin`).

    Args:
        point: Shape (2,).
        polygon: Vertices, shape (k, 2), k >= 3.
    """
    x, y = (float(v) for v in np.asarray(point, dtype=np.float64))
    return float(polygon_margin(x, y, np.ascontiguousarray(polygon, dtype=np.float64)))


def registration_margin_cells(error_m: float, resolution: float) -> int:
    """The edge margin [cells] that keeps a foot off invalid cells the map may have moved.

    A candidate with a margin of ``m`` cells has its centre at least ``(m + 0.5)`` cells
    from any invalid cell; a map that lies up to ``error_m`` off where the controller's
    world puts it needs ``(m + 0.5) * resolution >= error_m``.
    """
    if not (math.isfinite(error_m) and error_m > 0.5 * resolution):
        return 0
    # A billionth of a cell of slack: an error that is an exact multiple of half cells
    # divides a hair above it (0.07 / 0.02 = 3.5000000000000004) and would cost a cell.
    return min(math.ceil(error_m / resolution - 0.5 - 1e-9), MAX_SEARCH_CELLS)


# Candidates tested at once, nearest first; the last size repeats to the end.
_CHUNKS = (1, 8, 32, *([128] * 64))


@dataclass(frozen=True)
class Foothold:
    """A chosen foothold.

    Attributes:
        position: World position of the foot's ground point: cell centre and mapped height,
            shape (3,) [m].
        cell: Index ``[i, j]`` in the score map.
        moved: Distance from the nominal position [m].
        score: The cell's score.
        region: The steppable region the cell lies in (its label in the score map's
            :class:`~footfall.planning.regions.Regions`).
    """

    position: npt.NDArray[np.float64]
    cell: tuple[int, int]
    moved: float
    score: float
    region: int = 0


class FootholdSearch:
    """Nearest-acceptable-cell search on a score map.

    Args:
        config: Radius and stability margin.
        resolution: Cell side of the maps it will search [m].
    """

    def __init__(self, config: FootholdConfig, resolution: float) -> None:
        radius_cells = config.search_radius / resolution if resolution > 0 else math.inf
        if not (math.isfinite(radius_cells) and radius_cells <= MAX_SEARCH_CELLS):
            raise ConfigError(
                f"a search radius of {config.search_radius} m on {resolution} m cells is "
                f"beyond {MAX_SEARCH_CELLS} cells"
            )
        self.config = config
        self.resolution = resolution
        self.offsets, self.distances = sorted_offsets(config.search_radius / resolution)
        self.radius_cells = float(self.distances[-1])
        self._cache_key: ScoreMap | None = None
        self._cache: Regions | None = None

    def search(
        self,
        nominal_xy: npt.ArrayLike,
        scores: ScoreMap,
        heights: npt.NDArray[np.float64],
        accept: Callable[[npt.NDArray[np.float64]], bool] | None = None,
        first_accepted: Callable[[npt.NDArray[np.float64]], int] | None = None,
        min_margin_cells: int = 0,
        keep_region_at: npt.ArrayLike | None = None,
    ) -> Foothold | None:
        """The nearest acceptable cell to a nominal foot position, well inside its region.

        Cells with the full edge margin are searched first, or, in a steppable region too
        small for it, the region's core (its deepest cells: a small stone's middle, not its
        rim) where that is at least a cell deep (a strip or a speck of valid cells is no
        place to aim for); the narrower margins only when none of those passes, down to
        the configured least margin or ``min_margin_cells``, whichever is wider (a map that
        may lie off where the feet think it is). With ``keep_region_at`` (the foothold
        planned before), candidates in that point's region count as ``region_hysteresis``
        nearer at each margin: a re-plan keeps the region while it has an acceptable cell
        as far inside as any other region offers and not that much farther away, rather
        than flipping to another side of an edge that happens to be a cell nearer.

        Args:
            nominal_xy: Nominal foot position in the world, shape (2,) [m].
            scores: Score map (validity per cell).
            heights: Mapped heights aligned with ``scores``, NaN where unknown [m].
            accept: Extra test of a candidate ground point (x, y, z): reachability,
                stability. All candidates pass when None.
            first_accepted: The same test for many candidates at once, for speed: given
                ground points in search order, shape (m, 3), the index of the first that
                passes, or -1. Used instead of ``accept`` when given.
            min_margin_cells: The least edge margin this search accepts [cells].
            keep_region_at: World point (x, y) whose region to prefer [m]; None for none.

        Returns:
            The foothold, or None when no cell within the radius passes.
        """
        nominal = np.asarray(nominal_xy, dtype=np.float64)
        if nominal.shape != (2,) or not np.all(np.abs(nominal) < 1e9):
            raise ConfigError(f"a nominal foothold must be two finite coordinates, got {nominal}")
        res = scores.resolution
        origin = np.asarray(scores.origin)
        centre = np.floor((nominal - origin) / res).astype(np.int64)
        cells = centre + self.offsets
        n_i, n_j = scores.valid.shape
        inside = (cells[:, 0] >= 0) & (cells[:, 0] < n_i) & (cells[:, 1] >= 0) & (cells[:, 1] < n_j)
        cells, distances = cells[inside], self.distances[inside]
        tried = np.zeros(len(cells), dtype=bool)
        if first_accepted is None:

            def first_accepted(points: npt.NDArray[np.float64]) -> int:
                if accept is None:
                    return 0 if len(points) else -1
                return next((k for k, p in enumerate(points) if accept(p)), -1)

        least = max(self.config.min_edge_margin_cells, int(min_margin_cells))
        regions = self.regions(scores)
        depth = regions.depth[cells[:, 0], cells[:, 1]]
        label = regions.labels[cells[:, 0], cells[:, 1]]
        core = regions.core_by_label[label]
        kept = self.region_at(keep_region_at, scores) if keep_region_at is not None else 0
        # Distances with the kept region's hysteresis taken off [cells].
        ranked = distances - (self.config.region_hysteresis / res) * (kept and label == kept)
        for margin in range(max(self.config.edge_margin_cells, least), least - 1, -1):
            ok = (depth >= np.maximum(np.minimum(margin, np.maximum(core, 1)), least)) & ~tried
            tried |= ok
            candidates = cells[ok]
            cell_scores = scores.score[candidates[:, 0], candidates[:, 1]]
            # Distance (the kept region's less its hysteresis), then score.
            order = np.lexsort((cell_scores, np.round(ranked[ok], 9)))
            ordered = candidates[order]
            # The nominal cell keeps the nominal position (no adjustment); others their centre.
            xy = origin + (ordered + 0.5) * res
            xy[(ordered[:, 0] == centre[0]) & (ordered[:, 1] == centre[1])] = nominal
            points = np.column_stack([xy, heights[ordered[:, 0], ordered[:, 1]]])
            start = 0
            for size in _CHUNKS:  # the nearest few first: most searches end there
                if start >= len(points):
                    break
                k = first_accepted(points[start : start + size])
                if k >= 0:
                    k += start
                    i, j = (int(v) for v in ordered[k])
                    moved = float(np.hypot(*(xy[k] - nominal)))
                    score = float(cell_scores[order[k]])
                    return Foothold(points[k], (i, j), moved, score, int(regions.labels[i, j]))
                start += size
        return None

    def regions(self, scores: ScoreMap) -> Regions:
        """The score map's steppable regions, depths up to the full margin; cached per map."""
        if self._cache_key is not scores or self._cache is None:
            self._cache_key = scores
            self._cache = steppable_regions(scores.valid, self.config.edge_margin_cells)
        return self._cache

    def level(self, regions: Regions, cell: tuple[int, int], least: int = 0) -> int:
        """The widest margin at which :meth:`search` takes a cell; -1 where it never does.

        A cell at its region's core (at least a cell deep) or at the full margin counts as
        the full margin; a shallower one as its depth; one shallower than ``least``, never.
        """
        depth = int(regions.depth[cell])
        if depth < max(least, 0):
            return -1
        core = int(regions.core_by_label[regions.labels[cell]])
        return max(self.config.edge_margin_cells, least) if depth >= max(core, 1) else depth

    def needless_jump(
        self,
        origin_xy: npt.ArrayLike,
        kept_xy: npt.ArrayLike,
        foothold: Foothold,
        scores: ScoreMap,
        heights: npt.NDArray[np.float64],
        least_margin: int,
        first_accepted: Callable[[npt.NDArray[np.float64]], int],
    ) -> bool:
        """Whether a foothold left the region of the one planned before needlessly.

        Needlessly: the one before (at ``kept_xy``) still served, valid and passing
        ``first_accepted``, and the new one lies no farther inside its region than the
        search asks (:meth:`level`) nor nearer the search's origin ``origin_xy`` (the
        nominal foothold) by ``region_hysteresis`` or a cell, whichever is more: a flip
        across an edge that came a cell nearer. One beyond the search radius of the origin
        no longer served.
        """
        cell = self.cell_at(kept_xy, scores)
        centre = self.cell_at(origin_xy, scores)
        if cell is None or centre is None:
            return False
        regions = self.regions(scores)
        had = int(regions.labels[cell])
        if not had or had == foothold.region:
            return False
        before = self.level(regions, cell, least_margin)
        if before < 0 or self.level(regions, foothold.cell, least_margin) > before:
            return False
        if math.dist(cell, centre) > self.radius_cells:
            return False
        gained = math.dist(cell, centre) - math.dist(foothold.cell, centre)
        if gained * scores.resolution >= max(self.config.region_hysteresis, scores.resolution):
            return False
        x, y = np.asarray(kept_xy, dtype=np.float64)[:2]
        return first_accepted(np.array([[x, y, heights[cell]]])) == 0

    def cell_at(self, xy: npt.ArrayLike, scores: ScoreMap) -> tuple[int, int] | None:
        """The score map's cell under a world point (x, y) [m]; None off the map."""
        cell = np.floor((np.asarray(xy, dtype=np.float64)[:2] - scores.origin) / scores.resolution)
        if not np.all(np.isfinite(cell)):
            return None
        i, j = (int(v) for v in cell)
        n_i, n_j = scores.valid.shape
        return (i, j) if 0 <= i < n_i and 0 <= j < n_j else None

    def region_at(self, xy: npt.ArrayLike, scores: ScoreMap) -> int:
        """The region a world point (x, y) lies in on the score map; 0 for none [m]."""
        cell = self.cell_at(xy, scores)
        return 0 if cell is None else int(self.regions(scores).labels[cell])
