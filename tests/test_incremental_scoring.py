"""Scoring only what a frame changed gives the whole window's scores."""

from __future__ import annotations

import numpy as np
from hypothesis import example, given, settings
from hypothesis import strategies as st

from depth_scenes import CAMERA, looking, render
from footfall.mapping.engine import HeightMapConfig
from footfall.mapping.height_map import HeightMap
from footfall.mapping.snapshot import MapSnapshot
from footfall.scoring.incremental import IncrementalScorer
from footfall.scoring.walkability import ScoreMap, score_map


def assert_same(a: ScoreMap, b: ScoreMap) -> None:
    np.testing.assert_array_equal(a.valid, b.valid)
    for name in ("slope", "proximity", "score"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    assert a.origin == b.origin


@settings(max_examples=6, deadline=None)
@given(
    start_x=st.floats(0.0, 1.2),
    start_y=st.floats(-0.8, 0.8),
    yaw=st.floats(-0.6, 0.6),
    turn=st.floats(-0.08, 0.08),
    step=st.floats(0.005, 0.06),
)
@example(start_x=0.0, start_y=0.0, yaw=0.5, turn=0.0, step=0.046875)  # once cost 9864 cells
def test_a_walking_cameras_map_scored_incrementally_equals_scoring_it_whole(
    start_x, start_y, yaw, turn, step
):
    """A camera walks among boxes (edges, shadows, the floor), the window follows it; every
    frame the incremental scores equal the whole window's, cell for cell, and never cost
    more cells than scoring the window whole."""
    scored = walk_and_score(96, start_x, start_y, yaw, turn, step)
    assert max(scored) <= 96 * 96


def test_a_slow_camera_in_a_wide_window_scores_fewer_cells_than_the_window():
    """Once the map holds something, a camera creeping on scores only what it changed."""
    scored = walk_and_score(160, 0.6, 0.0, 0.0, 0.0, 0.01)
    assert min(scored[1:]) < 160 * 160


def walk_and_score(size, start_x, start_y, yaw, turn, step) -> list[int]:
    """Cells scored each frame; the scores checked against the whole window's every frame."""
    heights = HeightMap(HeightMapConfig(size=size))
    scorer = IncrementalScorer()
    scored = []
    for k in range(10):
        heading = yaw + k * turn
        position = np.array(
            [start_x + k * step * np.cos(heading), start_y + k * step * np.sin(heading), 0.45]
        )
        pose = looking(position, heading, 0.7)
        heights.recentre((float(position[0]), float(position[1])))
        heights.integrate_depth(render(pose), CAMERA, pose, stride=2)
        snapshot = heights.snapshot()
        assert_same(scorer.score(snapshot), score_map(snapshot))
        scored.append(scorer.cells_scored)
    return scored


def test_results_handed_out_are_never_written_to_again():
    """A score map already published keeps its values when the next frame is scored."""
    heights = HeightMap(HeightMapConfig(size=64))
    scorer = IncrementalScorer()
    pose = looking((0.5, 0.0, 0.45), 0.0, 0.7)
    heights.integrate_depth(render(pose), CAMERA, pose, stride=2)
    first = scorer.score(heights.snapshot())
    kept = {name: getattr(first, name).copy() for name in ("slope", "score", "valid")}
    pose = looking((0.55, 0.05, 0.45), 0.2, 0.7)
    heights.recentre((0.55, 0.05))
    heights.integrate_depth(render(pose), CAMERA, pose, stride=2)
    scorer.score(heights.snapshot())
    for name, values in kept.items():
        np.testing.assert_array_equal(getattr(first, name), values)


def test_a_new_shape_or_a_jump_is_scored_whole():
    """A snapshot of another size, or a window that jumped farther than it can overlap,
    is scored whole."""
    scorer = IncrementalScorer()
    flat = np.zeros((32, 32))
    snapshot = MapSnapshot(flat, np.ones_like(flat, dtype=bool), (0.0, 0.0), 0.02)
    scorer.score(snapshot)
    far = MapSnapshot(flat, np.ones_like(flat, dtype=bool), (5.0, 0.0), 0.02)
    assert_same(scorer.score(far), score_map(far))
    assert scorer.cells_scored == 32 * 32
