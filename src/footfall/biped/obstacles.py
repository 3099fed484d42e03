"""Obstacles from a point cloud (dissertation §6.3.1) for the biped planner.

Camera points pass a pass-through filter (depth at most 5 m) and a voxel grid (2 cm), go
to the map frame of the floor under the camera (eqs. 73-78; :mod:`footfall.pointcloud.ground`),
lose the ground (points within a clearance of the floor: a known plane, from the camera's
height and pitch or plane coefficients, the dissertation's "ground plane approach"; or
the floor RANSAC finds near the expected up axis), and are grouped by Euclidean cluster
extraction (tolerance 0.30 m, at least 5 points) in memory linear in the points. Each
cluster gets its centroid and a box aligned with its principal axes (PCA in the ground
plane), which becomes one circle or a chain of circles (eqs. 79-81); a cluster whose box's
circles would cover free floor (a wall, an L, a room) is covered by circles along its
medial line instead (:mod:`footfall.biped.cluster_cover`). The
inverted-cone detector of Manduchi et al. (eqs. 71-72) is the alternative to ground removal.

Errata: eqs. 76-78 rotate by +90 degrees, which maps the optical frame's x right and y down
to left and up; for the optical frame (x right, y down, z forward) the camera-to-base
rotation is ``[[0, 0, 1], [-1, 0, 0], [0, -1, 0]]``. In eq. 74 the lower-left entry of the
y rotation is ``-sin``. Eq. 71 compares the vertical coordinates of both points.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace

import numpy as np
import numpy.typing as npt
from scipy.spatial.transform import Rotation

from footfall.biped.avoidance import Circle
from footfall.biped.cluster_cover import (
    FreeFloorGrid,
    ObstacleCluster,
    cover_cluster,
    describe_cluster,
)
from footfall.checks import require_non_negative, require_positive
from footfall.errors import ConfigError, DatasetError
from footfall.pointcloud.filters import (
    euclidean_clusters,
    inverted_cone_points,
    voxel_downsample,
)
from footfall.pointcloud.ground import OPTICAL_TO_BASE, CameraOverFloor, GroundPlane, find_ground

GROUND_METHODS = ("plane", "ransac", "cones")


@dataclass(frozen=True)
class DetectionConfig:
    """Obstacle detection settings (dissertation values where it gives them).

    Attributes:
        max_depth: Pass-through filter: camera points farther than this along z go [m].
        voxel_size: Voxel grid side before everything else [m]; 0 keeps every point.
        ground: ``"plane"`` (remove points near the known ground), ``"ransac"`` (find the
            floor near the expected up axis) or ``"cones"`` (Manduchi's inverted cones).
        ground_height: Height of the known ground plane in the map frame [m] (map-frame
            clouds; a camera-frame cloud's floor is z = 0 by construction).
        ground_clearance: Points at most this high above the ground count as ground [m].
        max_obstacle_height: Points higher than this above the ground are overhead (a
            ceiling, a lamp, a door frame's lintel) and obstruct nothing [m].
        ransac_threshold: Inlier distance of a RANSAC plane [m].
        ransac_iterations: RANSAC hypotheses per plane.
        ground_max_tilt_deg: Largest angle between the ground's normal and the expected up
            axis [deg]; None: 15 when the up axis is known (a map-frame cloud, a camera
            pose given), 50 for the guess of a level camera.
        min_ground_fraction: Smallest share of the points a ground candidate must hold (a
            floor seen between furniture may hold only a few per cent).
        min_ground_extent: Least spread of the ground's points in both directions [m].
        camera_height_range: Plausible heights of a camera over its floor [m]: a
            camera-frame cloud's ground is the lowest large level plane this far below it.
        cluster_tolerance: Euclidean clustering radius [m].
        min_cluster_size: Smallest cluster kept [points, after the voxel grid].
        cone_min_height: ``H_min`` of eq. 71 [m].
        cone_max_height: ``H_max`` of eq. 71 [m].
        cone_max_slope: ``theta_max`` of eq. 72 [rad].
        floor_cell: Cell side of the free-floor grid [m].
        medial_min_gain_m2: A cluster's circles follow its medial line when they leave this
            much more floor free than its box's circles (and at least half of what those
            cover) [m^2]; infinite keeps every box's circles.
        medial_min_radius: Smallest circle along a medial line [m].
    """

    max_depth: float = 5.0
    voxel_size: float = 0.02
    ground: str = "ransac"
    ground_height: float = 0.0
    ground_clearance: float = 0.05
    max_obstacle_height: float = 2.0
    ransac_threshold: float = 0.02
    ransac_iterations: int = 200
    ground_max_tilt_deg: float | None = None
    min_ground_fraction: float = 0.02
    min_ground_extent: float = 0.5
    camera_height_range: tuple[float, float] = (0.1, 3.0)
    cluster_tolerance: float = 0.30
    min_cluster_size: int = 5
    cone_min_height: float = 0.05
    cone_max_height: float = 1.0
    cone_max_slope: float = math.radians(45.0)
    floor_cell: float = 0.05
    medial_min_gain_m2: float = 0.1
    medial_min_radius: float = 0.075

    def __post_init__(self) -> None:
        if self.ground == "cone":  # the singular, as earlier versions spelt it
            object.__setattr__(self, "ground", "cones")
        if self.ground not in GROUND_METHODS:
            raise ConfigError(
                f"ground must be one of {', '.join(GROUND_METHODS)}, got {self.ground!r}"
            )
        require_positive(
            "obstacle detection",
            cluster_tolerance=self.cluster_tolerance,
            min_cluster_size=self.min_cluster_size,
            max_depth=self.max_depth,
            medial_min_radius=self.medial_min_radius,
        )
        require_non_negative("obstacle detection", voxel_size=self.voxel_size)
        if not self.max_obstacle_height > self.ground_clearance:
            raise ConfigError(
                "max obstacle height must exceed the ground clearance, got "
                f"{self.max_obstacle_height}"
            )
        tilt = self.ground_max_tilt_deg
        if tilt is not None and not 0 < tilt < 90:
            raise ConfigError(f"ground tilt tolerance must lie in (0, 90) degrees, got {tilt}")
        low, high = self.camera_height_range
        if not (math.isfinite(high) and 0 <= low < high):
            raise ConfigError(
                f"the camera height range must be two finite heights, low to high, got "
                f"{self.camera_height_range}"
            )
        require_non_negative("obstacle detection", min_ground_extent=self.min_ground_extent)
        if not self.medial_min_gain_m2 >= 0:  # infinite: the dissertation's circles always
            raise ConfigError(
                f"medial_min_gain_m2 must be a number >= 0, got {self.medial_min_gain_m2!r}"
            )

    def tilt_rad(self, up_known: bool) -> float:
        """The ground's tilt tolerance [rad]."""
        if self.ground_max_tilt_deg is not None:
            return math.radians(self.ground_max_tilt_deg)
        return math.radians(15.0 if up_known else 50.0)


def camera_to_map(
    points_in_camera: npt.ArrayLike,
    robot_position: npt.ArrayLike = (0.0, 0.0, 0.0),
    robot_rpy: npt.ArrayLike = (0.0, 0.0, 0.0),
    camera_in_base: npt.ArrayLike = (0.0, 0.0, 0.0),
) -> npt.NDArray[np.float64]:
    """Camera (optical) frame -> base_link -> map (eqs. 73-78, corrected).

    Args:
        points_in_camera: Shape (n, 3) [m].
        robot_position: base_link origin in the map, shape (3,) [m].
        robot_rpy: base_link roll, pitch, yaw in the map (x-y-z Euler) [rad].
        camera_in_base: Camera origin in base_link, shape (3,) [m].
    """
    p = np.asarray(points_in_camera, dtype=np.float64) @ OPTICAL_TO_BASE.T + np.asarray(
        camera_in_base
    )
    rotation = Rotation.from_euler("xyz", np.asarray(robot_rpy, dtype=np.float64))
    return rotation.apply(p) + np.asarray(robot_position, dtype=np.float64)


@dataclass(frozen=True)
class Detection:
    """What the detector found.

    Attributes:
        clusters: Obstacles, largest component first.
        points_in_map: The points after the pass-through filter and the voxel grid, in the
            map frame.
        obstacle_mask: Which of them belong to obstacles (ground removed).
        ground: The ground plane in the map frame.
        camera: For a camera-frame cloud, the camera over the floor the map frame stands on
            (found by RANSAC, or as given); None for a map-frame cloud.
        prior_up_in_camera: The up axis the camera pose given (or a level camera) implies,
            in the camera frame; None for a map-frame cloud.
        ground_in_camera: For a camera-frame cloud, the ground plane in the camera frame.
        points_in: Finite points read.
        voxel_size_m: Voxel side used [m].
        detect_ms: Detection time [ms].
    """

    clusters: list[ObstacleCluster]
    points_in_map: npt.NDArray[np.float64]
    obstacle_mask: npt.NDArray[np.bool_]
    ground: GroundPlane
    camera: CameraOverFloor | None
    prior_up_in_camera: npt.NDArray[np.float64] | None
    ground_in_camera: GroundPlane | None
    points_in: int
    voxel_size_m: float
    detect_ms: float

    @property
    def circles(self) -> list[Circle]:
        """Every cluster's circles, not inflated."""
        return [c for cluster in self.clusters for c in cluster.circles]

    @property
    def ground_normal(self) -> npt.NDArray[np.float64]:
        """Normal of the ground plane in the map frame."""
        return self.ground.normal


def _known_plane(points_in_map, config: DetectionConfig, angle_deg: float) -> GroundPlane:
    """The known ground ``z = ground_height`` and the share of points on it."""
    on = np.abs(points_in_map[:, 2] - config.ground_height) < config.ground_clearance
    fraction = float(on.mean()) if len(points_in_map) else 0.0
    return GroundPlane(np.array([0.0, 0.0, 1.0]), -config.ground_height, fraction, angle_deg)


def _to_map(
    p: npt.NDArray[np.float64],
    c: DetectionConfig,
    camera: CameraOverFloor | None,
    ground_plane: npt.ArrayLike | None,
    rng: np.random.Generator,
) -> tuple[npt.NDArray[np.float64], GroundPlane, CameraOverFloor, npt.NDArray, GroundPlane]:
    """Camera-frame points in the map frame of their floor, and that floor."""
    prior = camera or CameraOverFloor.from_angles()
    prior_up = prior.up_in_camera
    up_known = camera is not None or ground_plane is not None
    if ground_plane is not None:  # the plane fixes the pose; the angles say how far off it is
        prior = CameraOverFloor.from_plane(ground_plane)
    if c.ground == "ransac":
        found = find_ground(
            p,
            prior.up_in_camera,
            c.tilt_rad(up_known),
            c.ransac_threshold,
            c.ransac_iterations,
            c.min_ground_fraction,
            rng=rng,
            below_origin=True,
            height_range_m=c.camera_height_range,
            min_extent_m=c.min_ground_extent,
        )
        floor = CameraOverFloor.from_up(found.normal, found.offset_m)
        in_camera = GroundPlane(
            found.normal,
            found.offset_m,
            found.inlier_fraction,
            math.degrees(math.acos(float(np.clip(found.normal @ prior_up, -1, 1)))),
            found.candidates,
        )
    else:
        if c.ground == "plane" and prior.height_m == 0 and ground_plane is None:
            raise ConfigError(
                "ground 'plane' on a camera-frame cloud needs the camera's height over the "
                "floor (--camera-height) or the plane (--ground-plane A B C D)"
            )
        floor = prior
        up = floor.up_in_camera
        angle = math.degrees(math.acos(float(np.clip(up @ prior_up, -1, 1))))
        in_camera = GroundPlane(up, floor.height_m, 0.0, angle)
    points_in_map = floor.to_map(p)
    on = np.abs(points_in_map[:, 2]) < c.ransac_threshold
    ground = GroundPlane(
        np.array([0.0, 0.0, 1.0]),
        0.0,
        float(on.mean()),
        in_camera.angle_to_up_deg,
        in_camera.candidates,
    )
    if c.ground != "ransac":
        in_camera = GroundPlane(
            in_camera.normal, in_camera.offset_m, ground.inlier_fraction, in_camera.angle_to_up_deg
        )
    return points_in_map, ground, floor, prior_up, in_camera


def detect_obstacles(
    points: npt.ArrayLike,
    frame: str = "camera",
    config: DetectionConfig | None = None,
    camera: CameraOverFloor | None = None,
    ground_plane: npt.ArrayLike | None = None,
    rng: np.random.Generator | None = None,
) -> Detection:
    """Obstacles in a point cloud.

    Args:
        points: Shape (n, 3) [m], in the camera (optical) frame or already in the map frame.
        frame: ``"camera"`` or ``"map"``.
        config: Detection settings.
        camera: The camera's pose over the floor (camera-frame input); None: a level camera
            at an unknown height.
        ground_plane: Plane coefficients ``a b c d`` of the floor in the camera frame
            (camera-frame input).
        rng: Random generator for RANSAC (seeded for repeatable results).

    Raises:
        DatasetError: An empty cloud, none left after filtering, or no ground found.
        ConfigError: An unknown frame, or the plane method without a known plane.
    """
    started = time.perf_counter()
    c = config or DetectionConfig()
    rng = rng or np.random.default_rng(0)
    p = np.asarray(points, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 3 or len(p) == 0:
        raise DatasetError(f"the point cloud is empty or not of shape (n, 3): {p.shape}")
    p = p[np.all(np.isfinite(p), axis=1)]
    points_in = len(p)
    if frame == "camera":
        p = p[(p[:, 2] > 0) & (p[:, 2] <= c.max_depth)]  # pass-through along the optical axis
    elif frame != "map":
        raise ConfigError(f"frame must be 'camera' or 'map', got {frame!r}")
    if len(p) == 0:
        raise DatasetError("no point is left after the pass-through filter")
    p = voxel_downsample(p, c.voxel_size)
    floor: CameraOverFloor | None = None
    prior_up = in_camera = None
    if frame == "camera":
        p, ground, floor, prior_up, in_camera = _to_map(p, c, camera, ground_plane, rng)
    elif c.ground == "ransac":
        ground = find_ground(
            p,
            (0.0, 0.0, 1.0),
            c.tilt_rad(True),
            c.ransac_threshold,
            c.ransac_iterations,
            c.min_ground_fraction,
            rng=rng,
            min_extent_m=c.min_ground_extent,
        )
    else:
        ground = _known_plane(p, c, 0.0)
    height = ground.heights(p)
    below_overhead = height < c.max_obstacle_height
    if c.ground == "cones":
        keep = inverted_cone_points(p, c.cone_min_height, c.cone_max_height, c.cone_max_slope)
        floor_points = ~keep
        keep &= below_overhead
    else:
        keep = (height > c.ground_clearance) & below_overhead
        floor_points = np.abs(height) <= max(c.ransac_threshold, 0.5 * c.ground_clearance)
    kept = p[keep]
    grid = FreeFloorGrid.build(kept[:, :2], p[floor_points, :2], c.floor_cell)
    clusters: list[ObstacleCluster] = []
    for component, idx in enumerate(
        euclidean_clusters(kept, c.cluster_tolerance, c.min_cluster_size)
    ):
        parts = cover_cluster(
            kept[idx], grid, describe_cluster, c.medial_min_gain_m2, c.medial_min_radius
        )
        clusters.extend(replace(part, component=component) for part in parts)
    detect_ms = 1000.0 * (time.perf_counter() - started)
    return Detection(
        clusters, p, keep, ground, floor, prior_up, in_camera, points_in, c.voxel_size, detect_ms
    )
