"""Rolling height map: cell transforms, scrolling, integration and fusion."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from footfall.benchmarking import synthetic_depth_frame
from footfall.mapping.engine import HeightMapConfig
from footfall.mapping.height_map import HeightMap
from footfall.mapping.reference import integrate_depth_latest

coordinates = st.floats(-500.0, 500.0, allow_nan=False)


@given(
    coordinates, coordinates, st.sampled_from([0.01, 0.02, 0.05]), st.sampled_from([16, 128, 256])
)
@settings(max_examples=200, deadline=None)
def test_world_cell_world_round_trip(x, y, resolution, size):
    """A point lies in its cell; the cell's centre maps back to that cell; buffer indices wrap."""
    m = HeightMap(HeightMapConfig(size=size, resolution=resolution), centre=(x, y))
    cell = m.cell_of([x, y])
    centre = m.centre_of(cell)
    assert np.all(np.abs(centre - [x, y]) <= 0.5 * resolution + 1e-9)
    np.testing.assert_array_equal(m.cell_of(centre), cell)
    np.testing.assert_array_equal(m.buffer_index(cell), np.mod(cell, size))
    assert m.contains(cell)  # the window is centred on the point
    assert not m.contains(cell + [size, 0]) and not m.contains(cell - [0, size])


def _fill(m: HeightMap, rng: np.random.Generator, centre: np.ndarray) -> None:
    """Write random heights over the whole window around ``centre``."""
    res = m.config.resolution
    n = m.config.size
    i, j = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    xy = (m.origin + np.stack([i.ravel(), j.ravel()], 1) + 0.5) * res
    pts = np.column_stack([xy, rng.uniform(-1, 1, len(xy))])
    m.integrate_points(pts, np.append(centre, 1.0))


@given(st.integers(0, 2**32 - 1))
@settings(max_examples=15, deadline=None)
def test_scrolling_keeps_cells_still_in_the_window(seed):
    """Scrolling 50 m in random directions: cells that stay in the window keep their data,
    cells that scroll in are unknown."""
    rng = np.random.default_rng(seed)
    m = HeightMap(HeightMapConfig(size=64, resolution=0.05))
    position = np.zeros(2)
    _fill(m, rng, position)
    travelled = 0.0
    while travelled < 50.0:
        before_origin = m.origin.copy()
        before = m.snapshot()
        step = rng.uniform(0.02, 1.5) * np.array(
            [np.cos(a := rng.uniform(0, 2 * np.pi)), np.sin(a)]
        )
        position = position + step
        travelled += float(np.linalg.norm(step))
        m.recentre(tuple(position))
        after = m.snapshot()
        shift = m.origin - before_origin
        n = m.config.size
        for i in range(0, n, 7):
            for j in range(0, n, 5):
                old = np.array([i, j]) + shift  # the same global cell in the old snapshot
                if np.all((old >= 0) & (old < n)):
                    assert after.known[i, j] == before.known[old[0], old[1]]
                    if after.known[i, j]:
                        assert after.heights[i, j] == before.heights[old[0], old[1]]
                else:
                    assert not after.known[i, j]
        if rng.uniform() < 0.3:
            _fill(m, rng, position)


@given(st.integers(0, 2**32 - 1))
@settings(max_examples=15, deadline=None)
def test_a_snapshot_holds_each_cells_layers_in_world_order(seed):
    """Every layer of a snapshot's cell [i, j] is the buffer's at the global cell origin +
    (i, j); an unknown cell has NaN heights, spread and variance and no parts or points."""
    rng = np.random.default_rng(seed)
    m = HeightMap(HeightMapConfig(size=32, resolution=0.05))
    position = rng.uniform(-3.0, 3.0, 2)
    m.recentre(tuple(position))
    _fill(m, rng, position)
    m.recentre(tuple(position + rng.uniform(-0.6, 0.6, 2)))
    snapshot = m.snapshot()
    cells = m.origin + np.stack(np.meshgrid(np.arange(32), np.arange(32), indexing="ij"), -1)
    b = m.buffer_index(cells)
    known = m.layers.known[b[..., 0], b[..., 1]]
    np.testing.assert_array_equal(snapshot.known, known)
    for name, empty in (("heights", np.nan), ("spread", np.nan), ("variance", np.nan),
                        ("parts", 0), ("points", 0)):  # fmt: skip
        layer = getattr(m.layers, name)[b[..., 0], b[..., 1]]
        np.testing.assert_array_equal(getattr(snapshot, name), np.where(known, layer, empty))
    assert snapshot.origin == pytest.approx(tuple(m.origin * 0.05))


