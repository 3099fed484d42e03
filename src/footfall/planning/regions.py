"""Steppable regions of a score map: connected valid areas and how deep inside them a cell is.

ETH's perceptive locomotion places feet inside steppable regions segmented from the map
rather than on the nearest valid cell. Here a region is a connected area of valid cells
(8-connected: a foot a cell wide steps across a diagonal); a cell's depth is how many
cells of valid ground surround it (every cell within that many steps along the grid's
rows and columns is valid and on the map, up to a cap); and a region's core is the depth
of its deepest cell. A foothold well inside a region lies at the wanted margin or at the
region's core, whichever is shallower: on a stone too small for the wanted margin, its
middle rather than its rim.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from scipy import ndimage

from footfall.errors import ConfigError

# Neighbours that join cells into one region: all eight.
_CONNECTIVITY = np.ones((3, 3), dtype=bool)


@dataclass(frozen=True)
class Regions:
    """The steppable regions of one score map, index ``[i, j]`` as the map's.

    Attributes:
        labels: Region of each cell, 1 to ``count``; 0 for invalid cells.
        depth: Margin of valid cells around each cell (every cell within that many steps
            along rows and columns valid), at most the cap it was computed to; -1 for
            invalid cells [cells].
        core_by_label: Deepest depth in each region, index by label (index 0, outside
            every region, is -1) [cells].
    """

    labels: npt.NDArray[np.int32]
    depth: npt.NDArray[np.int64]
    core_by_label: npt.NDArray[np.int64]

    @property
    def count(self) -> int:
        """Number of regions."""
        return len(self.core_by_label) - 1

    def core(self) -> npt.NDArray[np.int64]:
        """Each cell's region's core [cells]; -1 for invalid cells."""
        return self.core_by_label[self.labels]


def steppable_regions(valid: npt.ArrayLike, max_depth: int) -> Regions:
    """Segment a validity grid into regions, with each cell's depth up to ``max_depth``.

    Args:
        valid: Cells a foot may use, shape (N, M).
        max_depth: The widest margin worth measuring [cells], >= 0.

    Raises:
        ConfigError: On a grid that is not 2-D or a negative ``max_depth``.
    """
    ok = np.asarray(valid, dtype=bool)
    if ok.ndim != 2:
        raise ConfigError(f"steppable regions need a 2-D validity grid, got shape {ok.shape}")
    if max_depth < 0:
        raise ConfigError(f"max_depth must be >= 0, got {max_depth}")
    depth = np.where(ok, 0, -1).astype(np.int64)
    inner = ok.copy()
    for margin in range(1, max_depth + 1):
        inner = erode_once(inner)
        if not inner.any():
            break
        depth[inner] = margin
    labels, count = ndimage.label(ok, structure=_CONNECTIVITY)
    core = np.full(count + 1, -1, dtype=np.int64)
    np.maximum.at(core, labels.ravel(), depth.ravel())
    core[0] = -1
    return Regions(labels.astype(np.int32), depth, core)


def erode_once(cells: npt.NDArray[np.bool_]) -> npt.NDArray[np.bool_]:
    """Cells set with their four neighbours (the grid's border cells never are)."""
    out = cells.copy()
    out[1:, :] &= cells[:-1, :]
    out[:-1, :] &= cells[1:, :]
    out[:, 1:] &= cells[:, :-1]
    out[:, :-1] &= cells[:, 1:]
    out[[0, -1], :] = False
    out[:, [0, -1]] = False
    return out
