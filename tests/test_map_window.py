"""The rolling map's window: buffer indices and global cells round-trip, and a move names
exactly the cells that left."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from footfall.errors import ConfigError
from footfall.mapping.window import MapWindow

SIZES = st.integers(8, 40)
RESOLUTIONS = st.sampled_from([0.01, 0.02, 0.05, 0.1])
CENTRES = st.tuples(st.floats(-50.0, 50.0), st.floats(-50.0, 50.0))


def _held(window: MapWindow) -> set[tuple[int, int]]:
    """The global cells the window holds."""
    i0, j0 = (int(v) for v in window.origin)
    n = window.size
    return {(i, j) for i in range(i0, i0 + n) for j in range(j0, j0 + n)}


@given(SIZES, RESOLUTIONS, CENTRES)
def test_every_held_cell_has_one_buffer_slot_and_back(size, resolution, centre):
    """The N x N cells of the window map one to one onto the buffer, and the buffer slot
    of a cell gives the cell back; the centre's own cell is held."""
    window = MapWindow(size, resolution, centre)
    cells = np.array(sorted(_held(window)))
    slots = window.buffer_index(cells)
    assert len({tuple(s) for s in slots}) == size * size
    np.testing.assert_array_equal(window.global_cell(slots), cells)
    assert window.contains(window.cell_of(centre))
    assert window.contains(cells).all()


@given(SIZES, RESOLUTIONS, CENTRES, CENTRES)
def test_a_move_names_exactly_the_cells_that_left(size, resolution, start, end):
    """After a move, the buffer rows and columns it names are those whose cells the
    window no longer holds (all of them after a jump of a whole window); the others keep
    their cells."""
    window = MapWindow(size, resolution, start)
    before = {tuple(window.buffer_index(c)): c for c in _held(window)}
    leaving = window.move(end)
    after = {tuple(window.buffer_index(c)): c for c in _held(window)}
    changed = {slot for slot in before if before[slot] != after[slot]}
    if leaving is None:
        assert not _held(window) & set(before.values())
        return
    named = set()
    for axis, rows in leaving:
        for r in rows:
            named |= {(int(r), j) if axis == 0 else (j, int(r)) for j in range(size)}
    assert named == changed


def test_a_centre_off_the_world_is_refused():
    """A centre that is not two finite coordinates in range names the problem."""
    for centre in ((np.nan, 0.0), (0.0, np.inf), (2e7, 0.0), (1.0,)):
        with pytest.raises(ConfigError, match="map centre"):
            MapWindow(16, 0.02, centre)
