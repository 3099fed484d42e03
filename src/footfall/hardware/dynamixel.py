"""A hexapod on Dynamixel servos: the backend that drives a real robot's bus.

It talks to the servos through ROBOTIS' ``dynamixel-sdk`` over a serial adapter (U2D2,
USB2AX), Protocol 1.0 or 2.0 as the robot's ``[hardware]`` table says
(:mod:`footfall.hardware.config`), on :class:`~footfall.hardware.bus.DynamixelBus`. Every
control tick it clamps the joint targets to their limits and sends goal positions with
moving speeds (Protocol 2.0: profile velocities) in one sync write, then reads back on a
schedule that fits the bus. A servo's error bits, a servo that stops answering or answers
garbage, and a port that fails raise :class:`~footfall.errors.BackendError` naming the
servo and the cause.
"""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np
import numpy.typing as npt
from scipy.spatial.transform import Rotation

from footfall.backends import BackendSetup
from footfall.errors import BackendError, ConfigError
from footfall.hardware.bus import DynamixelBus
from footfall.hardware.config import HardwareConfig, hardware_from_options
from footfall.messages import JointTargets, RobotState

# Targets of a joint standing still still get this speed, so a servo never crawls [rad/s].
MIN_SPEED = 0.05
# A goal held away from its joint is reached at a speed that closes the gap in this [s].
CATCH_UP = 0.1

Attitude = Callable[[], tuple[Rotation, npt.NDArray[np.float64]]]


class DynamixelHexapod:
    """The hexapod's 18 joints on a Dynamixel bus.

    Args:
        config: The bus and its servos.
        control_period: The control loop's period, for the read schedule [s].
        attitude: Where the body's attitude and rates come from (an IMU, a pose source);
            level and still when None.
        clock: The robot's clock [s]; the monotonic clock when None.

    Attributes:
        bus: The servos and what they last said.
        clamped: Joint targets moved inside their limits before sending.
    """

    realtime = True

    def __init__(
        self,
        config: HardwareConfig,
        control_period: float = 0.01,
        attitude: Attitude | None = None,
        clock: Callable[[], float] | None = None,
    ) -> None:
        self.config = config
        self.attitude = attitude
        start = time.monotonic()
        self.clock = clock or (lambda: time.monotonic() - start)
        self.control_period = control_period
        self.bus = DynamixelBus(config, control_period)
        self._lower, self._upper = config.lower().ravel(), config.upper().ravel()
        self.torque = any(self.bus.torque_enabled())
        self._last_goal = self.bus.positions.copy()
        self.clamped = 0

    @property
    def fault(self) -> str:
        """Why the bus cannot go on, or ""."""
        return self.bus.fault

    @classmethod
    def open(cls, setup: BackendSetup) -> DynamixelHexapod:
        """The robot's servos, from the ``[hardware]`` table of ``setup.options["robot"]``.

        ``setup.options``: ``robot`` (a built-in name or a TOML file with a ``[hardware]``
        table), ``port`` (overrides the table's), ``protocol`` (when the table names none),
        ``control_period`` [s].

        Raises:
            ConfigError: On a missing port or a malformed table.
            BackendError: When the port does not open or a servo does not answer.
        """
        options = dict(setup.options)
        config = hardware_from_options(setup.spec, options)
        period = float(options.pop("control_period", 0.01))
        if options:
            raise ConfigError(
                f"the dynamixel backend has no option {', '.join(options)}; "
                "it takes robot, port, protocol, control_period"
            )
        if not config.port:
            raise ConfigError("the servo bus has no port: set [hardware] port, or port=PATH")
        return cls(config, period)

    # -- the backend interface --------------------------------------------------------
    def read(self) -> RobotState:
        """The joints as last read, and the attitude source's body attitude."""
        if self.attitude is not None:
            orientation, rates = self.attitude()
        else:
            orientation, rates = Rotation.identity(), np.zeros(3)
        return RobotState(
            time=self.clock(),
            joint_positions=self.bus.positions.reshape(6, 3).copy(),
            joint_velocities=self.bus.velocities.reshape(6, 3).copy(),
            orientation_body_in_world=orientation,
            angular_velocity_body_in_body=rates,
        )

    def command(self, targets: JointTargets) -> None:
        """Send the targets (clamped to the joint limits), then read back this tick's servos.

        Raises:
            BackendError: When a servo reports an error, stops answering or the port fails.
        """
        if self.bus.fault:
            raise BackendError(self.bus.fault)
        if not self.torque:
            return
        goal = np.asarray(targets.positions, dtype=float).ravel()
        clamped = np.clip(goal, self._lower, self._upper)
        self.clamped += int(np.count_nonzero(clamped != goal))
        # Fast enough for the planned rate and this tick's step of the goal, and to close
        # a gap to where the joint was last read in CATCH_UP seconds.
        rates = np.max(
            [
                np.abs(np.asarray(targets.velocities, dtype=float).ravel()),
                np.abs(clamped - self._last_goal) / self.control_period,
                np.abs(clamped - self.bus.positions) / CATCH_UP,
            ],
            axis=0,
        )
        self.bus.send(clamped, np.maximum(rates, MIN_SPEED))
        self._last_goal = clamped
        self.bus.poll()

    def set_torque(self, enabled: bool) -> None:
        """Torque on where the joints are (each goal first set to its position), or off.

        Raises:
            BackendError: When a servo does not take it (a hardware error keeps it off).
        """
        bus = self.bus
        if enabled and not self.torque:
            bus.poll_all()
            bus.send(bus.positions, np.full(len(bus.servos), MIN_SPEED))
            self._last_goal = bus.positions.copy()
        bus.sync_write("torque_enable", [int(enabled)] * len(bus.servos))
        self.torque = bool(enabled)
        # A sync write draws no answer: read every servo's torque back to know it took.
        said = bus.torque_enabled()
        refused = [s.name for s, on in zip(bus.servos, said, strict=True) if on != enabled]
        if refused:
            bus.fault = f"torque {'on' if enabled else 'off'} refused by {', '.join(refused)}"
            raise BackendError(bus.fault)

    def health(self) -> tuple[npt.NDArray[np.float64], ...]:
        """Temperatures [deg C], voltages [V] and loads (fractions of stall), shape (18,)."""
        bus = self.bus
        return bus.temperatures.copy(), bus.voltages.copy(), bus.loads.copy()

    def advance(self, duration: float) -> None:
        """Nothing to compute: the servos move by themselves."""

    def close(self) -> None:
        """Release the port (the servos keep their torque as it is)."""
        self.bus.close()
