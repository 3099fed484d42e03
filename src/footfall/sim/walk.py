"""A simulated walk: the nodes of the robot, its camera and its task on the MuJoCo backend.

It is one module: the settings of a walk, the robot's nodes built from them, the run and
its metrics change together whenever a node or a metric is added.
"""

from __future__ import annotations

import dataclasses
import itertools
import math
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from footfall.control_loop import WalkingGraph, WalkLog
from footfall.errors import ConfigError
from footfall.mapping.drift import DriftConfig
from footfall.mapping.height_map import HeightMapConfig
from footfall.messages import GaitState, GroundPrior, Touchdown, WalkCommand
from footfall.metrics import walk_metrics
from footfall.motion.feedback import FeedbackConfig
from footfall.motion.gait import GaitConfig
from footfall.motion.walker import WalkController
from footfall.nodes.mapping import MappingNode
from footfall.nodes.navigation import NavigatorNode
from footfall.nodes.pose_guard import PoseGuardNode
from footfall.planning.navigation import NavigationConfig
from footfall.planning.terrain_planner import TerrainPlanner, TerrainPlannerConfig
from footfall.robot.planar import PlanarPose
from footfall.robot.spec import HexapodSpec
from footfall.runtime.bus import Bus, InProcessBus
from footfall.runtime.fault_spec import FaultSpec
from footfall.runtime.faults import RAW_POSE_TOPIC, FaultyLink, TickFaults
from footfall.runtime.scheduler import SimulatedScheduler, WallClockScheduler
from footfall.scoring.walkability import ScoreConfig, ScoreMap
from footfall.sim.hexapod import MujocoHexapod
from footfall.sim.model import CameraMount
from footfall.sim.sensors import SimCameraNode, SimPoseNode
from footfall.sim.task import TerrainTask
from footfall.sim.terrain import TERRAIN_NAMES, Terrain, make_terrain
from footfall.sim.truth import TrueScores, foothold_metrics

