"""Walkability scores: the Sobel slope, the edge-proximity score, validity."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from footfall.mapping.snapshot import MapSnapshot
from footfall.scoring.reference import score_grid_numpy, shadow_rims_numpy, shadowed_cells_numpy
from footfall.scoring.walkability import (
    ScoreConfig,
    edge_cells,
    score_heights,
    score_map,
    shadow_rims,
    shadowed_cells,
)
from footfall.sim.terrain import Course

CONFIG = ScoreConfig()


@given(
    st.integers(0, 2**32 - 1),
    st.integers(1, 30),
    st.integers(1, 30),
    st.floats(0.0, 1.0),
    st.floats(0.0, 1.0),
    st.integers(1, 4),
)
@settings(max_examples=80, deadline=None)
def test_compiled_shadow_rules_match_numpy_reference(seed, rows, cols, unseen, hit, rim_cells):
    """The compiled shadow and shadow-rim rules equal their whole-array definitions on maps
    of random seen cells, parts hit and point counts, the window's borders included."""
    rng = np.random.default_rng(seed)
    known = rng.uniform(size=(rows, cols)) >= unseen
    parts = (rng.uniform(size=(rows, cols, 16)) < hit) @ (1 << np.arange(16))
    parts = np.where(known, parts, 0).astype(np.uint16)
    points = np.where(known, rng.integers(0, 100, (rows, cols)), 0)
    config = ScoreConfig(shadow_points=int(rng.integers(1, 80)), shadow_rim_cells=rim_cells)
    np.testing.assert_array_equal(
        shadowed_cells(parts, points, config),
        shadowed_cells_numpy(parts, points, config.shadow_points),
    )
    np.testing.assert_array_equal(
        shadow_rims(parts, points, known, config),
        shadow_rims_numpy(parts, points, known, config.shadow_points, rim_cells),
    )


@given(st.integers(0, 2**32 - 1), st.integers(8, 40), st.integers(8, 40), st.floats(0.0, 0.3))
@settings(max_examples=60, deadline=None)
def test_compiled_scores_match_numpy_reference(seed, rows, cols, unknown_fraction):
    """The numba kernel equals the plain-NumPy definition, unknown cells included."""
    rng = np.random.default_rng(seed)
    h = rng.normal(0.0, 0.05, (rows, cols))
    h[rng.uniform(size=h.shape) < unknown_fraction] = np.nan
    ours = score_heights(h, 0.02, CONFIG)
    ref = score_grid_numpy(
        h, 0.02, CONFIG.kernel_1d, CONFIG.slope_weight, CONFIG.proximity_weight, CONFIG.threshold
    )
    for a, b in zip(ours[:3], ref[:3], strict=True):
        np.testing.assert_allclose(a, b, atol=1e-12, equal_nan=True)
    np.testing.assert_array_equal(ours[3], ref[3])


@given(st.floats(-0.6, 0.6), st.floats(-0.6, 0.6))
@settings(max_examples=50, deadline=None)
def test_uniform_ramp_has_its_slope_and_no_proximity(gx, gy):
    """On a plane the Sobel slope is the gradient (rise over run) and proximity vanishes."""
    res = 0.02
    i, j = np.meshgrid(np.arange(30), np.arange(30), indexing="ij")
    h = gx * i * res + gy * j * res
    slope, proximity, _, _ = score_heights(h, res, CONFIG)
    inner = (slice(5, -5), slice(5, -5))
    np.testing.assert_allclose(slope[inner], np.hypot(gx, gy), atol=1e-9)
    np.testing.assert_allclose(proximity[inner], 0.0, atol=1e-12)


def test_step_edge_is_invalid_and_far_cells_valid():
    """Cells next to a 5 cm step are invalid on both sides; cells far from it are valid."""
    h = np.zeros((40, 40))
    h[20:, :] = 0.05
    _, _, _, valid = score_heights(h, 0.02, CONFIG)
    assert not valid[19:21, 10].any()
    assert valid[10, 10] and valid[30, 10]


def test_cells_near_unknown_are_invalid():
    """A cell whose kernel window reaches an unknown cell, or the map border, is invalid."""
    h = np.zeros((40, 40))
    h[20, 20] = np.nan
    _, _, score, valid = score_heights(h, 0.02, CONFIG)
    half = CONFIG.kernel_size // 2
    assert np.isnan(score[20, 20])
    assert not valid[20 - half : 21 + half, 20 - half : 21 + half].any()
    assert valid[20 - half - 1, 20] and valid[20, 20 + half + 1]
    assert not valid[:half, :].any() and not valid[:, -half:].any()
    assert valid[half, 10]


