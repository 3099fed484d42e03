"""What the rolling map stores per cell, and the buffers one frame is binned into.

Both are laid out as the window's circular buffer (:mod:`footfall.mapping.window`):
index ``[i mod N, j mod N]`` for global cell ``(i, j)``. The compiled kernels
(:mod:`footfall.mapping.kernels`) take them as plain arrays; :mod:`footfall.mapping.fusion`
is the one place that hands them over.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt


@dataclass
class CellLayers:
    """The map's layers, shape (N, N) each.

    Attributes:
        heights: Fused height [m].
        variance: Variance of the height [m^2].
        known: Whether the cell holds a height.
        spread: Largest in-frame height range beyond the camera's noise [m].
        parts: Bit mask of the cell's 4 x 4 parts any point has fallen in.
        points: Points that have fallen in the cell since it became known.
        assumed: Known without being seen (ground under the standing robot).
    """

    heights: npt.NDArray[np.float64]
    variance: npt.NDArray[np.float64]
    known: npt.NDArray[np.bool_]
    spread: npt.NDArray[np.float64]
    parts: npt.NDArray[np.uint16]
    points: npt.NDArray[np.int64]
    assumed: npt.NDArray[np.bool_]

    @classmethod
    def empty(cls, size: int) -> CellLayers:
        """Layers of an N x N map where nothing is known."""
        n = size
        return cls(
            heights=np.zeros((n, n), dtype=np.float64),
            variance=np.zeros((n, n), dtype=np.float64),
            known=np.zeros((n, n), dtype=bool),
            spread=np.zeros((n, n), dtype=np.float64),
            parts=np.zeros((n, n), dtype=np.uint16),
            points=np.zeros((n, n), dtype=np.int64),
            assumed=np.zeros((n, n), dtype=bool),
        )

    def forget(self, leaving: list[tuple[int, npt.NDArray[np.int64]]] | None) -> None:
        """Make cells unknown: buffer rows (axis 0) or columns (axis 1); None for all."""
        if leaving is None:
            self.known[:] = False
            self.assumed[:] = False
            return
        for axis, rows in leaving:
            if axis == 0:
                self.known[rows, :] = False
                self.assumed[rows, :] = False
            else:
                self.known[:, rows] = False
                self.assumed[:, rows] = False


@dataclass
class FrameBuffers:
    """One frame binned into cells, before it is fused into the layers.

    Attributes:
        top: Highest point per cell [m].
        low: Lowest point per cell [m].
        range2: Squared range of the cell's points from the sensor [m^2].
        total: Sum of the cell's point heights [m].
        count: Points per cell.
        parts: Bit mask of the cell's parts hit in this frame.
        stamp: Frame id that last touched each cell (so a cell is listed once per frame).
        touched: Flat buffer indices of the cells the frame touched, first ``n`` valid.
        frame_id: Id of the newest frame.
    """

    top: npt.NDArray[np.float64]
    low: npt.NDArray[np.float64]
    range2: npt.NDArray[np.float64]
    total: npt.NDArray[np.float64]
    count: npt.NDArray[np.int64]
    parts: npt.NDArray[np.uint16]
    stamp: npt.NDArray[np.int64]
    touched: npt.NDArray[np.int64]
    frame_id: int = 0

    @classmethod
    def empty(cls, size: int) -> FrameBuffers:
        """Buffers for an N x N map."""
        n = size
        return cls(
            top=np.zeros((n, n), dtype=np.float64),
            low=np.zeros((n, n), dtype=np.float64),
            range2=np.zeros((n, n), dtype=np.float64),
            total=np.zeros((n, n), dtype=np.float64),
            count=np.zeros((n, n), dtype=np.int64),
            parts=np.zeros((n, n), dtype=np.uint16),
            stamp=np.zeros((n, n), dtype=np.int64),
            touched=np.zeros(n * n, dtype=np.int64),
        )

    def next_frame(self) -> int:
        """A new frame's id."""
        self.frame_id += 1
        return self.frame_id

    def bins(self) -> tuple[npt.NDArray, ...]:
        """The per-cell bins in the kernels' order: top, low, range2, total, count, parts."""
        return (self.top, self.low, self.range2, self.total, self.count, self.parts)

    def cells(
        self, n_touched: int, ideal: bool
    ) -> tuple[npt.NDArray[np.int64], npt.NDArray[np.int64], npt.NDArray[np.float64]]:
        """Buffer rows and columns of the frame's cells, and their heights [m].

        An ideal camera's cell is its highest point; a noisy one's the mean of its points.
        """
        n = self.top.shape[0]
        idx = self.touched[:n_touched]
        i, j = idx // n, idx % n
        z = self.top[i, j] if ideal else self.total[i, j] / self.count[i, j]
        return i, j, z

    def lower(self, i: npt.NDArray[np.int64], j: npt.NDArray[np.int64], offset: float) -> None:
        """Take a vertical offset out of the frame's cells ``(i, j)`` [m]."""
        self.top[i, j] -= offset
        self.low[i, j] -= offset
        self.total[i, j] -= offset * self.count[i, j]
