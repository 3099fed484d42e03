"""Route planning for the hexapod: the cost grid, the search, following, the navigator node."""

from __future__ import annotations

import itertools
import math
import time

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st
from scipy.sparse import lil_matrix
from scipy.sparse.csgraph import dijkstra as scipy_dijkstra

from footfall.messages import GaitState, GaitStatus, MapUpdate, Mode, WalkCommand
from footfall.nodes.navigation import NavigatorNode
from footfall.planning import traversability
from footfall.planning.footholds import FootholdConfig
from footfall.planning.navigation import NavigationConfig, NoRoute, Route, follow_route, plan_route
from footfall.planning.route_kernels import dijkstra, segment_points, taut_indices
from footfall.planning.traversability import (
    TraversabilityConfig,
    cost_grid,
    longest_gap,
    span_radius,
)
from footfall.robot.planar import PlanarPose
from footfall.robot.spec import load_spec
from footfall.runtime.bus import InProcessBus
from footfall.scoring.walkability import score_heights

RES = 0.02
SPEC = load_spec("default")
SPAN = span_radius(SPEC)


def _update(heights: np.ndarray, origin=(-1.0, -1.0), known=None, sequence=1) -> MapUpdate:
    """A map update scored by the real scorer; ``known`` False cells are unseen."""
    h = np.array(heights, dtype=np.float64)
    if known is not None:
        h[~known] = np.nan
    slope, proximity, score, valid = score_heights(h, RES)
    return MapUpdate(
        stamp=0.0,
        sequence=sequence,
        heights=h,
        known=np.isfinite(h),
        spread=None,
        slope=slope,
        proximity=proximity,
        score=score,
        valid=valid,
        origin=origin,
        resolution=RES,
    )


def _grid_xy(n=150, origin=(-1.0, -1.0)):
    xs = origin[0] + (np.arange(n) + 0.5) * RES
    ys = origin[1] + (np.arange(n) + 0.5) * RES
    return np.meshgrid(xs, ys, indexing="ij")


def _with_box(heights, x, y, cx, cy, half, top):
    inside = (np.abs(x - cx) <= half) & (np.abs(y - cy) <= half)
    return np.where(inside, top, heights)


@given(st.integers(0, 2**32 - 1), st.integers(2, 9), st.integers(2, 9), st.floats(0.0, 0.4))
@settings(max_examples=60, deadline=None)
def test_the_search_finds_the_least_route_cost_to_every_cell(seed, rows, cols, lethal_share):
    """Dijkstra over the 8-connected grid against SciPy's on the same graph (move cost:
    length times the mean of the two cells' costs; lethal cells cannot be entered)."""
    rng = np.random.default_rng(seed)
    cost = rng.uniform(1.0, 5.0, (rows, cols))
    cost[rng.random((rows, cols)) < lethal_share] = np.inf
    cost[0, 0] = rng.uniform(1.0, 5.0)
    distance = np.empty((rows, cols))
    parent = np.empty((rows, cols), dtype=np.int64)
    dijkstra(cost, 0, 0, RES, distance, parent)
    graph = lil_matrix((rows * cols, rows * cols))
    for i in range(rows):
        for j in range(cols):
            for di in (-1, 0, 1):
                for dj in (-1, 0, 1):
                    ni, nj = i + di, j + dj
                    if (di or dj) and 0 <= ni < rows and 0 <= nj < cols:
                        if np.isfinite(cost[i, j]) and np.isfinite(cost[ni, nj]):
                            length = math.hypot(di, dj) * RES
                            graph[i * cols + j, ni * cols + nj] = (
                                length * 0.5 * (cost[i, j] + cost[ni, nj])
                            )
    expected = scipy_dijkstra(graph.tocsr(), indices=0).reshape(rows, cols)
    np.testing.assert_allclose(distance, expected, rtol=1e-9)
    # Following the parents from any reached cell ends at the start.
    for i, j in zip(*np.nonzero(np.isfinite(distance)), strict=True):
        flat, hops = i * cols + j, 0
        while parent.flat[flat] >= 0:
            flat, hops = int(parent.flat[flat]), hops + 1
            assert hops <= rows * cols
        assert flat == 0


