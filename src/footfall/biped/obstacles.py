"""Obstacles from a point cloud (dissertation §6.3.1) for the biped planner.

Camera points pass a pass-through filter (depth at most 5 m), go from the camera frame
to ``base_link`` and the ``map`` frame (eqs. 73-78), lose the ground (above a known
ground plane, the dissertation's "ground plane approach"; or the dominant plane found by
RANSAC when the floor is in view), and are grouped by Euclidean cluster extraction on a
kd-tree (tolerance 0.30 m, at least 5 points). Each cluster gets its centroid and a box
aligned with its principal axes (PCA in the ground plane), which becomes one circle or a
chain of circles (eqs. 79-81). The inverted-cone detector of Manduchi et al. (eqs. 71-72)
is the alternative to ground removal.

Errata: eqs. 76-78 rotate by +90 degrees, which maps the optical frame's x right and y down
to left and up; for the optical frame (x right, y down, z forward) the camera-to-base
rotation is ``[[0, 0, 1], [-1, 0, 0], [0, -1, 0]]``. In eq. 74 the lower-left entry of the
y rotation is ``-sin``. Eq. 71 compares the vertical coordinates of both points.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree
from scipy.spatial.transform import Rotation

from footfall.biped.avoidance import Circle
from footfall.biped.maps import box_circles
from footfall.errors import ConfigError, DatasetError

# Optical camera frame (x right, y down, z forward) -> base_link (x forward, y left, z up).
OPTICAL_TO_BASE = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])


@dataclass(frozen=True)
class DetectionConfig:
    """Obstacle detection settings (dissertation values where it gives them).

    Attributes:
        max_depth: Pass-through filter: camera points farther than this along z go [m].
        ground: ``"plane"`` (remove points near the known ground height), ``"ransac"`` (fit
            and remove the dominant plane) or ``"cone"`` (Manduchi's inverted cones).
        ground_height: Height of the known ground plane in the map frame [m].
        ground_clearance: Points this close to the ground count as ground [m].
        ransac_threshold: Inlier distance of the RANSAC plane [m].
        ransac_iterations: RANSAC hypotheses.
        cluster_tolerance: Euclidean clustering radius [m].
        min_cluster_size: Smallest cluster kept [points].
        cone_min_height: ``H_min`` of eq. 71 [m].
        cone_max_height: ``H_max`` of eq. 71 [m].
        cone_max_slope: ``theta_max`` of eq. 72 [rad].
    """

    max_depth: float = 5.0
    ground: str = "plane"
    ground_height: float = 0.0
    ground_clearance: float = 0.05
    ransac_threshold: float = 0.02
    ransac_iterations: int = 200
    cluster_tolerance: float = 0.30
    min_cluster_size: int = 5
    cone_min_height: float = 0.05
    cone_max_height: float = 1.0
    cone_max_slope: float = math.radians(45.0)

    def __post_init__(self) -> None:
        if self.ground not in ("plane", "ransac", "cone"):
            raise ConfigError(f"ground must be 'plane', 'ransac' or 'cone', got {self.ground!r}")
        if not (self.cluster_tolerance > 0 and self.min_cluster_size >= 1 and self.max_depth > 0):
            raise ConfigError("cluster tolerance, cluster size and max depth must be positive")


@dataclass(frozen=True)
class ObstacleCluster:
    """One detected obstacle.

    Attributes:
        centroid: Mean of its points, shape (3,) [m].
        centre: Centre of its principal-axes box in the ground plane, shape (2,) [m].
        width: Box extent along the first principal axis [m].
        depth: Box extent along the second [m].
        height: Vertical extent [m].
        yaw: Heading of the first principal axis [rad].
        points: How many points it has.
        circles: Its circles (eqs. 79-81), not inflated.
    """

    centroid: npt.NDArray[np.float64]
    centre: npt.NDArray[np.float64]
    width: float
    depth: float
    height: float
    yaw: float
    points: int
    circles: tuple[Circle, ...] = field(default=())


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


def ransac_plane(
    points: npt.NDArray[np.float64], threshold: float, iterations: int, rng: np.random.Generator
) -> tuple[npt.NDArray[np.float64], float, npt.NDArray[np.bool_]]:
    """The plane ``n . p + d = 0`` with the most points within ``threshold``.

    Returns:
        Unit normal, offset and the inlier mask.
    """
    if len(points) < 3:
        raise DatasetError("RANSAC needs at least 3 points")
    best = (np.array([0.0, 0.0, 1.0]), 0.0, np.zeros(len(points), dtype=bool))
    for _ in range(iterations):
        a, b, c = points[rng.choice(len(points), 3, replace=False)]
        normal = np.cross(b - a, c - a)
        norm = np.linalg.norm(normal)
        if norm < 1e-12:
            continue
        normal /= norm
        d = -float(normal @ a)
        inliers = np.abs(points @ normal + d) < threshold
        if inliers.sum() > best[2].sum():
            best = (normal, d, inliers)
    normal, d, inliers = best
    # Refine by least squares on the inliers.
    if inliers.sum() >= 3:
        centre = points[inliers].mean(axis=0)
        normal = np.linalg.svd(points[inliers] - centre, full_matrices=False)[2][-1]
        d = -float(normal @ centre)
        inliers = np.abs(points @ normal + d) < threshold
    return normal, d, inliers


def euclidean_clusters(
    points: npt.NDArray[np.float64], tolerance: float, min_size: int
) -> list[npt.NDArray[np.int64]]:
    """Euclidean cluster extraction on a kd-tree.

    Points linked by chains of neighbours closer than ``tolerance`` form a cluster;
    clusters smaller than ``min_size`` go.
    """
    if len(points) == 0:
        return []
    pairs = cKDTree(points).query_pairs(tolerance, output_type="ndarray")
    graph = coo_matrix(
        (np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(len(points), len(points))
    )
    _, labels = connected_components(graph, directed=False)
    clusters = [np.flatnonzero(labels == k) for k in np.unique(labels)]
    return sorted((c for c in clusters if len(c) >= min_size), key=len, reverse=True)


def inverted_cone_points(
    points: npt.NDArray[np.float64], config: DetectionConfig
) -> npt.NDArray[np.bool_]:
    """Points on an obstacle by Manduchi's test (eqs. 71-72).

    A point is an obstacle point when another lies in its upward or downward cone:
    ``H_min < |dz| < H_max`` and ``|dz| / |dp| > sin(theta_max)``.
    """
    reach = config.cone_max_height / math.sin(config.cone_max_slope)
    pairs = cKDTree(points).query_pairs(reach, output_type="ndarray")
    if len(pairs) == 0:
        return np.zeros(len(points), dtype=bool)
    delta = points[pairs[:, 1]] - points[pairs[:, 0]]
    dz = np.abs(delta[:, 2])
    compatible = (dz > config.cone_min_height) & (dz < config.cone_max_height)
    compatible &= dz / np.linalg.norm(delta, axis=1) > math.sin(config.cone_max_slope)
    mask = np.zeros(len(points), dtype=bool)
    mask[pairs[compatible].ravel()] = True
    return mask


def describe_cluster(points: npt.NDArray[np.float64]) -> ObstacleCluster:
    """Centroid, principal-axes box in the ground plane and circles of one cluster."""
    centroid = points.mean(axis=0)
    xy = points[:, :2] - centroid[:2]
    if len(points) >= 2 and np.ptp(xy, axis=0).max() > 1e-9:
        _, vectors = np.linalg.eigh(np.cov(xy.T))
        axis = vectors[:, -1]  # the principal direction
    else:
        axis = np.array([1.0, 0.0])
    yaw = math.atan2(axis[1], axis[0])
    frame = np.array([axis, [-axis[1], axis[0]]])
    local = xy @ frame.T
    lo, hi = local.min(axis=0), local.max(axis=0)
    width, depth = max(float(hi[0] - lo[0]), 0.01), max(float(hi[1] - lo[1]), 0.01)
    centre = centroid[:2] + 0.5 * (lo + hi) @ frame
    height = float(np.ptp(points[:, 2]))
    circles = tuple(box_circles(centre, width, depth, yaw))
    return ObstacleCluster(centroid, centre, width, depth, height, yaw, len(points), circles)


@dataclass(frozen=True)
class Detection:
    """What the detector found.

    Attributes:
        clusters: Obstacles, largest first.
        points_in_map: The points after the pass-through filter, in the map frame.
        obstacle_mask: Which of them belong to obstacles (ground removed).
        ground_normal: Normal of the ground plane (RANSAC), or +z.
    """

    clusters: list[ObstacleCluster]
    points_in_map: npt.NDArray[np.float64]
    obstacle_mask: npt.NDArray[np.bool_]
    ground_normal: npt.NDArray[np.float64]

    @property
    def circles(self) -> list[Circle]:
        """Every cluster's circles, not inflated."""
        return [c for cluster in self.clusters for c in cluster.circles]


def detect_obstacles(
    points: npt.ArrayLike,
    frame: str = "camera",
    config: DetectionConfig | None = None,
    robot_position: npt.ArrayLike = (0.0, 0.0, 0.0),
    robot_rpy: npt.ArrayLike = (0.0, 0.0, 0.0),
    camera_in_base: npt.ArrayLike = (0.0, 0.0, 0.0),
    rng: np.random.Generator | None = None,
) -> Detection:
    """Obstacles in a point cloud.

    Args:
        points: Shape (n, 3) [m], in the camera (optical) frame or already in the map frame.
        frame: ``"camera"`` or ``"map"``.
        config: Detection settings.
        robot_position: base_link in the map [m] (camera-frame input).
        robot_rpy: base_link attitude in the map [rad] (camera-frame input).
        camera_in_base: Camera origin in base_link [m] (camera-frame input).
        rng: Random generator for RANSAC (seeded for repeatable results).

    Raises:
        DatasetError: An empty cloud, or none left after filtering.
        ConfigError: An unknown frame.
    """
    c = config or DetectionConfig()
    p = np.asarray(points, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 3 or len(p) == 0:
        raise DatasetError(f"the point cloud is empty or not of shape (n, 3): {p.shape}")
    p = p[np.all(np.isfinite(p), axis=1)]
    if frame == "camera":
        p = p[(p[:, 2] > 0) & (p[:, 2] <= c.max_depth)]  # pass-through along the optical axis
        p = camera_to_map(p, robot_position, robot_rpy, camera_in_base)
    elif frame != "map":
        raise ConfigError(f"frame must be 'camera' or 'map', got {frame!r}")
    if len(p) == 0:
        raise DatasetError("no point is left after the pass-through filter")
    normal = np.array([0.0, 0.0, 1.0])
    if c.ground == "plane":
        keep = p[:, 2] > c.ground_height + c.ground_clearance
    elif c.ground == "ransac":
        normal, _, inliers = ransac_plane(
            p, c.ransac_threshold, c.ransac_iterations, rng or np.random.default_rng(0)
        )
        keep = ~inliers
    else:
        keep = inverted_cone_points(p, c)
    kept = p[keep]
    clusters = [
        describe_cluster(kept[idx])
        for idx in euclidean_clusters(kept, c.cluster_tolerance, c.min_cluster_size)
    ]
    return Detection(clusters, p, keep, normal)
