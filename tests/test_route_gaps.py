"""The route planner and gaps: a trench a step cannot span closes the way, one it can does not."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from footfall.messages import MapUpdate
from footfall.planning.footholds import FootholdConfig
from footfall.planning.navigation import NavigationConfig, NoRoute, Route, plan_route
from footfall.planning.traversability import (
    TraversabilityConfig,
    _shadowed,
    cost_grid,
    longest_gap,
    span_radius,
)
from footfall.robot.spec import load_spec

RES = 0.02
N = 150
ORIGIN = (-1.0, -1.0)
SPEC = load_spec("default")
SPAN = span_radius(SPEC)
STEP = longest_gap(SPEC, FootholdConfig().search_radius)


def _trench(width: float, hidden: bool = False, until_y: float = math.inf) -> MapUpdate:
    """Flat ground with a trench 30 cm deep across x = 0.5 m up to ``until_y``.

    Its floor and walls are no foothold (``valid`` False), exactly ``width`` wide; ``hidden``
    leaves all but the cell at either wall unseen, as a camera looking across it sees it.
    """
    xs = ORIGIN[0] + (np.arange(N) + 0.5) * RES
    ys = ORIGIN[1] + (np.arange(N) + 0.5) * RES
    x, y = np.meshgrid(xs, ys, indexing="ij")
    inside = (np.abs(x - 0.5) < width / 2) & (y < until_y)
    heights = np.where(inside, -0.3, 0.0)
    if hidden:
        inner = (np.abs(x - 0.5) < width / 2 - RES) & (y < until_y)
        heights[inner] = np.nan
    known = np.isfinite(heights)
    zeros = np.zeros((N, N))
    return MapUpdate(
        stamp=0.0,
        sequence=1,
        heights=heights,
        known=known,
        spread=None,
        slope=zeros,
        proximity=zeros,
        score=zeros,
        valid=known & ~inside,
        origin=ORIGIN,
        resolution=RES,
    )


def _route(update: MapUpdate, max_gap_m: float = STEP) -> Route | NoRoute:
    grid = cost_grid(update, TraversabilityConfig(), SPAN, max_gap_m=max_gap_m)
    return plan_route(grid, (-0.6, 0.0), (1.7, 0.0), NavigationConfig().for_robot(SPEC))


def test_the_longest_gap_is_the_stride_and_the_search_reach():
    """The default robot's stride (0.15 m) and the foothold search (0.16 m): 0.31 m."""
    assert STEP == pytest.approx(SPEC.stride_length + FootholdConfig().search_radius)
    assert STEP == pytest.approx(0.31)


@pytest.mark.parametrize("hidden", [False, True])
def test_a_trench_wider_than_a_step_closes_the_way_and_a_narrower_one_does_not(hidden):
    """A trench across the whole way a fifth narrower than the longest step is crossed
    straight on; one a fifth wider leaves no route (the robot stands and says why rather
    than freezing at its edge), seen whole or with its floor hidden. Without the rule the
    wide trench would be walked into: the gap rule is what decides."""
    narrow = _route(_trench(0.8 * STEP, hidden))
    assert isinstance(narrow, Route)
    assert np.abs(narrow.points_in_world[:, 1]).max() < 0.05
    wide = _route(_trench(1.2 * STEP, hidden))
    assert isinstance(wide, NoRoute)
    assert "no route" in wide.reason
    assert isinstance(_route(_trench(1.2 * STEP, hidden), max_gap_m=math.inf), Route)


def test_a_wide_trench_with_a_way_round_is_gone_round():
    """The same wide trench ending at y = 0.4 m: the body centre passes beyond its end,
    never over it."""
    route = _route(_trench(1.2 * STEP, hidden=True, until_y=0.4))
    assert isinstance(route, Route)
    p = route.points_in_world
    samples = np.concatenate(
        [a + np.linspace(0, 1, 40)[:, None] * (b - a) for a, b in itertools.pairwise(p)]
    )
    over = np.abs(samples[:, 0] - 0.5) < 0.6 * STEP
    assert over.any() and samples[over, 1].min() > 0.4


