"""Walkability score map (thesis §6.2): slope plus edge proximity; lower is better.

- Slope (eqs. 6.1-6.3): the Sobel operator in physical units, the magnitude of the height
  gradient as rise over run: ``S_g = C_g * |grad h|``, with ``G = sobel / (8 * res)``.
- Edge proximity (eq. 6.4): ``S_p = C_p * |sum(K * (h_ij - h_xy))| / n^2`` over the n x n
  window around the cell, ``K`` a Gaussian with peak 1. A uniform slope cancels (K is
  symmetric); a ledge, a box edge or a hole rim does not, and the rejected band grows
  with the height difference.

A cell is valid when it is known, every cell its kernel reaches is known (and inside
the map), ``S_g + S_p`` is below the threshold and, for a mapped cell, the points that
fell in it within one frame never spanned more than ``max_cell_spread`` in height (a cell
straddling an edge, or a groove narrower than the grid, hides in its maximum but not in
its spread), nor did those of its eight neighbours, and it is not partly in a shadow (a
well-seen cell with a part no point ever hit: a groove narrower than the grid, seen at a
grazing angle, hides behind its near edge, see :func:`shadowed_cells`). The last sliver of
a rim before a shadow (the floor past a trench's near edge, which the camera never sees)
counts as unseen (:func:`shadow_rims`), so the invalid band before the edge stands where
the true edge puts it. Defaults reproduce thesis
Figs. 6.6-6.8 on the course terrain: box tops, the ramp and the floor valid; box edges,
the hole rim, the pillar's and the pedestal's sides invalid. The window (5 cells, 10 cm,
sigma 2 cm) suits the default robot's 2.4 cm feet: the middle of a 9 cm cobblestone is
valid, its grooves and edges are not.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from footfall.checks import require_non_negative, require_positive
from footfall.errors import ConfigError
from footfall.mapping.kernels import SUB
from footfall.mapping.snapshot import MapSnapshot
from footfall.scoring import kernels


@dataclass(frozen=True)
class ScoreConfig:
    """Score parameters.

    Attributes:
        slope_weight: ``C_g``, per unit of rise over run.
        proximity_weight: ``C_p`` [1/m].
        kernel_size: ``n``, side of the proximity window [cells]; odd.
        kernel_sigma: Standard deviation of the Gaussian ``K`` [cells].
        threshold: Cells scoring at or above this are invalid.
        max_cell_spread: A cell whose points have spanned more height than this within one
            frame, beyond what its slope explains, straddles an edge or a groove too narrow
            for the grid, and is invalid [m]. A 1 cm groove seen from the camera's height
            and distance shows only about 5 mm of its depth.
        noise_sigmas: A noisy map's slope and proximity count only beyond this many
            standard deviations of what its cells' height noise alone gives them (an exact
            map, the simulator's, has none).
        shadow_points: A cell that has caught at least this many points with a part of it
            (one of its 4 x 4) never hit lies partly in a shadow, and is invalid: a groove
            too narrow for the grid, seen at a grazing angle, hides behind its near edge.
            Fewer points than this may miss a part by chance.
        shadow_rim_cells: The sliver of a rim before a shadow (:func:`shadow_rims`) is
            scored unseen only when at least this many cells beyond it are unknown. Seen
            from above at 45 degrees or lower, a drop casts a shadow at least as long as it
            is deep; a shorter shadow hides a shallow drop (a groove between cobblestones),
            whose one-cell edge band the scorer already keeps, or a gap narrower than it.
    """

    slope_weight: float = 1.0
    proximity_weight: float = 300.0
    kernel_size: int = 5
    kernel_sigma: float = 1.0
    threshold: float = 0.5
    max_cell_spread: float = 0.002
    noise_sigmas: float = 2.5
    shadow_points: int = 48
    shadow_rim_cells: int = 3

    def __post_init__(self) -> None:
        if self.kernel_size < 3 or self.kernel_size % 2 == 0:
            raise ConfigError(f"kernel_size must be odd and >= 3, got {self.kernel_size}")
        require_positive("score", kernel_sigma=self.kernel_sigma, threshold=self.threshold)
        require_non_negative(
            "score", slope_weight=self.slope_weight, proximity_weight=self.proximity_weight
        )
        if self.shadow_points < 1:
            raise ConfigError(f"shadow_points must be >= 1, got {self.shadow_points}")
        if self.shadow_rim_cells < 1:
            raise ConfigError(f"shadow_rim_cells must be >= 1, got {self.shadow_rim_cells}")

    @property
    def kernel_1d(self) -> npt.NDArray[np.float64]:
        """One axis of the separable Gaussian kernel, peak 1, shape (n,)."""
        k = np.arange(self.kernel_size) - self.kernel_size // 2
        return np.exp(-0.5 * (k / self.kernel_sigma) ** 2)


@dataclass(frozen=True)
class ScoreMap:
    """Scores of a map window, index ``[i, j]`` along world ``x`` and ``y``.

    Attributes:
        slope: Height gradient magnitude, rise over run; NaN where unknown.
        proximity: Edge proximity ``|sum(K (h_ij - h_xy))| / n^2`` [m]; NaN where unknown.
        score: ``C_g * slope + C_p * proximity``; NaN where unknown.
        valid: Cells a foot may use.
        origin: World ``(x, y)`` of the corner of cell ``[0, 0]`` [m].
        resolution: Cell side [m].
    """

    slope: npt.NDArray[np.float64]
    proximity: npt.NDArray[np.float64]
    score: npt.NDArray[np.float64]
    valid: npt.NDArray[np.bool_]
    origin: tuple[float, float]
    resolution: float


def score_heights(
    heights: npt.ArrayLike,
    resolution: float,
    config: ScoreConfig | None = None,
    sigma: npt.ArrayLike | None = None,
) -> tuple[
    npt.NDArray[np.float64], npt.NDArray[np.float64], npt.NDArray[np.float64], npt.NDArray[np.bool_]
]:
    """Slope, proximity, total score and validity of a height grid.

    Args:
        heights: Shape (N, M) [m]; NaN marks unknown cells.
        resolution: Cell side [m].
        config: Score parameters.
        sigma: Height noise of each cell, shape (N, M) [m]; None or NaN for none.

    Returns:
        ``(slope, proximity, score, valid)``, each shape (N, M); the score counts the slope
        and proximity beyond what the noise explains (``ScoreConfig.noise_sigmas``).
    """
    c = config or ScoreConfig()
    h = np.asarray(heights, dtype=np.float64)
    if h.ndim != 2:
        raise ConfigError(f"heights to score must be a 2-D grid, got shape {h.shape}")
    if not (math.isfinite(resolution) and resolution > 0):
        raise ConfigError(f"the grid's resolution must be positive, got {resolution}")
    known = np.isfinite(h)
    h0 = np.where(known, h, 0.0)
    slope, proximity, score = (np.empty_like(h0) for _ in range(3))
    valid = np.empty(h0.shape, dtype=bool)
    noise = np.zeros_like(h0) if sigma is None else np.nan_to_num(np.asarray(sigma, float))
    kernels.score_grid(
        h0,
        known,
        noise,
        c.noise_sigmas,
        1.0 / (8.0 * resolution),
        c.kernel_1d,
        c.slope_weight,
        c.proximity_weight,
        c.threshold,
        slope,
        proximity,
        score,
        valid,
    )
    return slope, proximity, score, valid


def _around(values: npt.NDArray, reduce: np.ufunc) -> npt.NDArray:
    """``reduce`` (``np.maximum`` or ``np.minimum``) over each cell's 3 x 3 neighbourhood.

    Separable, edge cells padded with their own values: a few whole-array passes, several
    times faster on a 256 x 256 map than ``scipy.ndimage``'s generic filters.
    """
    p = np.pad(values, 1, mode="edge")
    rows = reduce(reduce(p[:-2], p[1:-1]), p[2:])
    return reduce(reduce(rows[:, :-2], rows[:, 1:-1]), rows[:, 2:])


def edge_cells(
    spread: npt.ArrayLike, slope: npt.ArrayLike, resolution: float, config: ScoreConfig
) -> npt.NDArray[np.bool_]:
    """Cells that straddle an edge: their points span more height than a plane would.

    A plane at the least slope around the cell (a ramp's, not a step's, whose Sobel slope
    is high on the step's cells only) spans ``slope * diagonal`` by itself.

    Args:
        spread: Height range of the points in each cell, NaN where unknown [m].
        slope: Sobel slope (rise over run), NaN where unknown.
        resolution: Cell side [m].
        config: Score parameters (``max_cell_spread``).
    """
    least = _around(np.nan_to_num(np.asarray(slope, dtype=np.float64), nan=0.0), np.minimum)
    planar = least * resolution * math.sqrt(2.0)
    return np.nan_to_num(np.asarray(spread), nan=0.0) > config.max_cell_spread + planar


def shadowed_cells(
    parts: npt.ArrayLike, points: npt.ArrayLike, config: ScoreConfig
) -> npt.NDArray[np.bool_]:
    """Cells partly in a shadow: well seen, yet with a part no point has ever fallen in.

    The shadow may reach on past the cell's side: where half or more of the parts along a
    side were never hit, the neighbour across it (which may hold the rest of the groove in
    a sliver too thin for a part of its own) is shadowed too.

    Args:
        parts: Each cell's bits of hit parts (:class:`~footfall.mapping.height_map.MapSnapshot`).
        points: Points each cell has caught.
        config: Score parameters (``shadow_points``).
    """
    bits = np.ascontiguousarray(parts, dtype=np.uint16)
    out = np.empty(bits.shape, dtype=bool)
    kernels.shadowed_cells(
        bits, np.ascontiguousarray(points, dtype=np.int64), config.shadow_points, SUB, out
    )
    return out


def shadow_rims(
    parts: npt.ArrayLike, points: npt.ArrayLike, known: npt.ArrayLike, config: ScoreConfig
) -> npt.NDArray[np.bool_]:
    """Slivers of a rim at the edge of a shadow: cells to score as unseen.

    A camera looking over the near rim of a trench or a pit never sees the floor just past
    it; the cell the rim ends in catches the rim's last millimetres on one side and nothing
    on the other, and its height is the rim's: the map puts the edge up to a cell late.
    Such a cell is known and well seen on one side (the neighbour there has caught at least
    ``shadow_points``), yet half or more of its parts along the opposite side were never
    hit and at least ``shadow_rim_cells`` cells across that side are unknown (beyond the
    window counts as unknown). Scored as unknown, it keeps the kernel's band of invalid
    cells where the true edge puts it.
    """
    bits = np.ascontiguousarray(parts, dtype=np.uint16)
    out = np.empty(bits.shape, dtype=bool)
    kernels.shadow_rims(
        bits,
        np.ascontiguousarray(points, dtype=np.int64),
        np.ascontiguousarray(known, dtype=bool),
        config.shadow_points,
        config.shadow_rim_cells,
        SUB,
        out,
    )
    return out


def score_map(snapshot: MapSnapshot, config: ScoreConfig | None = None) -> ScoreMap:
    """Score a height-map snapshot.

    A cell that straddles an edge (:func:`edge_cells`) is invalid, and so are its eight
    neighbours: the edge may lie anywhere in it. It holds two levels (a stone's rim and the
    gap's floor, the face between them) and its one height shows whichever the last frame
    saw; so the map is scored twice, once with the cell at its top (the highest of its
    neighbours) and once at its bottom (its height less its spread, or its lowest
    neighbour if lower), and a cell is valid only if valid in both, scoring the worse: a
    foot nearby keeps its distance from both sides of the edge. A cell partly
    in a shadow (:func:`shadowed_cells`) is invalid too, and the sliver of a rim at a
    shadow's edge (:func:`shadow_rims`) is scored as unseen.
    """
    c = config or ScoreConfig()
    sigma = None if snapshot.variance is None else np.sqrt(snapshot.variance)
    heights = snapshot.heights
    if snapshot.parts is not None and snapshot.points is not None:
        rims = shadow_rims(snapshot.parts, snapshot.points, np.isfinite(heights), c)
        if rims.any():
            heights = np.where(rims, np.nan, heights)
    slope, proximity, score, valid = score_heights(heights, snapshot.resolution, c, sigma)
    if snapshot.spread is None:
        return ScoreMap(slope, proximity, score, valid, snapshot.origin, snapshot.resolution)
    edge = edge_cells(snapshot.spread, slope, snapshot.resolution, c)
    if edge.any():
        top = _around(np.nan_to_num(heights, nan=-np.inf), np.maximum)
        bottom = np.minimum(
            _around(np.nan_to_num(heights, nan=np.inf), np.minimum),
            heights - np.nan_to_num(snapshot.spread, nan=0.0),
        )
        slope, proximity, score, valid = score_heights(
            np.where(edge, top, heights), snapshot.resolution, c, sigma
        )
        low = score_heights(np.where(edge, bottom, heights), snapshot.resolution, c, sigma)
        slope, proximity, score = (
            np.fmax(a, b) for a, b in zip((slope, proximity, score), low[:3], strict=True)
        )
        valid &= low[3] & ~_around(edge, np.logical_or)
    if snapshot.parts is not None and snapshot.points is not None:
        valid &= ~shadowed_cells(snapshot.parts, snapshot.points, c)
    return ScoreMap(slope, proximity, score, valid, snapshot.origin, snapshot.resolution)
