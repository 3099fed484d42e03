"""Rolling height map: an N x N two-dimensional circular buffer that follows the robot.

The window (:mod:`footfall.mapping.window`) says which global cells the buffer holds;
moving it (:meth:`HeightMap.recentre`) erases only the rows and columns that scroll out, so
a move costs O(N * cells moved), never a copy of the map. Erased cells become unknown.

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
height against the map (:mod:`footfall.mapping.drift`). Ground under the standing robot
may be assumed before it is seen (:mod:`footfall.mapping.assumed`).

Invalid readings (no return, NaN, out of range) never touch the map; neither do points
outside the window, which are counted. :class:`HeightMap` is the numba engine of
:mod:`footfall.mapping.engine`.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import numpy.typing as npt
from scipy.spatial.transform import Rotation

from footfall.errors import ConfigError
from footfall.mapping import kernels
from footfall.mapping.assumed import check_assumed
from footfall.mapping.drift import DriftCompensator, Registration, frame_offset
from footfall.mapping.engine import HeightMapConfig, IntegrationStats
from footfall.mapping.fusion import bin_depth, bin_points, fuse, integration_stats
from footfall.mapping.layers import CellLayers, FrameBuffers
from footfall.mapping.snapshot import MapSnapshot
from footfall.mapping.window import MapWindow
from footfall.sensing.camera import PinholeCamera
from footfall.sensing.pose import Pose

# A cell's height difference counts at most this much in a frame's misfit [m].
MISFIT_CAP_M = 0.05
# A frame's points count towards their cells' ``points`` (the evidence that a never-hit
# part lies in a shadow) only from a new viewpoint: the camera moved this far [m] or turned
# this much [rad] since the last frame that counted. A camera standing still puts its rays
# on the same spots every frame, and its sparse rows miss the same parts.
NEW_VIEW_M = 0.005
NEW_VIEW_RAD = 0.005


class HeightMap:
    """A rolling 2.5-D height map in the world (map) frame.

    Args:
        config: Size, resolution and fusion rule.
        centre: World ``(x, y)`` the window starts centred on [m].

    Attributes:
        config: The settings.
        window: Which global cells the buffer holds.
        layers: What each cell holds.
        frame: The newest frame, binned into cells.
        drift: The vertical drift compensation.
    """

    def __init__(
        self, config: HeightMapConfig | None = None, centre: tuple[float, float] = (0.0, 0.0)
    ) -> None:
        self.config = config or HeightMapConfig()
        n = self.config.size
        self.window = MapWindow(n, self.config.resolution, centre)
        self.layers = CellLayers.empty(n)
        self.frame = FrameBuffers.empty(n)
        self.drift = DriftCompensator(self.config.drift)
        self._last_view: tuple[npt.NDArray[np.float64], Rotation | None] | None = None

    # The layers and the window, as the buffer holds them ----------------------------------
    @property
    def heights(self) -> npt.NDArray[np.float64]:
        """Cell heights in buffer order, shape (N, N) [m] (meaningful where ``known``)."""
        return self.layers.heights

    @property
    def known(self) -> npt.NDArray[np.bool_]:
        """Which cells hold a height, in buffer order, shape (N, N)."""
        return self.layers.known

    @property
    def spread(self) -> npt.NDArray[np.float64]:
        """In-frame height range beyond the noise, in buffer order, shape (N, N) [m]."""
        return self.layers.spread

    @property
    def assumed(self) -> npt.NDArray[np.bool_]:
        """Which cells are known without being seen, in buffer order, shape (N, N)."""
        return self.layers.assumed

    @property
    def origin(self) -> npt.NDArray[np.int64]:
        """The global cell at the window's corner, shape (2,)."""
        return self.window.origin

    def cell_of(self, xy: npt.ArrayLike) -> npt.NDArray[np.int64]:
        """Global cell indices of world points, shape (..., 2)."""
        return self.window.cell_of(xy)

    def centre_of(self, cell: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """World ``(x, y)`` of global cells' centres, shape (..., 2) [m]."""
        return self.window.centre_of(cell)

    def buffer_index(self, cell: npt.ArrayLike) -> npt.NDArray[np.int64]:
        """Buffer indices of global cells (wrap-around), shape (..., 2)."""
        return self.window.buffer_index(cell)

    def contains(self, cell: npt.ArrayLike) -> npt.NDArray[np.bool_]:
        """Whether global cells lie inside the current window, shape (...)."""
        return self.window.contains(cell)

    def height_at(self, xy: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Mapped heights at world points [m], NaN where unknown or outside the window."""
        cell = self.cell_of(xy)
        inside = self.contains(cell)
        idx = self.buffer_index(cell)
        out = np.full(inside.shape, np.nan)
        i, j = idx[..., 0][inside], idx[..., 1][inside]
        out[inside] = np.where(self.known[i, j], self.heights[i, j], np.nan)
        return out

    def recentre(self, centre: tuple[float, float]) -> None:
        """Move the window to be centred on a world point; cells that scroll out are erased."""
        self.layers.forget(self.window.move(centre))

    # Integration -----------------------------------------------------------------------
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
        n_touched = bin_depth(
            self.frame, self.window, depth, camera, camera_pose, depth_scale, stride, counts
        )
        registration = None
        if self.config.drift.enabled:
            registration = self._register(n_touched, camera.noise.is_ideal)
            if not registration.consistent:
                return replace(
                    integration_stats(counts, 0),
                    vertical_offset_m=registration.measured_m,
                    inconsistent=True,
                )
        if self.assumed.any():
            hit = self.frame.touched[:n_touched]
            check_assumed(self.layers, self.window, hit, depth, camera, camera_pose, depth_scale)
        new_view = self._new_view(camera_pose.position, camera_pose.rotation)
        fuse(self.frame, self.layers, n_touched, self.config, camera.noise, new_view)
        stats = integration_stats(counts, n_touched)
        if registration is None:
            return stats
        return replace(stats, vertical_offset_m=registration.offset_m, settled=registration.settled)

    def assume_ground(
        self, points_in_world: npt.ArrayLike, sensor_position: npt.ArrayLike
    ) -> IntegrationStats:
        """Take ground the robot knows without seeing it (under its feet) into unknown cells.

        The cells this fills are *assumed* (:mod:`footfall.mapping.assumed`): the first depth
        frame whose point falls in one confirms it, and a frame that sees through one
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
        n_touched = bin_depth(
            self.frame, self.window, depth, camera, camera_pose, depth_scale, stride, counts
        )
        ideal = camera.noise.is_ideal
        frame = self.frame
        i, j, z = frame.cells(n_touched, ideal)
        frame_range = (frame.top[i, j] - frame.low[i, j]) if ideal else np.zeros(len(z))
        flat = self.config.drift.flat_m
        seen = self.known[i, j] & (frame_range < flat) & (self.spread[i, j] < flat)
        if int(seen.sum()) < self.config.drift.min_cells:
            return math.nan
        difference = z[seen] - self.heights[i[seen], j[seen]] - self.drift.offset_m
        return float(np.mean(np.minimum(np.abs(difference), MISFIT_CAP_M)))

    def _register(self, n_touched: int, ideal: bool) -> Registration:
        """Measure the frame's vertical offset against the map and take it out of the frame."""
        frame = self.frame
        i, j, z = frame.cells(n_touched, ideal)
        seen = self.known[i, j]
        frame_range = (frame.top[i, j] - frame.low[i, j]) if ideal else np.zeros(len(z))
        measured = frame_offset(
            z[seen],
            frame_range[seen],
            self.heights[i[seen], j[seen]],
            self.spread[i[seen], j[seen]],
            self.config.drift,
        )
        registration = self.drift.judge(measured)
        if registration.consistent and registration.offset_m != 0.0:
            frame.lower(i, j, registration.offset_m)
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
        n_touched = bin_points(self.frame, self.window, p, sensor_position, counts)
        new_view = self._new_view(sensor_position, None)
        fuse(self.frame, self.layers, n_touched, self.config, new_view=new_view)
        return integration_stats(counts, n_touched)

    # Views -------------------------------------------------------------------------------
    def snapshot(self) -> MapSnapshot:
        """The window as arrays ordered by world position (cell [0, 0] at the window corner)."""
        layers = self.layers
        n = self.config.size
        out = (
            np.empty((n, n), dtype=bool),
            np.empty((n, n), dtype=np.float64),
            np.empty((n, n), dtype=np.float64),
            np.empty((n, n), dtype=np.float64),
            np.empty((n, n), dtype=np.uint16),
            np.empty((n, n), dtype=np.int64),
        )
        wrap_i, wrap_j = (-s for s in self.window.roll())
        kernels.unroll(
            wrap_i,
            wrap_j,
            (layers.known, layers.heights, layers.spread, layers.variance, layers.parts,
             layers.points),
            out,
        )  # fmt: skip
        known, heights, spread, variance, parts, points = out
        return MapSnapshot(
            heights=heights,
            known=known,
            origin=self.window.origin_m,
            resolution=self.config.resolution,
            spread=spread,
            variance=variance,
            parts=parts,
            points=points,
        )
