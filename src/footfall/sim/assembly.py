"""The robot's own nodes on one bus, from the backend and the sources the settings name.

It is the one place where a walk's robot is put together: the backend, camera and pose
source come from their registries; the pose guard, mapping, movement and servo nodes are
footfall's own. The run's metrics are judged against the terrain's truth.
"""

from __future__ import annotations

import dataclasses
import itertools
import time
from collections import deque
from dataclasses import dataclass, field

import numpy as np

from footfall.backends import BackendSetup, HexapodBackend
from footfall.backends.attitude import ImuAttitude, PoseAttitude
from footfall.backends.registry import BACKENDS
from footfall.control_loop import WalkingGraph, WalkLog
from footfall.errors import ConfigError
from footfall.messages import DepthFrame, GaitState, GroundPrior
from footfall.metrics import walk_metrics
from footfall.motion.walker import WalkController
from footfall.nodes.mapping import MappingNode
from footfall.nodes.pose_guard import PoseGuardNode
from footfall.nodes.sources import CAMERAS, POSES, CameraSource, PoseSource, SourceSetup
from footfall.planning.terrain_planner import TerrainPlanner
from footfall.robot.planar import PlanarPose
from footfall.robot.spec import HexapodSpec
from footfall.runtime.bus import Bus
from footfall.runtime.cpu_meter import CpuMeter, MeteredBus
from footfall.runtime.faults import FaultyLink
from footfall.runtime.node_thread import NodeThread
from footfall.runtime.scheduler import WallClockScheduler
from footfall.sensing.pose import Pose
from footfall.sim.model import CameraMount
from footfall.sim.task import TerrainTask
from footfall.sim.terrain import Terrain
from footfall.sim.truth import judge_footholds
from footfall.sim.walk_metrics import (
    MappingMetrics,
    NoWalk,
    Robustness,
    SchedulerMetrics,
    WalkMetrics,
    WalkOutcome,
    WalkSetup,
)
from footfall.sim.walk_settings import WalkResult, WalkSettings

# The ground around the standing robot is known from its feet within this radius [m].
START_PRIOR_RADIUS = 0.6
# What may wait for the perception thread (a newer one replaces the oldest): a camera's
# render, depth frames from a camera that publishes from the control loop.
PERCEPTION_WAITING = {"camera": 1, DepthFrame.TOPIC: 2}


def open_sources(
    settings: WalkSettings,
    mount: CameraMount,
    backend: HexapodBackend,
    sensors: Bus,
    meter: CpuMeter,
    thread: NodeThread | None,
    color: bool,
    color_hz: float | None,
    spec: HexapodSpec | None = None,
) -> tuple[CameraSource, PoseSource, str]:
    """The camera and pose source the settings name, publishing on ``sensors``.

    ``mount`` is the settings' camera placed on the robot (:meth:`CameraMount.on`).

    A camera may take ``thread`` for its heavy work; its pose source then answers it on
    that thread. Returns the camera, the pose source and the camera's name on ``meter`` (the
    simulator's own sources are charged as the simulator's: ``sim_camera``, ``sim_pose``).
    """
    camera_node = ("sim_" if settings.camera_source == "sim" else "") + "camera"
    pose_node = ("sim_" if settings.pose_source == "sim" else "") + "pose"
    camera = CAMERAS.get(settings.camera_source).open(
        SourceSetup(
            MeteredBus(sensors, meter, camera_node),
            backend,
            mount,
            color,
            options=dict(settings.camera_options),
            color_hz=color_hz,
            thread=thread,
            thread_bus=MeteredBus(thread.bus, meter, camera_node) if thread else None,
        )
    )
    on_thread = thread is not None and getattr(camera, "thread", None) is thread
    pose = POSES.get(settings.pose_source).open(
        SourceSetup(
            MeteredBus(thread.bus if on_thread else sensors, meter, pose_node),
            backend,
            mount,
            camera=camera,
            options=dict(settings.pose_options),
            spec=spec,
            seed=settings.seed,
        )
    )
    return camera, pose, camera_node


