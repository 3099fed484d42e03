"""One look of the biped's head camera: depth image -> point cloud -> obstacle circles.

The cloud goes to the map frame with the camera's pose (the simulator's; Archie has no
pose estimator of its own), then through the dissertation's detector (§6.3.1) with the
floor at z = 0 known. Circles seen before are kept (the robot remembers what has gone out
of view); a new circle that overlaps a remembered one replaces it when it is larger, so
an obstacle seen from nearer or from another side grows to its fuller outline.

A camera sees only an obstacle's near faces, and the circles of a face alone leave its far
side out. Each obstacle point is therefore extended away from the camera by
``HIDDEN_DEPTH`` (an obstacle is taken to be at least that deep behind what is seen), and
the extended cloud is what the detector clusters.
"""

from __future__ import annotations

import numpy as np

from footfall.biped.avoidance import Circle
from footfall.biped.obstacles import DetectionConfig, detect_obstacles
from footfall.errors import DatasetError
from footfall.sensing.pose import Pose
from footfall.sim.biped_sim import BipedSimulation
from footfall.sim.camera import SimDepthCamera

DETECTION = DetectionConfig(ground="plane", ground_height=0.0, voxel_size=0.03)
HIDDEN_DEPTH = 0.3  # [m]
HIDDEN_SPACING = 0.05  # [m]


def cloud_in_world(camera: SimDepthCamera, sim: BipedSimulation) -> tuple[np.ndarray, Pose]:
    """The camera's view: points in the world frame, shape (n, 3) [m], and its pose."""
    depth, pose = camera.capture(sim.data)
    points, _ = camera.intrinsics.depth_to_points(depth)
    return pose.rotation.apply(points) + pose.position, pose


def merge_circles(known: list[Circle], new: list[Circle]) -> list[Circle]:
    """Remembered circles updated with a new look's.

    Every circle of the new look is kept; a remembered circle goes when a larger new one
    overlaps it, and a new circle is dropped when a remembered one that overlaps it is at
    least as large.
    """
    kept = list(known)
    added = []
    for c in new:
        overlapping = [k for k in kept if np.hypot(k.x - c.x, k.y - c.y) < max(k.r, c.r)]
        if any(k.r >= c.r for k in overlapping):
            continue
        kept = [k for k in kept if k not in overlapping]
        added.append(c)
    return kept + added


def extend_hidden(points: np.ndarray, camera_xy: np.ndarray) -> np.ndarray:
    """Points above the floor repeated behind themselves, away from the camera [m]."""
    high = points[points[:, 2] > DETECTION.ground_clearance]
    if len(high) == 0:
        return points
    away = high[:, :2] - camera_xy
    away /= np.maximum(np.linalg.norm(away, axis=1, keepdims=True), 1e-9)
    steps = np.arange(HIDDEN_SPACING, HIDDEN_DEPTH + 1e-9, HIDDEN_SPACING)
    behind = [np.column_stack([high[:, :2] + d * away, high[:, 2]]) for d in steps]
    return np.vstack([points, *behind])


def look(camera: SimDepthCamera, sim: BipedSimulation, known: list[Circle]) -> list[Circle]:
    """Update the remembered obstacle circles with what the camera sees now."""
    points, pose = cloud_in_world(camera, sim)
    if len(points):
        points = extend_hidden(points, pose.position[:2])
    try:
        detection = detect_obstacles(points, frame="map", config=DETECTION)
    except DatasetError:  # nothing but floor, or nothing at all, in view
        return known
    return merge_circles(known, detection.circles)
