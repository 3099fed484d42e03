"""Score only what changed: a rolling map re-scored where a frame or a move touched it.

A depth frame touches the part of the window its camera sees (about half of a 256 x 256 map
with its context, for the main job's camera); scoring the whole window every frame spends
the rest on cells whose inputs did not change. Every rule of
:func:`~footfall.scoring.walkability.score_map` is local: a cell's scores depend only on the
map within ``REACH`` cells of it (the shadow rim looks 3 cells across, the scorer's window
and the edge cells' neighbours add 4), so

- a cell whose inputs (height, known, spread, variance, parts, points) changed moves the
  scores of the cells within ``REACH`` of it, and those are scored again from the map
  within ``REACH`` of them;
- a move of the window brings new cells in on one side and puts the window's border, where
  the scorer treats what lies beyond as unknown, over other cells: the bands within
  ``REACH`` of both new borders are scored again.

The result is the whole window's score map, equal to scoring the snapshot whole, cell for
cell (the tests hold the two equal over a walking camera's frames).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import numpy.typing as npt

from footfall.mapping.snapshot import MapSnapshot
from footfall.scoring.walkability import ScoreConfig, ScoreMap, score_map

_INPUTS = ("heights", "known", "spread", "variance", "parts", "points")
_EMPTY = {"heights": np.nan, "known": False, "spread": np.nan, "variance": np.nan}
_SCORES = ("slope", "proximity", "score", "valid")

Box = tuple[int, int, int, int]  # rows [i0, i1), columns [j0, j1)


def _shifted(a: npt.NDArray, di: int, dj: int, empty: object) -> npt.NDArray:
    """``a`` moved by ``(-di, -dj)`` cells (a window moved by ``(di, dj)``), ``empty`` in."""
    out = np.full_like(a, empty)
    n, m = a.shape
    src = (slice(max(di, 0), n + min(di, 0)), slice(max(dj, 0), m + min(dj, 0)))
    dst = (slice(max(-di, 0), n + min(-di, 0)), slice(max(-dj, 0), m + min(-dj, 0)))
    out[dst] = a[src]
    return out


def _changed(a: npt.NDArray | None, b: npt.NDArray | None) -> npt.NDArray[np.bool_] | None:
    """Cells where two layers differ (NaN equal to NaN); None when either is absent."""
    if a is None or b is None:
        return None
    if a.dtype.kind == "f":
        return ~((a == b) | (np.isnan(a) & np.isnan(b)))
    return a != b


class IncrementalScorer:
    """Scores successive snapshots of one rolling map, re-scoring only what changed.

    Args:
        config: Score parameters.

    Attributes:
        cells_scored: Cells scored (with their context) by the last call.
    """

    REACH = 7

    def __init__(self, config: ScoreConfig | None = None) -> None:
        self.config = config or ScoreConfig()
        self._inputs: MapSnapshot | None = None
        self._scores: ScoreMap | None = None
        self._cell: tuple[int, int] = (0, 0)
        self.cells_scored = 0

    def score(self, snapshot: MapSnapshot) -> ScoreMap:
        """The snapshot's score map (new arrays: earlier results are never written to)."""
        cell = tuple(round(v / snapshot.resolution) for v in snapshot.origin)
        before, scores = self._inputs, self._scores
        if (
            before is None
            or scores is None
            or before.heights.shape != snapshot.heights.shape
            or before.resolution != snapshot.resolution
            or any((getattr(before, k) is None) != (getattr(snapshot, k) is None) for k in _INPUTS)
            or max(abs(cell[0] - self._cell[0]), abs(cell[1] - self._cell[1]))
            >= snapshot.size - 2 * self.REACH
        ):
            result = score_map(snapshot, self.config)
            self.cells_scored = snapshot.heights.size
        else:
            di, dj = cell[0] - self._cell[0], cell[1] - self._cell[1]
            result = self._update(snapshot, before, scores, di, dj)
        self._inputs, self._scores, self._cell = snapshot, result, cell
        return result

    def _update(
        self, snapshot: MapSnapshot, before: MapSnapshot, scores: ScoreMap, di: int, dj: int
    ) -> ScoreMap:
        n, m = snapshot.heights.shape
        r = self.REACH
        changed = np.zeros((n, m), dtype=bool)
        for name in _INPUTS:
            old = getattr(before, name)
            if old is not None and (di or dj):
                old = _shifted(old, di, dj, _EMPTY.get(name, 0))
            diff = _changed(old, getattr(snapshot, name))
            if diff is not None:
                changed |= diff
        boxes: list[Box] = []
        rows, cols = np.nonzero(changed.any(axis=1))[0], np.nonzero(changed.any(axis=0))[0]
        if rows.size:
            boxes.append((rows[0] - r, rows[-1] + 1 + r, cols[0] - r, cols[-1] + 1 + r))
        # The window's new borders: cells brought in, and cells the border now lies over.
        if di:
            boxes += [(0, r + max(-di, 0), 0, m), (n - r - max(di, 0), n, 0, m)]
        if dj:
            boxes += [(0, n, 0, r + max(-dj, 0)), (0, n, m - r - max(dj, 0), m)]
        # Each box cut at the window's border, and the map within REACH of it (its context).
        parts = []
        for i0, i1, j0, j1 in boxes:
            i0, i1, j0, j1 = max(i0, 0), min(i1, n), max(j0, 0), min(j1, m)
            context = (max(i0 - r, 0), min(i1 + r, n), max(j0 - r, 0), min(j1 + r, m))
            parts.append(((i0, i1, j0, j1), context))
        # The contexts may cost more than the window (a camera that sees most of it,
        # moving): then the window is scored whole.
        work = sum((a1 - a0) * (b1 - b0) for _, (a0, a1, b0, b1) in parts)
        if work >= n * m:
            self.cells_scored = n * m
            return score_map(snapshot, self.config)
        out = {
            name: _shifted(getattr(scores, name), di, dj, False if name == "valid" else np.nan)
            if di or dj
            else getattr(scores, name).copy()
            for name in _SCORES
        }
        self.cells_scored = work
        for (i0, i1, j0, j1), (a0, a1, b0, b1) in parts:
            part = score_map(self._window(snapshot, a0, a1, b0, b1), self.config)
            inner = (slice(i0 - a0, i1 - a0), slice(j0 - b0, j1 - b0))
            for name in _SCORES:
                out[name][i0:i1, j0:j1] = getattr(part, name)[inner]
        return ScoreMap(**out, origin=snapshot.origin, resolution=snapshot.resolution)

    @staticmethod
    def _window(snapshot: MapSnapshot, i0: int, i1: int, j0: int, j1: int) -> MapSnapshot:
        """The snapshot's cells ``[i0, i1) x [j0, j1)``."""
        cut = {
            name: None if getattr(snapshot, name) is None else getattr(snapshot, name)[i0:i1, j0:j1]
            for name in _INPUTS
        }
        origin = (
            snapshot.origin[0] + i0 * snapshot.resolution,
            snapshot.origin[1] + j0 * snapshot.resolution,
        )
        return replace(snapshot, **cut, origin=origin)
