"""Pinhole depth camera: depth image -> points in the camera frame (thesis §4.2).

The camera frame is the optical one: x right, y down, z forward along the optical axis.
A depth pixel ``I(u, v)`` is the distance along the optical axis, so (eqs. 4.6-4.8)::

    z = I(u, v),   x = z (u - cx) / fx,   y = z (v - cy) / fy

with ``(u, v)`` the column and row of the pixel and ``fx, fy, cx, cy`` in pixels.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from footfall.errors import ConfigError, DepthImageError
from footfall.sensing.noise import IDEAL, DepthNoiseModel


@dataclass(frozen=True)
class DepthStats:
    """What became of a depth image's pixels.

    Attributes:
        valid: Pixels turned into points.
        zero: Pixels with no reading (0).
        non_finite: NaN or infinite pixels.
        negative: Negative pixels.
        out_of_range: Pixels nearer than ``min_range`` or beyond ``max_range``.
    """

    valid: int = 0
    zero: int = 0
    non_finite: int = 0
    negative: int = 0
    out_of_range: int = 0

    @property
    def dropped(self) -> int:
        """Pixels that gave no point."""
        return self.zero + self.non_finite + self.negative + self.out_of_range


@dataclass(frozen=True)
class PinholeCamera:
    """Intrinsics of a pinhole depth camera.

    Attributes:
        fx: Focal length along image columns [px].
        fy: Focal length along image rows [px].
        cx: Principal point column [px].
        cy: Principal point row [px].
        width: Image width [px].
        height: Image height [px].
        min_range: Depth below this is dropped [m].
        max_range: Depth beyond this is dropped [m].
        noise: How far its readings scatter with range (:mod:`footfall.sensing.noise`);
            ideal by default.
    """

    fx: float
    fy: float
    cx: float
    cy: float
    width: int
    height: int
    min_range: float = 0.0
    max_range: float = 10.0
    noise: DepthNoiseModel = IDEAL

    def __post_init__(self) -> None:
        values = {"fx": self.fx, "fy": self.fy, "cx": self.cx, "cy": self.cy}
        values |= {"min_range": self.min_range}
        for name, value in values.items():
            if not math.isfinite(value):
                raise ConfigError(f"camera {name} must be a finite number, got {value}")
        if not (self.fx > 0 and self.fy > 0):
            raise ConfigError(f"focal lengths must be positive, got fx={self.fx}, fy={self.fy}")
        if not (self.width > 0 and self.height > 0):
            raise ConfigError(f"image size must be positive, got {self.width}x{self.height}")
        if not 0 <= self.min_range < self.max_range:
            raise ConfigError(
                f"need 0 <= min_range < max_range, got {self.min_range}, {self.max_range}"
            )

    @classmethod
    def from_matrix(
        cls,
        K: npt.ArrayLike,
        width: int,
        height: int,
        min_range: float = 0.0,
        max_range: float = 10.0,
    ) -> PinholeCamera:
        """A camera from a 3x3 intrinsic matrix ``[[fx, 0, cx], [0, fy, cy], [0, 0, 1]]``.

        Raises:
            ConfigError: If K is not 3x3 or has skew.
        """
        k = np.asarray(K, dtype=np.float64)
        if k.shape != (3, 3):
            raise ConfigError(f"intrinsic matrix must be 3x3, got shape {k.shape}")
        if abs(k[0, 1]) > 1e-12 or not np.allclose(k[2], [0, 0, 1]) or abs(k[1, 0]) > 1e-12:
            raise ConfigError(
                f"intrinsic matrix must be [[fx, 0, cx], [0, fy, cy], [0, 0, 1]], got {k.tolist()}"
            )
        return cls(k[0, 0], k[1, 1], k[0, 2], k[1, 2], width, height, min_range, max_range)

    @classmethod
    def from_fov(
        cls,
        horizontal_fov: float,
        vertical_fov: float,
        width: int,
        height: int,
        max_range: float = 10.0,
    ) -> PinholeCamera:
        """A centred camera with the given fields of view [rad]."""
        fx = 0.5 * width / math.tan(0.5 * horizontal_fov)
        fy = 0.5 * height / math.tan(0.5 * vertical_fov)
        return cls(fx, fy, 0.5 * width, 0.5 * height, width, height, 0.0, max_range)

    @property
    def matrix(self) -> npt.NDArray[np.float64]:
        """The 3x3 intrinsic matrix."""
        return np.array([[self.fx, 0.0, self.cx], [0.0, self.fy, self.cy], [0.0, 0.0, 1.0]])

    def scaled(self, width: int, height: int) -> PinholeCamera:
        """The same camera at another image size (same fields of view)."""
        sx, sy = width / self.width, height / self.height
        return PinholeCamera(
            self.fx * sx,
            self.fy * sy,
            self.cx * sx,
            self.cy * sy,
            width,
            height,
            self.min_range,
            self.max_range,
            self.noise,
        )

    def depth_in_metres(
        self, depth: npt.ArrayLike, depth_scale: float | None = None
    ) -> npt.NDArray:
        """Check a depth image and say how to read it.

        Args:
            depth: Shape (height, width): float metres, or unsigned integers with a scale.
            depth_scale: Metres per unit for integer depth (e.g. 0.001 for millimetres,
                1/5000 for TUM). Must be None or 1 for float depth.

        Returns:
            The depth as given (no copy); multiply by :meth:`scale_for` to get metres.

        Raises:
            DepthImageError: Wrong shape, an unsupported dtype, or integer depth without a scale.
        """
        d = np.asarray(depth)
        if d.shape != (self.height, self.width):
            raise DepthImageError(
                f"depth image has shape {d.shape}, the camera expects ({self.height}, {self.width})"
            )
        if d.dtype.kind == "f":
            if depth_scale not in (None, 1.0):
                raise DepthImageError("float depth is in metres already; pass no depth_scale")
        elif d.dtype.kind == "u":
            if depth_scale is None or not depth_scale > 0:
                raise DepthImageError(
                    f"integer depth ({d.dtype}) needs a positive depth_scale in metres per unit"
                )
        else:
            raise DepthImageError(
                f"depth must be float metres or unsigned integers, got dtype {d.dtype}"
            )
        return d

    @staticmethod
    def scale_for(depth: npt.NDArray, depth_scale: float | None) -> float:
        """Metres per depth unit for an image checked by :meth:`depth_in_metres`."""
        return 1.0 if depth.dtype.kind == "f" else float(depth_scale)  # type: ignore[arg-type]

    @staticmethod
    def units_per_metre_for(depth: npt.NDArray, depth_scale: float | None) -> float:
        """Whole depth units per metre (1000 for mm, 5000 for TUM), or 0 when not whole.

        Integer depth is divided by this rather than multiplied by its inverse: the real
        quotient of 5 v / 5000 and v / 1000 is the same, so a depth in TUM units and the
        same depth in millimetres give bit-identical metres.
        """
        if depth.dtype.kind == "f" or not depth_scale:
            return 0.0
        units = 1.0 / float(depth_scale)
        whole = round(units)
        return float(whole) if whole >= 1 and abs(units - whole) <= 1e-9 * units else 0.0

    @classmethod
    def to_metres(cls, depth: npt.NDArray, depth_scale: float | None) -> npt.NDArray[np.float64]:
        """Depth in metres, float64, from an image checked by :meth:`depth_in_metres`."""
        units = cls.units_per_metre_for(depth, depth_scale)
        if units:
            return depth.astype(np.float64) / units
        return depth.astype(np.float64) * cls.scale_for(depth, depth_scale)

    def organized_points(
        self, depth: npt.ArrayLike, depth_scale: float | None = None
    ) -> npt.NDArray[np.float64]:
        """Back-project every pixel: shape (height, width, 3) [m], NaN where depth is invalid."""
        d = self.depth_in_metres(depth, depth_scale)
        z = self.to_metres(d, depth_scale)
        valid = np.isfinite(z) & (z > 0) & (z >= self.min_range) & (z <= self.max_range)
        z = np.where(valid, z, np.nan)
        u = np.arange(self.width, dtype=np.float64)
        v = np.arange(self.height, dtype=np.float64)[:, None]
        return np.stack([z * (u - self.cx) / self.fx, z * (v - self.cy) / self.fy, z], axis=-1)

    def depth_to_points(
        self, depth: npt.ArrayLike, depth_scale: float | None = None, stride: int = 1
    ) -> tuple[npt.NDArray[np.float64], DepthStats]:
        """Back-project the valid pixels of a depth image into the camera frame.

        Args:
            depth: Shape (height, width): float metres, or unsigned integers with a scale.
            depth_scale: Metres per unit for integer depth.
            stride: Keep every ``stride``-th row and column (downsampling).

        Returns:
            Points, shape (n, 3) [m], and what became of the pixels.

        Raises:
            DepthImageError: On a malformed image (see :meth:`depth_in_metres`).
        """
        if stride < 1:
            raise DepthImageError(f"stride must be >= 1, got {stride}")
        d = self.depth_in_metres(depth, depth_scale)[::stride, ::stride]
        z = self.to_metres(d, depth_scale)
        finite = np.isfinite(z)
        zero = finite & (z == 0)
        negative = finite & (z < 0)
        in_range = finite & (z > 0) & (z >= self.min_range) & (z <= self.max_range)
        stats = DepthStats(
            valid=int(in_range.sum()),
            zero=int(zero.sum()),
            non_finite=int((~finite).sum()),
            negative=int(negative.sum()),
            out_of_range=int((finite & (z > 0) & ~in_range).sum()),
        )
        rows, cols = np.nonzero(in_range)
        zv = z[rows, cols]
        u = cols * stride
        v = rows * stride
        points = np.stack([zv * (u - self.cx) / self.fx, zv * (v - self.cy) / self.fy, zv], axis=1)
        return points, stats