def test_the_edge_of_what_was_seen_is_no_gap():
    """Ground seen up to a line and nothing beyond (the view's edge, or a block's shadow
    with ground beyond it), ground the scorer finds no foothold on at the robot's level,
    and a long unseen stretch between a rim and a drop far off (beyond the top of a flight
    of stairs): no gap, the unseen cells stay passable."""
    update = _trench(0.0)
    heights = update.heights.copy()
    heights[100:, :] = np.nan
    heights[60:70, 40:60] = np.nan
    heights[148:, :] = -0.5  # a drop seen at the window's far end, 1 m past the rim
    known = np.isfinite(heights)
    valid = known & (heights > -0.1)
    valid[20:45, 20:45] = False  # half a metre of noisy ground
    valid[97:100, :] = False  # the rim before the unseen stretch
    unseen = MapUpdate(**{**update.__dict__, "heights": heights, "known": known, "valid": valid})
    grid = cost_grid(unseen, TraversabilityConfig(), SPAN, max_gap_m=STEP)
    assert not grid.gap[:148].any()
    assert not grid.lethal[:120].any()


def test_a_deep_pit_the_feet_step_round_is_no_gap():
    """A square pit 0.45 m a side, 30 cm deep, wider than a step but shorter than the legs'
    span: the feet step aside round it, so it is no gap; a trench of the same width
    running 1 m is one."""
    xs = ORIGIN[0] + (np.arange(N) + 0.5) * RES
    x, y = np.meshgrid(xs, xs, indexing="ij")
    for half_length, is_gap in ((0.225, False), (0.5, True)):
        inside = (np.abs(x - 0.5) < 0.225) & (np.abs(y - 0.3) < half_length)
        heights = np.where(inside, -0.3, 0.0)
        update = _trench(0.0)
        pit = MapUpdate(**{**update.__dict__, "heights": heights, "valid": ~inside})
        grid = cost_grid(pit, TraversabilityConfig(), SPAN, max_gap_m=STEP)
        assert grid.gap.any() == is_gap


def _shadowed_by_hand(known, usable, deep, max_run):
    out = np.zeros_like(known)
    for flip in (False, True):
        k, u, d = (a.T if flip else a for a in (known, usable, deep))
        rows, cols = k.shape
        for i in range(rows):
            for j in range(cols):
                if k[i, j]:
                    continue
                left = [c for c in range(j) if k[i, c]]
                right = [c for c in range(j + 1, cols) if k[i, c]]
                if not (left and right) or right[0] - left[-1] - 1 > max_run:
                    continue
                ends = (left[-1], right[0])
                if not any(u[i, c] for c in ends) and any(d[i, c] for c in ends):
                    out[(j, i) if flip else (i, j)] = True
    return out


@given(
    seed=st.integers(0, 2**32 - 1),
    shape=st.tuples(st.integers(1, 12), st.integers(1, 12)),
    shares=st.tuples(st.floats(0.0, 1.0), st.floats(0.0, 1.0), st.floats(0.0, 1.0)),
    max_run=st.integers(0, 12),
)
@settings(max_examples=200, deadline=None)
def test_hidden_trench_cells_are_found_as_a_scan_finds_them(seed, shape, shares, max_run):
    """An unseen cell is taken as inside a trench exactly when, along its row or its
    column, it lies in an unseen run of at most ``max_run`` cells whose nearest seen cells
    on both sides are no foothold and one of them deep: the same as scanning each line."""
    rng = np.random.default_rng(seed)
    known = rng.random(shape) < shares[0]
    usable = known & (rng.random(shape) < shares[1])
    deep = known & ~usable & (rng.random(shape) < shares[2])
    assert np.array_equal(
        _shadowed(known, usable, deep, max_run), _shadowed_by_hand(known, usable, deep, max_run)
    )
