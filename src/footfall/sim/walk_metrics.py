"""A walk's metrics, typed: what ``metrics.json`` holds, section by section.

Each section is measured by the part that knows it: the per-tick record
(:class:`~footfall.metrics.GaitMetrics`), the terrain's truth
(:class:`~footfall.sim.truth.FootholdMetrics`), the mapping node, the pose guard and the
faulty link, the scheduler, the navigator, the network bridge. :meth:`WalkMetrics.to_json`
flattens them into the one ``metrics.json`` object, in that order; a section (or a value)
that does not apply to a walk is left out rather than written as null.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field, fields

from footfall.metrics import GaitMetrics
from footfall.sim.truth import FootholdMetrics


def _present(section: object) -> dict[str, object]:
    """A section's fields, leaving out those that are None."""
    return {f.name: v for f in fields(section) if (v := getattr(section, f.name)) is not None}


@dataclass(frozen=True)
class WalkOutcome:
    """How the walk ended.

    Attributes:
        reached_goal: The body ended within the goal tolerance, without a fall.
        goal_distance_m: Distance from the body's last position to the goal [m] (NaN when
            the robot does not know where it is).
        footholds_adjusted: Footholds the planner moved off their nominal place.
        frozen: Whether the walker ended frozen.
        frozen_reason: Why, or "".
    """

    reached_goal: bool
    goal_distance_m: float
    footholds_adjusted: int
    frozen: bool
    frozen_reason: str


@dataclass(frozen=True)
class WalkSetup:
    """What was walked.

    Attributes:
        blind: The thesis' blind baseline.
        robot: The robot's name.
        terrain: The terrain's name.
        gait: The gait's name.
        seed: The terrain's seed.
        control_rate_hz: Controller rate [Hz].
        commanded_body_height_m: Commanded body height [m].
        stride_m: The gait's stride [m].
    """

    blind: bool
    robot: str
    terrain: str
    gait: str
    seed: int
    control_rate_hz: float
    commanded_body_height_m: float
    stride_m: float


@dataclass(frozen=True)
class MappingMetrics:
    """What the camera and the mapping node did (planned walking).

    Attributes:
        frames: Depth frames fused.
        frames_skipped_no_pose: Frames with no pose estimate near their time.
        frames_repeated: Frames that repeated the previous image while the camera moved.
        frames_inconsistent: Frames whose vertical offset jumped (not fused).
        map_offset_max_m: Largest vertical drift correction [m].
        frames_at_alternative_pose: Frames fused at the estimate's own pose after a jump.
        map_update_ms_median: Median time to fuse a frame [ms].
        frames_replaced_waiting: Frames a newer one replaced while they waited for a
            mapping thread (a robot's mapping that fell behind its camera).
        camera: The camera source's own timing figures (``render_ms_median`` for the
            simulated one).
    """

    frames: int
    frames_skipped_no_pose: int
    frames_repeated: int
    frames_inconsistent: int
    map_offset_max_m: float
    frames_at_alternative_pose: int
    map_update_ms_median: float
    frames_replaced_waiting: int = 0
    camera: dict[str, float] = field(default_factory=dict)

    def to_json(self) -> dict[str, object]:
        """The fields, the camera's figures flattened in."""
        out = {f.name: getattr(self, f.name) for f in fields(self) if f.name != "camera"}
        return {**out, **self.camera}


@dataclass(frozen=True)
class Robustness:
    """What went wrong on the way and what the robot did about it.

    Attributes:
        freezes: Times the walker froze.
        stale_stops: Times it stood for a stale pose or map.
        registration_error_max_m: Largest sum of pose corrections over a map cell's
            lifetime [m] (planned walking).
        pose_jumps_detected: Pose estimates the guard took for jumps (planned walking).
        pose_jumps_refuted: Of those, ones the map showed were right.
        faults: What the injected faults did, by kind (faults asked for).
        foothold_region_jumps: Re-plans that moved a leg's foothold to another steppable
            region, no deeper inside it, while the foothold planned before still served
            (planned walking).
    """

    freezes: int
    stale_stops: int
    registration_error_max_m: float | None = None
    pose_jumps_detected: int | None = None
    pose_jumps_refuted: int | None = None
    faults: dict[str, int] | None = None
    foothold_region_jumps: int | None = None


