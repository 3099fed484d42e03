"""The biped's commands: obstacles from a point cloud, and a planned walk around them."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

from footfall.biped.maps import PlanMap, dissertation_map, load_map
from footfall.biped.obstacles import Detection, DetectionConfig, detect_obstacles
from footfall.biped.planner import WalkPlan, plan_walk
from footfall.errors import ConfigError
from footfall.io.clouds import read_points
from footfall.pointcloud.ground import CameraOverFloor, GroundPlane
from footfall.reports import write_json


@dataclass(frozen=True)
class CloudRequest:
    """A point cloud to detect obstacles in (``footfall obstacles``, ``plan --cloud``).

    Attributes:
        cloud: A ``.pcd``, ``.ply`` or ``.npy`` file.
        frame: ``"camera"`` or ``"map"``: the frame the points are in.
        ground: Ground removal: ``"ransac"``, ``"plane"`` or ``"cones"``.
        camera_height: Camera height above the floor [m]; None when not known.
        camera_pitch_deg: How far the camera looks down [deg]; None when not known.
        camera_roll_deg: How far its right side dips [deg]; None when not known.
        ground_plane: The floor ``a x + b y + c z + d = 0`` in the camera frame.
        camera_height_range: Heights the camera may stand over its floor [m].
        voxel_size: Voxel grid side [m].
        max_obstacle_height: Points higher above the floor are overhead [m].
        cluster_tolerance: Euclidean clustering radius [m].
        min_cluster_size: Smallest obstacle [points].
    """

    cloud: Path
    frame: str = "camera"
    ground: str = "ransac"
    camera_height: float | None = None
    camera_pitch_deg: float | None = None
    camera_roll_deg: float | None = None
    ground_plane: tuple[float, float, float, float] | None = None
    camera_height_range: tuple[float, float] = (0.1, 3.0)
    voxel_size: float = 0.02
    max_obstacle_height: float = 2.0
    cluster_tolerance: float = 0.30
    min_cluster_size: int = 5

    def camera(self) -> CameraOverFloor | None:
        """The camera's pose over the floor the request gives, or None."""
        given = (self.camera_height, self.camera_pitch_deg, self.camera_roll_deg)
        if all(v is None for v in given):
            return None
        height, pitch, roll = (0.0 if v is None else float(v) for v in given)
        return CameraOverFloor.from_angles(height, math.radians(pitch), math.radians(roll))


def detect(request: CloudRequest) -> Detection:
    """Read the cloud and detect its obstacles."""
    points = read_points(request.cloud)
    config = DetectionConfig(
        ground=request.ground,
        voxel_size=request.voxel_size,
        max_obstacle_height=request.max_obstacle_height,
        cluster_tolerance=request.cluster_tolerance,
        min_cluster_size=request.min_cluster_size,
        camera_height_range=request.camera_height_range,
    )
    if request.frame == "map" and (request.camera() or request.ground_plane) is not None:
        raise ConfigError("a camera pose or --ground-plane only applies to a camera-frame cloud")
    return detect_obstacles(
        points, request.frame, config, camera=request.camera(), ground_plane=request.ground_plane
    )


def _plane_json(plane: GroundPlane) -> dict[str, object]:
    return {
        "normal": [float(v) for v in plane.normal],
        "offset_m": float(plane.offset_m),
        "inlier_fraction": float(plane.inlier_fraction),
        "angle_to_up_deg": float(plane.angle_to_up_deg),
    }