@given(
    st.integers(0, 2**32 - 1),
    st.integers(1, 30),
    st.integers(1, 30),
    st.integers(0, 12),
    st.floats(0.0, 1.0),
)
@settings(max_examples=60, deadline=None)
def test_the_wall_tops_in_reach_are_the_octagon_the_repeated_filters_grow(
    seed, rows, cols, radius, empty
):
    """The compiled octagon maximum equals ``radius`` alternating 3 x 3 cross and square
    maximum filters, the grid's sides included."""
    from scipy import ndimage

    rng = np.random.default_rng(seed)
    a = rng.normal(0.0, 0.1, (rows, cols))
    a[rng.random((rows, cols)) < empty] = -np.inf
    square = np.ones((3, 3), dtype=bool)
    cross = np.array([[0, 1, 0], [1, 1, 1], [0, 1, 0]], dtype=bool)
    expected = a
    for k in range(radius):
        expected = ndimage.maximum_filter(
            expected, footprint=square if k % 2 else cross, mode="nearest"
        )
    np.testing.assert_array_equal(traversability._disc_max(a, radius), expected)


@given(st.integers(0, 2**32 - 1), st.integers(1, 4), st.floats(0.05, 1.0))
@settings(max_examples=40, deadline=None)
def test_the_ground_median_is_that_of_the_valid_heights_in_the_window(seed, half_sub, share):
    """Away from the map's sides, each cell's ground is the median of the valid heights on
    the sampled cells of its window; a window with none valid is infinite."""
    rng = np.random.default_rng(seed)
    n, step = 40, traversability.MEDIAN_STRIDE
    heights = rng.normal(0.0, 0.1, (n, n))
    valid = rng.random((n, n)) < share
    ground = traversability._masked_median(heights, valid, half_sub * step)
    sub_h, sub_v = heights[::step, ::step], valid[::step, ::step]
    for a in range(half_sub, sub_h.shape[0] - half_sub):
        for b in range(half_sub, sub_h.shape[1] - half_sub):
            window = np.s_[a - half_sub : a + half_sub + 1, b - half_sub : b + half_sub + 1]
            v = sub_h[window][sub_v[window]]
            g = ground[a * step : (a + 1) * step, b * step : (b + 1) * step]
            expected = np.median(v) if v.size else np.inf
            assert np.allclose(g, expected, rtol=0, atol=1e-12)


def test_a_tall_box_is_lethal_within_the_legs_span_and_a_low_step_is_not():
    """A 30 cm block rules out every body position whose legs would reach it; a 5 cm step
    costs nothing extra: the legs climb it."""
    x, y = _grid_xy()
    flat = np.zeros_like(x)
    grid = cost_grid(
        _update(_with_box(flat, x, y, 0.5, 0.5, 0.15, 0.3)), TraversabilityConfig(), SPAN
    )
    d = np.hypot(np.maximum(np.abs(x - 0.5) - 0.15, 0), np.maximum(np.abs(y - 0.5) - 0.15, 0))
    assert grid.lethal[d < SPAN - 2 * RES].all()
    assert not grid.lethal[d > SPAN + 3 * RES].any()
    step = cost_grid(_update(np.where(x > 0.4, 0.05, 0.0)), TraversabilityConfig(), SPAN)
    assert not step.lethal.any()