@dataclass(frozen=True)
class SchedulerMetrics:
    """How the wall clock kept up (``--realtime``).

    Attributes:
        control_overruns: Ticks that ran past their deadline.
        control_ticks_skipped: Ticks skipped to catch up.
        control_max_late_s: Latest a tick started [s].
    """

    control_overruns: int
    control_ticks_skipped: int
    control_max_late_s: float


@dataclass(frozen=True)
class NavigationMetrics:
    """What the navigator did.

    Attributes:
        no_route: It found no route and stood still.
        no_route_reason: Why, or "".
        replans: Routes planned.
        replan_ms_median: Median time of a replan (cost grid and search) [ms].
        replan_ms_p95: Its 95th percentile [ms].
        routes_blocked: Times ground ahead of a stuck walker was kept out of routes.
        looks: Times the robot turned to look at a place its map had not seen.
    """

    no_route: bool
    no_route_reason: str
    replans: int
    replan_ms_median: float | None = None
    replan_ms_p95: float | None = None
    routes_blocked: int | None = None
    looks: int | None = None


@dataclass(frozen=True)
class CommandTiming:
    """How long each tick's command step took (a replan holding a tick up shows here).

    Attributes:
        command_ms_median: Median [ms].
        command_ms_p99: 99th percentile [ms].
        command_ms_max: Longest [ms].
    """

    command_ms_median: float
    command_ms_p99: float
    command_ms_max: float


@dataclass(frozen=True)
class BridgeTraffic:
    """Messages the network bridge carried, by topic (``footfall robot``).

    Attributes:
        bridge_forwarded: Sent out to the network.
        bridge_received: Taken in from it.
        link: The radio link's sending end (``runtime/link.py``): per bulk topic the
            messages sent, their bytes, those dropped for a newer one; whole maps sent;
            messages acknowledged. None on a full-precision link.
        command_latency_ms: From a station's command (its wall-clock stamp) to the first
            joint targets computed with it: ``median``, ``p95``, ``max`` [ms] and ``count``
            (commands to a limp robot not counted); None when no command came.
    """

    bridge_forwarded: dict[str, int]
    bridge_received: dict[str, int]
    link: dict | None = None
    command_latency_ms: dict[str, float] | None = None


@dataclass(frozen=True)
class ServoBusMetrics:
    """What a walk's servo bus carried, by the emulated bus's byte clock (``--servo-bus``).

    Attributes:
        protocol: Dynamixel protocol, 1 or 2.
        baud: Bits per second.
        servos: Servos on the bus.
        ticks: Control ticks that sent targets.
        packets: Instruction and status packets, set-up included.
        errors: Status packets with an error, and instructions that arrived corrupted.
        bytes_per_tick: Bytes on the wire per control tick (writes and reads).
        write_bytes_per_tick: Of the goal writes and their answers.
        read_bytes_per_tick: Of the read instructions and their status packets.
        write_ms_per_tick: Wire time of the writes per tick [ms].
        read_ms_per_tick: Wire time of the reads per tick, return delays included [ms].
        utilisation: Mean share of a control period the bus was busy.
        utilisation_max: The busiest tick's share.
        reads_per_tick: Servos read one by one each tick (the read schedule).
        joint_targets_clamped: Joint targets moved inside their limits before sending.
        joint_targets_over_speed: Joint targets faster than their servo model's no-load
            speed (the real servo would lag them).
        fault: Why the bus stopped the walk, or "".
    """

    protocol: int
    baud: int
    servos: int
    ticks: int
    packets: int
    errors: int
    bytes_per_tick: float
    write_bytes_per_tick: float
    read_bytes_per_tick: float
    write_ms_per_tick: float
    read_ms_per_tick: float
    utilisation: float
    utilisation_max: float
    reads_per_tick: int
    joint_targets_clamped: int
    joint_targets_over_speed: int
    fault: str


