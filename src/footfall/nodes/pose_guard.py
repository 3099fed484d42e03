"""The pose guard: raw pose estimates in, estimates consistent with odometry out.

A visual SLAM system's estimate can jump (a relocalisation, a wrong loop closure); the
thesis saw its height variations turn into artefacts of the height map (§9.2). Between two
estimates the robot's own odometry knows how far it went: the walking controller's reference
pose (integrated from the executed command, re-registered on every estimate it is given)
and the IMU's gravity direction. The guard compares how far each raw estimate moved from
the last one with how far odometry moved; an estimate that moved farther than odometry and
noise explain is a jump. The guard then re-registers: from that estimate on it applies the
world-frame correction that puts the jumped estimate where the last one and odometry's
motion say the robot is, so the map is not smeared with two frames and the controller's
world does not lurch. Corrections compose over several jumps. Comparing motions, not poses,
a slow disagreement between the estimate and odometry (a foot slipping, SLAM drifting) is
never taken for a jump.

The robot's own motion can also outrun odometry: a foot that slips off a stone lets the
body lurch by centimetres while the commanded motion says it stood. An estimate that
followed such a lurch is right, and re-registering it would put the map out of register.
So a re-registration is a hypothesis the map tests: until the map's verdict comes, the
guard publishes beside each corrected estimate the one it would have published without
the re-registration (``pose/alternative``, before the corrected one); the mapping node
places its next frame both ways, fuses it where it fits the map and says which it took
(``pose/registered``). When that was the alternative, the guard undoes the re-registration.
A verdict that does not come within ``VERDICT_WAIT_S`` (no frame, or a map that cannot tell
the two apart: flat ground) lets the re-registration stand.

A jump smaller than the allowance passes (a few centimetres, two degrees): the height map's
drift compensation takes its vertical part. A jittery estimate widens the allowance to
several times its own measured scatter, so that its noise is not taken for jumps (each
false re-registration would shift the map under the feet).

The guard also fuses what passes with the robot's own senses, as a legged robot's state
estimator does: the body's tilt is the IMU's (gravity is a better reference for roll and
pitch than a camera's estimate), and its horizontal position and heading move from the
odometry's prediction towards the estimate by a gain each estimate. The gain is the steady
Kalman gain of a random walk (odometry's error per estimate, ``odometry_noise_m``) measured
by the estimate, whose noise the guard measures as it goes (the scatter of the estimates'
motion about odometry's): a clean estimate is taken almost as is, a jittery one is averaged
over many frames while its slow drift is still followed. What the feet need is not the
truest pose but one that stays consistent with the map over the four or five seconds
between the camera seeing a cell and a hind foot stepping on it: every centimetre the
published pose follows the estimate's drift in that time is a centimetre the map moves
under the feet. The odometry's error per estimate is therefore taken small (0.1 mm: the
walking robot's legs move its body as commanded to a fraction of a millimetre per
estimate, slowly biased), and a drifting estimate is followed over many seconds (at three
times the default SLAM noise, the gain a 0.3 mm odometry error gives lets the map slide
two to four centimetres under a hind foot and puts feet in the cobblestones' grooves).
Height is left to the map's drift compensation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from footfall.checks import require_positive
from footfall.errors import ConfigError
from footfall.messages import GaitStatus, LogLine, PoseEstimate, RobotState
from footfall.robot.planar import PlanarPose
from footfall.runtime.bus import Bus
from footfall.sensing.pose import Pose

# Where the guard publishes the estimate without its latest re-registration, and where
# the map says which of the two its frame fitted.
ALTERNATIVE_POSE_TOPIC = "pose/alternative"
REGISTERED_POSE_TOPIC = "pose/registered"
# A re-registration the map has not judged within this time stands [s].
VERDICT_WAIT_S = 1.0
# A registered pose is the alternative when they lie this close [m].
SAME_POSE_M = 1e-6


@dataclass(frozen=True)
class PoseGuardConfig:
    """How far an estimate may move from the odometry's prediction.

    An allowance is a constant plus a rate times the time since the last accepted estimate
    (odometry error grows while no estimate comes), or ``jump_sigmas`` times the scatter
    the guard measures in the estimates' motion about odometry's, when that is wider: a
    jittery estimate's own noise is never taken for a jump.

    Attributes:
        position_m: Horizontal and vertical allowance [m].
        position_rate_mps: Its growth [m/s].
        angle_deg: Heading and tilt allowance [degrees].
        angle_rate_dps: Its growth [degrees/s].
        odometry_noise_m: Odometry's horizontal error per estimate [m], for the gain.
        min_gain: The smallest share of the estimate taken per estimate.
        noise_memory: Estimates over which the estimate's noise is averaged.
        jump_sigmas: An allowance is at least this many standard deviations of the
            measured scatter (horizontal, vertical and heading apart).
        imu_tilt: Take the body's roll and pitch from the IMU.
    """

    position_m: float = 0.03
    position_rate_mps: float = 0.1
    angle_deg: float = 2.0
    angle_rate_dps: float = 2.0
    odometry_noise_m: float = 0.0001
    min_gain: float = 0.01
    noise_memory: int = 20
    jump_sigmas: float = 5.0
    imu_tilt: bool = True

    def __post_init__(self) -> None:
        require_positive(
            "pose guard",
            position_m=self.position_m,
            position_rate_mps=self.position_rate_mps,
            angle_deg=self.angle_deg,
            angle_rate_dps=self.angle_rate_dps,
            odometry_noise_m=self.odometry_noise_m,
            jump_sigmas=self.jump_sigmas,
        )
        if not 0.0 < self.min_gain <= 1.0:
            raise ConfigError(f"pose guard min_gain must lie in (0, 1], got {self.min_gain}")
        if self.noise_memory < 1:
            raise ConfigError(f"pose guard noise_memory must be >= 1, got {self.noise_memory}")


def heading(rotation: Rotation) -> float:
    """Heading of a body's x axis in the ground plane [rad]."""
    x_axis = rotation.apply([1.0, 0.0, 0.0])
    return math.atan2(x_axis[1], x_axis[0])


