"""Standing up and sitting down: joint targets from where the legs are, at bounded rates.

A robot switched on lies where its torque-off left it; a robot switched off should not
drop. :class:`PostureMove` takes the legs from their measured (or last commanded) joint
angles through waypoints of foot positions in the body frame, never moving a joint faster
than the servos' rate limit nor a foot faster than ``FOOT_SPEED``:

- **stand up**: the joints move together to the feet's rest positions at the sitting
  height (the belly still on the ground), then the feet press straight down and the body
  rises to the standing height;
- **sit down**: the feet rise straight up in the body frame, the body lowers onto its
  belly; then the torque can go off.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from footfall.errors import UnreachableTargetError
from footfall.messages import JointTargets
from footfall.robot.kinematics import LegKinematics
from footfall.robot.spec import HexapodSpec

FOOT_SPEED = 0.15  # fastest a foot moves while standing up or sitting down [m/s]
RISE_SPEED = 0.05  # the body's vertical speed while rising or lowering [m/s]
STANDING_TOLERANCE = 0.01  # feet this near their standing stance already stand [m]
BELLY_CLEARANCE = 0.005  # the sitting body's bottom above the ground [m]


def sitting_height(spec: HexapodSpec) -> float:
    """Body frame height when the belly rests on the ground [m]."""
    return spec.body_size[2] / 2.0 + BELLY_CLEARANCE


def stance_in_body(spec: HexapodSpec, height: float) -> npt.NDArray[np.float64]:
    """Foot centres at rest with the body at ``height`` above the ground, shape (6, 3) [m]."""
    feet = spec.rest_feet_in_body(height)
    feet[:, 2] += spec.foot_radius
    return feet


class PostureMove:
    """Joint targets along a path of foot waypoints, at bounded joint rates and foot speeds.

    Args:
        spec: The robot.
        start: Joint angles the move starts from, shape (6, 3) [rad].
        waypoints: Foot centres in the body frame to pass through, each shape (6, 3) [m].
            The first is reached by moving the joints together (the legs may start
            anywhere); the rest by moving the feet along straight lines.
        speed: The feet's speed along the straight lines [m/s].

    Raises:
        UnreachableTargetError: When a waypoint is out of a leg's reach.
    """

    def __init__(
        self,
        spec: HexapodSpec,
        start: npt.ArrayLike,
        waypoints: list[npt.NDArray[np.float64]],
        speed: float = RISE_SPEED,
    ) -> None:
        self.kinematics = LegKinematics(spec)
        self.max_rate = spec.servo.max_rate
        self.speed = min(speed, FOOT_SPEED)
        self.joints = np.asarray(start, dtype=float).reshape(6, 3).copy()
        self._first = self.kinematics.inverse_in_body(waypoints[0])
        self._lines = list(waypoints[1:])
        self.feet = self.kinematics.forward_in_body(self.joints)

    @property
    def done(self) -> bool:
        """Whether the last waypoint is reached."""
        return self._first is None and not self._lines

    def step(self, dt: float, stamp: float = 0.0) -> JointTargets:
        """The next joint targets, ``dt`` seconds on [s]."""
        before = self.joints.copy()
        if self._first is not None:
            self._joint_step(dt)
        elif self._lines:
            self._line_step(dt)
        rates = (self.joints - before) / dt if dt > 0 else np.zeros((6, 3))
        return JointTargets(self.joints.copy(), rates, stamp)

    def _joint_step(self, dt: float) -> None:
        """All joints toward the first waypoint together, the largest at the rate limit.

        The step is shortened until no foot moves faster than ``FOOT_SPEED``.
        """
        assert self._first is not None
        gap = self._first - self.joints
        largest = float(np.abs(gap).max())
        fraction = 1.0 if largest == 0 else min(1.0, self.max_rate * dt / largest)
        for _ in range(20):
            candidate = self.joints + fraction * gap
            feet = self.kinematics.forward_in_body(candidate)
            moved = float(np.linalg.norm(feet - self.feet, axis=1).max())
            if moved <= FOOT_SPEED * dt or fraction < 1e-6:
                break
            fraction *= 0.9 * FOOT_SPEED * dt / moved
        self.joints, self.feet = candidate, feet
        if fraction >= 1.0:
            self._first = None

    def _line_step(self, dt: float) -> None:
        """The feet along straight lines to the next waypoint, at ``speed``."""
        target = self._lines[0]
        gap = target - self.feet
        largest = float(np.linalg.norm(gap, axis=1).max())
        fraction = 1.0 if largest == 0 else min(1.0, self.speed * dt / largest)
        feet = self.feet + fraction * gap
        try:
            joints = self.kinematics.inverse_in_body(feet)
        except UnreachableTargetError:
            self._lines.clear()  # hold where the legs are: the next waypoint is out of reach
            return
        largest_rate = float(np.abs(joints - self.joints).max()) / dt if dt > 0 else 0.0
        if largest_rate > self.max_rate:  # near a singular pose: slow down
            fraction *= self.max_rate / largest_rate
            feet = self.feet + fraction * gap
            joints = self.kinematics.inverse_in_body(feet)
        self.joints, self.feet = joints, feet
        if fraction >= 1.0:
            self._lines.pop(0)


def stand_up(spec: HexapodSpec, joints: npt.ArrayLike, height: float) -> PostureMove | None:
    """The move from the joint angles ``joints`` to standing at ``height`` [m].

    None when the feet already stand there (within ``STANDING_TOLERANCE``).
    """
    kinematics = LegKinematics(spec)
    feet = kinematics.forward_in_body(np.asarray(joints, dtype=float).reshape(6, 3))
    standing = stance_in_body(spec, height)
    if float(np.linalg.norm(feet - standing, axis=1).max()) <= STANDING_TOLERANCE:
        return None
    low = min(sitting_height(spec), height)
    # The feet go to their rest places at the height they are at (no lower than standing,
    # no higher than sitting), then press down.
    start_z = np.clip(feet[:, 2], standing[:, 2], stance_in_body(spec, low)[:, 2])
    under = standing.copy()
    under[:, 2] = start_z
    return PostureMove(spec, joints, [under, standing])


def sit_down(spec: HexapodSpec, joints: npt.ArrayLike) -> PostureMove:
    """The move from the joint angles ``joints`` down onto the belly, feet kept in place."""
    kinematics = LegKinematics(spec)
    start = np.asarray(joints, dtype=float).reshape(6, 3)
    feet = kinematics.forward_in_body(start)
    seated = feet.copy()
    seated[:, 2] = stance_in_body(spec, sitting_height(spec))[:, 2]
    return PostureMove(spec, start, [feet, seated])