@dataclass
class WalkMetrics:
    """Everything a walk measured; :meth:`to_json` is ``metrics.json``.

    Attributes:
        gait: What the per-tick record says (distance, fall, tilt, steps).
        footholds: The footholds against the terrain's truth.
        outcome: How it ended.
        setup: What was walked.
        robustness: Freezes, stops, pose jumps and injected faults.
        mapping: The camera and the map (planned walking), else None.
        scheduler: The wall clock's overruns (``--realtime``), else None.
        navigation: The navigator (planned routes), else None.
        commands: Command-step timing, else None.
        navigated: Whether routes were planned (None: not said).
        bridge: The network bridge's traffic (``footfall robot``), else None.
        servo_bus: The servo bus's traffic (a Dynamixel bus), else None.
        nodes: Per node: CPU seconds, share of one core per second walked, calls, median
            and 95th percentile latency [ms] (the simulator's names start with ``sim``),
            else None.
        estimator: The estimator's error against the truth at the end (``--pose
            estimator``, :meth:`~footfall.nodes.estimator_pose.EstimatorPose.drift`), else None.
    """

    gait: GaitMetrics
    footholds: FootholdMetrics
    outcome: WalkOutcome
    setup: WalkSetup
    robustness: Robustness
    mapping: MappingMetrics | None = None
    scheduler: SchedulerMetrics | None = None
    navigation: NavigationMetrics | None = None
    commands: CommandTiming | None = None
    navigated: bool | None = None
    bridge: BridgeTraffic | None = None
    servo_bus: ServoBusMetrics | None = None
    nodes: dict[str, dict[str, float]] | None = None
    estimator: dict[str, float] | None = None

    @property
    def fell(self) -> bool:
        """Whether the body fell."""
        return self.gait.fell

    @property
    def reached_goal(self) -> bool:
        """Whether the walk reached its goal, without a fall."""
        return self.outcome.reached_goal

    def to_json(self) -> dict[str, object]:
        """The ``metrics.json`` object."""
        out = self.gait.to_json()
        out.update(_present(self.footholds))
        out.update(asdict(self.outcome))  # the walker's own frozen state replaces the log's
        out.update(asdict(self.setup))
        if self.mapping is not None:
            out.update(self.mapping.to_json())
        out.update(_present(self.robustness))
        for section in (self.scheduler, self.navigation, self.commands):
            if section is not None:
                out.update(_present(section))
        if self.navigated is not None:
            out["navigated"] = self.navigated
        if self.bridge is not None:
            out.update(asdict(self.bridge))
        if self.servo_bus is not None:
            out["servo_bus"] = asdict(self.servo_bus)
        if self.estimator is not None:
            out.update(self.estimator)
        if self.nodes is not None:
            out["cpu_per_node"] = {name: n["cpu_s"] for name, n in self.nodes.items()}
            own = sum(n["cpu_s"] for name, n in self.nodes.items() if not name.startswith("sim"))
            seconds = self.gait.sim_seconds
            out["cpu_own_share"] = own / seconds if seconds > 0 else 0.0
            out["nodes"] = self.nodes
        return out


@dataclass
class NoWalk:
    """The metrics of a run that never walked (a robot left in torque-off).

    Attributes:
        robot: The robot's name.
        terrain: The terrain's name.
        seed: The terrain's seed.
        wall_seconds: How long it ran [s].
        bridge: The network bridge's traffic, else None.
    """

    robot: str
    terrain: str
    seed: int
    wall_seconds: float
    bridge: BridgeTraffic | None = None

    @property
    def fell(self) -> bool:
        """It did not walk, so it did not fall."""
        return False

    @property
    def reached_goal(self) -> bool:
        """It did not walk, so it did not get there."""
        return False

    def to_json(self) -> dict[str, object]:
        """The ``metrics.json`` object: nothing walked, nothing to judge."""
        out: dict[str, object] = {
            "walked": False,
            "sim_seconds": 0.0,
            "wall_seconds": self.wall_seconds,
            "distance_m": 0.0,
            "fell": False,
            "reached_goal": False,
            "invalid_footholds": 0,
            "touchdowns": 0,
            "frozen": False,
            "frozen_reason": "",
            "robot": self.robot,
            "terrain": self.terrain,
            "seed": self.seed,
        }
        if self.bridge is not None:
            out.update(asdict(self.bridge))
        return out