@dataclass
class WalkingRobot:
    """The hexapod's own nodes on a bus: camera, pose, mapping, movement, servo.

    The backend, the camera and the pose source are the ones the settings name in their
    registries (the MuJoCo robot, its rendered camera and its true pose by default); the
    run is judged against the terrain's truth.

    Attributes:
        spec: The robot.
        settings: What is simulated.
        terrain: The terrain it stands on.
        backend: The robot (the MuJoCo one by default).
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
        meter: CPU time and latency per node (the simulator's under names from ``sim``).
        camera_node: The camera source's name on the meter (``sim_camera`` for the
            simulator's rendered camera).
        perception_thread: The thread the camera's render, the pose source and the mapping
            node run on, when not the control loop's.
        pose_source: The pose source (planned walking), else None.
    """

    spec: HexapodSpec
    settings: WalkSettings
    terrain: Terrain
    backend: HexapodBackend
    bus: Bus
    graph: WalkingGraph
    camera: CameraSource | None
    mapping: MappingNode | None
    guard: PoseGuardNode | None = None
    link: FaultyLink | None = None
    simulated_until: float = 0.0
    control_seconds: float = 0.0
    control_cpu_seconds: float = 0.0
    meter: CpuMeter = field(default_factory=CpuMeter)
    camera_node: str = "camera"
    perception_thread: NodeThread | None = None
    pose_source: PoseSource | None = None

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
        color_hz: float | None = None,
        meter: CpuMeter | None = None,
        perception_thread: bool = False,
    ) -> WalkingRobot:
        """Put the robot on the terrain, let it settle, and start its nodes on ``bus``.

        Blind, only the movement and servo nodes run; planned, the camera, pose, pose guard
        and mapping nodes too, with the ground under the standing robot as a prior and a
        first frame. The camera and the pose source publish through a faulty link when the
        settings ask for faults. With ``color`` the camera also renders colour images (for
        a station), at most ``color_hz`` a second when given. Each node's work is charged
        to it on ``meter`` (a new one when None). With ``perception_thread`` the mapping node,
        the simulator's render and the pose source answering it run on a thread of their
        own (:mod:`footfall.runtime.node_thread`; the render stays in the loop when faults
        are injected between the sensors and the rest): a robot on the wall clock then
        never waits for a frame; its maps reach the control loop at the next tick. A
        simulated walk keeps them in the loop, repeatable to the bit.
        """
        meter = meter if meter is not None else CpuMeter()
        camera_mount = None if settings.blind else settings.camera.on(spec.camera)
        height = settings.command.body_height
        setup = BackendSetup(spec, height, terrain, camera_mount, dict(settings.backend_options))
        backend = BACKENDS.get(settings.backend).open(setup)
        backend.advance(settings.settle_seconds)
        planner = camera = pose_source = mapping = guard = thread = None
        camera_node = "camera"
        link = FaultyLink(bus, settings.faults, settings.seed) if settings.faults.active else None
        if not settings.blind:
            planner = TerrainPlanner(spec, settings.planner)
            standing = backend.read()
            # A robot that does not know where it stands starts at the terrain's start.
            body = standing.position_body_in_world
            if body is None:
                body = np.array([*terrain.start, float(terrain.height(*terrain.start)) + height])
            if perception_thread:
                thread = NodeThread(bus, "perception", waiting=PERCEPTION_WAITING)
            mapping = MappingNode(
                MeteredBus(thread.bus if thread is not None else bus, meter, "mapping"),
                settings.map,
                settings.score,
                centre=(body[0], body[1]),
                reject_repeats=True,
            )
            sensors: Bus = link if link is not None else bus
            # Injected faults stand between the sensors and the rest, on the control loop.
            offered = thread if link is None else None
            assert camera_mount is not None
            camera, pose_source, camera_node = open_sources(
                settings, camera_mount, backend, sensors, meter, offered, color, color_hz, spec
            )
            guard = PoseGuardNode(MeteredBus(bus, meter, "pose_guard"))
            if hasattr(backend, "attitude") and backend.attitude is None:
                # A robot without an IMU of its own takes its attitude from its camera's
                # IMU where the camera has one, else from its pose source.
                imu = getattr(camera, "has_imu", False)
                if not imu and getattr(pose_source, "needs_imu", False):
                    raise ConfigError(
                        f"the {settings.pose_source} pose source needs an IMU: the robot's "
                        "own, or its camera's (a RealSense D435i)"
                    )
                backend.attitude = ImuAttitude(bus) if imu else PoseAttitude(bus)
            if standing.feet_in_world is not None:
                ground = float(np.mean(standing.feet_in_world[:, 2])) - spec.foot_radius
            else:
                ground = float(body[2]) - height
            bus.publish(GroundPrior.TOPIC, GroundPrior(0.0, body, ground, START_PRIOR_RADIUS))
            with meter.measure(camera_node):
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
            bus, backend, controller, command_timeout, log_ticks, meter=meter
        )
        return cls(
            spec,
            settings,
            terrain,
            backend,
            bus,
            graph,
            camera,
            mapping,
            guard,
            link,
            meter=meter,
            camera_node=camera_node,
            perception_thread=thread.start() if thread is not None else None,
            pose_source=pose_source,
        )

    def step(self, t: float, dt: float) -> None:
        """One control tick at ``t``, the physics over ``dt``, and the camera if due [s].

        A tick later than the physics has come (a wall-clock scheduler skipped ticks after
        an overrun) first lets the robot live through the gap holding its last joint
        targets, as servos do when their controller is late: simulated time stays the
        controller's.
        """
        if t > self.simulated_until + 1e-9:
            with self.meter.measure("sim_physics"):
                self.backend.advance(t - self.simulated_until)
        if self.link is not None:
            self.link.advance(t)
        if self.perception_thread is not None:
            self.perception_thread.spin()  # the frames and maps made since the last tick
        t0, cpu0 = time.perf_counter(), time.thread_time()
        self.graph.step(t, dt)
        self.control_seconds = time.perf_counter() - t0
        self.control_cpu_seconds = time.thread_time() - cpu0
        self.simulated_until = t + dt
        if self.camera is not None:
            with self.meter.measure(self.camera_node):
                self.camera.tick(t + dt)

    def close(self) -> None:
        """Release the renderer, stop the perception thread, close the backend's port."""
        if self.camera is not None:
            self.camera.close()  # on the perception thread, if it renders there
        if self.perception_thread is not None:
            self.perception_thread.close()
        close = getattr(self.backend, "close", None)
        if callable(close):
            close()

    def warnings(self) -> dict[str, int]:
        """The simulator's warnings by name (none from a backend that keeps no such count)."""
        count = getattr(self.backend, "warnings", None)
        return count() if callable(count) else {}

    def result(self, task: TerrainTask, wall_seconds: float, scheduler: object) -> WalkResult:
        """The record and metrics of the run so far, judged against the terrain's truth."""
        spec, settings, terrain = self.spec, self.settings, self.terrain
        log = self.graph.recorder.log
        controller = self.graph.movement.controller
        status = task.status
        assert status is not None
        base = settings.command
        if not log.time:  # never walked (a robot left in torque-off)
            idle = NoWalk(spec.name, terrain.name, settings.seed, wall_seconds)
            return WalkResult(log, idle, self.warnings(), terrain, [], None)
        gait = walk_metrics(
            log,
            commanded_speed_mps=base.speed,
            wall_seconds=wall_seconds,
            foot_radius=spec.foot_radius,
            ground=terrain.height,
            frozen_reason=status.frozen_reason,
        )
        final = log.array("body_position_in_world")[-1, :2]
        goal = task.goal
        metrics = WalkMetrics(
            gait=gait,
            footholds=judge_footholds(
                log, terrain, settings.map.resolution, settings.score, spec.foot_radius, goal
            ),
            outcome=WalkOutcome(
                reached_goal=bool(task.at_goal(final) and not gait.fell),
                goal_distance_m=float(np.linalg.norm(goal - final)),
                footholds_adjusted=status.footholds_adjusted,
                frozen=status.state is GaitState.FROZEN,
                frozen_reason=status.frozen_reason,
            ),
            setup=WalkSetup(
                blind=settings.blind,
                robot=spec.name,
                terrain=terrain.name,
                gait=settings.gait.kind,
                seed=settings.seed,
                control_rate_hz=settings.control_rate_hz,
                commanded_body_height_m=base.body_height,
                stride_m=controller.config.stride,
            ),
            robustness=self._robustness(log),
            nodes=self.meter.report(gait.sim_seconds),
        )
        bus = getattr(self.backend, "bus_metrics", None)
        if callable(bus):
            metrics.servo_bus = bus()
        drift, truth = getattr(self.pose_source, "drift", None), self.backend.read()
        if callable(drift) and truth.position_body_in_world is not None:
            body = Pose(truth.position_body_in_world, truth.orientation_body_in_world)
            metrics.estimator = drift(body)
        if self.mapping is not None and self.camera is not None:
            metrics.mapping = MappingMetrics(
                frames=self.mapping.frames,
                **self.mapping.counts(),
                **self.mapping.timing(),
                frames_replaced_waiting=(
                    sum(self.perception_thread.dropped.values())
                    if self.perception_thread is not None
                    else 0
                ),
                camera=self.camera.timing(),
            )
        if isinstance(scheduler, WallClockScheduler):
            metrics.scheduler = SchedulerMetrics(
                control_overruns=scheduler.stats.overruns,
                control_ticks_skipped=scheduler.stats.skipped,
                control_max_late_s=scheduler.stats.max_late_s,
            )
        return WalkResult(
            log=log,
            metrics=metrics,
            warnings=self.warnings(),
            terrain=terrain,
            touchdowns=list(controller.touchdowns),
            scores=self.mapping.scores if self.mapping is not None else None,
        )

    def _robustness(self, log: WalkLog) -> Robustness:
        """Freezes, stale stops, pose corrections and jumps, and what injected faults did."""
        frozen = GaitState.FROZEN.value
        registration = self.graph.movement.controller.registration
        planner = self.graph.movement.controller.planner
        return Robustness(
            freezes=sum(b == frozen and a != frozen for a, b in itertools.pairwise(log.state)),
            stale_stops=self.graph.movement.stops,
            registration_error_max_m=None if registration is None else registration.largest_m,
            pose_jumps_detected=None if self.guard is None else self.guard.jumps,
            pose_jumps_refuted=None if self.guard is None else self.guard.refuted,
            faults=None if self.link is None else dataclasses.asdict(self.link.counts),
            foothold_region_jumps=None if planner is None else planner.region_jumps,
        )