@pytest.mark.parametrize("width", [0.05, 0.10, 0.15])
def test_a_deep_narrow_trench_is_straddled_and_a_wide_pit_is_not(width):
    """The rim of a trench 30 cm deep, narrower than a step, is at the robot's own level: a
    body centred over it is not in a wall (its feet find the platforms), even where the
    scorer leaves nothing valid under the body; a pit wider than the legs' span is neither
    walked into nor over, but round."""
    x, y = _grid_xy()
    trench = np.where(np.abs(x - 0.5) <= width / 2, -0.3, 0.0)
    step = longest_gap(SPEC, FootholdConfig().search_radius)
    grid = cost_grid(_update(trench), TraversabilityConfig(), SPAN, max_gap_m=step)
    assert np.isfinite(grid.cost[np.abs(x - 0.5) < 0.03]).all()
    pit = np.where(np.hypot(x - 0.5, y - 0.5) <= 0.6, -0.3, 0.0)
    wide = cost_grid(_update(pit), TraversabilityConfig(), SPAN)
    into = plan_route(wide, (-0.8, 0.5), (0.5, 0.5), NavigationConfig().for_robot(SPEC))
    assert isinstance(into, NoRoute)
    past = plan_route(wide, (-0.8, 0.5), (1.8, 0.5), NavigationConfig().for_robot(SPEC))
    assert isinstance(past, Route)
    p = past.points_in_world
    samples = np.concatenate(
        [a + np.linspace(0, 1, 40)[:, None] * (b - a) for a, b in itertools.pairwise(p)]
    )
    assert np.hypot(samples[:, 0] - 0.5, samples[:, 1] - 0.5).min() > 0.6


@given(st.integers(0, 2**32 - 1), st.integers(1, 25), st.integers(1, 25), st.integers(0, 9))
@settings(max_examples=60, deadline=None)
def test_enclosed_unseen_cells_are_those_a_walk_along_rows_and_columns_finds(
    seed, rows, cols, max_run
):
    """Against a walk from each unseen cell to the nearest seen cells either way along its
    row and its column: enclosed when both are seen without a foothold, one deep, and the
    run between them is at most ``max_run`` long."""
    rng = np.random.default_rng(seed)
    known = rng.random((rows, cols)) < rng.random()
    usable = known & (rng.random((rows, cols)) < rng.random())
    deep = known & (rng.random((rows, cols)) < 0.3)
    got = traversability._shadowed(known, usable, deep, max_run)
    expected = np.zeros_like(known)
    for i, j in zip(*np.nonzero(~known), strict=True):
        for di, dj in ((0, 1), (1, 0)):
            ends = []
            for sign in (-1, 1):
                a, b = i, j
                while 0 <= a < rows and 0 <= b < cols and not known[a, b]:
                    a, b = a + sign * di, b + sign * dj
                ends.append((a, b) if 0 <= a < rows and 0 <= b < cols else None)
            if None in ends:
                continue
            run = max(ends[1][0] - ends[0][0], ends[1][1] - ends[0][1]) - 1
            bare = not usable[ends[0]] and not usable[ends[1]]
            expected[i, j] |= run <= max_run and bare and (deep[ends[0]] or deep[ends[1]])
    np.testing.assert_array_equal(got, expected)


def test_unknown_ground_is_passable_but_dearer_than_seen_ground():
    """Unseen cells cost more per metre than seen flat ones, and are never lethal."""
    x, _ = _grid_xy()
    grid = cost_grid(_update(np.zeros_like(x), known=x < 0.5), TraversabilityConfig(), SPAN)
    assert not grid.lethal.any()
    assert grid.cost[x > 1.2].min() > grid.cost[x < 0.0].max()


