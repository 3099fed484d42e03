"""The terrain planner: footholds planned together with the body height."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from footfall.mapping.snapshot import MapSnapshot
from footfall.planning.footholds import FootholdConfig
from footfall.planning.step_plan import NoFoothold, StepPoses
from footfall.planning.terrain_planner import TerrainPlanner, TerrainPlannerConfig
from footfall.robot.kinematics import LegKinematics
from footfall.robot.planar import PlanarPose
from footfall.robot.spec import load_spec
from footfall.scoring.walkability import score_map

RES = 0.02
FRONT = np.array([True, False, False, False, False, True])  # LF and RF swing
SUPPORT_AFTER = np.array([True, False, True, True, False, True])  # a ripple-like support


def _planner(
    spec, heights: np.ndarray, config: TerrainPlannerConfig | None = None
) -> TerrainPlanner:
    """A planner over a map with the given heights; cell [0, 0] has its corner at (-1, -1)."""
    snapshot = MapSnapshot(
        heights=heights,
        known=np.isfinite(heights),
        origin=(-1.0, -1.0),
        resolution=RES,
        spread=np.zeros_like(heights),
    )
    planner = TerrainPlanner(spec, config)
    planner.update(snapshot, score_map(snapshot))
    return planner


def _ledge(drop: float, edge_x: float) -> np.ndarray:
    """Flat ground at 0 for x < edge_x, ``-drop`` beyond (a step down)."""
    x = -1.0 + (np.arange(100) + 0.5) * RES
    return np.where(x[:, None] < edge_x, 0.0, -drop) * np.ones((1, 100))


def _standing_feet(spec) -> np.ndarray:
    feet = spec.rest_feet_in_body()
    feet[:, 2] = spec.foot_radius
    return feet


def _poses() -> StepPoses:
    here = PlanarPose()
    return StepPoses(now=here, touchdown=here, liftoff=here, stable=(here,))


def test_a_step_down_is_reached_by_lowering_the_body(default_spec):
    """Front feet whose nominal footholds lie 12 cm down, beyond what the legs reach from the
    commanded height, get them: the plan allows only lower bodies, at which every foot
    (supporting and chosen) is reached."""
    spec = default_spec
    drop = 0.12
    planner = _planner(spec, _ledge(drop, edge_x=0.2))
    feet = _standing_feet(spec)
    nominal = feet.copy()
    nominal[FRONT, 0] += 0.06  # onto the lower level, well clear of the edge
    nominal[FRONT, 2] = spec.foot_radius - drop
    kin = LegKinematics(spec)
    high = spec.body_height + 0.05
    # From the high body the lower level is out of reach of the front legs.
    for leg in np.flatnonzero(FRONT):
        p = nominal[leg] - [0.0, 0.0, high]
        assert not kin.reachable(int(leg), p, planner.config.reach_margin)
    heights = high + np.arange(-0.08, 0.0001, 0.005)
    plan = planner.plan(nominal, FRONT, SUPPORT_AFTER, feet, _poses(), heights)
    assert not isinstance(plan, NoFoothold), plan
    assert plan.body_z.size and plan.body_z.max() < high
    for z in plan.body_z:
        for leg in range(6):
            p = plan.targets[leg] - [0.0, 0.0, z]
            assert kin.reachable(leg, p), (leg, z)
    # The chosen front footholds are on the lower level.
    np.testing.assert_allclose(plan.targets[FRONT, 2], spec.foot_radius - drop)


def test_a_leg_with_nowhere_to_go_steps_where_it_stands_only_when_the_body_stays(default_spec):
    """The right middle foot's nominal foothold lies on unseen ground. Turning on the spot
    (the body stays), the leg steps where it stands, on a valid cell; walking on (the body
    travels), the step has no foothold and says which leg."""
    spec = default_spec
    rm = spec.leg_names.index("RM")
    feet = _standing_feet(spec)
    y = -1.0 + (np.arange(100) + 0.5) * RES
    heights = np.zeros((100, 100))
    heights[:, y < feet[rm, 1] - 0.03] = np.nan  # unseen beyond the foot
    planner = _planner(spec, heights)
    swing = np.zeros(6, dtype=bool)
    swing[rm] = True
    nominal = feet.copy()
    nominal[rm, 1] -= 0.2  # where a turn or a sidestep would put it: unseen
    plan = planner.plan(nominal, swing, ~swing | swing, feet, _poses(), [spec.body_height])
    assert not isinstance(plan, NoFoothold), plan
    assert np.hypot(*(plan.targets[rm, :2] - feet[rm, :2])) < planner.config.footholds.search_radius
    i, j = ((plan.targets[rm, :2] - (-1.0)) // RES).astype(int)
    assert planner.scores.valid[i, j]
    ahead = PlanarPose(0.06, 0.0, 0.0)
    travelling = StepPoses(now=PlanarPose(), touchdown=ahead, liftoff=ahead, stable=(ahead,))
    refused = planner.plan(nominal, swing, ~swing | swing, feet, travelling, [spec.body_height])
    assert isinstance(refused, NoFoothold) and "leg RM" in refused.reason


def test_the_body_keeps_its_least_clearance(default_spec):
    """Terrain under the body rules out the heights that would bring the body within the
    least clearance; when none is left the plan names the problem."""
    spec = default_spec
    flat = np.zeros((100, 100))
    planner = _planner(spec, flat)
    feet = _standing_feet(spec)
    lowest = planner.config.min_body_clearance + 0.5 * spec.body_size[2]
    heights = np.arange(0.02, 0.2, 0.005)
    plan = planner.plan(feet, FRONT, SUPPORT_AFTER, feet, _poses(), heights)
    assert not isinstance(plan, NoFoothold), plan
    assert plan.body_z.min() >= lowest - 1e-9
    too_low = np.arange(0.0, lowest - 0.005, 0.005)
    reason = planner.plan(feet, FRONT, SUPPORT_AFTER, feet, _poses(), too_low)
    assert isinstance(reason, NoFoothold) and "above the terrain under it" in reason.reason


@given(st.floats(0.0, 0.1), st.floats(-0.05, 0.05))
@settings(max_examples=40, deadline=None)
def test_every_planned_height_reaches_every_foot(default_spec, drop, shift):
    """Whatever the terrain's step, each height the plan allows reaches every foot with the
    planner's margins; a plan that cannot says why."""
    spec = default_spec
    planner = _planner(spec, _ledge(drop, edge_x=0.1))
    feet = _standing_feet(spec)
    nominal = feet.copy()
    nominal[FRONT, 0] += shift
    heights = np.arange(0.04, 0.2, 0.005)
    plan = planner.plan(nominal, FRONT, SUPPORT_AFTER, feet, _poses(), heights)
    if isinstance(plan, NoFoothold):
        why = plan.reason
        assert why.startswith("leg ") or "body" in why or "supporting feet" in why
        assert plan.leg == (why.split()[1].rstrip(":") if why.startswith("leg ") else "")
        return
    kin = LegKinematics(spec)
    for z in plan.body_z:
        for leg in np.flatnonzero(FRONT):
            p = plan.targets[leg] - [0.0, 0.0, z]
            assert kin.reachable(int(leg), p, planner.config.reach_margin - 1e-9)
        for leg in np.flatnonzero(~FRONT):
            p = feet[leg] - [0.0, 0.0, z]
            assert kin.reachable(int(leg), p, 0.5 * planner.config.reach_margin - 1e-9)


