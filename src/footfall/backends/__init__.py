"""The interface between footfall and a robot: simulated, mocked or real.

A backend reads the robot's state (joint encoders, IMU attitude) and takes joint targets.
The MuJoCo simulation (:mod:`footfall.sim.hexapod`) is one implementation, the mock of
:mod:`footfall.backends.mock` another, Dynamixel servos (:mod:`footfall.hardware.dynamixel`)
a third; a driver for another robot's servo bus implements the same four methods and a
constructor, :meth:`HexapodBackend.open`, and joins
:data:`footfall.backends.registry.BACKENDS` with one line (``docs/extending.md``).

The contract every backend keeps:

- **Units and frames.** Joint angles [rad] and rates [rad/s], shape (6, 3), legs in the
  spec's order (counter-clockwise from the front left), joints coxa, femur, tibia, with
  the angle conventions of ``docs/frames.md``; the IMU attitude rotates body-frame vectors
  into the world (z up); the gyro in the body frame [rad/s]. What the robot cannot know
  (its position in the world, where its feet are, which touch the ground) is None.
- **Timing.** ``read`` returns the newest state without waiting; ``command`` queues the
  targets and returns at once. ``advance(duration)`` lets ``duration`` seconds pass: a
  simulator computes them (``realtime`` False, and a wall-clock scheduler paces the loop);
  hardware waits for them, or returns at once when its own clock runs (``realtime`` True).
  ``RobotState.time`` is the backend's clock [s].
- **Torque.** A backend starts with the torque on; the servo node switches it off at once
  (the robot starts limp) and on when the mode is walking, then stands the robot up from
  where its joints are; before switching it off again it sits the robot down. Torque on
  must not move a joint (a servo's goal is set to where it is first). With the torque
  off, targets are dropped, not queued.
- **Optional.** ``close()`` releases a port or device at the end of a run;
  ``health()`` returns the servos' temperatures [deg C], voltages [V] and loads
  (fractions of stall torque), shape (18,) each, for the servo status.
- **Faults.** When the robot cannot go on (a servo that stops answering, overheats or is
  overloaded), ``command`` raises :class:`~footfall.errors.BackendError` naming the servo
  and the cause. The servo node then logs it and sends no more targets: the servos hold
  their last goal, the robot stands where it is (``ServoNode.fault`` says why), and the
  walk resumes only in a new run.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Protocol

if TYPE_CHECKING:  # the robot's parser lists the backends without loading the messages
    from footfall.messages import JointTargets, RobotState
    from footfall.robot.spec import HexapodSpec


@dataclass(frozen=True)
class BackendSetup:
    """What a backend is opened with.

    Attributes:
        spec: The robot.
        body_height: Body height the robot stands at [m].
        world: What a simulator puts the robot in (a :class:`~footfall.sim.terrain.Terrain`);
            a real robot ignores it.
        camera: The depth camera a simulator renders (a
            :class:`~footfall.sim.model.CameraMount`), or None for none.
        options: Backend-specific settings from ``footfall robot --backend-option
            KEY=VALUE`` (a serial port, a baud rate).
    """

    spec: HexapodSpec
    body_height: float
    world: object = None
    camera: object = None
    options: dict[str, str] = field(default_factory=dict)


class HexapodBackend(Protocol):
    """What the servo node and the control loop need from a robot.

    Attributes:
        realtime: True when ``advance`` is a real wait (hardware: time passes by itself);
            False when it computes the next state (a simulator or a mock), which a
            wall-clock scheduler then paces.
    """

    realtime: bool

    def read(self) -> RobotState:
        """The latest state."""
        ...

    def command(self, targets: JointTargets) -> None:
        """Send joint position and rate targets to the servos."""
        ...

    def set_torque(self, enabled: bool) -> None:
        """Switch the servos' torque on (they hold their targets) or off (limp)."""
        ...

    def advance(self, duration: float) -> None:
        """Let ``duration`` seconds pass (a simulator steps; a real robot waits)."""
        ...


class BackendFactory(Protocol):
    """A registered backend: a class (or any callable) with ``open``."""

    def open(self, setup: BackendSetup) -> HexapodBackend:
        """The backend, connected and standing at ``setup.body_height``."""
        ...
