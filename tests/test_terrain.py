"""Terrains: the MuJoCo geometry matches each ground-truth height function."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from footfall.errors import ConfigError
from footfall.robot.spec import load_spec
from footfall.sim.hexapod import MujocoHexapod
from footfall.sim.model import ROBOT_GEOM_GROUP
from footfall.sim.terrain import Cobblestones, Stairs
from footfall.sim.terrains import TERRAINS, make_terrain


def _ray_heights(sim: MujocoHexapod, xy: np.ndarray) -> np.ndarray:
    """Height of the simulated ground under each point, by casting rays down (robot excluded)."""
    groups = np.ones(6, dtype=np.uint8)
    groups[ROBOT_GEOM_GROUP] = 0
    geom = np.zeros(1, dtype=np.int32)
    out = []
    for x, y in xy:
        distance = mujoco.mj_ray(
            sim.model,
            sim.data,
            np.array([x, y, 2.0]),
            np.array([0.0, 0.0, -1.0]),
            groups,
            1,
            -1,
            geom,
        )
        out.append(2.0 - distance)
    return np.array(out)


@pytest.mark.parametrize("name", TERRAINS.names())
def test_simulated_ground_matches_ground_truth(name):
    """Away from walls the simulated surface is the terrain's height function (to 2 mm)."""
    terrain = make_terrain(name, seed=4)
    sim = MujocoHexapod(load_spec("default"), terrain)
    rng = np.random.default_rng(0)
    xy = np.column_stack([rng.uniform(-0.3, terrain.goal[0], 600), rng.uniform(-0.8, 0.8, 600)])
    # Keep points whose neighbourhood is free of walls (the height field smooths them):
    # no jump between samples 1 cm apart (a 30 degree ramp rises 6 mm over one).
    offsets = np.arange(-2, 3) * 0.01
    near = np.stack(
        [[terrain.height(xy[:, 0] + dx, xy[:, 1] + dy) for dy in offsets] for dx in offsets]
    )
    jumps = np.maximum(
        np.abs(np.diff(near, axis=0)).max(axis=(0, 1)),
        np.abs(np.diff(near, axis=1)).max(axis=(0, 1)),
    )
    wall_free = jumps < 0.008
    heights = _ray_heights(sim, xy[wall_free])
    np.testing.assert_allclose(
        heights, terrain.height(xy[wall_free, 0], xy[wall_free, 1]), atol=0.002
    )
    assert wall_free.sum() > 100


def test_stairs_go_up_then_down():
    """The staircase rises by `rise` per tread to steps * rise and comes back down."""
    stairs = Stairs(rise=0.05, tread=0.2, steps=3, landing=0.4, start_x=0.5)
    xs = np.arange(0.0, stairs.end_x + 0.5, 0.01)
    profile = stairs.height(xs, 0.0)
    assert profile.max() == pytest.approx(0.15)
    assert set(np.round(np.unique(profile), 6)) == {0.0, 0.05, 0.1, 0.15}
    assert profile[0] == 0 and profile[-1] == 0
    assert stairs.goal[0] > stairs.end_x
    # Each tread and the top landing are as long as asked.
    top = xs[np.isclose(profile, 0.15)]
    assert top[-1] - top[0] == pytest.approx(0.4, abs=0.011)
    first = xs[np.isclose(profile, 0.05) & (xs < top[0])]
    assert first[-1] - first[0] == pytest.approx(0.2, abs=0.011)


def test_cobblestones_are_seeded():
    """The same seed lays the same stones; another seed differs; grooves are at floor level."""
    a, b, c = Cobblestones(seed=1), Cobblestones(seed=1), Cobblestones(seed=2)
    xs, ys = np.meshgrid(np.linspace(0.6, 3.0, 97), np.linspace(-0.6, 0.6, 49))
    np.testing.assert_array_equal(a.height(xs, ys), b.height(xs, ys))
    assert not np.array_equal(a.height(xs, ys), c.height(xs, ys))
    groove_x = a.start_x + a.stone  # a groove between the first two rows of stones
    assert np.all(a.height(np.full(5, groove_x), np.linspace(-0.5, 0.5, 5)) == 0.0)


def test_unknown_terrain_names_the_choices():
    """An unknown terrain lists the known ones."""
    with pytest.raises(ConfigError, match="flat, stairs, cobblestones, course"):
        make_terrain("lava")


