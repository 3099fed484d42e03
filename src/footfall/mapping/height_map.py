"""Rolling height map: an N x N two-dimensional circular buffer that follows the robot.

A world point ``(x, y)`` falls in the global cell ``(floor(x / res), floor(y / res))``
(thesis eq. 4.11 with ``res`` in metres per cell) and is stored at buffer index
``(i mod N, j mod N)``. The buffer holds the window of global cells
``[origin, origin + N)`` on each axis; moving the window (:meth:`HeightMap.recentre`)
erases only the rows and columns that scroll out, so a move costs O(N * cells moved),
never a copy of the map. Erased cells become unknown.

Fusion of a new frame (``HeightMapConfig.fusion``): within one frame, each cell takes the
highest point that falls in it (the top of whatever is there: the side of a box seen at a
slant is lower than its top), or for a noisy camera the mean of its points (the highest
would be the top of the noise). Across frames:

- ``latest`` (default, the thesis' rule): the newest frame's value replaces the cell;
- ``max``: the highest value ever seen stays;
- ``variance``: a scalar Kalman update whose measurement noise is the camera's
  (:mod:`footfall.sensing.noise`; for an ideal camera ``range_noise * r^2``), gated so a
  value far off the estimate (the scene changed) replaces it. Over frames a real floor's
  noise averages down.

Each cell also keeps the largest height range of its points within one frame beyond what
the camera's noise explains (``noise_spread_sigmas`` standard deviations): a cell that
straddles an edge shows it, a noisy flat floor does not. And it keeps which quarters-of-a-
quarter (4 x 4 parts) of it any point has fallen in, and how many points: a groove too
narrow for the grid, seen at a grazing angle, hides in the shadow of its near edge, and
the part of the cell it crosses is never hit however often the rest is.

With drift compensation on (``HeightMapConfig.drift``), each frame is first registered in
height against the map (:mod:`footfall.mapping.drift`). The buffer, its window arithmetic
and the integration that writes it are one module: they share the buffer's layout.

Invalid readings (no return, NaN, out of range) never touch the map; neither do points
outside the window, which are counted.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from enum import StrEnum

import numpy as np
import numpy.typing as npt
from scipy.spatial.transform import Rotation

from footfall.errors import ConfigError
from footfall.mapping import kernels
from footfall.mapping.drift import DriftCompensator, DriftConfig, Registration, frame_offset
from footfall.sensing.camera import DepthStats, PinholeCamera
from footfall.sensing.noise import IDEAL, DepthNoiseModel
from footfall.sensing.pose import Pose


class FusionRule(StrEnum):
    """How a new observation of a cell combines with what the map holds."""

    LATEST = "latest"
    MAX = "max"
    VARIANCE = "variance"


_RULE_CODES = {
    FusionRule.LATEST: kernels.FUSE_LATEST,
    FusionRule.MAX: kernels.FUSE_MAX,
    FusionRule.VARIANCE: kernels.FUSE_VARIANCE,
}


# An assumed cell (:meth:`HeightMap.assume_ground`) is contradicted when the camera's
# reading through its centre lies this much beyond it, plus three standard deviations of
# the camera's noise there [m].
SEE_THROUGH_M = 0.02
# The largest world coordinate a map window may be centred on [m] (cell indices stay exact).
MAX_COORDINATE = 1e7
# A cell's height difference counts at most this much in a frame's misfit [m].
MISFIT_CAP_M = 0.05
# A frame's points count towards their cells' ``points`` (the evidence that a never-hit
# part lies in a shadow) only from a new viewpoint: the camera moved this far [m] or turned
# this much [rad] since the last frame that counted. A camera standing still puts its rays
# on the same spots every frame, and its sparse rows miss the same parts.
NEW_VIEW_M = 0.005
NEW_VIEW_RAD = 0.005
# Nor from a sensor whose noise at the cell exceeds this share of a part's side: its points
# scatter over the parts, and quantized depth lays them on stripes with never-hit parts
# between them.
EVIDENCE_NOISE_SHARE = 0.2


@dataclass(frozen=True)
class HeightMapConfig:
    """Height map settings.

    Attributes:
        size: Cells per side, N.
        resolution: Cell side [m].
        fusion: Fusion rule across frames.
        range_noise: Depth noise coefficient of the ``variance`` rule: the standard deviation
            of a reading at range r is ``range_noise * r^2`` [1/m].
        process_noise: Standard deviation added to a cell per update (``variance``) [m].
        gate: Innovation gate of the ``variance`` rule [standard deviations].
        noise_spread_sigmas: In-frame height range of a cell the camera's noise alone
            explains [standard deviations of the noise at the cell's range].
        drift: Vertical drift compensation of each frame against the map (off by default;
            see :mod:`footfall.mapping.drift`).
    """

    size: int = 256
    resolution: float = 0.02
    fusion: FusionRule = FusionRule.LATEST
    range_noise: float = 0.003
    process_noise: float = 0.002
    gate: float = 4.0
    noise_spread_sigmas: float = 6.0
    drift: DriftConfig = field(default_factory=DriftConfig)

    def __post_init__(self) -> None:
        object.__setattr__(self, "fusion", FusionRule(self.fusion))
        if self.size < 8:
            raise ConfigError(f"height map size must be >= 8 cells, got {self.size}")
        if not (math.isfinite(self.resolution) and 1e-4 <= self.resolution <= 100.0):
            raise ConfigError(
                f"height map resolution must lie in [0.0001, 100] m, got {self.resolution}"
            )
        for name in ("range_noise", "process_noise", "gate", "noise_spread_sigmas"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0):
                raise ConfigError(f"height map {name} must be a number >= 0, got {value}")

    @property
    def extent(self) -> float:
        """Side of the mapped square [m]."""
        return self.size * self.resolution


@dataclass(frozen=True)
class IntegrationStats:
    """What became of one frame's readings.

    Attributes:
        depth: Pixel counts (valid, zero, non-finite, negative, out of range).
        outside: Valid readings that fell outside the map window.
        cells_updated: Map cells the frame wrote.
        vertical_offset_m: The frame's height above the map where they overlap, taken out
            before fusion (drift compensation) [m]; NaN when not estimated.
        inconsistent: The frame was not fused: its offset jumped, beyond drift.
        settled: The offset moved to a new level that several frames agree on.
    """

    depth: DepthStats
    outside: int
    cells_updated: int
    vertical_offset_m: float = math.nan
    inconsistent: bool = False
    settled: bool = False


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


class HeightMap:
    """A rolling 2.5-D height map in the world (map) frame.

    Args:
        config: Size, resolution and fusion rule.
        centre: World ``(x, y)`` the window starts centred on [m].
    """

    def __init__(
        self, config: HeightMapConfig | None = None, centre: tuple[float, float] = (0.0, 0.0)
    ) -> None:
        self.config = config or HeightMapConfig()
        n = self.config.size
        self._inv_res = 1.0 / self.config.resolution
        self.heights = np.zeros((n, n), dtype=np.float64)
        self.variance = np.zeros((n, n), dtype=np.float64)
        self.known = np.zeros((n, n), dtype=bool)
        self.spread = np.zeros((n, n), dtype=np.float64)
        self.parts = np.zeros((n, n), dtype=np.uint16)
        self.points = np.zeros((n, n), dtype=np.int64)
        self.assumed = np.zeros((n, n), dtype=bool)
        self._frame_h = np.zeros((n, n), dtype=np.float64)
        self._frame_lo = np.zeros((n, n), dtype=np.float64)
        self._frame_r2 = np.zeros((n, n), dtype=np.float64)
        self._frame_sum = np.zeros((n, n), dtype=np.float64)
        self._frame_n = np.zeros((n, n), dtype=np.int64)
        self._frame_parts = np.zeros((n, n), dtype=np.uint16)
        self._stamp = np.zeros((n, n), dtype=np.int64)
        self._touched = np.zeros(n * n, dtype=np.int64)
        self._frame_id = 0
        self._last_view: tuple[npt.NDArray[np.float64], Rotation | None] | None = None
        self.origin = self._origin_for(centre)
        self.drift = DriftCompensator(self.config.drift)

    # Geometry -------------------------------------------------------------------------
    def _origin_for(self, centre: tuple[float, float]) -> npt.NDArray[np.int64]:
        c = np.asarray(centre, dtype=np.float64)
        if c.shape != (2,) or not np.all(np.isfinite(c)) or np.any(np.abs(c) > MAX_COORDINATE):
            raise ConfigError(
                f"a map centre must be two finite coordinates within {MAX_COORDINATE:g} m, "
                f"got {centre!r}"
            )
        cell = np.floor(c * self._inv_res).astype(np.int64)
        return cell - self.config.size // 2

    def cell_of(self, xy: npt.ArrayLike) -> npt.NDArray[np.int64]:
        """Global cell indices of world points, shape (..., 2)."""
        return np.floor(np.asarray(xy, dtype=np.float64) * self._inv_res).astype(np.int64)

    def centre_of(self, cell: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """World ``(x, y)`` of global cells' centres, shape (..., 2) [m]."""
        return (np.asarray(cell, dtype=np.float64) + 0.5) * self.config.resolution

    def buffer_index(self, cell: npt.ArrayLike) -> npt.NDArray[np.int64]:
        """Buffer indices of global cells (wrap-around), shape (..., 2)."""
        return np.mod(np.asarray(cell, dtype=np.int64), self.config.size)

    def contains(self, cell: npt.ArrayLike) -> npt.NDArray[np.bool_]:
        """Whether global cells lie inside the current window, shape (...)."""
        offset = np.asarray(cell, dtype=np.int64) - self.origin
        return np.all((offset >= 0) & (offset < self.config.size), axis=-1)

    def height_at(self, xy: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Mapped heights at world points [m], NaN where unknown or outside the window."""
        cell = self.cell_of(xy)
        inside = self.contains(cell)
        idx = self.buffer_index(cell)
        out = np.full(inside.shape, np.nan)
        i, j = idx[..., 0][inside], idx[..., 1][inside]
        known = self.known[i, j]
        values = np.where(known, self.heights[i, j], np.nan)
        out[inside] = values
        return out

    # Moving the window -----------------------------------------------------------------
    def recentre(self, centre: tuple[float, float]) -> None:
        """Move the window to be centred on a world point; cells that scroll out are erased."""
        new_origin = self._origin_for(centre)
        n = self.config.size
        for axis in (0, 1):
            shift = int(new_origin[axis] - self.origin[axis])
            if shift == 0:
                continue
            if abs(shift) >= n:
                self.known[:] = False
                self.assumed[:] = False
                break
            if shift > 0:  # cells [origin, origin + shift) leave
                leaving = np.arange(self.origin[axis], self.origin[axis] + shift)
            else:  # cells [new_origin + n, origin + n) leave
                leaving = np.arange(new_origin[axis] + n, self.origin[axis] + n)
            rows = np.mod(leaving, n)
            if axis == 0:
                self.known[rows, :] = False
                self.assumed[rows, :] = False
            else:
                self.known[:, rows] = False
                self.assumed[:, rows] = False
        self.origin = new_origin

    # Integration -----------------------------------------------------------------------
    def _origin_code(self) -> npt.NDArray[np.int64]:
        n = self.config.size
        return np.array(
            [self.origin[0], self.origin[1], self.origin[0] % n, self.origin[1] % n], dtype=np.int64
        )

    def _next_frame(self) -> int:
        self._frame_id += 1
        return self._frame_id

    def _new_view(self, sensor_position: npt.ArrayLike, rotation: Rotation | None) -> bool:
        """Whether a frame from here counts as a new view (``NEW_VIEW_M``, ``NEW_VIEW_RAD``)."""
        position = np.asarray(sensor_position, dtype=np.float64)
        last = self._last_view
        if last is not None:
            moved = float(np.linalg.norm(position - last[0])) >= NEW_VIEW_M
            turned = (
                rotation is not None
                and last[1] is not None
                and (rotation * last[1].inv()).magnitude() >= NEW_VIEW_RAD
            )
            if not (moved or turned):
                return False
        self._last_view = (position, rotation)
        return True

    def _fuse(self, n_touched: int, noise: DepthNoiseModel = IDEAL, new_view: bool = True) -> None:
        c = self.config
        kernels.fuse(
            self._touched,
            n_touched,
            self._frame_h,
            self._frame_lo,
            self._frame_r2,
            self._frame_sum,
            self._frame_n,
            self._frame_parts,
            self.heights,
            self.spread,
            self.variance,
            self.known,
            self.parts,
            self.points,
            new_view,
            EVIDENCE_NOISE_SHARE * c.resolution / kernels.SUB,
            _RULE_CODES[c.fusion],
            c.range_noise,
            c.process_noise,
            c.gate,
            np.array([noise.base_m, noise.quadratic_per_m, noise.offset_m]),
            c.noise_spread_sigmas,
        )

    def integrate_depth(
        self,
        depth: npt.ArrayLike,
        camera: PinholeCamera,
        camera_pose: Pose,
        depth_scale: float | None = None,
        stride: int = 1,
    ) -> IntegrationStats:
        """Add one depth image taken from ``camera_pose`` (the camera's pose in the world).

        Args:
            depth: Shape (height, width): float metres or unsigned integers with a scale.
            camera: Intrinsics; the optical frame is x right, y down, z forward.
            camera_pose: Pose of the optical frame in the world (the map frame, z up).
            depth_scale: Metres per unit of integer depth.
            stride: Use every ``stride``-th row and column.

        Returns:
            Pixel and cell counts.

        Raises:
            DepthImageError: On a malformed image.
        """
        counts = np.zeros(kernels.N_COUNTS, dtype=np.int64)
        n_touched = self._bin(depth, camera, camera_pose, depth_scale, stride, counts)
        registration = None
        if self.config.drift.enabled:
            registration = self._register(n_touched, camera.noise.is_ideal)
            if not registration.consistent:
                return replace(
                    self._stats(counts, 0),
                    vertical_offset_m=registration.measured_m,
                    inconsistent=True,
                )
        if self.assumed.any():
            self._check_assumed(n_touched, depth, camera, camera_pose, depth_scale)
        self._fuse(
            n_touched,
            camera.noise,
            self._new_view(camera_pose.position, camera_pose.rotation),
        )
        stats = self._stats(counts, n_touched)
        if registration is None:
            return stats
        return replace(stats, vertical_offset_m=registration.offset_m, settled=registration.settled)

    def assume_ground(
        self, points_in_world: npt.ArrayLike, sensor_position: npt.ArrayLike
    ) -> IntegrationStats:
        """Take ground the robot knows without seeing it (under its feet) into unknown cells.

        The cells this fills are *assumed*: the first depth frame whose point falls in one
        confirms it, and a frame that sees through one (its reading along the ray through
        the cell's centre lies beyond it: the floor past a pit's rim the robot stands at)
        erases it. Cells known already keep what they hold.
        """
        p = np.ascontiguousarray(points_in_world, dtype=np.float64)
        if p.ndim != 2 or p.shape[1] != 3:
            raise ConfigError(f"points must have shape (n, 3), got {p.shape}")
        cells = self.cell_of(p[:, :2])
        inside = self.contains(cells)
        idx = self.buffer_index(cells[inside])
        fresh = ~self.known[idx[:, 0], idx[:, 1]]
        stats = self.integrate_points(p[inside][fresh], sensor_position)
        i, j = idx[fresh, 0], idx[fresh, 1]
        self.assumed[i, j] = self.known[i, j]
        return stats

    def _check_assumed(
        self,
        n_touched: int,
        depth: npt.ArrayLike,
        camera: PinholeCamera,
        camera_pose: Pose,
        depth_scale: float | None,
    ) -> None:
        """Confirm the assumed cells a binned frame hits; erase those it sees through."""
        n = self.config.size
        idx = self._touched[:n_touched]
        self.assumed.flat[idx] = False
        i, j = np.nonzero(self.assumed)
        if not len(i):
            return
        global_cell = self.origin + np.mod(np.column_stack([i, j]) - self.origin % n, n)
        centre = np.column_stack([self.centre_of(global_cell), self.heights[i, j]])
        in_camera = camera_pose.rotation.inv().apply(centre - camera_pose.position)
        z = in_camera[:, 2]
        ahead = z > camera.min_range
        u = np.full(len(z), -1, dtype=np.int64)
        v = np.full(len(z), -1, dtype=np.int64)
        u[ahead] = np.round(camera.fx * in_camera[ahead, 0] / z[ahead] + camera.cx)
        v[ahead] = np.round(camera.fy * in_camera[ahead, 1] / z[ahead] + camera.cy)
        seen = ahead & (u >= 0) & (u < camera.width) & (v >= 0) & (v < camera.height)
        if not seen.any():
            return
        d = camera.depth_in_metres(depth, depth_scale)
        reading = d[v[seen], u[seen]].astype(np.float64) * camera.scale_for(d, depth_scale)
        valid = np.isfinite(reading) & (reading > camera.min_range) & (reading <= camera.max_range)
        sigma = camera.noise.sigma_m(z[seen])  # elementwise on the ranges
        beyond = valid & (reading > z[seen] + SEE_THROUGH_M + 3.0 * sigma)
        gone_i, gone_j = i[seen][beyond], j[seen][beyond]
        self.known[gone_i, gone_j] = False
        self.assumed[gone_i, gone_j] = False

    def _bin(
        self,
        depth: npt.ArrayLike,
        camera: PinholeCamera,
        camera_pose: Pose,
        depth_scale: float | None,
        stride: int,
        counts: npt.NDArray[np.int64],
    ) -> int:
        """Bin one image into the frame buffers; returns how many cells it touched."""
        d = camera.depth_in_metres(depth, depth_scale)
        if stride < 1:
            raise ConfigError(f"stride must be >= 1, got {stride}")
        return int(
            kernels.bin_depth(
                d,
                camera.scale_for(d, depth_scale),
                camera.units_per_metre_for(d, depth_scale),
                stride,
                camera.fx,
                camera.fy,
                camera.cx,
                camera.cy,
                camera.min_range,
                camera.max_range,
                camera_pose.rotation.as_matrix(),
                camera_pose.position,
                self._inv_res,
                self._origin_code(),
                self._frame_h,
                self._frame_lo,
                self._frame_r2,
                self._frame_sum,
                self._frame_n,
                self._frame_parts,
                not camera.noise.is_ideal,
                self._stamp,
                self._next_frame(),
                self._touched,
                counts,
            )
        )

    def _frame_cells(self, n_touched: int, ideal: bool) -> tuple[npt.NDArray[np.int64], ...]:
        """Buffer rows and columns of the binned frame's cells, and their heights [m]."""
        n = self.config.size
        idx = self._touched[:n_touched]
        i, j = idx // n, idx % n
        z = self._frame_h[i, j] if ideal else self._frame_sum[i, j] / self._frame_n[i, j]
        return i, j, z

    def misfit(
        self,
        depth: npt.ArrayLike,
        camera: PinholeCamera,
        camera_pose: Pose,
        depth_scale: float | None = None,
        stride: int = 1,
    ) -> float:
        """How far an image taken from ``camera_pose`` lies from the map, without fusing it.

        The mean over the cells both know, and both see flat (as drift compensation
        counts them: a cell across an edge differs with the viewpoint), of the height
        difference less the drift offset taken last, each truncated at ``MISFIT_CAP_M`` (a
        cell the map has not seen since something moved counts no more than that) [m]. A
        frame placed at the wrong pose puts the tops of things where the map has ground,
        and its misfit grows.

        Returns:
            The misfit; NaN when fewer than ``drift.min_cells`` cells overlap.

        Raises:
            DepthImageError: On a malformed image.
        """
        counts = np.zeros(kernels.N_COUNTS, dtype=np.int64)
        n_touched = self._bin(depth, camera, camera_pose, depth_scale, stride, counts)
        ideal = camera.noise.is_ideal
        i, j, z = self._frame_cells(n_touched, ideal)
        frame_range = (self._frame_h[i, j] - self._frame_lo[i, j]) if ideal else np.zeros(len(z))
        flat = self.config.drift.flat_m
        seen = self.known[i, j] & (frame_range < flat) & (self.spread[i, j] < flat)
        if int(seen.sum()) < self.config.drift.min_cells:
            return math.nan
        difference = z[seen] - self.heights[i[seen], j[seen]] - self.drift.offset_m
        return float(np.mean(np.minimum(np.abs(difference), MISFIT_CAP_M)))

    def _register(self, n_touched: int, ideal: bool) -> Registration:
        """Measure the frame's vertical offset against the map and take it out of the frame."""
        i, j, z = self._frame_cells(n_touched, ideal)
        seen = self.known[i, j]
        frame_range = (self._frame_h[i, j] - self._frame_lo[i, j]) if ideal else np.zeros(len(z))
        measured = frame_offset(
            z[seen],
            frame_range[seen],
            self.heights[i[seen], j[seen]],
            self.spread[i[seen], j[seen]],
            self.config.drift,
        )
        registration = self.drift.judge(measured)
        if registration.consistent and registration.offset_m != 0.0:
            offset = registration.offset_m
            self._frame_h[i, j] -= offset
            self._frame_lo[i, j] -= offset
            self._frame_sum[i, j] -= offset * self._frame_n[i, j]
        return registration

    def integrate_points(
        self, points_in_world: npt.ArrayLike, sensor_position: npt.ArrayLike
    ) -> IntegrationStats:
        """Add a point cloud already in the world frame, seen from ``sensor_position``.

        Args:
            points_in_world: Shape (n, 3) [m]; non-finite points are counted and skipped.
            sensor_position: Where the points were seen from, shape (3,) [m] (for ranges).
        """
        p = np.ascontiguousarray(points_in_world, dtype=np.float64)
        if p.ndim != 2 or p.shape[1] != 3:
            raise ConfigError(f"points must have shape (n, 3), got {p.shape}")
        counts = np.zeros(kernels.N_COUNTS, dtype=np.int64)
        n_touched = kernels.bin_points(
            p,
            np.asarray(sensor_position, dtype=np.float64),
            self._inv_res,
            self._origin_code(),
            self._frame_h,
            self._frame_lo,
            self._frame_r2,
            self._frame_sum,
            self._frame_n,
            self._frame_parts,
            self._stamp,
            self._next_frame(),
            self._touched,
            counts,
        )
        self._fuse(n_touched, new_view=self._new_view(sensor_position, None))
        return self._stats(counts, n_touched)

    @staticmethod
    def _stats(counts: npt.NDArray[np.int64], n_touched: int) -> IntegrationStats:
        k = kernels
        return IntegrationStats(
            depth=DepthStats(
                valid=int(counts[k.VALID] + counts[k.OUTSIDE]),
                zero=int(counts[k.ZERO]),
                non_finite=int(counts[k.NON_FINITE]),
                negative=int(counts[k.NEGATIVE]),
                out_of_range=int(counts[k.OUT_OF_RANGE]),
            ),
            outside=int(counts[k.OUTSIDE]),
            cells_updated=int(n_touched),
        )

    # Views -------------------------------------------------------------------------------
    def snapshot(self) -> MapSnapshot:
        """The window as arrays ordered by world position (cell [0, 0] at the window corner)."""
        shift = (-int(self.origin[0] % self.config.size), -int(self.origin[1] % self.config.size))
        known = np.roll(self.known, shift, axis=(0, 1))
        heights = np.where(known, np.roll(self.heights, shift, axis=(0, 1)), np.nan)
        spread = np.where(known, np.roll(self.spread, shift, axis=(0, 1)), np.nan)
        variance = np.where(known, np.roll(self.variance, shift, axis=(0, 1)), np.nan)
        parts = np.where(known, np.roll(self.parts, shift, axis=(0, 1)), 0).astype(np.uint16)
        points = np.where(known, np.roll(self.points, shift, axis=(0, 1)), 0)
        origin = (
            float(self.origin[0] * self.config.resolution),
            float(self.origin[1] * self.config.resolution),
        )
        return MapSnapshot(
            heights=heights,
            known=known,
            origin=origin,
            resolution=self.config.resolution,
            spread=spread,
            variance=variance,
            parts=parts,
            points=points,
        )