@given(st.integers(0, 2**32 - 1), st.integers(1, 6))
@example(seed=3628800, boxes=4)  # a shortcut that clipped a lethal cell's corner
@settings(max_examples=25, deadline=None)
def test_a_route_never_enters_a_lethal_cell(seed, boxes):
    """Among random tall blocks, every point along the route (sampled finely) lies on a
    cell the body may occupy, and the route ends at the goal when there is one."""
    rng = np.random.default_rng(seed)
    x, y = _grid_xy()
    h = np.zeros_like(x)
    for _ in range(boxes):
        h = _with_box(
            h, x, y, rng.uniform(0.3, 1.6), rng.uniform(-0.6, 1.6), rng.uniform(0.05, 0.2), 0.3
        )
    grid = cost_grid(_update(h), TraversabilityConfig(), SPAN)
    start, goal = (-0.7, 0.5), (1.7, 0.5)
    route = plan_route(grid, start, goal, NavigationConfig().for_robot(SPEC))
    start_cell = grid.cell_of(start)
    if isinstance(route, NoRoute):
        assert "goal" in route.reason
        return
    assert np.linalg.norm(route.points_in_world[-1] - goal) <= 0.1
    p = route.points_in_world
    for a, b in itertools.pairwise(p):
        for u in np.linspace(0, 1, 50):
            cell = grid.cell_of(a + u * (b - a))
            if np.hypot(*(a + u * (b - a) - start)) > 0.3 or np.isfinite(grid.cost[start_cell]):
                assert np.isfinite(grid.cost[cell]), f"route through lethal cell {cell}"


def test_a_wall_is_gone_round_and_an_enclosed_goal_has_no_route():
    """A wall across the straight line with a way round: the route leaves the line; the
    same goal walled in on every side: no route, and the reason says so."""
    x, y = _grid_xy()
    wall = np.where((np.abs(x - 0.5) <= 0.05) & (y < 1.1), 0.3, 0.0)
    grid = cost_grid(_update(wall), TraversabilityConfig(), SPAN)
    route = plan_route(grid, (-0.5, 0.0), (1.5, 0.0), NavigationConfig().for_robot(SPEC))
    assert isinstance(route, Route)
    assert route.points_in_world[:, 1].max() > 1.1 + SPAN - 0.05
    pen = np.where(
        (np.maximum(np.abs(x - 1.2), np.abs(y - 0.5)) <= 0.75)
        & (np.maximum(np.abs(x - 1.2), np.abs(y - 0.5)) >= 0.65),
        0.3,
        0.0,
    )
    closed = cost_grid(_update(pen), TraversabilityConfig(), SPAN)
    result = plan_route(closed, (-0.7, 0.5), (1.2, 0.5), NavigationConfig().for_robot(SPEC))
    assert isinstance(result, NoRoute)
    assert "no route" in result.reason or "cannot stand" in result.reason


def test_a_goal_beyond_the_map_is_headed_for_over_its_edge():
    """An off-map goal: the route leaves the window towards it and ends at the goal."""
    x, _ = _grid_xy()
    grid = cost_grid(_update(np.zeros_like(x)), TraversabilityConfig(), SPAN)
    route = plan_route(grid, (0.0, 0.5), (6.0, 0.5), NavigationConfig().for_robot(SPEC))
    assert isinstance(route, Route) and not route.goal_on_map
    np.testing.assert_allclose(route.points_in_world[-1], (6.0, 0.5))
    assert route.points_in_world[-2, 0] > 1.9  # the window's far edge


@given(st.floats(-math.pi, math.pi), st.floats(0.05, 2.0), st.floats(-math.pi, math.pi))
@settings(max_examples=100, deadline=None)
def test_following_turns_towards_the_route_and_walks_only_when_facing_it(yaw, distance, bearing):
    """The yaw rate has the sign of the heading error; past the turn-in-place angle the
    robot only turns; within it the command walks towards the aim point."""
    config = NavigationConfig()
    pose = PlanarPose(0.0, 0.0, yaw)
    end = (distance * math.cos(bearing), distance * math.sin(bearing))
    route = Route(np.array([[0.0, 0.0], end]), 1.0, True)
    command = follow_route(route, pose, WalkCommand(speed=0.1), config, 0.0)
    error = math.atan2(math.sin(bearing - yaw), math.cos(bearing - yaw))
    if abs(error) > 1e-3:
        assert math.copysign(1, command.yaw_rate) == math.copysign(1, error)
    if abs(error) > config.turn_in_place_rad:
        assert command.speed == 0.0
    else:
        vx, vy = command.velocity_in_body
        heading_in_world = yaw + math.atan2(vy, vx)
        assert abs(math.remainder(heading_in_world - bearing, 2 * math.pi)) < 1e-6
        assert command.speed > 0.0


