"""What a walk is asked to do, and what it gives back."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from footfall.backends.registry import BACKENDS
from footfall.checks import require_positive
from footfall.control_loop import WalkLog
from footfall.errors import ConfigError
from footfall.mapping.drift import DriftConfig
from footfall.mapping.engine import HeightMapConfig
from footfall.messages import Touchdown, WalkCommand
from footfall.motion.feedback import FeedbackConfig
from footfall.motion.gait import GaitConfig
from footfall.nodes.sources import CAMERAS, POSES
from footfall.planning.navigation import NavigationConfig
from footfall.planning.terrain_planner import TerrainPlannerConfig
from footfall.runtime.fault_spec import FaultSpec
from footfall.scoring.walkability import ScoreConfig, ScoreMap
from footfall.sim.model import CameraMount
from footfall.sim.terrain import Terrain
from footfall.sim.terrains import TERRAINS
from footfall.sim.walk_metrics import NoWalk, WalkMetrics


@dataclass(frozen=True)
class WalkSettings:
    """What to simulate.

    Attributes:
        terrain: Terrain name (see ``TERRAINS``).
        seconds: Longest walking time [s]; the walk ends early at the goal, after a fall,
            or when frozen for a while.
        command: Speed and body height; the heading is steered towards the terrain's goal.
        gait: Gait parameters.
        blind: The thesis' baseline: nominal footholds on the plane z = 0, no camera, no
            feedback. Otherwise the full loop: camera -> map -> scores -> footholds.
        camera: Depth camera (planned walking only).
        map: Height map settings (with vertical drift compensation by default).
        score: Score settings.
        planner: Foothold planner settings.
        feedback: Attitude and height feedback (planned walking only).
        control_rate_hz: Controller rate [Hz].
        settle_seconds: Time the robot stands still before walking [s].
        seed: Seed of random terrains.
        stop_at_goal: End the walk once the goal is reached.
        realtime: Pace the control ticks to the wall clock (as a real robot runs) instead
            of simulating as fast as the machine can.
        faults: Sensor and timing faults injected between the nodes (see
            :mod:`footfall.runtime.faults`); none by default.
        straight: Walk the straight line from the start to the goal (the thesis'
            behaviour) instead of the routes the navigator plans round what cannot be
            crossed (planned walking only; a blind walk always goes straight).
        goal: Goal ``(x, y)`` in the world [m]; the terrain's by default.
        navigation: Route planning settings.
        backend: The robot backend (a name in ``BACKENDS``): the MuJoCo robot by default.
        backend_options: Settings for the backend (``--backend-option KEY=VALUE``).
        camera_source: The depth camera (a name in ``CAMERAS``) planned walking maps with.
        pose_source: The pose source (a name in ``POSES``) that places the camera's images.
        camera_options: Settings for the camera source (``--camera-option KEY=VALUE``).
        pose_options: Settings for the pose source (``--pose-option KEY=VALUE``).
    """

    terrain: str = "flat"
    seconds: float = 20.0
    command: WalkCommand = field(default_factory=lambda: WalkCommand(speed=0.1))
    gait: GaitConfig = field(default_factory=GaitConfig)
    blind: bool = True
    camera: CameraMount = field(default_factory=lambda: CameraMount(width=320, height=240))
    map: HeightMapConfig = field(
        default_factory=lambda: HeightMapConfig(drift=DriftConfig(enabled=True))
    )
    score: ScoreConfig = field(default_factory=ScoreConfig)
    planner: TerrainPlannerConfig = field(default_factory=TerrainPlannerConfig)
    feedback: FeedbackConfig = field(default_factory=FeedbackConfig)
    control_rate_hz: float = 100.0
    settle_seconds: float = 0.5
    seed: int = 0
    stop_at_goal: bool = False
    realtime: bool = False
    faults: FaultSpec = field(default_factory=FaultSpec)
    straight: bool = False
    goal: tuple[float, float] | None = None
    navigation: NavigationConfig = field(default_factory=NavigationConfig)
    backend: str = "sim"
    backend_options: dict[str, str] = field(default_factory=dict)
    camera_source: str = "sim"
    pose_source: str = "sim"
    camera_options: dict[str, str] = field(default_factory=dict)
    pose_options: dict[str, str] = field(default_factory=dict)

    def __post_init__(self) -> None:
        # An unknown name is an error that lists the known ones.
        TERRAINS.check(self.terrain)
        BACKENDS.check(self.backend)
        if not self.blind:
            CAMERAS.check(self.camera_source)
            POSES.check(self.pose_source)
        require_positive("walk", seconds=self.seconds, control_rate_hz=self.control_rate_hz)
        if self.goal is not None and not (
            len(self.goal) == 2 and all(math.isfinite(v) for v in self.goal)
        ):
            raise ConfigError(f"a goal is two finite numbers (x, y) [m], got {self.goal!r}")
        if self.blind and self.faults.sensor_faults:
            raise ConfigError(
                "sensor faults need the camera and pose source: a blind walk has neither"
            )

    @property
    def navigates(self) -> bool:
        """Whether the walk follows planned routes (planned walking, not held straight)."""
        return not (self.blind or self.straight)


@dataclass(frozen=True)
class WalkResult:
    """Outcome of a simulated walk.

    Attributes:
        log: Per-tick record.
        metrics: Summary metrics (``to_json`` is the ``metrics.json`` content).
        warnings: MuJoCo warnings by name; empty for a healthy simulation.
        terrain: The terrain walked.
        touchdowns: Every touchdown with its nominal and chosen foothold.
        scores: The last score map (planned walking), else None.
    """

    log: WalkLog
    metrics: WalkMetrics | NoWalk
    warnings: dict[str, int]
    terrain: Terrain
    touchdowns: list[Touchdown]
    scores: ScoreMap | None
