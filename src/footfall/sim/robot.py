"""The simulated robot as a robot: its nodes on the network, driven by whoever connects.

``footfall robot`` runs the hexapod's own nodes (camera, pose, mapping, movement, servo on
the MuJoCo backend) paced to the wall clock, as the on-board computer would, and bridges
them to the network bus: its images, map, pose, state, status and log go out; commands
and the mode come in. It starts in torque-off and walks only while a station (or any
client) keeps commanding it: the movement node's watchdog stands it still when the
commands stop. The run ends when asked to, at the goal (``stop_at_goal``) or after a fall,
and its record is judged against the terrain's truth like a simulated walk.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from footfall.messages import JointTargets, Mode, ModeCommand, Posture, WalkCommand
from footfall.nodes.movement import COMMAND_TIMEOUT_S
from footfall.robot.spec import HexapodSpec
from footfall.runtime.bridge import Bridge
from footfall.runtime.bus import Bus, InProcessBus
from footfall.runtime.scheduler import WallClockScheduler
from footfall.sim.assembly import WalkingRobot
from footfall.sim.task import TerrainTask
from footfall.sim.terrains import make_terrain
from footfall.sim.walk_metrics import BridgeTraffic
from footfall.sim.walk_settings import WalkResult, WalkSettings

# What the robot sends out, and at most how often [Hz] (None: every message). The map
# goes at half the camera's 15 Hz: a station draws it at 5 Hz.
OUTGOING: dict[str, float | None] = {
    "depth": None,
    "color": 5.0,
    "pose": None,
    "map": 7.5,
    "status": 20.0,
    "state": 20.0,
    "log": None,
    "effector_targets": 20.0,
    "joint_targets": 20.0,
    "touchdown": None,
    "servo": None,
}
INCOMING = ("command", "mode")
# Stamps past this are wall-clock times (2001 onwards), not simulated seconds [s].
WALL_CLOCK_EPOCH_S = 1e9
# Asked to stop, the robot sits down for at most this long before the run ends [s].
SIT_DOWN_SECONDS = 5.0


@dataclass(frozen=True)
class RobotSettings:
    """How the simulated robot runs.

    Attributes:
        walk: The simulation (terrain, camera, gait, seed; its command's body height and
            speed are the robot's nominal ones).
        seconds: Longest run [s] (wall clock).
        stop_at_goal: End the run at the terrain's goal.
        command_timeout: The watchdog's limit [s].
        outgoing: Topics sent to the network with their largest rates [Hz].
    """

    walk: WalkSettings = field(default_factory=WalkSettings)
    seconds: float = 600.0
    stop_at_goal: bool = False
    command_timeout: float = COMMAND_TIMEOUT_S
    outgoing: dict[str, float | None] = field(default_factory=lambda: dict(OUTGOING))


def run_robot(
    spec: HexapodSpec,
    settings: RobotSettings,
    network: Bus,
    on_tick: Callable[[float], None] | None = None,
    should_stop: Callable[[], bool] | None = None,
    local: InProcessBus | None = None,
    on_build: Callable[[WalkingRobot], None] | None = None,
) -> tuple[WalkResult, Bridge]:
    """Run the simulated robot on the network until done.

    Args:
        spec: The robot.
        settings: How to run.
        network: The network bus (a ZenohBus) the robot is bridged to.
        on_tick: Called with the run time [s] after each tick.
        should_stop: Ends the run when it returns True (a signal handler's flag).
        local: The robot's own bus (a recorder may tap it: what comes in from the network
            is published on it too); a new one by default.
        on_build: Called with the robot once its nodes stand.

    Returns:
        The record and metrics, and the bridge (its traffic counts).
    """
    walk = settings.walk
    terrain = make_terrain(walk.terrain, seed=walk.seed)
    local = local if local is not None else InProcessBus()
    robot = WalkingRobot.build(
        spec,
        walk,
        terrain,
        local,
        command_timeout=settings.command_timeout,
        color=True,
        color_hz=settings.outgoing.get("color"),  # rendered no more often than sent
        perception_thread=True,  # a frame's render and fusion never hold up a command
    )
    if on_build is not None:
        on_build(robot)
    judge = TerrainTask(local, terrain, walk.command, settings.stop_at_goal, frozen_timeout=None)
    bridge = Bridge(local, network, settings.outgoing, INCOMING)
    if hasattr(network, "malformed"):  # malformed messages from the network count too
        robot.graph.movement.transport_dropped = lambda: sum(network.malformed.values())
    scheduler = WallClockScheduler(walk.control_rate_hz)
    dt = scheduler.period
    latency = CommandLatency(local)

    asked_to_stop: list[float] = []

    def tick(t: float) -> bool:
        if asked_to_stop:
            # Sitting down: nothing more comes in from the network.
            robot.step(t, dt)
            servo = robot.graph.servo
            seated = servo.posture in (Posture.LIMP, Posture.HALTED)
            return seated or t - asked_to_stop[0] > SIT_DOWN_SECONDS
        bridge.spin()
        robot.step(t, dt)
        latency.acted_on()
        if on_tick is not None:
            on_tick(t + dt)
        if should_stop is not None and should_stop():
            # Ctrl-C: the robot sits down before the run ends, whatever the station sends.
            asked_to_stop.append(t)
            local.publish(ModeCommand.TOPIC, ModeCommand(Mode.TORQUE_OFF, math.inf))
            return robot.graph.servo.posture in (Posture.LIMP, Posture.HALTED)
        return judge.should_stop(t + dt)

    wall_start = time.perf_counter()
    try:
        scheduler.run(tick, settings.seconds)
    finally:
        robot.close()
    result = robot.result(judge, time.perf_counter() - wall_start, scheduler)
    sender = getattr(network, "link_sender", None)
    result.metrics.bridge = BridgeTraffic(
        dict(bridge.forwarded),
        dict(bridge.received),
        link=sender.counts.to_json() if sender is not None else None,
        command_latency_ms=latency.summary(),
    )
    return result, bridge


class CommandLatency:
    """How long a station's commands take to reach the joints.

    A command stamped with the station's wall clock counts from that stamp to the first
    joint targets of the tick that delivered it, the first computed with it (a limp robot
    sends none: its commands are not counted). The two clocks agree on one machine, or
    with NTP across two.
    """

    def __init__(self, local: InProcessBus) -> None:
        self._arrived: list[float] = []
        self._targets_at: float | None = None
        self.latencies_s: list[float] = []
        local.subscribe(WalkCommand.TOPIC, self._arrive)
        local.subscribe(JointTargets.TOPIC, self._targets)

    def _arrive(self, command: WalkCommand) -> None:
        if command.stamp > WALL_CLOCK_EPOCH_S:  # a wall-clock stamp, not simulated time
            self._arrived.append(command.stamp)

    def _targets(self, _targets: JointTargets) -> None:
        if self._arrived and self._targets_at is None:
            self._targets_at = time.time()

    def acted_on(self) -> None:
        """The tick ended: its commands reached the joints, or none went out (limp)."""
        if self._targets_at is not None:
            self.latencies_s += [self._targets_at - stamp for stamp in self._arrived]
        self._arrived.clear()
        self._targets_at = None

    def summary(self) -> dict[str, float] | None:
        """Median, 95th percentile and largest latency [ms], and how many commands."""
        if not self.latencies_s:
            return None
        ms = np.asarray(self.latencies_s) * 1000.0
        return {
            "median": float(np.median(ms)),
            "p95": float(np.percentile(ms, 95)),
            "max": float(ms.max()),
            "count": len(ms),
        }
