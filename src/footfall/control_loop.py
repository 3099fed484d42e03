"""The fixed-rate control loop: the movement and servo nodes driving a robot, and its log.

:func:`run_control_loop` wires a graph on a bus: a command source, the movement node (the
walking controller) and the servo node (inverse kinematics and the backend), and runs it at
a fixed rate. Each tick the command goes out, the movement node publishes effector targets,
the servo node turns them into joint targets for the backend, the backend advances one
period and the servo node publishes the new state. Any
:class:`~footfall.backends.HexapodBackend` works: MuJoCo, the mock, a real robot's driver.
A :class:`WalkRecorder` keeps the per-tick record for metrics and plots.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field, fields

import numpy as np
import numpy.typing as npt

from footfall.backends import HexapodBackend
from footfall.errors import ConfigError
from footfall.messages import (
    EffectorTargets,
    GaitStatus,
    Mode,
    ModeCommand,
    RobotState,
    WalkCommand,
)
from footfall.motion.walker import WalkController
from footfall.nodes.movement import MovementNode
from footfall.nodes.servo import ServoNode
from footfall.runtime.bus import Bus, InProcessBus
from footfall.runtime.cpu_meter import CpuMeter, MeteredBus
from footfall.runtime.scheduler import SimulatedScheduler


@dataclass
class WalkLog:
    """Per-tick record of a walk: each list grows by one entry per control tick.

    :meth:`ring` makes a log that keeps only the latest rows.

    Attributes:
        time: Controller time [s].
        body_position_in_world: True body position, shape (3,) each [m] (NaN if unknown).
        roll: IMU roll [rad].
        pitch: IMU pitch [rad].
        tilt: Angle of the body z axis from vertical [rad].
        feet_in_world: True foot centres, shape (6, 3) each [m] (NaN if unknown).
        feet_commanded_in_world: Commanded foot centres, shape (6, 3) each [m].
        swinging: Which legs swing, shape (6,) each.
        contact: Which feet touch the ground, shape (6,) each (False if unknown).
        foot_orientations_in_world: Foot rotation matrices, shape (6, 3, 3) each (NaN if
            unknown).
        commanded_height: Commanded body height [m].
        reference_body_z: The controller's body height in the world (floor + height) [m].
        state: Gait state name.
    """

    time: list[float] = field(default_factory=list)
    body_position_in_world: list[npt.NDArray[np.float64]] = field(default_factory=list)
    roll: list[float] = field(default_factory=list)
    pitch: list[float] = field(default_factory=list)
    tilt: list[float] = field(default_factory=list)
    feet_in_world: list[npt.NDArray[np.float64]] = field(default_factory=list)
    feet_commanded_in_world: list[npt.NDArray[np.float64]] = field(default_factory=list)
    swinging: list[npt.NDArray[np.bool_]] = field(default_factory=list)
    contact: list[npt.NDArray[np.bool_]] = field(default_factory=list)
    foot_orientations_in_world: list[npt.NDArray[np.float64]] = field(default_factory=list)
    commanded_height: list[float] = field(default_factory=list)
    reference_body_z: list[float] = field(default_factory=list)
    state: list[str] = field(default_factory=list)

    @classmethod
    def ring(cls, max_ticks: int) -> WalkLog:
        """A log that keeps only the latest ``max_ticks`` rows (a long run's bounded memory)."""
        if max_ticks < 1:
            raise ConfigError(f"a walk log keeps at least one tick, got {max_ticks}")
        return cls(**{f.name: deque(maxlen=max_ticks) for f in fields(cls)})

    def array(self, name: str) -> npt.NDArray:
        """One field as a NumPy array with time along the first axis."""
        return np.asarray(getattr(self, name))


class WalkRecorder:
    """Keeps a :class:`WalkLog` from the messages of a walking graph.

    Args:
        bus: The bus.
        max_ticks: Keep only the latest this many rows; None keeps every row.
    """

    def __init__(self, bus: Bus, max_ticks: int | None = None) -> None:
        self.log = WalkLog() if max_ticks is None else WalkLog.ring(max_ticks)
        self._state: RobotState | None = None
        self._targets: EffectorTargets | None = None
        self._status: GaitStatus | None = None
        self._body_height = float("nan")
        bus.subscribe(RobotState.TOPIC, self._on_state)
        bus.subscribe(EffectorTargets.TOPIC, self._on_targets)
        bus.subscribe(GaitStatus.TOPIC, self._on_status)
        bus.subscribe(WalkCommand.TOPIC, self._on_command)

    def _on_state(self, message: RobotState) -> None:
        self._state = message

    def _on_targets(self, message: EffectorTargets) -> None:
        self._targets = message

    def _on_status(self, message: GaitStatus) -> None:
        self._status = message

    def _on_command(self, message: WalkCommand) -> None:
        self._body_height = message.body_height

    def record(self, t: float) -> bool:
        """Add a row at time ``t`` [s] when new effector targets went out; True if it did."""
        state, targets, status = self._state, self._targets, self._status
        if state is None or targets is None or status is None:
            return False
        self._targets = None
        log = self.log
        roll, pitch = state.roll_pitch
        log.time.append(t)
        log.body_position_in_world.append(
            state.position_body_in_world
            if state.position_body_in_world is not None
            else np.full(3, np.nan)
        )
        log.roll.append(roll)
        log.pitch.append(pitch)
        log.tilt.append(state.tilt)
        log.feet_in_world.append(
            state.feet_in_world if state.feet_in_world is not None else np.full((6, 3), np.nan)
        )
        log.feet_commanded_in_world.append(targets.feet_in_world)
        log.swinging.append(targets.swinging)
        log.contact.append(
            state.feet_in_contact if state.feet_in_contact is not None else np.zeros(6, dtype=bool)
        )
        log.foot_orientations_in_world.append(
            state.foot_orientations_in_world
            if state.foot_orientations_in_world is not None
            else np.full((6, 3, 3), np.nan)
        )
        log.commanded_height.append(self._body_height)
        log.reference_body_z.append(status.body_z)
        log.state.append(status.state.value)
        return True


@dataclass
class WalkingGraph:
    """The nodes that walk a robot, on one bus.

    Attributes:
        bus: The bus.
        backend: The robot.
        movement: The movement node.
        servo: The servo node.
        recorder: The per-tick record.
    """

    bus: Bus
    backend: HexapodBackend
    movement: MovementNode
    servo: ServoNode
    recorder: WalkRecorder
    meter: CpuMeter = field(default_factory=CpuMeter)

    @classmethod
    def build(
        cls,
        bus: Bus,
        backend: HexapodBackend,
        controller: WalkController,
        command_timeout: float | None = None,
        log_ticks: int | None = None,
        meter: CpuMeter | None = None,
    ) -> WalkingGraph:
        """Wire the movement and servo nodes and a recorder on ``bus``.

        The recorder keeps the latest ``log_ticks`` rows, or every row when None; each
        node's work is charged to it on ``meter`` (the backend's physics to ``sim_physics``,
        the recorder to ``sim_record``).
        """
        meter = meter if meter is not None else CpuMeter()
        recorder = WalkRecorder(MeteredBus(bus, meter, "sim_record"), log_ticks)
        movement = MovementNode(
            MeteredBus(bus, meter, "movement"), controller, command_timeout=command_timeout
        )
        servo = ServoNode(
            MeteredBus(bus, meter, "servo"),
            controller.spec,
            backend,
            stand_height=controller.height,
        )
        servo.publish_state()
        return cls(bus, backend, movement, servo, recorder, meter)

    def step(self, t: float, dt: float) -> None:
        """One control tick at ``t``, then the robot advances ``dt`` [s] and reports."""
        measure = self.meter.measure
        with measure("movement"):
            self.movement.tick(t)
        with measure("servo"):
            self.servo.tick(t, dt)
        with measure("sim_physics"):
            self.backend.advance(dt)
        with measure("servo"):
            self.servo.publish_state()
        with measure("sim_record"):
            self.recorder.record(t + dt)


def run_control_loop(
    backend: HexapodBackend,
    controller: WalkController,
    command: WalkCommand | Callable[[float], WalkCommand],
    seconds: float,
    control_rate_hz: float = 100.0,
    on_tick: Callable[[float], None] | None = None,
    stop: Callable[[WalkLog], bool] | None = None,
    bus: Bus | None = None,
) -> WalkLog:
    """Drive ``backend`` with ``controller`` for ``seconds`` at a fixed rate, in walking mode.

    Args:
        backend: The robot (simulated, mocked or real).
        controller: The walking controller.
        command: A fixed command, or a function of controller time returning one; published
            on the bus every tick.
        seconds: Duration [s].
        control_rate_hz: Control rate [Hz].
        on_tick: Called with the controller time after every tick (sensing, progress).
        stop: Ends the loop early when it returns True for the log so far.
        bus: The bus to wire the nodes on; a new in-process bus by default.

    Returns:
        The record of the run.
    """
    bus = bus if bus is not None else InProcessBus()
    graph = WalkingGraph.build(bus, backend, controller)
    bus.publish(ModeCommand.TOPIC, ModeCommand(Mode.WALKING))
    scheduler = SimulatedScheduler(control_rate_hz)
    dt = scheduler.period

    def tick(t: float) -> bool:
        current = command(t) if callable(command) else command
        bus.publish(WalkCommand.TOPIC, current)
        graph.step(t, dt)
        if on_tick is not None:
            on_tick(t + dt)
        return stop is not None and stop(graph.recorder.log)

    scheduler.run(tick, seconds)
    return graph.recorder.log
