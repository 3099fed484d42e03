"""The height map's window as plain arrays: what the scorer, planners and recorders read."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from footfall.errors import ConfigError


@dataclass(frozen=True)
class MapSnapshot:
    """The map window as plain arrays, index ``[i, j]`` along world ``x`` and ``y``.

    Attributes:
        heights: Shape (N, N) [m]; NaN where unknown.
        known: Shape (N, N).
        spread: Largest height range of the points that fell in each cell in one frame,
            beyond what the camera's noise explains, shape (N, N) [m]; NaN where unknown.
            A cell that straddles an edge or a narrow groove has a large spread even when
            its height looks flat.
        variance: Variance of each cell's height, shape (N, N) [m^2]; NaN where unknown
            (the fused estimate's for ``variance`` fusion, else the last reading's).
        parts: Which of each cell's ``SUB`` x ``SUB`` parts (``mapping.kernels.SUB``) a
            point has fallen in since the cell became known, bit ``SUB * a + b`` for part
            ``a`` along x and ``b`` along y, shape (N, N); 0 where unknown. A part the
            camera never hits while the rest of the cell is well seen lies in a shadow.
        points: Points that have fallen in each cell since it became known, shape (N, N).
        origin: World ``(x, y)`` of the corner of cell ``[0, 0]`` [m].
        resolution: Cell side [m].
    """

    heights: npt.NDArray[np.float64]
    known: npt.NDArray[np.bool_]
    origin: tuple[float, float]
    resolution: float
    spread: npt.NDArray[np.float64] | None = None
    variance: npt.NDArray[np.float64] | None = None
    parts: npt.NDArray[np.uint16] | None = None
    points: npt.NDArray[np.int64] | None = None

    def __post_init__(self) -> None:
        if not (math.isfinite(self.resolution) and self.resolution > 0):
            raise ConfigError(f"a map's resolution must be positive, got {self.resolution}")
        if np.ndim(self.heights) != 2 or np.shape(self.known) != np.shape(self.heights):
            raise ConfigError(
                f"a map needs 2-D heights and a known mask of one shape, got "
                f"{np.shape(self.heights)} and {np.shape(self.known)}"
            )
        if not all(math.isfinite(v) for v in self.origin):
            raise ConfigError(f"a map's origin must be finite, got {self.origin}")

    @property
    def size(self) -> int:
        """Cells per side."""
        return self.heights.shape[0]

    def cell_of(self, xy: npt.ArrayLike) -> npt.NDArray[np.int64]:
        """Snapshot indices ``(i, j)`` of world points, shape (..., 2) (may be out of range)."""
        p = np.asarray(xy, dtype=np.float64)
        return np.floor((p - np.asarray(self.origin)) / self.resolution).astype(np.int64)

    def centre_of(self, ij: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """World ``(x, y)`` of cell centres, shape (..., 2) [m]."""
        return np.asarray(self.origin) + (np.asarray(ij, dtype=np.float64) + 0.5) * self.resolution

    def centres(self) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
        """World x and y of every cell centre, each shape (N, N) [m]."""
        c = (np.arange(self.size) + 0.5) * self.resolution
        return np.meshgrid(self.origin[0] + c, self.origin[1] + c, indexing="ij")