def test_true_scores_see_what_a_perfect_camera_would():
    """The ground truth takes each cell's highest point and flags cells whose points span
    an edge: a 1 cm groove between stones is invalid in both cells it touches, however
    the grid falls; a stone's middle is valid; stones whose edges lie on cell centres give
    symmetric valid cores."""
    from footfall.scoring.walkability import ScoreConfig
    from footfall.sim.truth import TrueScores

    narrow = Cobblestones(groove=0.01, jitter=0.0, seed=0)
    truth = TrueScores(narrow, 0.02, ScoreConfig(), (0.0, 3.2, -0.8, 0.8))
    boundary = narrow.start_x + 5 * narrow.stone  # a groove centred here, along y
    assert not truth.valid_at((boundary - 0.01, 0.08))
    assert not truth.valid_at((boundary + 0.01, 0.08))
    middle = boundary + 0.5 * narrow.stone
    assert truth.valid_at((middle, -0.64 + 4.5 * narrow.stone))
    wide = Cobblestones(groove=0.06, jitter=0.0, seed=0)
    truth = TrueScores(wide, 0.02, ScoreConfig(), (0.0, 3.2, -0.8, 0.8))
    x0 = wide.start_x + 5 * wide.stone
    profile = [truth.valid_at((x0 + 0.01 + 0.02 * k, -0.64 + 4.5 * wide.stone)) for k in range(8)]
    assert profile == profile[::-1] and sum(profile) > 0


@settings(max_examples=8, deadline=None)
@given(
    offset=st.tuples(st.integers(0, 199), st.integers(0, 199)),
    seed=st.integers(0, 50),
)
def test_true_scores_find_a_cells_highest_point_up_to_its_sides(offset, seed):
    """Against a brute-force truth sampled 17 times per cell and axis: stepping stones'
    edges wherever they fall in the cells (a stone reaching a millimetre into a cell puts
    its top there, as a camera's points would) give the same valid cells."""
    from footfall.scoring.walkability import ScoreConfig
    from footfall.sim.terrain_relief import SteppingStones
    from footfall.sim.truth import TrueScores

    class Dense(TrueScores):
        SAMPLES = (*np.linspace(0.0, 1.0, 17)[:-1], 1.0 - 1e-4)

    stones = SteppingStones(gap=0.08, seed=seed)
    x0, y0 = 0.9 + 0.02 * offset[0] / 200, -0.3 + 0.02 * offset[1] / 200
    extent = (x0, x0 + 0.6, y0, y0 + 0.6)
    truth = TrueScores(stones, 0.02, ScoreConfig(), extent)
    dense = Dense(stones, 0.02, ScoreConfig(), extent)
    np.testing.assert_array_equal(truth.valid, dense.valid)


def test_only_geometry_beyond_every_gait_is_declared_impassable():
    """The rules take the terrain's own parameters against bounds from the robot: trenches
    and stone gaps wider than a foot can travel in one swing, ramps steeper than the feet's
    friction holds. None of the suite's rows is declared for either built-in robot (each was
    crossed by some walk), and a robot with slippery feet cannot hold a 20 degree ramp."""
    from dataclasses import replace

    from footfall.robot.limits import longest_step_m, steepest_slope_rad
    from footfall.robot.spec import load_spec
    from footfall.sim.terrains import TERRAINS, make_terrain

    for name in ("default", "phantomx"):
        spec = load_spec(name)
        for terrain in TERRAINS:
            kind = TERRAINS.get(terrain)
            for value in kind.sweep or (None,):
                params = {} if value is None else {kind.difficulty: value}
                assert make_terrain(terrain, 0, **params).impassable_for(spec) == ""
        # A leg reaches farther along the way than its stride, and no foot travels farther
        # in a swing than twice that.
        assert spec.stride_length < longest_step_m(spec) / 2 < spec.body_size[0] + 0.5
        wide = longest_step_m(spec)
        reason = make_terrain("gaps", 0, width=wide).impassable_for(spec)
        assert "trenches" in reason and f"{wide:g}" in reason
        assert make_terrain("stepping_stones", 0, gap=wide).impassable_for(spec)
        assert not make_terrain("gaps", 0, width=wide - 2.5 * spec.foot_radius).impassable_for(spec)
    slippery = replace(load_spec("default"), foot_friction=0.3)
    assert math.degrees(steepest_slope_rad(slippery)) == pytest.approx(16.7, abs=0.1)
    assert "friction 0.3" in make_terrain("ramps", slope_deg=20.0).impassable_for(slippery)
    assert make_terrain("ramps", slope_deg=15.0).impassable_for(slippery) == ""