def _course_scores(resolution: float = 0.02):
    course = Course()
    xs = np.arange(-0.2, 3.0, resolution) + resolution / 2
    ys = np.arange(-1.0, 1.0, resolution) + resolution / 2
    h = course.height(xs[:, None], ys[None, :])
    _, _, _, valid = score_heights(h, resolution, CONFIG)
    return xs, ys, valid


@pytest.mark.parametrize(
    ("where", "x", "y", "expected"),
    [
        ("box top", 0.9, 0.46, True),
        ("box edge", 0.9 - 0.13, 0.46, False),
        ("ramp middle", 1.6, 0.48, True),
        ("ramp low end", 1.42, 0.48, True),
        ("sloped pillar top", 2.35, 0.52, True),
        ("sloped pillar side", 2.35 + 0.14, 0.52, False),
        ("round pedestal top", 1.6, -0.5, True),
        ("round pedestal shoulder", 1.6 + 0.13, -0.5, False),
        ("tall box top", 2.3, -0.5, True),
        ("tall box edge", 2.3 - 0.11, -0.5, False),
        ("hole bottom", 0.9, -0.5, True),
        ("hole wall", 0.9 + 0.15, -0.5, False),
        ("hole rim", 0.9 + 0.19, -0.5, False),
        ("lane", 1.5, 0.0, True),
    ],
)
def test_course_features_score_as_in_thesis_figures(where, x, y, expected):
    """Thesis Figs. 6.6-6.8: box tops, ramp, pillar top, hole bottom valid; edges, rims and
    steep sides invalid (scored on the course's true surface)."""
    xs, ys, valid = _course_scores()
    i, j = int(np.argmin(np.abs(xs - x))), int(np.argmin(np.abs(ys - y)))
    assert bool(valid[i, j]) is expected, where


def test_bad_score_config_is_refused():
    """An even kernel or a non-positive threshold raise."""
    from footfall.errors import ConfigError

    with pytest.raises(ConfigError):
        ScoreConfig(kernel_size=6)
    with pytest.raises(ConfigError):
        ScoreConfig(threshold=0.0)


def _snapshot(heights: np.ndarray, spread: np.ndarray) -> MapSnapshot:
    return MapSnapshot(heights, np.isfinite(heights), (0.0, 0.0), 0.02, spread)


def test_cells_straddling_an_edge_are_found_but_not_a_ramp():
    """A cell whose points span a step is an edge cell; a ramp's cells span their slope
    times the diagonal and are not."""
    config = ScoreConfig()
    ramp_slope = 0.3
    ramp = np.full((20, 20), ramp_slope)
    spread = np.full((20, 20), ramp_slope * 0.02 * np.sqrt(2.0) * 0.95)
    assert not edge_cells(spread, ramp, 0.02, config).any()
    flat = np.zeros((20, 20))
    step = np.zeros((20, 20))
    step[10, :] = 0.01  # the cells on a 1 cm groove's far wall
    edge = edge_cells(step, flat, 0.02, config)
    assert edge[10].all() and edge.sum() == 20


def test_an_edge_cell_and_its_neighbours_are_invalid_and_scored_at_the_top_too():
    """A cell straddling a stone's edge whose height shows the groove side: it and its eight
    neighbours are invalid, and the floor two cells off scores the stone's edge."""
    heights = np.zeros((30, 30))
    heights[:, 15:] = 0.04  # a stone from column 15 on
    heights[:, 15] = 0.0  # the straddling column shows the groove side
    spread = np.zeros((30, 30))
    spread[:, 15] = 0.04
    scores = score_map(_snapshot(heights, spread))
    assert not scores.valid[5:25, 14:17].any()
    # Scored on the heights alone, the floor at column 13 (two cells from the stone's true
    # edge) would look farther from it than it is.
    _, _, plain, _ = score_heights(heights, 0.02, CONFIG)
    assert scores.score[15, 13] > plain[15, 13] + 0.1
    assert scores.valid[15, 5] and scores.valid[15, 25]


