"""The body's attitude for a robot whose backend has no IMU: from its pose source."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt
from scipy.spatial.transform import Rotation

from footfall.messages import PoseEstimate
from footfall.runtime.bus import Bus


class PoseAttitude:
    """The body's attitude from the newest pose estimate, for a robot without an IMU.

    Args:
        bus: Where the (guarded) pose estimates arrive.
    """

    def __init__(self, bus: Bus) -> None:
        self.rotation = Rotation.identity()
        bus.subscribe(PoseEstimate.TOPIC, self._on_pose, last=True)

    def _on_pose(self, estimate: PoseEstimate) -> None:
        self.rotation = estimate.body_in_world.rotation

    def __call__(self) -> tuple[Rotation, npt.NDArray[np.float64]]:
        """The attitude, and no rates (a pose source does not measure them)."""
        return self.rotation, np.zeros(3)