def test_jump_beyond_the_map_clears_it():
    """A pose that jumps farther than the map recentres it empty, without error."""
    m = HeightMap(HeightMapConfig(size=32, resolution=0.1))
    m.integrate_points([[0.0, 0.0, 1.0]], [0, 0, 2])
    m.recentre((1000.0, -1000.0))
    assert not m.known.any()
    m.integrate_points([[1000.0, -1000.0, 0.5]], [1000, -1000, 2])
    assert m.height_at([[1000.0, -1000.0]])[0] == 0.5


def test_compiled_update_matches_numpy_reference():
    """The numba kernel and the plain-NumPy reference build the same map from a frame."""
    depth, camera, pose = synthetic_depth_frame(np.random.default_rng(1))
    config = HeightMapConfig(size=128, resolution=0.02)
    m = HeightMap(config, centre=(1.0, 0.3))
    m.integrate_depth(depth, camera, pose)
    heights = np.zeros((128, 128))
    known = np.zeros((128, 128), dtype=bool)
    integrate_depth_latest(heights, known, tuple(m.origin), config.resolution, depth, camera, pose)
    np.testing.assert_array_equal(m.known, known)
    np.testing.assert_allclose(m.heights[known], heights[known], atol=1e-12)


def test_invalid_readings_never_overwrite_known_cells():
    """A frame of NaN, zero and negative depth changes nothing and is counted."""
    depth, camera, pose = synthetic_depth_frame(np.random.default_rng(2))
    m = HeightMap(HeightMapConfig(size=128), centre=(1.0, 0.0))
    m.integrate_depth(depth, camera, pose)
    heights, known = m.heights.copy(), m.known.copy()
    bad = np.full_like(depth, np.nan)
    bad[::2] = 0.0
    bad[::3] = -1.0
    stats = m.integrate_depth(bad, camera, pose)
    assert stats.depth.valid == 0 and stats.depth.dropped == depth.size
    np.testing.assert_array_equal(m.known, known)
    np.testing.assert_array_equal(m.heights, heights)


def test_points_outside_the_map_are_counted():
    """Points beyond the window are ignored and counted; non-finite points too."""
    m = HeightMap(HeightMapConfig(size=16, resolution=0.1))
    stats = m.integrate_points([[0.1, 0.1, 0.2], [50.0, 0.0, 0.3], [np.nan, 0.0, 0.0]], [0, 0, 1])
    assert (stats.depth.valid, stats.outside, stats.depth.non_finite) == (2, 1, 1)
    assert m.known.sum() == 1


@given(
    st.lists(
        st.tuples(st.floats(-0.79, 0.79), st.floats(-0.79, 0.79), st.floats(-0.1, 0.1)),
        min_size=1,
        max_size=40,
    ),
    st.integers(1, 3),
)
@settings(max_examples=100, deadline=None)
def test_a_cell_records_the_parts_its_points_fall_in(points, frames):
    """Over several frames, each cell's parts are exactly the 4 x 4 parts its points fell in
    (found with plain floor arithmetic) and its point count is theirs, over the frames seen
    from a new place only."""
    from footfall.mapping.kernels import SUB

    m = HeightMap(HeightMapConfig(size=16, resolution=0.1))
    p = np.array(points)
    for k in range(frames):
        for _ in range(2):  # the same view twice: the second adds no points
            m.integrate_points(p, [0.0, 0.01 * k, 1.0])
    snapshot = m.snapshot()
    in_cells = p[:, :2] * (1.0 / 0.1)
    cell = np.floor(in_cells)
    part = np.clip(np.floor((in_cells - cell) * SUB), 0, SUB - 1).astype(int)
    corner = np.round(np.asarray(snapshot.origin) / 0.1).astype(int)
    expected_parts = np.zeros(snapshot.heights.shape, dtype=np.int64)
    expected_points = np.zeros(snapshot.heights.shape, dtype=np.int64)
    for (i, j), (a, b) in zip(cell.astype(int) - corner, part, strict=True):
        expected_parts[i, j] |= 1 << (SUB * a + b)
        expected_points[i, j] += frames
    np.testing.assert_array_equal(snapshot.parts, expected_parts)
    np.testing.assert_array_equal(snapshot.points, expected_points)


def test_a_cell_that_scrolls_out_forgets_its_parts():
    """A cell erased by the window's move starts its parts and count afresh when seen again."""
    m = HeightMap(HeightMapConfig(size=16, resolution=0.1))
    m.integrate_points([[0.01, 0.01, 0.0], [0.09, 0.09, 0.0]], [0.0, 0.0, 1.0])
    m.recentre((5.0, 0.0))
    m.recentre((0.0, 0.0))
    m.integrate_points([[0.01, 0.01, 0.0]], [0.0, 0.0, 1.0])
    i, j = m.snapshot().cell_of([0.01, 0.01])
    assert m.snapshot().parts[i, j] == 1 and m.snapshot().points[i, j] == 1