@settings(max_examples=40, deadline=None)
@given(st.integers(8, 21), st.floats(0.01, 0.3), st.booleans(), st.booleans())
def test_an_edge_cell_keeps_feet_off_both_its_levels_whichever_it_shows(
    column, rise_m, shows_top, groove
):
    """A cell straddling a stone's edge holds the stone's rim and the floor below it:
    whichever of the two its height shows, no cell is valid that would not be valid with
    the edge at either side of the cell (the floor's last cell or the stone's first), and
    the cell and its neighbours are invalid. With ``groove`` the floor is one cell wide:
    only the edge cell sees it."""
    n = 30
    true = np.zeros((n, n))
    true[:, column + 1 :] = rise_m
    if groove:
        true[:, :column] = rise_m
    heights = true.copy()
    heights[:, column] = rise_m if shows_top else 0.0
    spread = np.zeros((n, n))
    spread[:, column] = rise_m
    valid = score_map(_snapshot(heights, spread)).valid
    floor_there, stone_there = true.copy(), true.copy()
    floor_there[:, column] = 0.0
    stone_there[:, column] = rise_m
    either = (
        score_heights(floor_there, 0.02, CONFIG)[3] & score_heights(stone_there, 0.02, CONFIG)[3]
    )
    rows = slice(5, n - 5)
    assert not (valid[rows] & ~either[rows]).any()
    assert not valid[rows, column - 1 : column + 2].any()


def test_a_well_seen_cell_with_a_part_never_hit_is_shadowed_with_the_neighbour_behind():
    """A cell whose low-x row of parts no point ever hit, after many points: it and its
    neighbour across that side are invalid; the same cell seen by few points, or seen
    everywhere, is not judged so; a single missing corner part does not reach across."""
    config = ScoreConfig()
    n = 9
    parts = np.full((n, n), 0xFFFF, dtype=np.uint16)
    points = np.full((n, n), 5 * config.shadow_points)
    parts[4, 4] = 0xFFFF & ~0x000F  # parts a = 0, the cell's low-x side
    parts[2, 2] = 0xFFFF & ~0x0001  # one corner part
    shadow = shadowed_cells(parts, points, config)
    assert set(zip(*np.nonzero(shadow), strict=True)) == {(4, 4), (3, 4), (2, 2)}
    sparse = points.copy()
    sparse[4, 4] = sparse[2, 2] = config.shadow_points - 1
    assert not shadowed_cells(parts, sparse, config).any()
    flat = np.zeros((n, n))
    snapshot = MapSnapshot(
        flat, np.ones((n, n), bool), (0.0, 0.0), 0.02, np.zeros((n, n)), parts=parts, points=points
    )
    valid = score_map(snapshot).valid
    assert not valid[4, 4] and not valid[3, 4] and valid[5, 4]


@pytest.mark.parametrize(
    "axis, towards, sliver_bits",
    [(0, 1, 0x000F), (0, -1, 0xF000), (1, 1, 0x1111), (1, -1, 0x8888)],
)
def test_the_sliver_of_a_rim_before_a_shadow_is_unseen_and_the_edge_band_stands_true(
    axis, towards, sliver_bits
):
    """A rim's last cell, hit only on the rim's side, with the shadow beyond it: it is scored
    as unseen, so every cell within the kernel's half-width of the true edge is invalid, as
    a perfect map would have it. A fully seen cell, a cell with the floor seen beyond it,
    one whose rim behind is barely seen, or one before a shadow shorter than
    ``shadow_rim_cells`` (a groove between stones), is left as it is."""
    config = ScoreConfig()
    n, edge, half = 20, 10, config.kernel_size // 2
    index = np.arange(n)[:, None] * np.ones((1, n), int)  # cell index along the way

    def oriented(a):
        a = a if towards > 0 else a[::-1]
        return a if axis == 0 else a.T

    along = oriented(index)
    heights = np.where(along > edge, np.nan, 0.0)  # the floor beyond the rim: never seen
    sliver = along == edge
    parts = np.where(along > edge, 0, np.where(sliver, sliver_bits, 0xFFFF)).astype(np.uint16)
    points = np.where(along > edge, 0, np.where(sliver, 3, 5 * config.shadow_points))
    known = np.isfinite(heights)
    assert np.array_equal(shadow_rims(parts, points, known, config), sliver)
    snapshot = MapSnapshot(heights, known, (0.0, 0.0), 0.02, parts=parts, points=points)
    valid = score_map(snapshot).valid
    inner = oriented(np.abs(index.T - n // 2) < n // 2 - half)  # away from the map's sides
    assert not valid[(along >= edge - half) & (along <= edge)].any()
    assert valid[(along == edge - half - 1) & inner].all()

    full = np.where(sliver, 0xFFFF, parts).astype(np.uint16)
    assert not shadow_rims(full, points, known, config).any()
    barely = np.where(along == edge - 1, 1, points)
    assert not shadow_rims(parts, barely, known, config).any()
    assert not shadow_rims(parts, points, np.ones((n, n), bool), config).any()
    run = config.shadow_rim_cells
    long_enough = known | (along > edge + run)  # ground seen again past the shadow
    assert np.array_equal(shadow_rims(parts, points, long_enough, config), sliver)
    short = known | (along >= edge + run)
    assert not shadow_rims(parts, points, short, config).any()
