"""The biped's commands: obstacles from a point cloud, and a planned walk around them."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from footfall.biped.maps import PlanMap, dissertation_map, load_map
from footfall.biped.obstacles import Detection, DetectionConfig, detect_obstacles
from footfall.biped.planner import WalkPlan, plan_walk
from footfall.errors import ConfigError
from footfall.io.clouds import read_points
from footfall.reports import write_json


@dataclass(frozen=True)
class CloudRequest:
    """A point cloud to detect obstacles in (``footfall obstacles``, ``plan --cloud``).

    Attributes:
        cloud: A ``.pcd``, ``.ply`` or ``.npy`` file.
        frame: ``"camera"`` or ``"map"``: the frame the points are in.
        ground: Ground removal: ``"plane"``, ``"ransac"`` or ``"cone"``.
        camera_height: Camera height above the ground [m].
        cluster_tolerance: Euclidean clustering radius [m].
        min_cluster_size: Smallest obstacle [points].
    """

    cloud: Path
    frame: str = "camera"
    ground: str = "plane"
    camera_height: float = 0.0
    cluster_tolerance: float = 0.30
    min_cluster_size: int = 5


def detect(request: CloudRequest) -> Detection:
    """Read the cloud and detect its obstacles."""
    points = read_points(request.cloud)
    config = DetectionConfig(
        ground=request.ground,
        cluster_tolerance=request.cluster_tolerance,
        min_cluster_size=request.min_cluster_size,
    )
    return detect_obstacles(
        points, request.frame, config, camera_in_base=(0.0, 0.0, request.camera_height)
    )


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
            }
            for c in d.clusters
        ]
        return {
            "cloud": str(self.request.cloud),
            "frame": self.request.frame,
            "ground": self.request.ground,
            "points": len(d.points_in_map),
            "obstacle_points": int(d.obstacle_mask.sum()),
            "clusters": clusters,
        }

    def write(self, out: Path) -> list[Path]:
        """Write ``obstacles.json`` and ``obstacles.png`` to ``out``."""
        from footfall.plots import plot_obstacles

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
        from footfall.plots import plot_plan

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
