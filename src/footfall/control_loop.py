"""The fixed-rate control loop: read the robot, update the controller, send joint targets.

It runs against any :class:`~footfall.backend.HexapodBackend`, so the same loop drives
the MuJoCo simulation and a real robot's servo driver; it records what happened in a
:class:`WalkLog` for metrics and plots.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from footfall.backend import HexapodBackend
from footfall.motion.gait import WalkCommand
from footfall.motion.walker import WalkController


@dataclass
class WalkLog:
    """Per-tick record of a walk. Each list grows by one entry per control tick.

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

    def array(self, name: str) -> npt.NDArray:
        """One field as a NumPy array with time along the first axis."""
        return np.asarray(getattr(self, name))


def run_control_loop(
    backend: HexapodBackend,
    controller: WalkController,
    command: WalkCommand | Callable[[float], WalkCommand],
    seconds: float,
    control_rate_hz: float = 100.0,
    on_tick: Callable[[float], None] | None = None,
    stop: Callable[[WalkLog], bool] | None = None,
) -> WalkLog:
    """Drive ``backend`` with ``controller`` for ``seconds`` at a fixed rate.

    Args:
        backend: The robot (simulated or real).
        controller: The walking controller.
        command: A fixed command, or a function of controller time returning one.
        seconds: Duration [s].
        control_rate_hz: Control rate [Hz].
        on_tick: Called with the controller time after every tick (sensing, progress).
        stop: Ends the loop early when it returns True for the log so far.

    Returns:
        The record of the run.
    """
    dt = 1.0 / control_rate_hz
    log = WalkLog()
    unknown3 = np.full(3, np.nan)
    state = backend.read()
    for k in range(round(seconds * control_rate_hz)):
        t = k * dt
        current = command(t) if callable(command) else command
        targets = controller.update(t, current, state)
        backend.command(targets)
        backend.advance(dt)
        state = backend.read()
        roll, pitch = state.roll_pitch
        log.time.append(t + dt)
        log.body_position_in_world.append(
            state.position_body_in_world if state.position_body_in_world is not None else unknown3
        )
        log.roll.append(roll)
        log.pitch.append(pitch)
        log.tilt.append(state.tilt)
        log.feet_in_world.append(
            state.feet_in_world if state.feet_in_world is not None else np.full((6, 3), np.nan)
        )
        log.feet_commanded_in_world.append(controller.feet_commanded_in_world)
        log.swinging.append(controller.swinging.copy())
        log.contact.append(
            state.feet_in_contact if state.feet_in_contact is not None else np.zeros(6, dtype=bool)
        )
        log.foot_orientations_in_world.append(
            state.foot_orientations_in_world
            if state.foot_orientations_in_world is not None
            else np.full((6, 3, 3), np.nan)
        )
        log.commanded_height.append(current.body_height)
        log.reference_body_z.append(controller.height)
        log.state.append(controller.state.value)
        if on_tick is not None:
            on_tick(t + dt)
        if stop is not None and stop(log):
            break
    return log
