"""What a RealSense camera hands over, in footfall's types, and librealsense's filters.

The conversions :mod:`footfall.hardware.realsense` applies to every frame: depth units as
set, a stream's intrinsics as a pinhole camera, extrinsics as a pose; and the filter chain.
"""

from __future__ import annotations

from dataclasses import dataclass
from types import ModuleType
from typing import Any

import numpy as np
import numpy.typing as npt
from scipy.spatial.transform import Rotation

from footfall.errors import CameraError, ConfigError
from footfall.sensing.camera import PinholeCamera
from footfall.sensing.noise import REALSENSE
from footfall.sensing.pose import Pose

FILTERS = ("decimation", "spatial", "temporal", "hole_filling")


def import_realsense() -> ModuleType:
    """``pyrealsense2``, or a clear error saying how to install it."""
    try:
        import pyrealsense2
    except ImportError as exc:
        raise ConfigError(
            "a RealSense camera needs librealsense's Python binding: install footfall's "
            "realsense extra (pip install 'footfall[realsense]')"
        ) from exc
    return pyrealsense2


@dataclass(frozen=True)
class DepthImage:
    """One depth image from the camera.

    Attributes:
        device_time: The device's timestamp [s] (its clock, or the host's where the
            device's frames are stamped with the host's).
        number: The device's frame number.
        depth: Shape (height, width) ``uint16`` depth units; 0 where nothing was measured.
        depth_scale: Metres per depth unit.
        camera: The depth stream's intrinsics (after decimation).
        color: The newest colour image when it was taken (colour streams on its own
            thread: the same instant's or the one before), shape (height, width, 3) RGB.
    """

    device_time: float
    number: int
    depth: npt.NDArray[np.uint16]
    depth_scale: float
    camera: PinholeCamera
    color: npt.NDArray[np.uint8] | None = None


@dataclass(frozen=True)
class MotionSample:
    """One gyro or accelerometer sample, in the depth camera's optical frame.

    Attributes:
        device_time: The device's timestamp [s].
        kind: ``"gyro"`` [rad/s] or ``"accel"`` [m/s^2].
        vector_in_camera: Shape (3,).
    """

    device_time: float
    kind: str
    vector_in_camera: npt.NDArray[np.float64]


@dataclass(frozen=True)
class RealSenseFilters:
    """librealsense's post-processing filters, as options say them.

    Attributes:
        decimation: Keep every n-th pixel in each direction (1: off; 2 to 8).
        spatial: Edge-preserving spatial smoothing.
        temporal: Smoothing over frames (holds a pixel through a dropout).
        hole_filling: Fill holes from the nearest neighbour.
    """

    decimation: int = 1
    spatial: bool = False
    temporal: bool = False
    hole_filling: bool = False

    def __post_init__(self) -> None:
        if not 1 <= self.decimation <= 8:
            raise ConfigError(f"RealSense decimation {self.decimation} is not 1 to 8")

    @classmethod
    def from_options(cls, options: dict[str, str]) -> RealSenseFilters:
        """``decimation=N``, ``spatial=1``, ``temporal=1``, ``hole_filling=1`` (0 or 1).

        Raises:
            ConfigError: A value that is not a whole number, or out of range.
        """
        values: dict[str, Any] = {}
        for name in FILTERS:
            if name in options:
                text = options[name]
                try:
                    number = int(text)
                except ValueError:
                    raise ConfigError(f"RealSense filter {name}={text!r} is not a number") from None
                if name != "decimation" and number not in (0, 1):
                    raise ConfigError(f"RealSense filter {name}={text!r}: give 0 or 1")
                values[name] = number if name == "decimation" else bool(number)
        return cls(**values)

    def build(self, rs: ModuleType) -> list[Any]:
        """The filters in librealsense's recommended order (spatial and temporal in disparity)."""
        chain: list[Any] = []
        if self.decimation > 1:
            decimation = rs.decimation_filter()
            decimation.set_option(rs.option.filter_magnitude, float(self.decimation))
            chain.append(decimation)
        if self.spatial or self.temporal:
            chain.append(rs.disparity_transform(True))
            if self.spatial:
                chain.append(rs.spatial_filter())
            if self.temporal:
                chain.append(rs.temporal_filter())
            chain.append(rs.disparity_transform(False))
        if self.hole_filling:
            chain.append(rs.hole_filling_filter())
        return chain


def depth_units(value: float) -> float:
    """Depth units as set: librealsense keeps them as float32 (0.001 reads 0.0010000000475)."""
    return float(str(np.float32(value)))


def pinhole(intrinsics: Any, rs: ModuleType) -> PinholeCamera:
    """A stream's ``rs.intrinsics`` as footfall's pinhole camera (RealSense noise).

    Raises:
        CameraError: A depth stream with lens distortion (footfall projects depth through an
            undistorted pinhole; RealSense depth streams are rectified).
    """
    if any(abs(c) > 1e-9 for c in intrinsics.coeffs) and intrinsics.model != rs.distortion.none:
        raise CameraError(
            f"the depth stream has lens distortion ({intrinsics.model}, {list(intrinsics.coeffs)});"
            " footfall needs rectified depth, as RealSense depth streams are"
        )
    return PinholeCamera(
        float(intrinsics.fx),
        float(intrinsics.fy),
        float(intrinsics.ppx),
        float(intrinsics.ppy),
        int(intrinsics.width),
        int(intrinsics.height),
        noise=REALSENSE,
    )


def extrinsics_pose(extrinsics: Any) -> Pose:
    """An ``rs.extrinsics`` (column-major rotation, translation) as a pose."""
    rotation = np.asarray(extrinsics.rotation, dtype=np.float64).reshape(3, 3).T
    return Pose(
        np.asarray(extrinsics.translation, dtype=np.float64), Rotation.from_matrix(rotation)
    )
