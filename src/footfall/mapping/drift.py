"""Vertical drift compensation: each new frame registered in height against the map.

A SLAM pose estimate drifts; its vertical error lifts or sinks every point of a frame
together, and fused into the map it leaves steps where there are none (thesis §9.2).
Where a new frame overlaps cells the map already knows, the median of their height
differences estimates that offset (elevation_mapping_cupy's drift compensation); the frame
is shifted by it before fusion. Only cells flat within the frame and in the map count:
an edge seen from another viewpoint differs for other reasons.

The offset of a drifting estimate changes slowly from frame to frame. A frame whose
offset differs from the last one taken by more than ``max_step_m`` is no drift: its pose is
inconsistent with the map's (a pose jump the guard let through), and it is not fused.
When ``settle_frames`` such frames in a row agree on the new offset, the estimate has
settled in a new frame: that offset is taken and the frames are fused again. A frame that
overlaps too little to measure its own offset takes the last one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from footfall.checks import require_positive
from footfall.errors import ConfigError


@dataclass(frozen=True)
class DriftConfig:
    """Vertical drift compensation settings.

    Attributes:
        enabled: Register frames in height against the map.
        min_cells: Overlapping flat cells needed to estimate an offset.
        max_step_m: Largest change of the offset from the last one taken that is drift;
            beyond, the frame is inconsistent [m].
        flat_m: A cell counts when its in-frame and mapped spread are below this [m].
        settle_frames: Inconsistent frames in a row, agreeing within ``flat_m``, after
            which their offset is taken.
    """

    enabled: bool = False
    min_cells: int = 100
    max_step_m: float = 0.03
    flat_m: float = 0.01
    settle_frames: int = 3

    def __post_init__(self) -> None:
        if self.min_cells < 1:
            raise ConfigError(f"drift min_cells must be >= 1, got {self.min_cells}")
        if self.settle_frames < 1:
            raise ConfigError(f"drift settle_frames must be >= 1, got {self.settle_frames}")
        require_positive("drift", max_step_m=self.max_step_m, flat_m=self.flat_m)


@dataclass(frozen=True)
class Registration:
    """The outcome of registering one frame.

    Attributes:
        measured_m: The frame's height above the map where they overlap [m]; NaN when
            too few cells overlap.
        offset_m: The offset taken out of the frame [m] (the measured one, or the last).
        consistent: Whether the frame is fused.
        settled: Whether the offset moved to a new level, after frames that agree on it.
    """

    measured_m: float
    offset_m: float
    consistent: bool
    settled: bool = False


def frame_offset(
    frame_z: npt.NDArray[np.float64],
    frame_range: npt.NDArray[np.float64],
    map_z: npt.NDArray[np.float64],
    map_spread: npt.NDArray[np.float64],
    config: DriftConfig,
) -> float:
    """Median height of a frame's cells above the map's, over flat overlapping cells [m].

    Args:
        frame_z: The frame's height of each touched cell that the map knows [m].
        frame_range: The height range of its points in each of those cells [m].
        map_z: The map's heights of those cells [m].
        map_spread: The map's spread of those cells [m].
        config: The settings.

    Returns:
        The offset, NaN with fewer than ``config.min_cells`` flat cells.
    """
    flat = (frame_range < config.flat_m) & (map_spread < config.flat_m)
    if int(flat.sum()) < config.min_cells:
        return math.nan
    return float(np.median(frame_z[flat] - map_z[flat]))


class DriftCompensator:
    """The offset taken last, and the run of inconsistent frames that may move it."""

    def __init__(self, config: DriftConfig) -> None:
        self.config = config
        self.offset_m = 0.0
        self._rejected: list[float] = []

    def judge(self, measured_m: float) -> Registration:
        """What to do with a frame measured ``measured_m`` above the map."""
        c = self.config
        if not math.isfinite(measured_m):
            return Registration(measured_m, self.offset_m, True)
        if abs(measured_m - self.offset_m) <= c.max_step_m:
            self._rejected.clear()
            self.offset_m = measured_m
            return Registration(measured_m, measured_m, True)
        self._rejected.append(measured_m)
        run = self._rejected[-c.settle_frames :]
        if len(run) == c.settle_frames and max(run) - min(run) <= c.flat_m:
            self._rejected.clear()
            self.offset_m = measured_m
            return Registration(measured_m, measured_m, True, settled=True)
        return Registration(measured_m, self.offset_m, False)