def _status(t: float, pose: PlanarPose, state=GaitState.STEPPING) -> GaitStatus:
    return GaitStatus(t, Mode.WALKING, state, "", "", pose, 0.09, 0, 0, 0.0)


def test_the_navigator_stands_still_without_a_route_and_goes_when_one_opens():
    """Walled in: after a few replans the command is to stand still, with the reason
    logged; the wall gone, the robot walks again."""
    x, y = _grid_xy()
    pen = np.where(np.maximum(np.abs(x - 0.5), np.abs(y - 0.5)) >= 0.9, 0.3, 0.0)
    bus = InProcessBus()
    logs = []
    bus.subscribe("log", logs.append)
    config = NavigationConfig(replan_period_s=0.1)
    navigator = NavigatorNode(bus, SPEC, (3.0, 0.5), config)
    pose, base = PlanarPose(0.5, 0.5, 0.0), WalkCommand(speed=0.1)
    t, sequence = 0.0, 1
    for _ in range(config.confirm_no_route + 1):
        bus.publish(MapUpdate.TOPIC, _update(pen, sequence=sequence))
        command = navigator.command(t, _status(t, pose), base)
        t, sequence = t + 0.2, sequence + 1
    assert navigator.no_route is not None
    assert command.speed == 0.0 and command.yaw_rate == 0.0
    assert any("standing still" in line.text for line in logs)
    bus.publish(MapUpdate.TOPIC, _update(np.zeros_like(x), sequence=sequence))
    command = navigator.command(t, _status(t, pose), base)
    assert navigator.no_route is None and navigator.route is not None
    assert command.speed > 0.0
    navigator.close()


def test_an_unchanged_map_without_a_route_is_confirmed_and_said():
    """One map, walled in, that never changes (a robot standing still with nothing new in
    view): the navigator plans on it again each period, confirms there is no route and says
    why, rather than waiting for a new map that would not come."""
    x, y = _grid_xy()
    pen = np.where(np.maximum(np.abs(x - 0.5), np.abs(y - 0.5)) >= 0.9, 0.3, 0.0)
    bus = InProcessBus()
    config = NavigationConfig(replan_period_s=0.1)
    navigator = NavigatorNode(bus, SPEC, (3.0, 0.5), config)
    bus.publish(MapUpdate.TOPIC, _update(pen))
    pose, base = PlanarPose(0.5, 0.5, 0.0), WalkCommand(speed=0.1)
    for k in range(10 * config.confirm_no_route):
        command = navigator.command(0.05 * k, _status(0.05 * k, pose), base)
    assert navigator.no_route is not None and "closed" in navigator.no_route.reason
    assert command.speed == 0.0
    navigator.close()


def _frozen(t: float, pose: PlanarPose, leg: str) -> GaitStatus:
    reason = f"leg {leg}: no valid, reachable and stable cell within 0.16 m"
    return GaitStatus(t, Mode.WALKING, GaitState.FROZEN, reason, leg, pose, 0.09, 0, 0, 0.0)


