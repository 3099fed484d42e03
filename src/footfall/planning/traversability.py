"""Where the hexapod's body may go: a cost grid over the rolling map, for route planning.

The foothold search asks where one foot may land; the route planner asks where the robot
as a whole may stand, legs spread around it. For a body centred on a cell it checks:

- **Walls.** A known cell more than ``max_rise_m`` above a known cell within
  ``wall_run_m`` is a wall face's top: no step the legs can take climbs it. The navigator
  remembers walls (a face seen obliquely may later leave its cell only the face's foot as
  height) until their cells are seen flat. A robot whose
  legs' span (``span_radius_m``) reaches a wall top higher than the ground it stands on
  (the median foothold-valid height over the span) by more than half ``max_rise_m`` would
  put a leg into it: lethal. A wall top at the robot's own level (the rim of a pit or a
  gap it straddles, however much of the floor below is seen) is not; the top of a block
  smaller than the span is no place to stand.
- **Support.** A foot needs a valid cell within ``support_radius_m`` of where its leg puts
  it, not far below the ground near it (a pit floor deeper than ``max_rise_m`` is out of
  reach). The share of known cells in the ring the feet sweep (between half the span and
  the span) without such a cell costs, and above ``max_unsupported`` is lethal.
- **Gaps.** A foot crosses a trench or a pit deeper than ``max_rise_m`` in one swing, so
  no farther than the longest step (``max_gap_m``: the stride plus the foothold search's
  reach forward). A body centre over such a drop (seen, or hidden between its seen sides)
  more than half that from every usable cell lies in a gap too wide to step: lethal, so a
  trench wider than a step closes the way (no route) instead of freezing the walk at its
  edge. Only such a stretch at least as long as the legs' span counts: round a shorter
  one (a pit, the crossing between four stepping stones) the feet step aside within their
  search, which the foothold planner does. Ground at the robot's level that the scorer
  finds no foothold on (noise, far away) is no gap.
- **Unknown.** Cells not yet seen are passable but cost ``unknown_cost`` more per metre
  (times their share of the span), so routes prefer what has been seen and are replanned
  as more is.
- **Clearance.** Within ``clearance_m`` of a lethal cell the cost rises to
  ``clearance_cost`` more, so routes keep off walls rather than graze them.

The legs' span is taken as a disc: the hexapod may face any way while it walks (it turns
on the spot), so its footprint is the disc its feet can take at any heading. Everything is
array filters over the map (SciPy, and compiled passes in
:mod:`footfall.planning.cost_kernels`), so a 256 x 256 grid takes milliseconds.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from numpy.lib.stride_tricks import sliding_window_view
from scipy import ndimage

from footfall.checks import require_non_negative, require_positive
from footfall.errors import ConfigError
from footfall.messages import MapUpdate
from footfall.planning import cost_kernels
from footfall.planning.cost_kernels import octagon_half_widths
from footfall.robot.scale import feet_span_m
from footfall.robot.spec import HexapodSpec

_SQUARE = np.ones((3, 3), dtype=bool)
# The ground level's median is taken on every this many cells along each axis.
MEDIAN_STRIDE = 3
# Below this share of valid cells in its span a body has no ground to stand on.
MIN_GROUND_SHARE = 0.05


@dataclass(frozen=True)
class TraversabilityConfig:
    """Cost grid settings.

    Attributes:
        span_radius_m: Radius of the disc the legs span around the body centre [m]; None
            takes it from the robot (see :func:`span_radius`).
        max_gap_m: Widest gap without footholds a step crosses [m]; None takes it from
            the robot and the foothold search (see :func:`longest_gap`).
        max_rise_m: Highest rise the legs climb as a step [m].
        wall_run_m: A rise within this horizontal run is a wall face [m].
        support_radius_m: A foot finds a foothold within this of where its leg puts it [m].
        max_unsupported: Share of the feet's ring without a foothold near that is lethal.
        unsupported_cost: Extra cost per metre of a fully unsupported ring.
        unknown_cost: Extra cost per metre of a span not yet seen at all.
        clearance_m: Distance from lethal cells within which the cost rises [m].
        clearance_cost: Extra cost per metre right beside a lethal cell.
    """

    span_radius_m: float | None = None
    max_gap_m: float | None = None
    max_rise_m: float = 0.10
    wall_run_m: float = 0.04
    support_radius_m: float = 0.08
    max_unsupported: float = 0.4
    unsupported_cost: float = 6.0
    unknown_cost: float = 2.0
    clearance_m: float = 0.25
    clearance_cost: float = 6.0

    def __post_init__(self) -> None:
        require_positive(
            "traversability",
            max_rise_m=self.max_rise_m,
            wall_run_m=self.wall_run_m,
            support_radius_m=self.support_radius_m,
            clearance_m=self.clearance_m,
        )
        if self.span_radius_m is not None:
            require_positive("traversability", span_radius_m=self.span_radius_m)
        if self.max_gap_m is not None:
            require_positive("traversability", max_gap_m=self.max_gap_m)
        if not 0 < self.max_unsupported <= 1:
            raise ConfigError(f"max_unsupported must lie in (0, 1], got {self.max_unsupported}")
        require_non_negative(
            "traversability",
            unsupported_cost=self.unsupported_cost,
            unknown_cost=self.unknown_cost,
            clearance_cost=self.clearance_cost,
        )


def span_radius(spec: HexapodSpec, margin_m: float = 0.05) -> float:
    """Radius of the disc the feet at rest reach, plus the foot and a margin [m].

    The margin covers a foot half a stride ahead of its rest position and a route followed
    a few centimetres off.
    """
    return feet_span_m(spec) + margin_m


def longest_gap(spec: HexapodSpec, search_radius_m: float) -> float:
    """The widest gap without footholds a foot steps across [m].

    A swing carries the foot one stride over the ground from where it lifted; the foothold
    search may move its landing up to ``search_radius_m`` farther on.
    """
    return spec.stride_length + search_radius_m


@dataclass(frozen=True)
class CostGrid:
    """Cost per metre of moving the body centre over each cell of a map window.

    Arrays are N x N, index ``[i, j]`` along world ``x`` and ``y`` (as the map's).

    Attributes:
        cost: Cost per metre, at least 1; ``inf`` where lethal.
        lethal: Cells the body centre must not enter.
        wall: Wall-top cells (see the module docstring).
        gap: Cells inside a gap wider than a step, seen or hidden (see the module docstring).
        wall_top: Their tops [m], NaN elsewhere.
        flat: Cells seen flat: no wall, and no face ever within them.
        unknown_share: Share of the span around each cell not yet seen.
        origin: World ``(x, y)`` of the corner of cell ``[0, 0]`` [m].
        resolution: Cell side [m].
    """

    cost: npt.NDArray[np.float64]
    lethal: npt.NDArray[np.bool_]
    wall: npt.NDArray[np.bool_]
    gap: npt.NDArray[np.bool_]
    wall_top: npt.NDArray[np.float64]
    flat: npt.NDArray[np.bool_]
    unknown_share: npt.NDArray[np.float64]
    origin: tuple[float, float]
    resolution: float

    @property
    def shape(self) -> tuple[int, int]:
        """Cells along x and y."""
        return self.cost.shape  # type: ignore[return-value]

    def cell_of(self, position_in_world: npt.ArrayLike) -> tuple[int, int]:
        """The cell holding a world ``(x, y)`` point (possibly outside the grid)."""
        p = np.asarray(position_in_world, dtype=np.float64)
        return (
            math.floor((p[0] - self.origin[0]) / self.resolution),
            math.floor((p[1] - self.origin[1]) / self.resolution),
        )

    def contains(self, cell: tuple[int, int]) -> bool:
        """Whether a cell index lies on the grid."""
        return 0 <= cell[0] < self.shape[0] and 0 <= cell[1] < self.shape[1]

    def centres_in_world(self, cells: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """World ``(x, y)`` of cell centres, shape (k, 2) for cells of shape (k, 2)."""
        c = np.asarray(cells, dtype=np.float64).reshape(-1, 2)
        return np.asarray(self.origin) + (c + 0.5) * self.resolution


def _disc_max(a: npt.NDArray[np.float64], radius_cells: int) -> npt.NDArray[np.float64]:
    """Greatest value within about ``radius_cells`` of each cell (an octagon).

    The octagon ``radius_cells`` alternating 3 x 3 cross and square maximum filters grow,
    in two compiled passes (:mod:`footfall.planning.cost_kernels`).
    """
    widths = octagon_half_widths(radius_cells)
    out = np.empty(a.shape, dtype=np.float64)
    scratch = np.empty((int(widths.max()) + 1, *a.shape))
    cost_kernels.octagon_max(np.ascontiguousarray(a, dtype=np.float64), widths, scratch, out)
    return out


def _masked_median(
    heights: npt.NDArray[np.float64], valid: npt.NDArray[np.bool_], half_cells: int
) -> npt.NDArray[np.float64]:
    """Median of the valid heights in the square of half-side ``half_cells`` around each cell.

    Taken on every ``MEDIAN_STRIDE``-th cell along each axis (every cell of the window
    costs a second on a 256 x 256 map), with the map's sides mirrored. Each window's
    samples are sorted with the cells that are not valid last, and the middle of the valid
    ones taken. A window with no valid cell gives +inf.
    """
    step = MEDIAN_STRIDE
    half = max(1, round(half_cells / step))
    sub = np.where(valid[::step, ::step], heights[::step, ::step], np.inf)
    windows = sliding_window_view(np.pad(sub, half, mode="reflect"), (2 * half + 1,) * 2)
    ordered = np.sort(windows.reshape(*sub.shape, -1), axis=-1)
    count = np.isfinite(ordered).sum(axis=-1)
    low = np.take_along_axis(ordered, np.maximum(count - 1, 0)[..., None] // 2, axis=-1)
    high = np.take_along_axis(ordered, (count // 2)[..., None], axis=-1)
    median = np.where(count > 0, 0.5 * (low[..., 0] + high[..., 0]), np.inf)
    full = np.repeat(np.repeat(median, step, axis=0), step, axis=1)
    return full[: heights.shape[0], : heights.shape[1]]


def _box_mean(
    a: npt.NDArray[np.float64], half_cells: int, outside: float
) -> npt.NDArray[np.float64]:
    """Mean over the square of half-side ``half_cells`` around each cell."""
    return ndimage.uniform_filter(a, size=2 * half_cells + 1, mode="constant", cval=outside)


def _shadowed(
    known: npt.NDArray[np.bool_],
    usable: npt.NDArray[np.bool_],
    deep: npt.NDArray[np.bool_],
    max_run: int,
) -> npt.NDArray[np.bool_]:
    """Unseen cells that lie, along a row or a column, inside a trench seen at both ends.

    The floor of a deep trench is hidden from a camera looking across it, while its near
    rim and something of its far side are seen: an unseen run of at most ``max_run`` cells
    whose nearest seen cells on both sides have no foothold, one of them deep, has none
    either. A longer run, or one with ground a foot can stand on at an end (the shadow
    behind a block, the edge of what has been seen), may be anything and stays unknown.
    """
    out = np.empty(known.shape, dtype=bool)
    cost_kernels.enclosed_unseen(
        np.ascontiguousarray(known),
        np.ascontiguousarray(usable),
        np.ascontiguousarray(deep),
        max_run,
        out,
    )
    return out


def _long_parts(mask: npt.NDArray[np.bool_], min_cells: int) -> npt.NDArray[np.bool_]:
    """The 8-connected parts of ``mask`` that reach at least ``min_cells`` along x or y."""
    labels, count = ndimage.label(mask, structure=_SQUARE)
    if count == 0:
        return mask
    keep = np.zeros(count + 1, dtype=bool)
    for k, box in enumerate(ndimage.find_objects(labels), start=1):
        keep[k] = max(box[0].stop - box[0].start, box[1].stop - box[1].start) >= min_cells
    return keep[labels]


def wall_faces(update: MapUpdate, config: TraversabilityConfig) -> npt.NDArray[np.bool_]:
    """Cells more than ``max_rise_m`` above a known cell within ``wall_run_m``: wall tops."""
    heights = np.asarray(update.heights, dtype=np.float64)
    known = np.asarray(update.known, dtype=bool) & np.isfinite(heights)
    run = max(1, round(config.wall_run_m / update.resolution))
    low = ndimage.minimum_filter(np.where(known, heights, np.inf), size=2 * run + 1, mode="nearest")
    return known & (heights - low > config.max_rise_m)


def cost_grid(
    update: MapUpdate,
    config: TraversabilityConfig,
    span_radius_m: float,
    remembered_tops: npt.NDArray[np.float64] | None = None,
    max_gap_m: float = math.inf,
) -> CostGrid:
    """The cost grid of a map update (see the module docstring).

    Args:
        update: Heights, known and valid cells of the map window.
        config: Settings.
        span_radius_m: Radius of the legs' span [m] (``config.span_radius_m`` if set wins).
        remembered_tops: Wall tops found on earlier updates, on this window's cells [m]
            (NaN where none): a wall stays one until its cell is seen flat (a face seen
            obliquely may leave its cell only the face's foot as height).
        max_gap_m: Widest gap a step crosses [m] (``config.max_gap_m`` if set wins).
    """
    res = update.resolution
    span = config.span_radius_m if config.span_radius_m is not None else span_radius_m
    widest = config.max_gap_m if config.max_gap_m is not None else max_gap_m
    heights = np.asarray(update.heights, dtype=np.float64)
    known = np.asarray(update.known, dtype=bool) & np.isfinite(heights)
    valid = np.asarray(update.valid, dtype=bool) & known

    def cells(length_m: float) -> int:
        return max(1, round(length_m / res))

    wall = wall_faces(update, config)
    top = heights
    # Seen flat: no rise beside it, and its points never spanned a face's height.
    flat = known & ~wall
    if update.spread is not None:
        flat &= ~(
            np.nan_to_num(np.asarray(update.spread, dtype=np.float64), nan=0.0) > config.max_rise_m
        )
    if remembered_tops is not None:
        held = np.isfinite(remembered_tops) & ~flat
        wall = wall | held
        top = np.where(held, np.fmax(heights, remembered_tops), heights)
    span_cells = cells(span)
    # The level the feet stand at: the median valid height over the span. A body beside a
    # trench, or over one, stands on the platforms its feet reach however much of the
    # trench floor is seen; a body over a block smaller than its span stands on the floor
    # around it, not on the block.
    weight = _box_mean(valid.astype(np.float64), span_cells, 0.0)
    ground = _masked_median(heights, valid, span_cells)
    ground[~(weight >= MIN_GROUND_SHARE) | ~np.isfinite(ground)] = -np.inf
    reach_top = _disc_max(np.where(wall, top, -np.inf), span_cells)
    # A robot with no valid ground in its span and a wall in reach is in the wall.
    lethal = (reach_top > -np.inf) & ~(reach_top <= ground + 0.5 * config.max_rise_m)

    usable = valid & (heights >= ground - config.max_rise_m)
    supported = ndimage.maximum_filter(
        usable, size=2 * cells(config.support_radius_m) + 1, mode="nearest"
    )
    inner_cells = max(0, span_cells // 2)
    unsupported = (known & ~supported).astype(np.float64)
    outer_area, inner_area = (2 * span_cells + 1) ** 2, (2 * inner_cells + 1) ** 2
    ring_unsupported = (
        _box_mean(unsupported, span_cells, 0.0) * outer_area
        - _box_mean(unsupported, inner_cells, 0.0) * inner_area
    ) / (outer_area - inner_area)
    ring_unsupported = np.clip(ring_unsupported, 0.0, 1.0)
    lethal |= ring_unsupported > config.max_unsupported
    gap = np.zeros_like(known)
    deep = known & (heights < ground - config.max_rise_m)
    # A gap is a drop: without a deep cell (most maps) there is none to look for.
    if math.isfinite(widest) and usable.any() and deep.any():
        to_foothold_m = ndimage.distance_transform_edt(~usable) * res
        hidden = _shadowed(known, usable, deep, cells(2.0 * widest))
        gap = _long_parts((deep | hidden) & (to_foothold_m > 0.5 * widest), 2 * span_cells)
        lethal |= gap
    unknown_share = np.clip(_box_mean((~known).astype(np.float64), span_cells, 1.0), 0.0, 1.0)

    cost = 1.0 + config.unknown_cost * unknown_share + config.unsupported_cost * ring_unsupported
    if lethal.any():
        distance_m = ndimage.distance_transform_edt(~lethal) * res
        cost += config.clearance_cost * np.clip(1.0 - distance_m / config.clearance_m, 0.0, 1.0)
    cost[lethal] = np.inf
    return CostGrid(
        cost=cost,
        lethal=lethal,
        wall=wall,
        gap=gap,
        wall_top=np.where(wall, top, np.nan),
        flat=flat,
        unknown_share=unknown_share,
        origin=(float(update.origin[0]), float(update.origin[1])),
        resolution=float(res),
    )
