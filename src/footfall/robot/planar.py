"""Planar body poses: position and heading in the ground plane, and constant-twist motion."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt


@dataclass(frozen=True)
class PlanarPose:
    """Pose of the body in the ground plane of the world frame.

    Attributes:
        x: Position along world x [m].
        y: Position along world y [m].
        yaw: Heading about world z [rad].
    """

    x: float = 0.0
    y: float = 0.0
    yaw: float = 0.0

    def points_to_world(self, points_in_body: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Map points, shape (n, 2) or (n, 3), from the body's planar frame to the world.

        Only x and y are transformed; a z column passes through unchanged.
        """
        p = np.array(points_in_body, dtype=np.float64)
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        x = c * p[..., 0] - s * p[..., 1] + self.x
        y = s * p[..., 0] + c * p[..., 1] + self.y
        p[..., 0], p[..., 1] = x, y
        return p

    def points_to_body(self, points_in_world: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Inverse of :meth:`points_to_world`."""
        p = np.array(points_in_world, dtype=np.float64)
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        dx, dy = p[..., 0] - self.x, p[..., 1] - self.y
        p[..., 0], p[..., 1] = c * dx + s * dy, -s * dx + c * dy
        return p

    def vectors_to_body(self, vectors_in_world: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Rotate free vectors, shape (n, 2) or (n, 3), from the world into the body's frame."""
        v = np.array(vectors_in_world, dtype=np.float64)
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        x, y = c * v[..., 0] + s * v[..., 1], -s * v[..., 0] + c * v[..., 1]
        v[..., 0], v[..., 1] = x, y
        return v

    def vectors_to_world(self, vectors_in_body: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Rotate free vectors, shape (n, 2) or (n, 3), from the body's frame into the world."""
        v = np.array(vectors_in_body, dtype=np.float64)
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        x, y = c * v[..., 0] - s * v[..., 1], s * v[..., 0] + c * v[..., 1]
        v[..., 0], v[..., 1] = x, y
        return v

    def moved(
        self, velocity_in_body: tuple[float, float], yaw_rate: float, dt: float
    ) -> PlanarPose:
        """The pose after moving ``dt`` seconds with a constant twist given in the body frame.

        Args:
            velocity_in_body: ``(vx, vy)`` [m/s].
            yaw_rate: [rad/s].
            dt: [s].
        """
        vx, vy = velocity_in_body
        dyaw = yaw_rate * dt
        if abs(dyaw) < 1e-9:
            fx, fy = vx * dt, vy * dt
        else:
            # Exact integral of a constant body twist: the body travels along a circular arc.
            s, c = math.sin(dyaw), math.cos(dyaw)
            fx = (vx * s - vy * (1.0 - c)) / yaw_rate
            fy = (vx * (1.0 - c) + vy * s) / yaw_rate
        cy, sy = math.cos(self.yaw), math.sin(self.yaw)
        return PlanarPose(self.x + cy * fx - sy * fy, self.y + sy * fx + cy * fy, self.yaw + dyaw)


def level_to_inclined(points_in_level: npt.ArrayLike, pitch: float) -> npt.NDArray[np.float64]:
    """Points or vectors, shape (..., 3), from the level body frame into the inclined one.

    The level body frame is the planar pose's, its origin at the body's height; the
    inclined frame is that frame turned by ``pitch`` about its y axis [rad] (positive nose
    down, as the IMU's pitch).
    """
    p = np.array(points_in_level, dtype=np.float64)
    if pitch == 0.0:
        return p
    c, s = math.cos(pitch), math.sin(pitch)
    x, z = c * p[..., 0] - s * p[..., 2], s * p[..., 0] + c * p[..., 2]
    p[..., 0], p[..., 2] = x, z
    return p


def inclined_to_level(points_in_inclined: npt.ArrayLike, pitch: float) -> npt.NDArray[np.float64]:
    """Inverse of :func:`level_to_inclined`."""
    return level_to_inclined(points_in_inclined, -pitch)