def test_a_walker_stuck_where_a_foot_has_not_looked_turns_to_look_once():
    """Flat ground seen only ahead and to the left: a robot facing +x whose right middle
    foot finds no foothold (its place unseen) keeps retrying and freezing; the navigator
    counts it stuck across the retries, turns it on the spot to face that place until it
    does, then follows the route again. Stuck at the same place again, it does not look a
    second time but keeps the ground ahead out of the route."""
    x, y = _grid_xy()
    seen = y > -0.1  # the right-hand side of the robot (y < 0) never came into view
    bus = InProcessBus()
    logs = []
    bus.subscribe("log", logs.append)
    navigator = NavigatorNode(bus, SPEC, (2.0, 0.0), NavigationConfig(blocked_after_s=1.0))
    bus.publish(MapUpdate.TOPIC, _update(np.zeros_like(x), known=seen))
    pose, base = PlanarPose(0.0, 0.0, 0.0), WalkCommand(speed=0.1)
    t = 0.0
    while t < 1.4:  # freezes, retries on fresh maps, freezes again, never moving
        frozen = int(t / 0.3) % 2 == 0
        status = _frozen(t, pose, "RM") if frozen else _status(t, pose)
        command = navigator.command(t, status, base)
        t += 0.05
    assert navigator.stuck.looks == 1
    assert any("RM has not seen where it steps" in line.text for line in logs)
    place = navigator.stuck.looked[0]
    assert place[1] < -0.1  # the right middle foot's place, on the unseen side
    facing = math.atan2(place[1] - pose.y, place[0] - pose.x)
    assert command.speed == 0.0 and command.yaw_rate < 0.0  # turning right, on the spot
    bus.publish(MapUpdate.TOPIC, _update(np.zeros_like(x), sequence=2))  # the look shows it
    while command.speed == 0.0 and command.yaw_rate < 0.0:
        pose = PlanarPose(0.0, 0.0, pose.yaw + command.yaw_rate * 0.05)
        command = navigator.command(t, _status(t, pose), base)
        t += 0.05
        assert t < 20.0
    assert abs(pose.yaw - facing) < math.radians(11.0)
    assert navigator.route is not None and command.yaw_rate > 0.0  # back towards the goal
    for _ in range(30):
        command = navigator.command(t, _frozen(t, pose, "RM"), base)
        t += 0.05
    assert navigator.stuck.looks == 1 and navigator.stuck.blocked_count == 1
    navigator.close()


def test_a_background_replan_leaves_the_command_tick_free():
    """On a worker thread a replan never holds up a command: each returns at once (the
    first ones standing still until the route comes), and the route arrives."""
    x, _ = _grid_xy(256, origin=(-2.56, -2.56))
    bus = InProcessBus()
    navigator = NavigatorNode(bus, SPEC, (2.0, 0.0), NavigationConfig(), background=True)
    bus.publish(MapUpdate.TOPIC, _update(np.zeros_like(x), origin=(-2.56, -2.56)))
    pose, base = PlanarPose(0.0, 0.0, 0.0), WalkCommand(speed=0.1)
    navigator.command(0.0, _status(0.0, pose), base)  # warm up the compiled search
    longest, deadline = 0.0, time.monotonic() + 30.0
    t = 0.0
    while navigator.route is None and time.monotonic() < deadline:
        t += 0.01
        start = time.perf_counter()
        navigator.command(t, _status(t, pose), base)
        longest = max(longest, time.perf_counter() - start)
        time.sleep(0.001)
    navigator.close()
    assert navigator.route is not None
    assert navigator.replans >= 1
    assert longest < min(navigator.plan_seconds), "a command waited for a replan"


def test_navigation_settings_are_checked():
    """Bad settings name what is wrong."""
    with pytest.raises(Exception, match="switch_margin"):
        NavigationConfig(switch_margin=1.5)
    with pytest.raises(Exception, match="max_unsupported"):
        TraversabilityConfig(max_unsupported=0.0)