def test_a_leg_left_nothing_by_the_legs_placed_before_it_is_placed_first():
    """Legs are placed one after another, each narrowing the body heights the next may use.
    A PhantomX's left front foot onto a 4 cm block, its right front foot into a 6 cm pit:
    placed in spec order (LF first), the block's foothold leaves only heights the pit is
    out of reach from; placed first, the right front foot's pit leaves the left one a
    foothold on the block, and every foot is reached at every height the plan allows."""
    spec = load_spec("phantomx")
    feet = _standing_feet(spec)
    x = -1.0 + (np.arange(100) + 0.5) * RES
    across, along = np.meshgrid(x, x, indexing="ij")
    heights = np.zeros((100, 100))
    block, pit = 0.04, 0.06
    lf, rf = feet[0], feet[5]
    heights[(abs(across - lf[0]) <= 0.04) & (abs(along - lf[1]) <= 0.04)] = block
    heights[(abs(across - rf[0]) <= 0.2) & (abs(along - rf[1]) <= 0.2)] = -pit
    planner = _planner(spec, heights)
    nominal = feet.copy()
    nominal[0, 2] += block
    nominal[5, 2] -= pit
    body_z = spec.body_height + np.arange(-0.1, 0.10001, 0.005)
    plan = planner.plan(nominal, FRONT, SUPPORT_AFTER, feet, _poses(), body_z)
    assert not isinstance(plan, NoFoothold), plan
    assert plan.targets[5, 2] == pytest.approx(spec.foot_radius - pit)
    kin = LegKinematics(spec)
    for z in plan.body_z:
        for leg in range(6):
            assert kin.reachable(leg, plan.targets[leg] - [0.0, 0.0, z]), (leg, z)


def test_no_map_no_plan(default_spec):
    """Before the camera has seen anything the planner says so."""
    planner = TerrainPlanner(default_spec)
    feet = _standing_feet(default_spec)
    reason = planner.plan(feet, FRONT, SUPPORT_AFTER, feet, _poses(), [0.09])
    assert isinstance(reason, NoFoothold) and "no map" in reason.reason


