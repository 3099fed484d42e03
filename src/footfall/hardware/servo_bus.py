"""The simulated hexapod behind an emulated Dynamixel bus (``footfall walk --servo-bus``).

Every joint command and reading goes through the Dynamixel backend
(:mod:`footfall.hardware.dynamixel`), ``dynamixel-sdk`` and a pseudo-terminal to emulated
servos (:mod:`footfall.hardware.emulator`) that turn the MuJoCo robot's joints; the IMU
and the simulator's ground truth come from the simulator directly, as a real robot's IMU
is not on its servo bus. The walk is the usual simulated one, so a robot's ``[hardware]``
table, its servo ids, directions, zeros and limits, can be dry-run before the robot is
powered.

Faults for the bus (``--backend-option fault=KIND:ID@SECONDS``): ``silent`` (the servo
stops answering), ``overheat`` (its error bit, and its torque off), ``checksum`` (its status
packets arrive corrupted), ``port`` (the adapter hangs up; ID ignored).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np

from footfall.backends import BackendSetup
from footfall.errors import ConfigError
from footfall.hardware.config import HardwareConfig, hardware_from_options
from footfall.hardware.dynamixel import DynamixelHexapod
from footfall.hardware.emulated_servos import EmulatedServos
from footfall.hardware.emulator import EmulatedBus, WireCounts
from footfall.messages import JointTargets, RobotState
from footfall.sim.hexapod import MujocoHexapod
from footfall.sim.walk_metrics import ServoBusMetrics

FAULTS = ("silent", "overheat", "checksum", "port")


@dataclasses.dataclass(frozen=True)
class BusFault:
    """A fault the emulated bus injects.

    Attributes:
        kind: One of :data:`FAULTS`.
        servo_id: The servo it strikes.
        time: When [s], simulated time.
    """

    kind: str
    servo_id: int
    time: float

    @classmethod
    def parse(cls, text: str) -> BusFault:
        """``KIND:ID@SECONDS``, e.g. ``overheat:5@3.0``.

        Raises:
            ConfigError: On another form or an unknown kind.
        """
        kind, _, rest = text.partition(":")
        servo, _, when = rest.partition("@")
        if kind not in FAULTS or not when:
            raise ConfigError(
                f"servo bus fault {text!r}: use KIND:ID@SECONDS, KIND one of {', '.join(FAULTS)}"
            )
        try:
            return cls(kind, int(servo or 0), float(when))
        except ValueError as exc:
            raise ConfigError(f"servo bus fault {text!r}: {exc}") from exc


def step_with_servos(
    simulator: MujocoHexapod,
    servos: EmulatedServos,
    duration: float,
    before_step: Callable[[float], None] | None = None,
) -> None:
    """Step the physics for ``duration`` [s], the emulated servos driving each step.

    ``before_step`` is called with the simulated time before each physics step.
    """
    dt = simulator.timestep
    for _ in range(max(1, round(duration / dt))):
        if before_step is not None:
            before_step(float(simulator.data.time))
        setpoints, rates = servos.drive(dt)
        simulator.drive(setpoints, rates, servos.torque)
        simulator.advance(dt)
        servos.sense(*simulator.joints())


class ServoBusHexapod:
    """The MuJoCo hexapod, its joints behind an emulated Dynamixel bus.

    Args:
        simulator: The simulated robot (standing, torque on).
        config: The bus and its servos (the port is the emulator's).
        control_period: The control loop's period [s].
        faults: Faults to inject.
        pace: Let the emulated servos answer at the byte clock's pace.
    """

    realtime = False

    def __init__(
        self,
        simulator: MujocoHexapod,
        config: HardwareConfig,
        control_period: float = 0.01,
        faults: tuple[BusFault, ...] = (),
        pace: bool = True,
    ) -> None:
        self.simulator = simulator
        self.servos = EmulatedServos(config)
        positions, _, _ = simulator.joints()
        self.servos.start(positions, torque=True)
        self.bus = EmulatedBus(self.servos, pace=pace)
        self.control_period = control_period
        self.faults = sorted(faults, key=lambda f: f.time)
        self._ticks: list[WireCounts] = []
        self._last = self.bus.counts.copy()
        try:
            self.dynamixel = DynamixelHexapod(
                dataclasses.replace(config, port=self.bus.port),
                control_period,
                attitude=self._imu,
                clock=lambda: float(simulator.data.time),
            )
        except Exception:
            self.bus.close()
            raise
        self._last = self.bus.counts.copy()

    @classmethod
    def open(cls, setup: BackendSetup) -> ServoBusHexapod:
        """The simulated robot on ``setup.world``, its servos on an emulated bus.

        ``setup.options``: ``protocol`` (1 or 2, when the robot's ``[hardware]`` table says
        none), ``robot`` (a built-in name or TOML file whose ``[hardware]`` table to use),
        ``fault`` (``KIND:ID@SECONDS``, comma-separated for several), ``control_period``
        [s].
        """
        options = dict(setup.options)
        config = hardware_from_options(setup.spec, options)  # its port: the emulator's
        faults = tuple(BusFault.parse(f) for f in options.pop("fault", "").split(",") if f)
        period = float(options.pop("control_period", 0.01))
        if options:
            raise ConfigError(
                f"the servo-bus backend has no option {', '.join(options)}; "
                "it takes protocol, robot, fault, control_period"
            )
        known = {s.servo_id for s in config.servos}
        for fault in faults:
            if fault.kind != "port" and fault.servo_id not in known:
                raise ConfigError(f"servo bus fault on servo {fault.servo_id}: no such servo")
        return cls(MujocoHexapod.open(setup), config, period, faults)

    def _imu(self):
        state = self.simulator.read()
        return state.orientation_body_in_world, state.angular_velocity_body_in_body

    def read(self) -> RobotState:
        """Joints as the bus last read them; the IMU and the ground truth from the simulator."""
        truth = self.simulator.read()
        joints = self.dynamixel.read()
        return dataclasses.replace(
            truth,
            time=joints.time,
            joint_positions=joints.joint_positions,
            joint_velocities=joints.joint_velocities,
        )

    def command(self, targets: JointTargets) -> None:
        """Joint targets over the bus (see :meth:`DynamixelHexapod.command`)."""
        try:
            self.dynamixel.command(targets)
        finally:
            counts = self.bus.counts.copy()
            self._ticks.append(counts - self._last)
            self._last = counts

    def set_torque(self, enabled: bool) -> None:
        """Torque over the bus."""
        self.dynamixel.set_torque(enabled)

    def health(self):
        """The servos' temperatures, voltages and loads, as the bus last read them."""
        return self.dynamixel.health()

    def advance(self, duration: float) -> None:
        """Step the physics, the emulated servos driving the joints at each step."""
        step_with_servos(self.simulator, self.servos, duration, self._inject)

    def _inject(self, now: float) -> None:
        while self.faults and self.faults[0].time <= now:
            fault = self.faults.pop(0)
            if fault.kind == "silent":
                self.bus.silence(fault.servo_id)
            elif fault.kind == "overheat":
                self.servos.overheat(fault.servo_id)
            elif fault.kind == "checksum":
                self.bus.corrupt(fault.servo_id)
            else:
                self.bus.close_port()

    @property
    def camera_mount(self):
        """The simulator's camera mount (the simulated camera renders through it)."""
        return self.simulator.camera_mount

    def warnings(self) -> dict[str, int]:
        """The simulator's warnings."""
        return self.simulator.warnings()

    def bus_metrics(self) -> ServoBusMetrics:
        """What the bus carried per control tick, by the emulator's byte clock."""
        ticks = self._ticks or [WireCounts()]
        period = self.control_period
        write_bytes = np.array([t.write_bytes for t in ticks], dtype=float)
        read_bytes = np.array([t.read_bytes for t in ticks], dtype=float)
        seconds = np.array([t.write_seconds + t.read_seconds for t in ticks])
        config = self.servos.config
        return ServoBusMetrics(
            protocol=config.protocol,
            baud=config.baud,
            servos=len(config.servos),
            ticks=len(self._ticks),
            packets=self.bus.counts.packets,
            errors=self.bus.counts.errors,
            bytes_per_tick=float(np.mean(write_bytes + read_bytes)),
            write_bytes_per_tick=float(np.mean(write_bytes)),
            read_bytes_per_tick=float(np.mean(read_bytes)),
            write_ms_per_tick=1e3 * float(np.mean([t.write_seconds for t in ticks])),
            read_ms_per_tick=1e3 * float(np.mean([t.read_seconds for t in ticks])),
            utilisation=float(np.mean(seconds)) / period,
            utilisation_max=float(np.max(seconds)) / period,
            reads_per_tick=self.dynamixel.bus.schedule.reads,
            joint_targets_clamped=self.dynamixel.clamped,
            joint_targets_over_speed=self.dynamixel.bus.over_speed,
            fault=self.dynamixel.fault,
        )

    def close(self) -> None:
        """Release the port and the emulator."""
        self.dynamixel.close()
        self.bus.close()