def tilt_between(a: Rotation, b: Rotation) -> float:
    """Angle between the world's up direction seen in two body attitudes [rad]."""
    up_a, up_b = a.inv().apply([0.0, 0.0, 1.0]), b.inv().apply([0.0, 0.0, 1.0])
    return float(np.arccos(np.clip(up_a @ up_b, -1.0, 1.0)))


def wrap(angle: float) -> float:
    """An angle in (-pi, pi] [rad]."""
    return math.atan2(math.sin(angle), math.cos(angle))


class PoseGuardNode:
    """Checks raw pose estimates against odometry and re-registers jumps.

    Args:
        bus: The bus.
        config: Allowances.
        raw_topic: Where the raw estimates come from.
    """

    name = "pose_guard"

    def __init__(
        self,
        bus: Bus,
        config: PoseGuardConfig | None = None,
        raw_topic: str = PoseEstimate.RAW_TOPIC,
    ) -> None:
        self.bus = bus
        self.config = config or PoseGuardConfig()
        self.correction = Pose.identity()  # world-frame: corrected = correction o raw
        self.jumps = 0
        self._last: PoseEstimate | None = None  # the last corrected (unfused) estimate
        self._odometry: PlanarPose | None = None
        self._odometry_then: PlanarPose | None = None  # odometry as the last one went out
        self._attitude: Rotation | None = None
        # Mean squares of the estimates' motion about odometry's: horizontal (per axis) and
        # vertical [m^2], heading [rad^2]; over ``_measured`` estimates so far.
        self._scatter = 0.0
        self._scatter_z = 0.0
        self._scatter_yaw = 0.0
        self._measured = 0
        self.gain = 1.0
        self.refuted = 0  # re-registrations the map undid
        self._latest_raw: PoseEstimate | None = None
        # While a re-registration awaits the map's verdict: the correction before it, when
        # it was made, and the alternatives published since.
        self._undo: Pose | None = None
        self._undo_since = 0.0
        self._alternatives: dict[float, PoseEstimate] = {}
        bus.subscribe(raw_topic, self._on_raw)
        bus.subscribe(REGISTERED_POSE_TOPIC, self._on_registered)
        bus.subscribe(GaitStatus.TOPIC, self._on_status, last=True)
        bus.subscribe(RobotState.TOPIC, self._on_state, last=True)

    def _on_status(self, status: GaitStatus) -> None:
        self._odometry = status.body_pose

    def _on_state(self, state: RobotState) -> None:
        self._attitude = state.orientation_body_in_world

    def _corrected(self, raw: PoseEstimate, correction: Pose | None = None) -> PoseEstimate:
        c = self.correction if correction is None else correction
        return PoseEstimate(raw.stamp, c.compose(raw.camera_in_world), c.compose(raw.body_in_world))

    def _on_raw(self, raw: PoseEstimate) -> None:
        self._latest_raw = raw
        estimate = self._corrected(raw)
        last, odometry, then = self._last, self._odometry, self._odometry_then
        published = estimate
        if self._undo is not None and raw.stamp - self._undo_since > VERDICT_WAIT_S:
            self._undo, self._alternatives = None, {}  # no verdict: the correction stands
        if last is not None and odometry is not None and then is not None:
            if raw.stamp > last.stamp:
                predicted = self._predicted(last, then, odometry)
                jump = self._residual(estimate, last, predicted, raw.stamp - last.stamp)
                if jump is not None:
                    self._reregister(raw, last, predicted, jump)
                    estimate = self._corrected(raw)
                else:
                    self._measure(estimate, last, predicted)
            published = self._fused(estimate, odometry)
            if self._undo is not None:
                # Before the corrected estimate: a frame waiting for its pose finds both.
                alternative = self._fused(self._corrected(raw, self._undo), odometry, gain=1.0)
                self._alternatives[raw.stamp] = alternative
                self.bus.publish(ALTERNATIVE_POSE_TOPIC, alternative)
        self._last = estimate
        self.bus.publish(PoseEstimate.TOPIC, published)
        self._odometry_then = self._odometry  # the controller has taken it by now

    def _on_registered(self, registered: PoseEstimate) -> None:
        """The map's verdict: undo the re-registration when it took the alternative."""
        if self._undo is None:
            return
        alternative = self._alternatives.get(registered.stamp)
        if alternative is None:
            return  # a verdict on a pose from before this re-registration
        took_alternative = (
            float(
                np.linalg.norm(
                    registered.body_in_world.position - alternative.body_in_world.position
                )
            )
            <= SAME_POSE_M
        )
        if took_alternative:
            self.correction = self._undo
            self.jumps -= 1
            self.refuted += 1
            if self._latest_raw is not None:
                self._last = self._corrected(self._latest_raw)
            self.bus.publish(
                LogLine.TOPIC,
                LogLine(
                    registered.stamp,
                    self.name,
                    "warning",
                    "the map placed the frame where the estimate said: the robot itself moved "
                    "beyond odometry (a slip), re-registration undone",
                ),
            )
        self._undo, self._alternatives = None, {}

    @staticmethod
    def _predicted(last: PoseEstimate, then: PlanarPose, now: PlanarPose) -> PlanarPose:
        """Where the corrected estimates should be now: the last one moved as odometry did."""
        c, s = math.cos(then.yaw), math.sin(then.yaw)
        dx, dy = now.x - then.x, now.y - then.y
        forward, left = c * dx + s * dy, -s * dx + c * dy  # the motion in the body's frame
        yaw = heading(last.body_in_world.rotation)
        c, s = math.cos(yaw), math.sin(yaw)
        p = last.body_in_world.position
        return PlanarPose(
            float(p[0]) + c * forward - s * left,
            float(p[1]) + s * forward + c * left,
            wrap(yaw + wrap(now.yaw - then.yaw)),
        )

    def _measure(self, estimate: PoseEstimate, last: PoseEstimate, predicted: PlanarPose) -> None:
        """Update the estimate's measured noise, and the gain it gives.

        The first ``noise_memory`` estimates are averaged evenly, later ones exponentially.
        """
        c = self.config
        body = estimate.body_in_world
        p = body.position
        self._measured += 1
        share = 1.0 / min(self._measured, c.noise_memory)
        square = 0.5 * ((float(p[0]) - predicted.x) ** 2 + (float(p[1]) - predicted.y) ** 2)
        self._scatter += (square - self._scatter) * share
        rise = float(p[2] - last.body_in_world.position[2])
        self._scatter_z += (rise * rise - self._scatter_z) * share
        turn = wrap(heading(body.rotation) - predicted.yaw)
        self._scatter_yaw += (turn * turn - self._scatter_yaw) * share
        q = c.odometry_noise_m**2
        # The motion between two estimates carries two of their errors and one of odometry's.
        r = max(0.5 * (self._scatter - q), 0.0)
        gain = 1.0 if r <= 1e-3 * q else (-q + math.sqrt(q * q + 4.0 * q * r)) / (2.0 * r)
        self.gain = min(max(gain, c.min_gain), 1.0)

    def _fused(
        self, estimate: PoseEstimate, odometry: PlanarPose, gain: float | None = None
    ) -> PoseEstimate:
        """The estimate blended with odometry in the plane, tilted as the IMU says."""
        c = self.config
        body = estimate.body_in_world
        camera_in_body = body.inverse().compose(estimate.camera_in_world)
        k = self.gain if gain is None else gain
        x = odometry.x + k * (float(body.position[0]) - odometry.x)
        y = odometry.y + k * (float(body.position[1]) - odometry.y)
        yaw = odometry.yaw + k * wrap(heading(body.rotation) - odometry.yaw)
        attitude = self._attitude if c.imu_tilt and self._attitude is not None else body.rotation
        rotation = Rotation.from_euler("z", wrap(yaw - heading(attitude))) * attitude
        fused = Pose(np.array([x, y, float(body.position[2])]), rotation)
        return PoseEstimate(estimate.stamp, fused.compose(camera_in_body), fused)

    def _residual(
        self, estimate: PoseEstimate, last: PoseEstimate, predicted: PlanarPose, elapsed: float
    ) -> str | None:
        """Why ``estimate`` is a jump from the prediction, or None when it is not."""
        c = self.config
        body = estimate.body_in_world
        k = c.jump_sigmas
        fixed = c.position_m + c.position_rate_mps * elapsed
        # A 2-D residual of per-axis variance s passes k sqrt(s) with odds exp(-k^2 / 2).
        position_limit = max(fixed, k * math.sqrt(self._scatter))
        vertical_limit = max(fixed, k * math.sqrt(self._scatter_z))
        angle_limit = max(
            math.radians(c.angle_deg + c.angle_rate_dps * elapsed), k * math.sqrt(self._scatter_yaw)
        )
        horizontal = math.hypot(body.position[0] - predicted.x, body.position[1] - predicted.y)
        vertical = abs(float(body.position[2] - last.body_in_world.position[2]))
        turn = abs(wrap(heading(body.rotation) - predicted.yaw))
        # With the IMU's tilt taken, an error in tilt never reaches the map: only heading
        # counts then.
        tilt = (
            tilt_between(body.rotation, self._attitude)
            if self._attitude is not None and not c.imu_tilt
            else 0.0
        )
        if horizontal > position_limit or vertical > vertical_limit:
            return f"moved {horizontal:.3f} m across and {vertical:.3f} m up beyond odometry"
        if turn > angle_limit or tilt > angle_limit:
            return (
                f"turned {math.degrees(turn):.1f} deg beyond odometry, tilted "
                f"{math.degrees(tilt):.1f} deg from the IMU"
            )
        return None

    def _reregister(
        self, raw: PoseEstimate, last: PoseEstimate, predicted: PlanarPose, why: str
    ) -> None:
        """Take the correction that puts ``raw`` where the prediction and the IMU say."""
        attitude = self._attitude if self._attitude is not None else last.body_in_world.rotation
        rotation = Rotation.from_euler("z", wrap(predicted.yaw - heading(attitude))) * attitude
        target = Pose(
            np.array([predicted.x, predicted.y, float(last.body_in_world.position[2])]), rotation
        )
        if self._undo is None:  # a second jump before the verdict: the map judges both
            self._undo, self._undo_since = self.correction, raw.stamp
        self.correction = target.compose(raw.body_in_world.inverse())
        self.jumps += 1
        self.bus.publish(
            LogLine.TOPIC,
            LogLine(
                raw.stamp,
                self.name,
                "warning",
                f"pose estimate jumped ({why}): re-registered on odometry",
            ),
        )