TERRAINS = TERRAIN_NAMES
# The ground around the standing robot is known from its feet within this radius [m].
START_PRIOR_RADIUS = 0.6


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

    def __post_init__(self) -> None:
        if self.terrain not in TERRAINS:
            raise ConfigError(
                f"unknown terrain {self.terrain!r}; choose one of {', '.join(TERRAINS)}"
            )
        if not self.seconds > 0:
            raise ConfigError(f"walk seconds must be positive, got {self.seconds}")
        if not self.control_rate_hz > 0:
            raise ConfigError(f"control rate must be positive, got {self.control_rate_hz}")
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
        metrics: Summary metrics (the ``metrics.json`` content).
        warnings: MuJoCo warnings by name; empty for a healthy simulation.
        terrain: The terrain walked.
        touchdowns: Every touchdown with its nominal and chosen foothold.
        scores: The last score map (planned walking), else None.
    """

    log: WalkLog
    metrics: dict[str, object]
    warnings: dict[str, int]
    terrain: Terrain
    touchdowns: list[Touchdown]
    scores: ScoreMap | None


@dataclass
class SimRobot:
    """The simulated hexapod's own nodes on a bus: camera, pose, mapping, movement, servo.

    Attributes:
        spec: The robot.
        settings: What is simulated.
        terrain: The terrain it stands on.
        backend: The MuJoCo robot.
        bus: The bus the nodes talk over.
        graph: The movement and servo nodes and the per-tick record.
        camera: The camera node (planned walking), else None.
        mapping: The mapping node (planned walking), else None.
        guard: The pose guard (planned walking), else None.
        link: The faulty link between the sensors and the rest (faults asked for), else
            None.
        simulated_until: Controller time the physics has been stepped to [s].
        control_seconds: Wall time of the last tick's control graph (controller, servo,
            physics step) [s].
        control_cpu_seconds: Its CPU time on this thread [s] (other processes on the
            machine do not change it).
    """

    spec: HexapodSpec
    settings: WalkSettings
    terrain: Terrain
    backend: MujocoHexapod
    bus: Bus
    graph: WalkingGraph
    camera: SimCameraNode | None
    mapping: MappingNode | None
    guard: PoseGuardNode | None = None
    link: FaultyLink | None = None
    simulated_until: float = 0.0
    control_seconds: float = 0.0
    control_cpu_seconds: float = 0.0

    @classmethod
    def build(
        cls,
        spec: HexapodSpec,
        settings: WalkSettings,
        terrain: Terrain,
        bus: Bus,
        command_timeout: float | None = None,
        color: bool = False,
        log_ticks: int | None = None,
    ) -> SimRobot:
        """Put the robot on the terrain, let it settle, and start its nodes on ``bus``.

        Blind, only the movement and servo nodes run; planned, the camera, pose, pose guard
        and mapping nodes too, with the ground under the standing robot as a prior and a
        first frame. The camera and the pose source publish through a faulty link when the
        settings ask for faults. With ``color`` the camera also renders colour images (for
        a station).
        """
        camera_mount = None if settings.blind else settings.camera
        height = settings.command.body_height
        backend = MujocoHexapod(spec, terrain, camera_mount, body_height=height)
        backend.advance(settings.settle_seconds)
        planner = camera = mapping = guard = None
        link = FaultyLink(bus, settings.faults, settings.seed) if settings.faults.active else None
        if not settings.blind:
            planner = TerrainPlanner(spec, settings.planner)
            standing = backend.read()
            assert standing.position_body_in_world is not None
            assert standing.feet_in_world is not None
            body = standing.position_body_in_world
            mapping = MappingNode(
                bus, settings.map, settings.score, centre=(body[0], body[1]), reject_repeats=True
            )
            sensors: Bus = link if link is not None else bus
            camera = SimCameraNode(sensors, backend, settings.camera, color=color)
            SimPoseNode(sensors, camera, topic=RAW_POSE_TOPIC)
            guard = PoseGuardNode(bus)
            ground = float(np.mean(standing.feet_in_world[:, 2])) - spec.foot_radius
            bus.publish(GroundPrior.TOPIC, GroundPrior(0.0, body, ground, START_PRIOR_RADIUS))
            camera.tick(0.0)
        controller = WalkController(
            spec,
            settings.gait,
            initial_pose=PlanarPose(*terrain.start),
            initial_height=height,
            planner=planner,
            feedback=None if settings.blind else settings.feedback,
        )
        if log_ticks is not None:
            controller.touchdowns = deque(maxlen=log_ticks)
        graph = WalkingGraph.build(
            bus, backend, controller, command_timeout=command_timeout, log_ticks=log_ticks
        )
        return cls(spec, settings, terrain, backend, bus, graph, camera, mapping, guard, link)

    def step(self, t: float, dt: float) -> None:
        """One control tick at ``t``, the physics over ``dt``, and the camera if due [s].

        A tick later than the physics has come (a wall-clock scheduler skipped ticks after
        an overrun) first lets the robot live through the gap holding its last joint
        targets, as servos do when their controller is late: simulated time stays the
        controller's.
        """
        if t > self.simulated_until + 1e-9:
            self.backend.advance(t - self.simulated_until)
        if self.link is not None:
            self.link.advance(t)
        t0, cpu0 = time.perf_counter(), time.thread_time()
        self.graph.step(t, dt)
        self.control_seconds = time.perf_counter() - t0
        self.control_cpu_seconds = time.thread_time() - cpu0
        self.simulated_until = t + dt
        if self.camera is not None:
            self.camera.tick(t + dt)

    def close(self) -> None:
        """Release the renderer."""
        if self.camera is not None:
            self.camera.close()

    def result(self, task: TerrainTask, wall_seconds: float, scheduler: object) -> WalkResult:
        """The record and metrics of the run so far, judged against the terrain's truth."""
        spec, settings, terrain = self.spec, self.settings, self.terrain
        log = self.graph.recorder.log
        controller = self.graph.movement.controller
        status = task.status
        assert status is not None
        base = settings.command
        if not log.time:  # never walked (a robot left in torque-off)
            metrics: dict[str, object] = {
                "walked": False,
                "sim_seconds": 0.0,
                "wall_seconds": wall_seconds,
                "distance_m": 0.0,
                "fell": False,
                "reached_goal": False,
                "invalid_footholds": 0,
                "touchdowns": 0,
                "frozen": False,
                "frozen_reason": "",
                "robot": spec.name,
                "terrain": terrain.name,
                "seed": settings.seed,
            }
            return WalkResult(log, metrics, self.backend.warnings(), terrain, [], None)
        metrics = walk_metrics(
            log,
            commanded_speed_mps=base.speed,
            wall_seconds=wall_seconds,
            foot_radius=spec.foot_radius,
            ground=terrain.height,
            frozen_reason=status.frozen_reason,
        )
        final = log.array("body_position_in_world")[-1, :2]
        goal = task.goal
        # Judge every foothold: the truth's grid covers wherever the feet went.
        feet = log.array("feet_in_world")[..., :2].reshape(-1, 2)
        low = np.minimum(feet.min(axis=0), goal) - 0.5
        high = np.maximum(feet.max(axis=0), goal) + 0.5
        extent = (
            min(-1.0, float(low[0])),
            max(float(goal[0]) + 1.0, float(high[0])),
            min(-1.5, float(low[1])),
            max(1.5, float(high[1])),
        )
        truth = TrueScores(terrain, settings.map.resolution, settings.score, extent)
        metrics.update(foothold_metrics(log, terrain, truth, spec.foot_radius))
        metrics.update(
            {
                "reached_goal": bool(task.at_goal(final) and not metrics["fell"]),
                "goal_distance_m": float(np.linalg.norm(goal - final)),
                "footholds_adjusted": status.footholds_adjusted,
                "frozen": status.state is GaitState.FROZEN,
                "frozen_reason": status.frozen_reason,
                "blind": settings.blind,
                "robot": spec.name,
                "terrain": terrain.name,
                "gait": settings.gait.kind.value,
                "seed": settings.seed,
                "control_rate_hz": settings.control_rate_hz,
                "commanded_body_height_m": base.body_height,
                "stride_m": controller.config.stride,
            }
        )
        if self.mapping is not None and self.camera is not None:
            metrics.update(
                {
                    "frames": self.mapping.frames,
                    **self.mapping.counts(),
                    **self.mapping.timing(),
                    **self.camera.timing(),
                }
            )
        frozen = GaitState.FROZEN.value
        metrics["freezes"] = sum(
            b == frozen and a != frozen for a, b in itertools.pairwise(log.state)
        )
        metrics["stale_stops"] = self.graph.movement.stops
        if controller.registration is not None:
            metrics["registration_error_max_m"] = controller.registration.largest_m
        if self.guard is not None:
            metrics["pose_jumps_detected"] = self.guard.jumps
            metrics["pose_jumps_refuted"] = self.guard.refuted
        if self.link is not None:
            metrics["faults"] = dataclasses.asdict(self.link.counts)
        if isinstance(scheduler, WallClockScheduler):
            metrics.update(
                {
                    "control_overruns": scheduler.stats.overruns,
                    "control_ticks_skipped": scheduler.stats.skipped,
                    "control_max_late_s": scheduler.stats.max_late_s,
                }
            )
        return WalkResult(
            log=log,
            metrics=metrics,
            warnings=self.backend.warnings(),
            terrain=terrain,
            touchdowns=list(controller.touchdowns),
            scores=self.mapping.scores if self.mapping is not None else None,
        )