def test_a_wall_stays_remembered_until_its_cells_are_seen_flat():
    """A face that a later frame leaves only its foot as height is still a wall (the
    navigator remembers it); once the cells are seen flat it is forgotten."""
    from footfall.nodes.navigation import WallMemory
    from footfall.planning.traversability import wall_faces

    x, _ = _grid_xy()
    wall = np.where(np.abs(x - 0.5) <= 0.03, 0.3, 0.0)
    memory = WallMemory()
    memory.note(_update(wall), wall_faces(_update(wall), TraversabilityConfig()))
    assert len(memory) > 0
    foot = _update(np.zeros_like(x))
    foot = MapUpdate(**{**foot.__dict__, "spread": np.where(np.abs(x - 0.5) <= 0.03, 0.25, 0.0)})
    held = cost_grid(foot, TraversabilityConfig(), SPAN, memory.window(foot))
    assert held.lethal[np.abs(x - 0.5) < 0.1].all()
    memory.forget_flat(held)
    seen_flat = _update(np.zeros_like(x), sequence=3)
    memory.forget_flat(cost_grid(seen_flat, TraversabilityConfig(), SPAN, memory.window(seen_flat)))
    assert len(memory) == 0


def test_the_navigator_keeps_a_wall_seen_only_between_its_replans():
    """A map update that shows a wall's face, then one whose grazing view leaves only the
    face's foot (and its spread): the replan on the second still finds the wall lethal,
    though the navigator never planned on the first."""
    x, _ = _grid_xy()
    band = np.abs(x - 0.5) <= 0.03
    bus = InProcessBus()
    navigator = NavigatorNode(bus, SPEC, (2.0, 0.0), NavigationConfig())
    bus.publish(MapUpdate.TOPIC, _update(np.where(band, 0.3, 0.0), sequence=1))
    foot = _update(np.zeros_like(x), sequence=2)
    bus.publish(
        MapUpdate.TOPIC, MapUpdate(**{**foot.__dict__, "spread": np.where(band, 0.25, 0.0)})
    )
    pose = PlanarPose(0.0, 0.0, 0.0)
    navigator.command(0.0, _status(0.0, pose), WalkCommand(speed=0.1))
    assert navigator.replans == 1 and navigator.grid is not None
    assert navigator.grid.lethal[np.abs(x - 0.5) < 0.1].all()
    navigator.close()


@given(st.tuples(*[st.floats(-0.9, 1.9) for _ in range(4)]))
@settings(max_examples=200, deadline=None)
@example(coords=(0.0, 0.0, 1.0, 0.5))
def test_a_segment_visits_every_cell_it_crosses(coords):
    """Each cell a straight segment passes through (found by sampling it densely) is one
    of the cells the line-of-sight check looks at, corners clipped included."""
    x, _ = _grid_xy()
    grid = cost_grid(_update(np.zeros_like(x)), TraversabilityConfig(), SPAN)
    a, b = np.array(coords[:2]), np.array(coords[2:])
    visited = {grid.cell_of(p) for p in _segment_points(grid, a, b)}
    dense = a + np.linspace(0.0, 1.0, 5001)[:, None] * (b - a)
    # A sample on a grid line (to rounding) touches a cell only at its edge or corner.
    in_cells = (dense - np.asarray(grid.origin)) / grid.resolution
    off_lines = np.all(np.abs(in_cells - np.round(in_cells)) > 1e-6, axis=1)
    assert {grid.cell_of(p) for p in dense[off_lines]} <= visited


def _segment_points(grid, a, b):
    (ox, oy), res = grid.origin, grid.resolution
    return segment_points(ox, oy, res, a[0], a[1], b[0], b[1])