@dataclass(frozen=True)
class ObstacleReport:
    """Obstacles found in a cloud.

    Attributes:
        request: The cloud and settings.
        detection: What was found.
    """

    request: CloudRequest
    detection: Detection

    def to_json(self) -> dict[str, object]:
        """The ``obstacles.json`` content."""
        d = self.detection
        clusters = [
            {
                "centroid": c.centroid.tolist(),
                "box": {
                    "x": float(c.centre[0]),
                    "y": float(c.centre[1]),
                    "width": c.width,
                    "depth": c.depth,
                    "height": c.height,
                    "yaw_rad": c.yaw,
                },
                "points": c.points,
                "circles": [{"x": k.x, "y": k.y, "r": k.r} for k in c.circles],
                "empty_fraction": c.empty_fraction,
                "free_floor_fraction": c.free_floor_fraction,
                "component": c.component,
            }
            for c in d.clusters
        ]
        ground = {**_plane_json(d.ground), "candidates": d.ground.candidates}
        if d.ground_in_camera is not None:
            ground["normal_in_camera"] = [float(v) for v in d.ground_in_camera.normal]
            ground["offset_in_camera_m"] = float(d.ground_in_camera.offset_m)
        out: dict[str, object] = {
            "cloud": str(self.request.cloud),
            "frame": self.request.frame,
            "ground": self.request.ground,
            "ground_plane": ground,
            "voxel_size_m": d.voxel_size_m,
            "points_in": d.points_in,
            "points_after_voxel": len(d.points_in_map),
            "points": len(d.points_in_map),
            "obstacle_points": int(d.obstacle_mask.sum()),
            "detect_ms": d.detect_ms,
            "clusters": clusters,
        }
        if d.camera is not None:
            out["camera"] = {
                "height_m": d.camera.height_m,
                "pitch_deg": math.degrees(d.camera.pitch_rad),
                "roll_deg": math.degrees(d.camera.roll_rad),
            }
        return out

    def write(self, out: Path) -> list[Path]:
        """Write ``obstacles.json`` and ``obstacles.png`` to ``out``."""
        from footfall.plots_biped import plot_obstacles

        out.mkdir(parents=True, exist_ok=True)
        paths = [out / "obstacles.json", out / "obstacles.png"]
        write_json(paths[0], self.to_json())
        plot_obstacles(self.detection, paths[1])
        return paths


def run_obstacles(request: CloudRequest) -> ObstacleReport:
    """Detect the obstacles of a cloud."""
    return ObstacleReport(request, detect(request))


@dataclass(frozen=True)
class PlanRequest:
    """What to plan (``footfall plan``): exactly one of a map file, a case or a cloud.

    Attributes:
        map: A JSON map file.
        case: One of the dissertation's 11 maps.
        cloud: A point cloud to detect the obstacles in.
        start: Start instead of the map's [m].
        goal: Goal instead of the map's [m] (needed with a cloud).
    """

    map: Path | None = None
    case: int | None = None
    cloud: CloudRequest | None = None
    start: tuple[float, float] | None = None
    goal: tuple[float, float] | None = None


@dataclass(frozen=True)
class PlanReport:
    """A planned biped walk.

    Attributes:
        plan_map: The map planned on.
        plan: Path, footsteps and centre-of-mass pattern.
    """

    plan_map: PlanMap
    plan: WalkPlan

    def to_json(self) -> dict[str, object]:
        """The ``plan.json`` content."""
        return self.plan.to_json()

    def write(self, out: Path) -> list[Path]:
        """Write ``plan.json`` and ``plan.png`` to ``out``."""
        from footfall.plots_biped import plot_plan

        out.mkdir(parents=True, exist_ok=True)
        paths = [out / "plan.json", out / "plan.png"]
        write_json(paths[0], self.to_json())
        plot_plan(self.plan, paths[1])
        return paths


def run_plan(request: PlanRequest) -> PlanReport:
    """Plan the walk a request asks for.

    Raises:
        ConfigError: Not exactly one source, or a cloud without a goal.
    """
    sources = [s for s in (request.map, request.case, request.cloud) if s is not None]
    if len(sources) != 1:
        raise ConfigError("plan needs exactly one of a map file, a case and a cloud")
    if request.cloud is not None:
        if request.goal is None:
            raise ConfigError("planning on a point cloud needs --goal X Y")
        detection = detect(request.cloud)
        start = (0.0, 0.0) if request.start is None else request.start
        plan_map = PlanMap(request.cloud.cloud.stem, start, request.goal, tuple(detection.circles))
    else:
        plan_map = (
            load_map(request.map) if request.map is not None else dissertation_map(request.case)
        )
        plan_map = plan_map.with_endpoints(request.start, request.goal)
    return PlanReport(plan_map, plan_walk(plan_map))
