"""The rolling map's window: which global cells its circular buffer holds, and where.

A world point ``(x, y)`` falls in the global cell ``(floor(x / res), floor(y / res))``
(thesis eq. 4.11 with ``res`` in metres per cell) and is stored at buffer index
``(i mod N, j mod N)``. The window holds the global cells ``[origin, origin + N)`` on each
axis; moving it names only the rows and columns that scroll out.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from footfall.errors import ConfigError

# The largest world coordinate a map window may be centred on [m] (cell indices stay exact).
MAX_COORDINATE = 1e7


class MapWindow:
    """An N x N window of global cells over the world plane.

    Args:
        size: Cells per side, N.
        resolution: Cell side [m].
        centre: World ``(x, y)`` the window starts centred on [m].
    """

    def __init__(self, size: int, resolution: float, centre: tuple[float, float]) -> None:
        self.size = size
        self.resolution = resolution
        self.inv_res = 1.0 / resolution
        self.origin = self.origin_for(centre)

    def origin_for(self, centre: tuple[float, float]) -> npt.NDArray[np.int64]:
        """The global cell at the corner of a window centred on ``centre``.

        Raises:
            ConfigError: On a centre that is not two finite coordinates within range.
        """
        c = np.asarray(centre, dtype=np.float64)
        if c.shape != (2,) or not np.all(np.isfinite(c)) or np.any(np.abs(c) > MAX_COORDINATE):
            raise ConfigError(
                f"a map centre must be two finite coordinates within {MAX_COORDINATE:g} m, "
                f"got {centre!r}"
            )
        cell = np.floor(c * self.inv_res).astype(np.int64)
        return cell - self.size // 2

    def cell_of(self, xy: npt.ArrayLike) -> npt.NDArray[np.int64]:
        """Global cell indices of world points, shape (..., 2)."""
        return np.floor(np.asarray(xy, dtype=np.float64) * self.inv_res).astype(np.int64)

    def centre_of(self, cell: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """World ``(x, y)`` of global cells' centres, shape (..., 2) [m]."""
        return (np.asarray(cell, dtype=np.float64) + 0.5) * self.resolution

    def buffer_index(self, cell: npt.ArrayLike) -> npt.NDArray[np.int64]:
        """Buffer indices of global cells (wrap-around), shape (..., 2)."""
        return np.mod(np.asarray(cell, dtype=np.int64), self.size)

    def global_cell(self, index: npt.ArrayLike) -> npt.NDArray[np.int64]:
        """Global cells held at buffer indices, shape (..., 2)."""
        n = self.size
        return self.origin + np.mod(np.asarray(index, dtype=np.int64) - self.origin % n, n)

    def contains(self, cell: npt.ArrayLike) -> npt.NDArray[np.bool_]:
        """Whether global cells lie inside the window, shape (...)."""
        offset = np.asarray(cell, dtype=np.int64) - self.origin
        return np.all((offset >= 0) & (offset < self.size), axis=-1)

    def code(self) -> npt.NDArray[np.int64]:
        """The origin as the kernels take it: ``(origin_i, origin_j, wrap_i, wrap_j)``."""
        n = self.size
        return np.array(
            [self.origin[0], self.origin[1], self.origin[0] % n, self.origin[1] % n], dtype=np.int64
        )

    @property
    def origin_m(self) -> tuple[float, float]:
        """World ``(x, y)`` of the window's corner [m]."""
        return (
            float(self.origin[0] * self.resolution),
            float(self.origin[1] * self.resolution),
        )

    def roll(self) -> tuple[int, int]:
        """The shift that puts the window's corner cell at buffer index [0, 0]."""
        return (-int(self.origin[0] % self.size), -int(self.origin[1] % self.size))

    def move(self, centre: tuple[float, float]) -> list[tuple[int, npt.NDArray[np.int64]]] | None:
        """Centre the window on a world point.

        Returns:
            The buffer rows (axis 0) and columns (axis 1) whose cells scrolled out, as
            ``(axis, indices)``; None when the window jumped by a whole window or more
            (every cell left).
        """
        new_origin = self.origin_for(centre)
        n = self.size
        leaving: list[tuple[int, npt.NDArray[np.int64]]] | None = []
        for axis in (0, 1):
            shift = int(new_origin[axis] - self.origin[axis])
            if shift == 0:
                continue
            if abs(shift) >= n:
                leaving = None
                break
            if shift > 0:  # cells [origin, origin + shift) leave
                cells = np.arange(self.origin[axis], self.origin[axis] + shift)
            else:  # cells [new_origin + n, origin + n) leave
                cells = np.arange(new_origin[axis] + n, self.origin[axis] + n)
            leaving.append((axis, np.mod(cells, n)))
        self.origin = new_origin
        return leaving