@pytest.mark.parametrize("leg", range(6))
def test_vectorised_reach_agrees_with_one_at_a_time(default_spec, leg):
    """``reachable`` over an array of targets gives what it gives for each alone."""
    kin = LegKinematics(default_spec)
    rng = np.random.default_rng(leg)
    targets = rng.uniform(-0.35, 0.35, (200, 3))
    many = kin.reachable(leg, targets, 0.01)
    assert many.shape == (200,) and many.any() and not many.all()
    assert [kin.reachable(leg, t, 0.01) for t in targets] == list(many)


def test_a_foothold_whose_knee_would_stand_in_a_block_is_moved(default_spec):
    """A front foot pulled in towards its hip has its knee 9 cm out beyond the foot. With a
    block under that knee too high for it (10.5 cm), the foothold moves to where the knee and
    tibia clear the terrain at every body height the plan allows; with a block the knee
    clears (3 cm), the same nominal foothold is kept; the foot's own cell is valid in both."""
    spec = default_spec
    kin = LegKinematics(spec)
    lf = spec.leg_names.index("LF")
    feet = _standing_feet(spec)
    out = feet[lf, :2] - spec.mount_positions_in_body[lf, :2]
    out /= np.linalg.norm(out)
    nominal = feet.copy()
    nominal[lf, :2] -= 0.09 * out
    swing = np.zeros(6, dtype=bool)
    swing[lf] = True
    z = spec.body_height
    knee = kin.knees_in_body(lf, nominal[lf] - [0.0, 0.0, z])
    assert 0.08 < (knee[:2] - nominal[lf, :2]) @ out and knee[2] + z < 0.13
    cells = -1.0 + (np.arange(100) + 0.5) * RES
    gx, gy = np.meshgrid(cells, cells, indexing="ij")
    beyond = (np.stack([gx, gy], axis=-1) - nominal[lf, :2]) @ out
    under_knee = (beyond > 0.06) & (np.hypot(gx - knee[0], gy - knee[1]) < 0.08)
    plans = {}
    for height in (0.03, 0.105):
        planner = _planner(spec, np.where(under_knee, height, 0.0))
        plan = planner.plan(nominal, swing, ~swing | swing, feet, _poses(), [z])
        assert not isinstance(plan, NoFoothold), plan
        plans[height] = plan
    assert not plans[0.03].adjusted[lf]
    moved = plans[0.105]
    assert moved.adjusted[lf]
    for body_z in moved.body_z:
        foot = moved.targets[lf] - [0.0, 0.0, body_z]
        knee = kin.knees_in_body(lf, foot) + [0.0, 0.0, body_z]
        for point in (knee, 0.5 * (knee + moved.targets[lf])):
            # The terrain within a link's radius (a foot's) of the point.
            rings = np.array([[0, 0], [1, 0], [-1, 0], [0, 1], [0, -1]])
            ring = point[:2] + spec.foot_radius * rings
            i, j = ((ring + 1.0) // RES).astype(int).T
            ground = 0.105 if under_knee[i, j].any() else 0.0
            assert point[2] >= ground + spec.foot_radius, (point, ground)


def test_a_foot_goes_up_a_step_only_from_a_body_that_can_lift_it_over_the_riser():
    """A short leg folds up when its foot passes beside the hip: it cannot lift the foot
    over a riser there unless the body stands high enough. The PhantomX's front feet lift
    off beside their hips and step onto a 4 cm step whose edge is just ahead: the plan
    allows only the body heights from which each front leg reaches the point above the
    edge by the swing clearance, and refuses some at which the legs reach their
    footholds."""
    spec = load_spec("phantomx")
    rise, edge_x = 0.04, 0.18  # the edge on a cell boundary
    planner = _planner(spec, -_ledge(rise, edge_x))  # up by ``rise`` beyond the edge
    feet = _standing_feet(spec)
    feet[FRONT, 0] = 0.11  # lifting off beside the hips
    nominal = _standing_feet(spec)
    nominal[FRONT, 0] = 0.25
    nominal[FRONT, 2] = spec.foot_radius + rise
    heights = np.arange(0.06, 0.2, 0.005)
    plan = planner.plan(nominal, FRONT, SUPPORT_AFTER, feet, _poses(), heights)
    assert not isinstance(plan, NoFoothold), plan
    np.testing.assert_allclose(plan.targets[FRONT, 2], spec.foot_radius + rise)
    kin = LegKinematics(spec)
    lift = planner.config.swing_clearance + spec.foot_radius + rise
    refused_for_the_swing = 0
    for z in heights:
        over_edge = []
        for leg in np.flatnonzero(FRONT):
            # Over the top, a little more than a centimetre past the edge: the leg reaches
            # it more easily than the edge itself, nearer the hip.
            way = np.linspace(feet[leg, :2], plan.targets[leg, :2], 200)
            edge = way[np.argmin(np.abs(way[:, 0] - edge_x - 0.015))]
            over_edge.append(kin.reachable(int(leg), np.array([*edge, lift - z])))
        reached = all(kin.reachable(leg, plan.targets[leg] - [0.0, 0.0, z]) for leg in range(6))
        if np.isclose(plan.body_z, z).any():
            assert all(over_edge), z
        elif reached and not all(over_edge):
            refused_for_the_swing += 1
    assert plan.body_z.size and refused_for_the_swing


def test_a_replan_keeps_each_foothold_on_its_side_of_a_trench(default_spec):
    """A trench under the front legs' nominal footholds: planned afresh, each foot goes to
    the nearer side; re-planned with the foothold planned before on the other side, it
    stays there, held by a 4 cm region hysteresis (its steppable region still has an
    acceptable cell) and no jump counts;
    re-planned from a foothold whose region has no acceptable cell within reach any more,
    it moves, a forced move that counts as no jump."""
    spec = default_spec
    feet = _standing_feet(spec)
    nominal = feet.copy()
    nominal[FRONT, 0] += 0.04
    x = -1.0 + (np.arange(100) + 0.5) * RES
    heights = np.zeros((100, 100))
    near_edge = nominal[0, 0] - 0.01
    heights[(x > near_edge) & (x < near_edge + 0.04)] = -0.1  # the trench
    heights[(x > 0.7) & (x < 0.8)] = -0.1  # a second trench, far ahead
    held = TerrainPlannerConfig(footholds=FootholdConfig(region_hysteresis=0.04))
    planner = _planner(spec, heights, held)
    body = [spec.body_height]
    fresh = planner.plan(nominal, FRONT, SUPPORT_AFTER, feet, _poses(), body)
    assert not isinstance(fresh, NoFoothold), fresh
    sides = fresh.targets[FRONT, 0] > near_edge
    other = fresh.targets.copy()
    other[FRONT, 0] = np.where(sides, near_edge - 0.08, near_edge + 0.12)
    kept = planner.plan(nominal, FRONT, SUPPORT_AFTER, feet, _poses(), body, previous=other)
    assert not isinstance(kept, NoFoothold), kept
    assert np.array_equal(kept.targets[FRONT, 0] > near_edge, ~sides)
    assert planner.region_jumps == 0
    beyond = fresh.targets.copy()
    beyond[FRONT, 0] = 0.9  # past the far trench: nothing of that region within reach
    moved = planner.plan(nominal, FRONT, SUPPORT_AFTER, feet, _poses(), body, previous=beyond)
    assert not isinstance(moved, NoFoothold), moved
    np.testing.assert_allclose(moved.targets, fresh.targets)
    assert planner.region_jumps == 0  # forced: the old region is out of reach


@settings(max_examples=100, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    unknown=st.floats(0.0, 0.6),
    foot_radius=st.sampled_from([0.005, 0.01, 0.012, 0.03]),
)
def test_terrain_under_is_the_highest_known_height_around_each_point(
    default_spec, seed, unknown, foot_radius
):
    """The compiled look-up gives, for each point, the highest known height at the point and
    a foot radius along x and y from it (cells off the window or unknown left out, -inf if
    none is known), as the map's own cell look-up does, for points on, across and off the
    window's edges."""
    from dataclasses import replace

    rng = np.random.default_rng(seed)
    heights = rng.uniform(-0.2, 0.2, size=(100, 100))
    heights[rng.random(heights.shape) < unknown] = np.nan
    planner = _planner(replace(default_spec, foot_radius=foot_radius), heights)
    points = rng.uniform(-1.1, 1.1, size=(7, 40, 2))
    points[0, :3] = [(-1.0, -1.0), (1.0 - 1e-12, 0.0), (0.0, 1.0)]  # on the window's edges
    snapshot = planner.snapshot
    expected = np.full(points.shape[:-1], -np.inf)
    for dx, dy in (
        (0, 0),
        (foot_radius, 0),
        (-foot_radius, 0),
        (0, foot_radius),
        (0, -foot_radius),
    ):
        cells = snapshot.cell_of(points + [dx, dy])
        inside = np.all((cells >= 0) & (cells < 100), axis=-1)
        value = np.full(points.shape[:-1], np.nan)
        value[inside] = heights[cells[inside, 0], cells[inside, 1]]
        expected = np.fmax(expected, np.where(np.isnan(value), -np.inf, value))
    np.testing.assert_array_equal(planner.terrain_under(points), expected)
    np.testing.assert_array_equal(planner.terrain_under(points[0, 0]), expected[0, :1])