def simulate_walk(
    spec: HexapodSpec,
    settings: WalkSettings,
    on_tick: Callable[[float], None] | None = None,
    terrain: Terrain | None = None,
    bus: Bus | None = None,
    on_build: Callable[[SimRobot], None] | None = None,
) -> WalkResult:
    """Walk the robot across a terrain in MuJoCo, towards the terrain's goal.

    The run is a graph of nodes on one bus: the simulated camera and pose source, the
    mapping node, the movement and servo nodes on the MuJoCo backend, and the task that
    steers to the goal and ends the run.

    Args:
        spec: The robot.
        settings: What to simulate.
        on_tick: Progress callback, called with the walk time [s] after each control tick.
        terrain: A terrain object to use instead of ``settings.terrain`` (custom terrains).
        bus: The bus to run the nodes on; a new in-process bus by default.
        on_build: Called with the robot once its nodes stand (a recorder notes the mapping
            node's settings).

    Returns:
        The record, metrics and simulator warnings.
    """
    terrain = terrain or make_terrain(settings.terrain, seed=settings.seed)
    bus = bus if bus is not None else InProcessBus()
    robot = SimRobot.build(spec, settings, terrain, bus)
    if on_build is not None:
        on_build(robot)
    navigator = (
        NavigatorNode(bus, spec, config=settings.navigation, background=settings.realtime)
        if settings.navigates
        else None
    )
    task = TerrainTask(
        bus,
        terrain,
        settings.command,
        settings.stop_at_goal,
        goal=settings.goal,
        navigator=navigator,
    )
    task.begin()
    scheduler = (
        WallClockScheduler(settings.control_rate_hz)
        if settings.realtime
        else SimulatedScheduler(settings.control_rate_hz)
    )
    dt = scheduler.period
    overruns = TickFaults(robot.link, dt) if robot.link is not None else None

    command_seconds: list[float] = []

    def tick(t: float) -> bool:
        if overruns is not None and overruns.skips(t):
            return False  # an earlier tick ran over this one's slot; the physics goes on
        t0 = time.perf_counter()
        task.command(t)  # with a navigator: hands maps over, and replans when not background
        command_seconds.append(time.perf_counter() - t0)
        robot.step(t, dt)
        if on_tick is not None:
            on_tick(t + dt)
        return task.should_stop(t + dt)

    wall_start = time.perf_counter()
    scheduler.run(tick, settings.seconds)
    wall_seconds = time.perf_counter() - wall_start
    robot.close()
    result = robot.result(task, wall_seconds, scheduler)
    if navigator is not None:
        navigator.close()
        result.metrics.update(navigation_metrics(navigator))
    if command_seconds:
        # How long the command step of a control tick took: a replan that held the tick up
        # shows here as its own duration.
        median, p99, top = 1e3 * np.percentile(command_seconds, [50.0, 99.0, 100.0])
        result.metrics["command_ms_median"] = float(median)
        result.metrics["command_ms_p99"] = float(p99)
        result.metrics["command_ms_max"] = float(top)
    result.metrics["navigated"] = navigator is not None
    return result


def navigation_metrics(navigator: NavigatorNode) -> dict[str, object]:
    """What the navigator did: whether it found no route and why, replans and their times."""
    return {
        "no_route": navigator.no_route is not None,
        "no_route_reason": navigator.no_route.reason if navigator.no_route is not None else "",
        **navigator.timing(),
    }
