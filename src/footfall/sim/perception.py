"""The perception loop in simulation: depth camera -> pose estimate -> height map -> scores.

Runs at the camera rate inside the control loop. Each frame: render depth, estimate the
camera pose (true, or with SLAM-like noise), recentre and update the rolling height map,
score it, and hand map and scores to the terrain planner.
"""

from __future__ import annotations

import math
import statistics
import time

from scipy.spatial.transform import Rotation

from footfall.mapping.height_map import HeightMap, HeightMapConfig
from footfall.motion.planar import PlanarPose
from footfall.planning.terrain_planner import TerrainPlanner
from footfall.scoring.walkability import ScoreConfig, ScoreMap, score_map
from footfall.sensing.pose import Pose, SlamNoise
from footfall.sim.camera import SimDepthCamera
from footfall.sim.hexapod import MujocoHexapod
from footfall.sim.model import CameraMount


class SimPerception:
    """Camera, map and scores of a simulated robot.

    Args:
        backend: The simulated robot (built with a camera mount).
        mount: The camera mount.
        map_config: Height map settings.
        score_config: Score settings.
        noise: Pose-estimate noise, or None for true poses.
        planner: Terrain planner to feed, if any.
    """

    def __init__(
        self,
        backend: MujocoHexapod,
        mount: CameraMount,
        map_config: HeightMapConfig,
        score_config: ScoreConfig,
        noise: SlamNoise | None = None,
        planner: TerrainPlanner | None = None,
    ) -> None:
        self.backend = backend
        self.camera = SimDepthCamera(backend.model, mount)
        self.noise = noise
        self.planner = planner
        self.score_config = score_config
        self.period = 1.0 / mount.rate_hz
        self._next_frame = 0.0
        self._torso = backend.model.body("torso").id
        body = self._true_body_pose()
        self._camera_in_body = body.inverse().compose(self.camera.pose(backend.data))
        self.height_map = HeightMap(
            map_config, centre=(float(body.position[0]), float(body.position[1]))
        )
        self.scores: ScoreMap | None = None
        self.body_pose_estimate: Pose = body
        self.update_ms: list[float] = []
        self.render_ms: list[float] = []
        self.pixels_dropped = 0
        self.points_outside = 0

    def _true_body_pose(self) -> Pose:
        data = self.backend.data
        return Pose(
            data.xpos[self._torso].copy(),
            Rotation.from_matrix(data.xmat[self._torso].reshape(3, 3)),
        )

    @property
    def frames(self) -> int:
        """Depth frames integrated so far."""
        return len(self.update_ms)

    def planar_body_estimate(self) -> PlanarPose:
        """The latest body pose estimate, in the ground plane."""
        p = self.body_pose_estimate
        x_axis = p.rotation.apply([1.0, 0.0, 0.0])
        return PlanarPose(
            float(p.position[0]), float(p.position[1]), math.atan2(x_axis[1], x_axis[0])
        )

    def maybe_update(self, t: float) -> bool:
        """Take and integrate a frame if one is due at time ``t``; True when it did."""
        if t + 1e-9 < self._next_frame:
            return False
        self._next_frame += self.period
        t0 = time.perf_counter()
        depth, true_pose = self.camera.capture(self.backend.data)
        t1 = time.perf_counter()
        pose = self.noise.estimate(true_pose, t) if self.noise is not None else true_pose
        self.body_pose_estimate = pose.compose(self._camera_in_body.inverse())
        body = self.body_pose_estimate.position
        self.height_map.recentre((float(body[0]), float(body[1])))
        stats = self.height_map.integrate_depth(depth, self.camera.intrinsics, pose)
        if self.planner is not None:
            snapshot = self.height_map.snapshot()
            self.scores = score_map(snapshot, self.score_config)
            self.planner.update(snapshot, self.scores)
        t2 = time.perf_counter()
        self.render_ms.append(1e3 * (t1 - t0))
        self.update_ms.append(1e3 * (t2 - t1))
        self.pixels_dropped += stats.depth.dropped
        self.points_outside += stats.outside
        return True

    def timing(self) -> dict[str, float]:
        """Median per-frame times [ms]."""
        return {
            "map_update_ms_median": statistics.median(self.update_ms)
            if self.update_ms
            else float("nan"),
            "render_ms_median": statistics.median(self.render_ms)
            if self.render_ms
            else float("nan"),
        }

    def close(self) -> None:
        """Release the renderer."""
        self.camera.close()