def test_within_a_frame_the_highest_point_wins():
    """Several points in one cell in one frame: the cell takes the highest."""
    m = HeightMap(HeightMapConfig(size=16, resolution=0.1))
    m.integrate_points([[0.05, 0.05, 0.1], [0.06, 0.04, 0.3], [0.07, 0.02, 0.2]], [0, 0, 1])
    assert m.height_at([[0.05, 0.05]])[0] == pytest.approx(0.3)


@pytest.mark.parametrize(("rule", "expected"), [("latest", 0.1), ("max", 0.5)])
def test_fusion_rules_across_frames(rule, expected):
    """Latest replaces; max keeps the highest seen."""
    m = HeightMap(HeightMapConfig(size=16, resolution=0.1, fusion=rule))
    for z in (0.2, 0.5, 0.1):
        m.integrate_points([[0.05, 0.05, z]], [0, 0, 1])
    assert m.height_at([[0.05, 0.05]])[0] == pytest.approx(expected)


def test_variance_fusion_averages_noise_and_follows_changes():
    """The variance rule averages noisy readings of a still surface, and a jump larger than
    its gate replaces the estimate."""
    rng = np.random.default_rng(0)
    m = HeightMap(
        HeightMapConfig(
            size=16, resolution=0.1, fusion="variance", range_noise=0.01, process_noise=0.0
        )
    )
    readings = 0.2 + rng.normal(0.0, 0.01, 200)
    for z in readings:
        m.integrate_points([[0.05, 0.05, z]], [0.05, 0.05, 1.2])  # range 1 m -> sigma 1 cm
    assert abs(m.height_at([[0.05, 0.05]])[0] - 0.2) < 0.003
    m.integrate_points([[0.05, 0.05, 0.6]], [0.05, 0.05, 1.6])
    assert m.height_at([[0.05, 0.05]])[0] == pytest.approx(0.6)


def _floor_with_pit(rim_x: float | None):
    """A depth frame of a floor at z = 0 that drops 0.3 m past ``rim_x`` (None: no drop)."""
    _, camera, pose = synthetic_depth_frame(np.random.default_rng(0))
    u = np.arange(camera.width) - camera.cx
    v = np.arange(camera.height)[:, None] - camera.cy
    rays = np.stack(
        [u / camera.fx + 0 * v, v / camera.fy + 0 * u, np.ones((camera.height, camera.width))], -1
    )
    down = np.minimum((rays @ pose.rotation.as_matrix().T)[..., 2], -1e-9)
    depth = -pose.position[2] / down  # along the optical axis: rays have z = 1 in the camera
    if rim_x is not None:
        x_floor = pose.position[0] + depth * (rays @ pose.rotation.as_matrix().T)[..., 0]
        depth = np.where(x_floor >= rim_x, (-0.3 - pose.position[2]) / down, depth)
    depth[depth > camera.max_range] = 0.0
    return depth.astype(np.float32), camera, pose


@pytest.mark.parametrize("rim_x", [0.35, 0.45, None])
def test_assumed_ground_the_camera_sees_through_is_erased(rim_x):
    """A disc of ground assumed round the standing robot that reaches past a pit's rim loses
    the cells past the rim once a frame sees through them; the cells under the robot, which
    the camera never sees, stay assumed; those it sees on the floor are confirmed; a cell
    known before is not overwritten by the assumption."""
    config = HeightMapConfig(size=128, resolution=0.02)
    m = HeightMap(config, centre=(0.0, 0.0))
    m.integrate_points(np.array([[0.51, 0.01, 0.05]]), np.array([0.0, 0.0, 0.3]))
    r = np.arange(-0.6, 0.61, 0.01)
    gx, gy = np.meshgrid(r, r)
    disc = np.hypot(gx, gy) <= 0.6
    m.assume_ground(np.column_stack([gx[disc], gy[disc], np.zeros(disc.sum())]), (0, 0, 0.3))
    assert m.height_at([0.51, 0.01]) == pytest.approx(0.05)
    assert np.isfinite(m.height_at([[0.55, 0.0], [0.0, 0.0], [0.3, 0.0]])).all()
    m.integrate_depth(*_floor_with_pit(rim_x))

    xs = np.arange(-0.55, 0.56, 0.02) + 0.01
    along = np.column_stack([xs, np.full(len(xs), 0.05)])
    h = m.height_at(along)
    under = xs < 0.1  # the camera's view starts 0.15 m ahead
    assert np.isfinite(h[under]).all()
    i, j = m.buffer_index(m.cell_of(along[under])).T
    assert m.assumed[i, j].all()
    seen_floor = (xs > 0.2) & (xs < (rim_x if rim_x is not None else 1.0) - 0.02)
    assert np.isfinite(h[seen_floor]).all()
    i, j = m.buffer_index(m.cell_of(along[seen_floor])).T
    assert not m.assumed[i, j].any()
    if rim_x is not None:
        assert np.isnan(h[xs > rim_x + 0.02]).all()
