"""Foothold search and the support-polygon test."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from footfall.planning.footholds import (
    FootholdConfig,
    FootholdSearch,
    point_in_polygon_margin,
    registration_margin_cells,
    sorted_offsets,
)
from footfall.planning.regions import steppable_regions
from footfall.scoring.walkability import ScoreMap

RES = 0.02


def _score_map(valid: np.ndarray, score: np.ndarray) -> ScoreMap:
    nan = np.full(valid.shape, np.nan)
    return ScoreMap(nan, nan, score, valid, (0.0, 0.0), RES)


@given(
    st.integers(0, 2**32 - 1),
    st.floats(0.0, 1.0),
    st.integers(0, 2),
    st.integers(0, 2),
    st.integers(0, 3),
    st.booleans(),
    st.sampled_from([0.0, 0.02, 0.05]),
)
@settings(max_examples=150, deadline=None)
def test_search_returns_the_nearest_acceptable_cell(
    seed, density, margin, fallback, floor, keep, hysteresis
):
    """Cross-check against brute force: the nearest valid cell with the full edge margin
    within the radius, ties by score, else the nearest with the next narrower margin, never
    narrower than the search's least margin (``min_margin_cells``, the map's possible
    misregistration) and wider first when that is wider; cells in the region of a kept
    point count as the hysteresis nearer; never an invalid or unknown cell; None when
    there is none."""
    rng = np.random.default_rng(seed)
    valid = rng.uniform(size=(30, 30)) < density
    score = rng.uniform(0, 0.5, (30, 30))
    heights = rng.uniform(-0.05, 0.05, (30, 30))
    heights[~valid & (rng.uniform(size=valid.shape) < 0.5)] = np.nan  # some unknown cells
    least = max(margin - fallback, 0)
    config = FootholdConfig(
        search_radius=0.1,
        edge_margin_cells=margin,
        min_edge_margin_cells=least,
        region_hysteresis=hysteresis,
    )
    search = FootholdSearch(config, RES)
    nominal = rng.uniform(0.1, 0.5, 2)
    kept = rng.uniform(0.0, 0.6, 2) if keep else None
    found = search.search(
        nominal, _score_map(valid, score), heights, min_margin_cells=floor, keep_region_at=kept
    )
    centre = np.floor(nominal / RES).astype(int)
    best = None
    lowest = max(least, floor)
    labels, depth = brute_force_labels(valid), brute_force_depth(valid, margin)
    kept_label = 0 if kept is None else labels[tuple(np.floor(kept / RES).astype(int))]
    for m in range(max(margin, lowest), lowest - 1, -1):
        for i in range(30):
            for j in range(30):
                d = np.hypot(i - centre[0], j - centre[1])
                core = depth[labels == labels[i, j]].max()
                usable = valid[i, j] and depth[i, j] >= max(min(m, max(core, 1)), lowest)
                if usable and d * RES <= 0.1 + 1e-9:
                    ranked = d - hysteresis / RES * (kept_label and labels[i, j] == kept_label)
                    key = (round(ranked, 9), score[i, j])
                    if best is None or key < best[0]:
                        best = (key, (i, j))
        if best is not None:
            break
    if best is None:
        assert found is None
    else:
        assert found is not None and found.cell == best[1]
        assert valid[found.cell]
        assert found.position[2] == heights[found.cell]


@given(st.floats(0.0, 0.2), st.sampled_from([0.01, 0.02, 0.05]))
def test_a_registration_margin_keeps_the_foot_centre_that_far_from_invalid_cells(error, res):
    """A margin of m cells puts the foot centre (m + 0.5) cells from the nearest invalid
    cell; the margin for an error is the least that covers it (to a billionth of a cell:
    0.07 m at 2 cm cells takes 3 cells, not 4, though 0.07 / 0.02 rounds above 3.5)."""
    m = registration_margin_cells(error, res)
    assert (m + 0.5) * res >= error - 1e-9 * res
    assert m == 0 or (m - 0.5) * res < error
    assert registration_margin_cells(0.07, 0.02) == 3


def test_valid_nominal_cell_keeps_the_nominal_position():
    """If the nominal cell is acceptable the foothold is not adjusted (thesis Fig. 6.8)."""
    valid = np.ones((20, 20), dtype=bool)
    found = FootholdSearch(FootholdConfig(), RES).search(
        [0.205, 0.193], _score_map(valid, np.zeros((20, 20))), np.zeros((20, 20))
    )
    assert found is not None and found.moved == 0.0
    np.testing.assert_allclose(found.position[:2], [0.205, 0.193])


def test_accept_callback_filters_candidates():
    """Constraints (reach, stability) reject candidates; the next nearest is taken."""
    valid = np.ones((20, 20), dtype=bool)
    search = FootholdSearch(
        FootholdConfig(search_radius=0.1, edge_margin_cells=0, min_edge_margin_cells=0), RES
    )
    found = search.search(
        [0.2, 0.2],
        _score_map(valid, np.zeros((20, 20))),
        np.zeros((20, 20)),
        accept=lambda p: p[0] < 0.17,
    )
    assert found is not None and found.position[0] < 0.17
    assert found.moved == pytest.approx(0.2 - 0.15, abs=0.011)


@given(st.integers(0, 2**32 - 1), st.floats(0.0, 1.0), st.floats(0.0, 1.0))
@settings(max_examples=100, deadline=None)
def test_a_batched_test_finds_what_the_one_by_one_test_finds(seed, density, keep):
    """Testing candidates many at once (`first_accepted`) picks the same foothold as
    testing them one by one (`accept`), whatever the test rejects."""
    rng = np.random.default_rng(seed)
    valid = rng.uniform(size=(40, 40)) < density
    scores = _score_map(valid, rng.uniform(0, 0.5, (40, 40)))
    heights = rng.uniform(-0.05, 0.05, (40, 40))
    search = FootholdSearch(FootholdConfig(search_radius=0.16), RES)
    salt = rng.uniform()

    def accept(point):
        return (np.sin(1e3 * point[0] + 7e2 * point[1] + salt) + 1) / 2 < keep

    def first_accepted(points):
        ok = [accept(p) for p in points]
        return ok.index(True) if True in ok else -1

    nominal = rng.uniform(0.2, 0.6, 2)
    one = search.search(nominal, scores, heights, accept=accept)
    many = search.search(nominal, scores, heights, first_accepted=first_accepted)
    assert (one is None) == (many is None)
    if one is not None:
        assert one.cell == many.cell and one.moved == many.moved
        np.testing.assert_array_equal(one.position, many.position)


def test_offsets_are_in_order_of_true_distance():
    """Candidates come nearest first (not in square rings)."""
    offsets, distances = sorted_offsets(5.0)
    assert np.all(np.diff(distances) >= 0)
    np.testing.assert_allclose(distances, np.hypot(offsets[:, 0], offsets[:, 1]))
    assert len(offsets) == np.sum(np.hypot(*np.mgrid[-5:6, -5:6]) <= 5.0)


def _inside_triangle(p, a, b, c) -> bool:
    def side(u, v, w):
        return (v[0] - u[0]) * (w[1] - u[1]) - (v[1] - u[1]) * (w[0] - u[0])

    s1, s2, s3 = side(a, b, p), side(b, c, p), side(c, a, p)
    return (s1 > 0 and s2 > 0 and s3 > 0) or (s1 < 0 and s2 < 0 and s3 < 0)


points = st.tuples(st.floats(-1, 1), st.floats(-1, 1)).map(np.array)


@given(points, points, points, points)
@settings(max_examples=300, deadline=None)
def test_support_margin_agrees_with_point_in_triangle(p, a, b, c):
    """The signed margin is positive exactly when the point is inside the triangle, and
    never exceeds the distance to any edge line."""
    area = abs((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))
    if area < 1e-3:
        return
    margin = point_in_polygon_margin(p, np.stack([a, b, c]))
    if abs(margin) < 1e-9:
        return
    assert (margin > 0) == _inside_triangle(p, a, b, c)
    for u, v in ((a, b), (b, c), (c, a)):
        d = abs((v[0] - u[0]) * (p[1] - u[1]) - (v[1] - u[1]) * (p[0] - u[0])) / np.hypot(*(v - u))
        assert margin <= d + 1e-9


def brute_force_depth(valid: np.ndarray, cap: int) -> np.ndarray:
    """Each cell's margin: the most steps along rows and columns (up to ``cap``) within
    which every cell is valid and on the grid; -1 for invalid cells."""
    n, m = valid.shape
    depth = np.full(valid.shape, -1)
    for i in range(n):
        for j in range(m):
            if not valid[i, j]:
                continue
            d = 0
            while d < cap:
                ring = [
                    (i + a, j + b)
                    for a in range(-d - 1, d + 2)
                    for b in range(-d - 1, d + 2)
                    if abs(a) + abs(b) <= d + 1
                ]
                if not all(0 <= p < n and 0 <= q < m and valid[p, q] for p, q in ring):
                    break
                d += 1
            depth[i, j] = d
    return depth


def brute_force_labels(valid: np.ndarray) -> np.ndarray:
    """Regions by flood fill over the eight neighbours; 0 for invalid cells."""
    labels = np.zeros(valid.shape, dtype=int)
    count = 0
    for start in zip(*np.nonzero(valid), strict=True):
        if labels[start]:
            continue
        count += 1
        stack = [start]
        labels[start] = count
        while stack:
            i, j = stack.pop()
            for a in (-1, 0, 1):
                for b in (-1, 0, 1):
                    p, q = i + a, j + b
                    inside = 0 <= p < valid.shape[0] and 0 <= q < valid.shape[1]
                    if inside and valid[p, q] and not labels[p, q]:
                        labels[p, q] = count
                        stack.append((p, q))
    return labels


@given(st.integers(0, 2**32 - 1), st.floats(0.0, 1.0), st.integers(0, 4), st.integers(3, 24))
@settings(max_examples=150, deadline=None)
def test_regions_and_depths_match_a_brute_force_segmentation(seed, density, cap, size):
    """Steppable regions are the 8-connected areas of valid cells, each cell's depth the
    margin of valid cells around it and each region's core its deepest cell, as a flood
    fill and a cell-by-cell count find them."""
    rng = np.random.default_rng(seed)
    valid = rng.uniform(size=(size, size + 3)) < density
    valid[size // 3 : size // 2, 2:-2] |= density > 0.5  # a wide band: deep cells too
    regions = steppable_regions(valid, cap)
    labels = brute_force_labels(valid)
    assert regions.count == labels.max()
    # The same partition, whatever the numbering.
    pairs = set(zip(labels[valid].tolist(), regions.labels[valid].tolist(), strict=True))
    assert len(pairs) == regions.count
    assert np.array_equal(regions.labels == 0, ~valid)
    depth = brute_force_depth(valid, cap)
    assert np.array_equal(regions.depth, depth)
    for label in range(1, labels.max() + 1):
        inside = labels == label
        (ours,) = set(regions.core()[inside].tolist())
        assert ours == depth[inside].max()


def test_a_small_stone_gives_its_middle_not_its_rim_and_a_replan_keeps_the_stone():
    """Two stones across a gap, the nominal foothold on the gap: the nearer stone, too
    small for the full margin, gives its middle cell, not the rim cell nearest the
    nominal one. Planned before on the farther stone, a re-plan keeps that stone while it
    has an acceptable cell less than the hysteresis farther than the other stone's, and
    leaves it once it has none, or once the nominal foothold moved well away from it."""
    valid = np.zeros((30, 30), dtype=bool)
    valid[10:13, 10:20] = True  # a stone three cells wide: its core is one cell deep
    valid[16:26, 10:20] = True  # a wide stone
    config = FootholdConfig(search_radius=0.12, edge_margin_cells=2, region_hysteresis=0.04)
    search = FootholdSearch(config, RES)
    scores = _score_map(valid, np.zeros((30, 30)))
    heights = np.zeros((30, 30))
    nominal = np.array([14.5, 15.5]) * RES  # on the gap: 3 cells from the small stone's middle
    found = search.search(nominal, scores, heights)
    assert found is not None and found.cell == (11, 15)  # the middle row, not the rim
    far = (np.array([19.5, 15.5])) * RES
    kept = search.search(nominal, scores, heights, keep_region_at=far)
    assert kept is not None and kept.region == search.region_at(far, scores)
    assert kept.cell == (18, 15)  # well inside the wide stone, 4 cells off: within 2 of 3
    assert kept.region != found.region

    def not_the_wide_stone(points: np.ndarray) -> int:
        rows = np.floor(points[:, 0] / RES)
        return next((k for k, r in enumerate(rows) if r < 16), -1)

    left = search.search(
        nominal, scores, heights, first_accepted=not_the_wide_stone, keep_region_at=far
    )
    assert left is not None and left.cell == (11, 15)
    moved = np.array([12.5, 15.5]) * RES  # the nominal foothold moved onto the small stone
    away = search.search(moved, scores, heights, keep_region_at=far)
    assert away is not None and away.cell == (11, 15)  # 1 cell against 6: the stone is left

    def any_point(points: np.ndarray) -> int:
        return 0 if len(points) else -1

    # Leaving the wide stone for a cell 1 cell nearer is needless; 2 cells (4 cm), not;
    # from a foothold beyond the search radius (0.12 m, 6 cells), not, however near.
    aside = dataclasses.replace(found, cell=(11, 11))  # the small stone's core, 5 cells off
    for kept_cell, new, needless in (
        ((18, 15), found, True),
        ((19, 15), found, False),
        ((18, 16), aside, True),  # 4.1 cells off: nearer than the new one
        ((20, 17), aside, False),  # 6.3 cells off: beyond the radius
    ):
        kept_xy = (np.array(kept_cell) + 0.5) * RES
        jumped = search.needless_jump(nominal, kept_xy, new, scores, heights, 0, any_point)
        assert jumped is needless, kept_cell


def _reference_margin(point: np.ndarray, polygon: np.ndarray) -> float:
    """The support margin written out in NumPy: the monotone-chain hull of the distinct
    vertices, then the least signed distance to its edges."""
    pts = np.unique(polygon, axis=0)

    def chain(ordered):
        out: list = []
        for p in ordered:
            while len(out) >= 2:
                o, a = out[-2], out[-1]
                if (a[0] - o[0]) * (p[1] - o[1]) - (a[1] - o[1]) * (p[0] - o[0]) > 1e-15:
                    break
                out.pop()
            out.append(p)
        return out

    if len(pts) < 3:
        return -np.inf
    hull = np.array(chain(pts)[:-1] + chain(pts[::-1])[:-1])
    if len(hull) < 3:
        return -np.inf
    edges = np.roll(hull, -1, axis=0) - hull
    normals = np.stack([edges[:, 1], -edges[:, 0]], axis=1)
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    return float(np.min(-np.einsum("ij,ij->i", point - hull, normals)))


@given(
    st.lists(st.tuples(st.sampled_from([-0.2, 0.0, 0.1]), st.floats(-0.3, 0.3)), max_size=3),
    st.lists(st.tuples(st.floats(-0.3, 0.3), st.floats(-0.3, 0.3)), min_size=1, max_size=6),
    points,
)
@settings(max_examples=300, deadline=None)
def test_the_compiled_support_margin_is_the_numpy_one(aligned, free, p):
    """The compiled margin equals the NumPy reference to the last bit, for polygons of one to
    nine vertices in any order, with repeated and collinear vertices."""
    polygon = np.array(aligned + free + free[:1], dtype=np.float64)
    assert point_in_polygon_margin(p, polygon) == _reference_margin(p, polygon)
