"""The floor under a camera: its pose over the floor, and RANSAC that takes the floor.

A camera-frame cloud (optical frame: x right, y down, z forward) goes to the map frame
of the floor under the camera: origin on the floor below the camera, x forward, y left,
z up. What fixes that frame is the floor plane, known or found:

- :class:`CameraOverFloor` from the camera's height, pitch (positive when it looks down)
  and roll (positive when its right side dips), or from plane coefficients
  ``a x + b y + c z + d = 0`` in the camera frame;
- :func:`find_ground`, RANSAC that accepts only planes whose normal lies within a
  tolerance of the expected up axis and, among the well-supported ones, takes the lowest
  (the floor under a table, not the table; never a wall or a row of people's backs).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from scipy.spatial.transform import Rotation

from footfall.errors import ConfigError, DatasetError
from footfall.pointcloud.planes import (
    AREA_CELL_M,
    LAYER_PARALLEL_DEG,
    best_plane,
    cells_covered,
    lowest_layer,
    plane_extent_m,
)

# Optical camera frame (x right, y down, z forward) -> level body (x forward, y left, z up).
OPTICAL_TO_BASE = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])


def _unit(v: npt.ArrayLike, what: str) -> npt.NDArray[np.float64]:
    a = np.asarray(v, dtype=np.float64)
    norm = float(np.linalg.norm(a))
    if a.shape != (3,) or not (math.isfinite(norm) and norm > 1e-12):
        raise ConfigError(f"{what} must be a finite non-zero 3-vector, got {v!r}")
    return a / norm


@dataclass(frozen=True)
class CameraOverFloor:
    """The camera's pose over a level floor: the camera frame -> map frame transform.

    Attributes:
        rotation_camera_to_map: Rotation of optical-frame vectors into the map frame.
        height_m: Camera height above the floor [m] (0 when not known: the map's origin
            is then the camera itself).
    """

    rotation_camera_to_map: Rotation
    height_m: float = 0.0

    @classmethod
    def from_angles(
        cls, height_m: float = 0.0, pitch_rad: float = 0.0, roll_rad: float = 0.0
    ) -> CameraOverFloor:
        """A camera over the floor from its height and attitude.

        ``height_m`` above the floor, pitched down by ``pitch_rad``, rolled by ``roll_rad``
        (right side down), heading along the map's x axis.
        """
        if not all(math.isfinite(v) for v in (height_m, pitch_rad, roll_rad)):
            raise ConfigError("camera height, pitch and roll must be finite")
        if height_m < 0:
            raise ConfigError(f"camera height must be >= 0, got {height_m}")
        if abs(pitch_rad) >= math.pi / 2 or abs(roll_rad) >= math.pi / 2:
            raise ConfigError("camera pitch and roll must lie within (-90, 90) degrees")
        base = Rotation.from_matrix(OPTICAL_TO_BASE)
        # Positive pitch about y tips x (forward) down; positive roll about x lifts y (left).
        return cls(Rotation.from_euler("xy", [roll_rad, pitch_rad]) * base, float(height_m))

    @classmethod
    def from_up(cls, up_in_camera: npt.ArrayLike, height_m: float) -> CameraOverFloor:
        """The camera over a floor whose upward normal in the camera frame is given.

        The map's x axis is the optical axis projected on the floor (for a camera looking
        straight down, the image's up direction).
        """
        z = _unit(up_in_camera, "the floor's normal")
        forward = np.array([0.0, 0.0, 1.0])
        if abs(forward @ z) > 0.999:
            forward = np.array([0.0, -1.0, 0.0])
        x = forward - (forward @ z) * z
        x /= np.linalg.norm(x)
        y = np.cross(z, x)
        return cls(Rotation.from_matrix(np.array([x, y, z])), float(height_m))

    @classmethod
    def from_plane(cls, coefficients: npt.ArrayLike) -> CameraOverFloor:
        """The camera over the plane ``a x + b y + c z + d = 0`` given in the camera frame.

        Raises:
            ConfigError: Coefficients that are not four finite numbers with a normal.
        """
        c = np.asarray(coefficients, dtype=np.float64)
        if c.shape != (4,) or not np.all(np.isfinite(c)):
            raise ConfigError(f"--ground-plane needs four finite numbers A B C D, got {c.tolist()}")
        normal, d = c[:3], float(c[3])
        norm = float(np.linalg.norm(normal))
        if norm < 1e-12:
            raise ConfigError("--ground-plane: the normal (A, B, C) is zero")
        normal, d = normal / norm, d / norm
        if d < 0:  # the camera (the origin) sits on the normal's side of its floor
            normal, d = -normal, -d
        return cls.from_up(normal, d)

    @property
    def up_in_camera(self) -> npt.NDArray[np.float64]:
        """The map's up axis in the camera frame, shape (3,)."""
        return self.rotation_camera_to_map.inv().apply([0.0, 0.0, 1.0])

    def _angles(self) -> npt.NDArray[np.float64]:
        body = self.rotation_camera_to_map * Rotation.from_matrix(OPTICAL_TO_BASE).inv()
        return body.as_euler("xyz")  # roll, pitch, yaw (0 for a camera over its floor)

    @property
    def pitch_rad(self) -> float:
        """How far the camera looks down [rad] (``from_angles``' pitch)."""
        return float(self._angles()[1])

    @property
    def roll_rad(self) -> float:
        """How far the camera's right side dips [rad] (``from_angles``' roll)."""
        return float(self._angles()[0])

    def to_map(self, points_in_camera: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Camera-frame points in the map frame, shape (n, 3) [m]."""
        p = self.rotation_camera_to_map.apply(np.asarray(points_in_camera, dtype=np.float64))
        return p + np.array([0.0, 0.0, self.height_m])


@dataclass(frozen=True)
class GroundPlane:
    """A ground plane ``normal . p + offset = 0`` in the frame of the points it was fit to.

    Attributes:
        normal: Unit normal, pointing up (towards the expected up axis), shape (3,).
        offset_m: ``d`` of the plane equation [m]; ``-offset_m`` is the plane's height at
            the frame's origin along ``normal``.
        inlier_fraction: Share of the points within the inlier distance.
        angle_to_up_deg: Angle between the normal and the expected up axis [deg].
        candidates: How many planes within the tilt tolerance had enough support.
    """

    normal: npt.NDArray[np.float64]
    offset_m: float
    inlier_fraction: float
    angle_to_up_deg: float
    candidates: int = 1

    def heights(self, points: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Signed distance of points above the plane, shape (n,) [m]."""
        return np.asarray(points, dtype=np.float64) @ self.normal + self.offset_m


def _angle_deg(a: npt.NDArray[np.float64], b: npt.NDArray[np.float64]) -> float:
    return math.degrees(math.acos(float(np.clip(a @ b, -1.0, 1.0))))


def find_ground(
    points: npt.ArrayLike,
    up: npt.ArrayLike,
    max_tilt_rad: float,
    threshold_m: float = 0.02,
    iterations: int = 200,
    min_fraction: float = 0.1,
    max_planes: int = 4,
    rng: np.random.Generator | None = None,
    below_origin: bool = False,
    parallel_deg: float = 10.0,
    height_range_m: tuple[float, float] | None = None,
    min_extent_m: float = 0.0,
) -> GroundPlane:
    """The floor: the lowest large plane whose normal is near ``up``.

    Planes are extracted one after another (RANSAC, each refined by least squares on its
    inliers, whose points then leave), as long as each holds at least ``min_fraction`` of
    the points. Of those parallel to the first, best-supported one, the one whose inliers
    lie lowest (median height along its normal) is the floor, and below it the search goes
    on: a floor seen between furniture may hold only a few per cent of the points, under
    a desk top or a bed that holds many more. A plane counts when it holds
    ``min_fraction``, spreads ``min_extent_m`` both ways and (below the origin) puts the
    origin within ``height_range_m`` above it.

    Args:
        points: Shape (n, 3) [m].
        up: The expected up axis in the points' frame, shape (3,).
        max_tilt_rad: Largest angle between a plane's normal and ``up`` [rad].
        threshold_m: Inlier distance [m].
        iterations: RANSAC hypotheses within the tilt tolerance per plane.
        min_fraction: Smallest share of the points a candidate must hold.
        max_planes: Most planes extracted.
        rng: Random generator (seeded: repeatable).
        below_origin: Only planes with the frame's origin above them (the camera frame's
            origin is the camera: its floor lies below it, a ceiling above).
        parallel_deg: Candidates more than this far from parallel to the best-supported
            one do not compete [deg].
        height_range_m: With ``below_origin``, the plausible heights of the origin (the
            camera) above the floor [m]; None: any.
        min_extent_m: Least spread of a floor's inliers in both directions of its plane
            (10th to 90th percentile) [m].

    Raises:
        DatasetError: Fewer than 3 points, or no plausible plane within the tolerance of
            ``up``.
    """
    p = np.asarray(points, dtype=np.float64)
    u = _unit(up, "the up axis")
    if len(p) < 3:
        raise DatasetError("finding the ground needs at least 3 points")
    if not 0 < max_tilt_rad < math.pi / 2:
        raise ConfigError(
            f"the ground's tilt tolerance must lie in (0, 90) degrees, got {max_tilt_rad}"
        )
    rng = rng or np.random.default_rng(0)
    cos_tilt = math.cos(max_tilt_rad)
    enough = min_fraction * len(p)

    def plausible(inliers, normal, d, under: bool = False) -> bool:
        """In the height range, and large.

        A plane found under a better-supported one spreads ``min_extent_m``; one of the
        best-supported, that much or a quarter of the view (a close-up of a table top).
        """
        if below_origin and height_range_m is not None:
            if not height_range_m[0] <= d <= height_range_m[1]:
                return False
        least = min_extent_m if under else min(min_extent_m, 0.25 * plane_extent_m(p, normal))
        return plane_extent_m(inliers, normal) >= least

    remaining = p
    candidates: list[tuple[npt.NDArray[np.float64], npt.NDArray[np.float64], float]] = []
    for _ in range(max_planes):
        if len(remaining) < 3:
            break
        plane = best_plane(remaining, u, cos_tilt, threshold_m, iterations, rng, below_origin)
        if plane is None:
            break
        normal, d = plane
        inliers = np.abs(remaining @ normal + d) < threshold_m
        if inliers.sum() < enough:
            break
        candidates.append((remaining[inliers], normal, d))
        remaining = remaining[~inliers]
    if not candidates:
        raise DatasetError(
            f"no plane within {math.degrees(max_tilt_rad):.0f} deg of the expected up axis "
            f"holds {min_fraction:.0%} of the points: give the camera's pitch and roll "
            "(--camera-pitch-deg, --camera-roll-deg) or the plane (--ground-plane A B C D)"
        )
    # Heights along the level surfaces' normal: the prior's up may be far off (a camera
    # pitched down with no pose given), and along it a higher plane can look lower. The
    # reference is the candidate that covers the most ground (cells of ``AREA_CELL_M``): a
    # plane through the feet of walls and furniture, or across the tops of several, can
    # hold as many points as a floor or a table top, but in strips. Only surfaces level
    # with it compete.
    reference = max(candidates, key=lambda c: cells_covered(c[0], c[1], AREA_CELL_M))[1]
    cos_parallel = math.cos(math.radians(parallel_deg))
    level = [c for c in candidates if c[1] @ reference >= cos_parallel]
    usable = [c for c in level if plausible(*c)]
    lowest = min(usable, key=lambda c: float(np.median(c[0] @ reference)), default=None)
    cos_layer = math.cos(math.radians(LAYER_PARALLEL_DEG))
    found = lowest_layer(p, lowest, reference, cos_layer, threshold_m, below_origin, enough,
                          plausible)  # fmt: skip
    if found is not None:
        lowest = found
        level.append(found)
    if lowest is None:
        where = ""
        if below_origin and height_range_m is not None:
            where = f" {height_range_m[0]:g} to {height_range_m[1]:g} m below the camera"
        raise DatasetError(
            f"no plane{where} within {math.degrees(max_tilt_rad):.0f} deg of the expected up "
            f"axis holds {min_fraction:.0%} of the points over {min_extent_m:g} m both ways: "
            "give the camera's pitch and roll (--camera-pitch-deg, --camera-roll-deg) or the "
            "plane (--ground-plane A B C D)"
        )
    _, normal, d = lowest
    fraction = float(np.count_nonzero(np.abs(p @ normal + d) < threshold_m)) / len(p)
    return GroundPlane(normal, d, fraction, _angle_deg(normal, u), len(level))
