"""The leg solver: reference foot positions to the foot targets the servos are sent.

It applies the body feedback (the body raised by the height correction, tilted by the
attitude correction), brings swinging feet that left their leg's workspace back in, keeps
each stance foot's contact point still as its round foot rolls, and gives the feet's
body-frame rates. A supporting foot out of reach raises
:class:`~footfall.errors.UnreachableTargetError`: the controller then freezes.

A supporting foot right under its hip is the exception. There the coxa's angle is that of a
vector of almost no length: a millimetre of the body's feedback swings it by tens of
degrees, past its range, though the coxa's angle hardly moves the foot. Such a foot is
turned about the coxa axis into the range when that moves it by at most
``NEAR_AXIS_SLIP_M``, instead of freezing the robot for a slip it would not feel.

A round foot rolls as its tibia tilts during stance: holding the sphere's centre still
would make it slide by ``r * dpsi`` (``psi`` the tibia's pitch). So the solver keeps the
*contact point* still instead, moving the commanded centre by the rolling displacement
``-r * (psi - psi_touchdown)`` along the leg's horizontal direction.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from scipy.spatial.transform import Rotation

from footfall.motion.feedback import BodyFeedback
from footfall.robot.kinematics import LegKinematics
from footfall.robot.planar import PlanarPose, inclined_to_level, level_to_inclined

# A foot drawn in stops this far inside the stretched leg [m].
_DRAWN_IN_SLACK = 1e-4
# A swinging foot out of reach is lowered in steps of this until the leg reaches it [m].
_LOWERING_STEP = 0.005
# A supporting foot beyond its coxa's range is turned into it if that moves it this little [m].
NEAR_AXIS_SLIP_M = 0.003


@dataclass(frozen=True)
class FootTargets:
    """What the controller asks of the legs at one tick.

    Attributes:
        feet_in_body: Foot-sphere centres in the body frame, shape (6, 3) [m].
        velocities_in_body: Their rates in the body frame, shape (6, 3) [m/s].
    """

    feet_in_body: npt.NDArray[np.float64]
    velocities_in_body: npt.NDArray[np.float64]


class LegSolver:
    """Foot targets with feedback, reach limits and rolling.

    Args:
        kinematics: The legs' kinematics.
        foot_radius: Radius of the round feet [m].

    Attributes:
        rolling_in_world: Rolling displacement of each stance foot, shape (6, 3) [m].
    """

    def __init__(self, kinematics: LegKinematics, foot_radius: float) -> None:
        self.kinematics = kinematics
        self.foot_radius = foot_radius
        # How far a swinging foot out of reach may be lowered: up to the leg's length, for
        # a foot lifted over an obstacle as it passes close to the body may be above what
        # the leg reaches however short its step height.
        self._drops = np.arange(0.0, kinematics.L2 + kinematics.L3, _LOWERING_STEP)
        self.rolling_in_world = np.zeros((6, 3))
        self._tibia_pitch_at_touchdown = np.full(6, np.nan)  # psi when the foot came down

    def touched_down(self, leg: int) -> None:
        """A foot came down: its rolling is measured from its next stance tick."""
        self._tibia_pitch_at_touchdown[leg] = np.nan

    def lifted(self, leg: int) -> None:
        """A foot lifted off: it no longer rolls."""
        self.rolling_in_world[leg] = 0.0

    def rotate(self, rotation: npt.NDArray[np.float64]) -> None:
        """Turn the rolling displacements with the world (pose re-registration)."""
        self.rolling_in_world[:, :2] = self.rolling_in_world[:, :2] @ rotation.T

    def within_reach(
        self, feet_in_body: npt.NDArray[np.float64], swinging: npt.NDArray[np.bool_]
    ) -> npt.NDArray[np.float64]:
        """Bring a swinging foot that left its leg's workspace back in.

        A swing lifted over the terrain can ask for more than a leg reaches near the body;
        the foot then flies as high as the leg allows. A swing whose path sweeps past the
        coxa's range (the body lagging behind the plan) is turned back to the range's edge.
        A foot that lifted off a stretched leg while the body moved on (a late tick, the
        body rising to a new floor) is drawn in towards its femur joint until the leg
        reaches it. Supporting feet are never moved.
        """
        out = feet_in_body.copy()
        k = self.kinematics
        for leg in np.flatnonzero(swinging & ~k.reachable_all(out)):
            for candidate in (out[leg], self.within_coxa_range(int(leg), out[leg])):
                lowered = candidate - np.outer(self._drops, [0.0, 0.0, 1.0])
                ok = k.reachable(int(leg), lowered)
                if ok.any():
                    out[leg] = lowered[int(np.argmax(ok))]
                    break
                drawn = self.drawn_in(int(leg), candidate)
                if self.kinematics.reachable(int(leg), drawn):
                    out[leg] = drawn
                    break
        return out

    def drawn_in(self, leg: int, foot_in_body: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
        """The foot moved towards its femur joint to just inside the stretched leg [m]."""
        k = self.kinematics
        points = np.zeros((6, 3))
        points[leg] = foot_in_body
        x, y, z = k.body_to_leg(points)[leg]
        d = math.hypot(x, y)
        r = d - k.L1
        reach = math.hypot(r, z)
        stretched = k.L2 + k.L3 - _DRAWN_IN_SLACK
        if reach <= stretched or d == 0.0:
            return foot_in_body.copy()
        s = stretched / reach
        d_new = k.L1 + r * s
        points[leg] = [x * d_new / d, y * d_new / d, z * s]
        return k.leg_to_body(points)[leg]

    def within_coxa_range(
        self, leg: int, foot_in_body: npt.NDArray[np.float64]
    ) -> npt.NDArray[np.float64]:
        """The foot turned about the coxa axis to within the coxa's joint range [m]."""
        points = np.zeros((6, 3))
        points[leg] = foot_in_body
        in_leg = self.kinematics.body_to_leg(points)[leg]
        margin = 1e-3
        yaw = np.clip(
            math.atan2(in_leg[1], in_leg[0]),
            self.kinematics.lower[0] + margin,
            self.kinematics.upper[0] - margin,
        )
        radius = math.hypot(in_leg[0], in_leg[1])
        points[leg] = [radius * math.cos(yaw), radius * math.sin(yaw), in_leg[2]]
        return self.kinematics.leg_to_body(points)[leg]

    def near_axis_in_range(
        self, feet_in_body: npt.NDArray[np.float64], stance: npt.NDArray[np.bool_]
    ) -> npt.NDArray[np.float64]:
        """Supporting feet beyond their coxa's range turned into it, where that hardly moves them.

        A foot within ``NEAR_AXIS_SLIP_M`` of where its leg reaches with the coxa at its
        range's edge (a foot under its hip) is moved there; any other foot is left as asked
        (the inverse kinematics then refuses it).
        """
        k = self.kinematics
        in_leg = k.body_to_leg(feet_in_body)
        yaw = np.arctan2(in_leg[:, 1], in_leg[:, 0])
        beyond = stance & ((yaw < k.lower[0]) | (yaw > k.upper[0]))
        if not beyond.any():
            return feet_in_body
        out = feet_in_body.copy()
        for leg in np.flatnonzero(beyond):
            turned = self.within_coxa_range(int(leg), feet_in_body[leg])
            if float(np.linalg.norm(turned - feet_in_body[leg])) <= NEAR_AXIS_SLIP_M:
                out[leg] = turned
        return out

    def solve(
        self,
        feet_in_body: npt.NDArray[np.float64],
        swinging: npt.NDArray[np.bool_],
        pose: PlanarPose,
        feedback: BodyFeedback,
        twist: tuple[tuple[float, float], float],
        swing_velocity_in_world: npt.NDArray[np.float64],
        incline: float = 0.0,
    ) -> FootTargets:
        """The foot targets of one tick.

        Args:
            feet_in_body: Reference feet in the body frame, shape (6, 3) [m]: stance feet
                at their contact anchors, swing feet on their paths.
            swinging: Which legs swing, shape (6,).
            pose: The reference body pose (for the world-frame rolling).
            feedback: The attitude and height corrections to apply.
            twist: Body velocity in the body frame [m/s] and yaw rate [rad/s], as applied.
            swing_velocity_in_world: World velocities of the feet, shape (6, 3) [m/s].
            incline: The body's pitch [rad]: the reference body frame is inclined by it.

        Raises:
            UnreachableTargetError: If a supporting foot is out of its leg's reach.
        """
        anchors = feet_in_body.copy()
        # Feedback: raise the body by the height correction, and command it tilted by the
        # attitude correction (feet in a body frame rotated by R(roll, pitch)).
        anchors[:, 2] -= feedback.height_correction
        if np.any(feedback.tilt_correction):
            tilt = Rotation.from_euler("xy", feedback.tilt_correction)
            anchors = anchors @ tilt.as_matrix()
        anchors = self.within_reach(anchors, swinging)
        stance = ~swinging
        feet = self.near_axis_in_range(anchors, stance)
        angles = self.kinematics.inverse_in_body(feet)
        pitch = angles[:, 1] + angles[:, 2]
        new = stance & np.isnan(self._tibia_pitch_at_touchdown)
        self._tibia_pitch_at_touchdown[new] = pitch[new]
        rolling_in_body = np.zeros((6, 3))
        for _ in range(2):  # fixed point: the rolling moves the foot, which changes psi
            roll = -self.foot_radius * (pitch - self._tibia_pitch_at_touchdown)
            radial = np.stack([np.cos(angles[:, 0]), np.sin(angles[:, 0]), np.zeros(6)], axis=1)
            rolling_in_leg = np.where(stance[:, None], roll[:, None] * radial, 0.0)
            rolling_in_body = (
                self.kinematics.leg_to_body(rolling_in_leg) - self.kinematics.mounts_in_body
            )
            feet = self.near_axis_in_range(anchors + rolling_in_body, stance)
            angles = self.kinematics.inverse_in_body(feet)
            pitch = angles[:, 1] + angles[:, 2]
        self.rolling_in_world = pose.vectors_to_world(inclined_to_level(rolling_in_body, incline))
        (vx, vy), yaw_rate = twist
        # Velocity of each foot in the body frame: its own world velocity, minus the body's
        # motion (translation and rotation about z).
        # (Level: the body's pitch changes slowly and is left out of the feet's rates.)
        rates = pose.vectors_to_body(swing_velocity_in_world)
        rates[:, 0] += -vx + yaw_rate * feet[:, 1]
        rates[:, 1] += -vy - yaw_rate * feet[:, 0]
        rates = level_to_inclined(rates, incline)
        return FootTargets(feet_in_body=feet, velocities_in_body=rates)