def reference_taut(cost, origin, resolution, points):
    """String pulling as plain NumPy, point by point (what the compiled kernel must keep)."""

    def cost_at(xy):
        ij = np.floor((xy - np.asarray(origin)) / resolution).astype(np.int64)
        n, m = cost.shape
        on = (ij[:, 0] >= 0) & (ij[:, 0] < n) & (ij[:, 1] >= 0) & (ij[:, 1] < m)
        out = np.full(len(xy), np.inf)
        out[on] = cost[ij[on, 0], ij[on, 1]]
        return out

    def cells_on(a, b):  # a point in every cell the segment crosses, from its grid lines
        u, v = (a - np.asarray(origin)) / resolution, (b - np.asarray(origin)) / resolution
        cuts = [np.array([0.0, 1.0])]
        for k in range(2):
            if abs(v[k] - u[k]) > 1e-12:
                lo, hi = sorted((u[k], v[k]))
                lines = np.arange(math.floor(lo) + 1, math.ceil(hi))
                cuts.append((lines - u[k]) / (v[k] - u[k]))
        t = np.unique(np.clip(np.concatenate(cuts), 0.0, 1.0))
        t = np.concatenate([[0.0], 0.5 * (t[:-1] + t[1:]), [1.0]])
        return a + t[:, None] * (b - a)

    along = cost_at(points)
    kept, i = [0], 0
    while i < len(points) - 1:
        best = i + 1
        for j in range(i + 2, len(points)):
            worst = float(np.max(along[i : j + 1]))
            line = cost_at(cells_on(points[i], points[j]))
            if not (np.all(np.isfinite(line)) and float(np.max(line)) <= worst + 1e-9):
                break
            best = j
        kept.append(best)
        i = best
    return kept


@settings(max_examples=150, deadline=None)
@given(
    costs=st.lists(
        st.sampled_from([1.0, 1.0, 1.0, 1.5, 2.0, np.inf, np.nan]), min_size=400, max_size=400
    ),
    steps=st.lists(st.integers(0, 7), min_size=1, max_size=40),
    start=st.tuples(st.integers(0, 19), st.integers(0, 19)),
    origin=st.tuples(st.floats(-2.0, 2.0), st.floats(-2.0, 2.0)),
    resolution=st.sampled_from([0.02, 0.05, 0.1]),
)
def test_compiled_string_pulling_keeps_the_points_the_plain_rule_keeps(
    costs, steps, start, origin, resolution
):
    """On any cost grid (cheap, dear, lethal and unknown cells) and any 8-connected path of
    cell centres, leaving the grid or not, the kernel keeps exactly the reference's points."""
    cost = np.array(costs).reshape(20, 20)
    moves = [(1, 0), (-1, 0), (0, 1), (0, -1), (1, 1), (1, -1), (-1, 1), (-1, -1)]
    cells = [start]
    for k in steps:
        cells.append((cells[-1][0] + moves[k][0], cells[-1][1] + moves[k][1]))
    points = np.asarray(origin) + (np.array(cells, dtype=np.float64) + 0.5) * resolution
    kept = taut_indices(cost, origin[0], origin[1], resolution, points)
    assert kept.tolist() == reference_taut(cost, origin, resolution, points)


@settings(max_examples=60, deadline=None)
@given(
    tops=st.dictionaries(
        st.tuples(st.integers(-40, 40), st.integers(-40, 40)), st.floats(0.0, 1.0), max_size=60
    ),
    flat=st.integers(0, 2**32 - 1),
    origin=st.tuples(st.integers(-30, 30), st.integers(-30, 30)),
)
def test_forgetting_flat_cells_is_the_cell_by_cell_rule(tops, flat, origin):
    """Remembered walls go exactly where the grid shows flat cells, wherever its window
    lies: the same as visiting every flat cell of the grid."""
    from types import SimpleNamespace

    from footfall.nodes.navigation import WallMemory

    resolution = 0.02
    flat_cells = np.random.default_rng(flat).random((32, 24)) < 0.5
    grid = SimpleNamespace(
        origin=(origin[0] * resolution, origin[1] * resolution),
        resolution=resolution,
        flat=flat_cells,
    )
    memory = WallMemory()
    memory._tops = dict(tops)
    memory.forget_flat(grid)
    expected = dict(tops)
    for i, j in zip(*np.nonzero(flat_cells), strict=True):
        expected.pop((int(i) + origin[0], int(j) + origin[1]), None)
    assert memory._tops == expected
