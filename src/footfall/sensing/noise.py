"""Depth noise of real sensors: how far a reading at range z scatters along its ray.

The axial standard deviation grows with the square of the range, as the structured-light
and stereo models used by elevation mapping packages have it::

    sigma(z) = base_m + quadratic_per_m * (z - offset_m)^2      [m]

- Kinect-class structured light (Kinect v1, Asus Xtion, PrimeSense): Nguyen, Izadi and
  Lovell, "Modeling Kinect sensor noise for improved 3D reconstruction and tracking"
  (3DIMPVT 2012): ``0.0012 + 0.0019 (z - 0.4)^2``, 1.2 mm at 0.4 m, 6 mm at 2 m.
- RealSense-class active stereo (D415/D435): the depth RMS error of a stereo pair is
  ``z^2 * subpixel / (focal * baseline)``; with Intel's 0.08 px subpixel, 50 mm baseline
  and a 385 px focal length at 640 x 480 that is ``0.0042 z^2``, plus 1 mm.
- Ideal: the simulator's camera, exact to floating point.

A height map takes a cell's in-frame height range beyond what this noise explains as the
evidence of an edge, and fuses cells by a Kalman update weighted by it.
"""

from __future__ import annotations

from dataclasses import dataclass

from footfall.checks import require_non_negative
from footfall.errors import ConfigError


@dataclass(frozen=True)
class DepthNoiseModel:
    """Axial depth noise ``base_m + quadratic_per_m * (z - offset_m)^2`` [m].

    Attributes:
        base_m: Noise at ``offset_m`` [m].
        quadratic_per_m: Growth with the square of the range [1/m].
        offset_m: Range of the least noise [m].
    """

    base_m: float = 0.0
    quadratic_per_m: float = 0.0
    offset_m: float = 0.0

    def __post_init__(self) -> None:
        require_non_negative(
            "depth noise",
            base_m=self.base_m,
            quadratic_per_m=self.quadratic_per_m,
            offset_m=self.offset_m,
        )

    @property
    def is_ideal(self) -> bool:
        """Whether the sensor is exact (the simulator's camera)."""
        return self.base_m == 0 and self.quadratic_per_m == 0

    def sigma_m(self, range_m: float) -> float:
        """Axial standard deviation of a reading at ``range_m`` [m]."""
        return self.base_m + self.quadratic_per_m * (range_m - self.offset_m) ** 2


IDEAL = DepthNoiseModel()
KINECT = DepthNoiseModel(0.0012, 0.0019, 0.4)
REALSENSE = DepthNoiseModel(0.001, 0.0042, 0.0)
SENSORS = {"ideal": IDEAL, "kinect": KINECT, "realsense": REALSENSE}


def sensor_noise(name: str) -> DepthNoiseModel:
    """The noise model of a sensor class by name.

    Raises:
        ConfigError: An unknown name (the known ones are listed).
    """
    try:
        return SENSORS[name]
    except KeyError:
        raise ConfigError(f"unknown sensor {name!r}; known: {', '.join(SENSORS)}") from None
