"""The pose guard: raw pose estimates in, estimates consistent with odometry out.

A visual SLAM system's estimate can jump (a relocalisation, a wrong loop closure); the
thesis saw its height variations turn into artefacts of the height map (§9.2). Between two
estimates the robot's own odometry knows how far it went: the walking controller's reference
pose (integrated from the executed command, re-registered on every estimate it is given)
and the IMU's gravity direction. The guard compares each raw estimate with that prediction;
an estimate that moved farther than odometry and noise explain is a jump. The guard then
re-registers: from that estimate on it applies the world-frame correction that puts the
jumped estimate where odometry says the robot is, so the map is not smeared with two
frames and the controller's world does not lurch. Corrections compose over several jumps.

A jump smaller than the allowance passes (a few centimetres, two degrees): the height map's
drift compensation takes its vertical part.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from footfall.errors import ConfigError
from footfall.messages import GaitStatus, LogLine, PoseEstimate, RobotState
from footfall.robot.planar import PlanarPose
from footfall.runtime.bus import Bus
from footfall.runtime.faults import RAW_POSE_TOPIC
from footfall.sensing.pose import Pose


@dataclass(frozen=True)
class PoseGuardConfig:
    """How far an estimate may move from the odometry's prediction.

    An allowance is a constant plus a rate times the time since the last accepted estimate
    (odometry error grows while no estimate comes).

    Attributes:
        position_m: Horizontal and vertical allowance [m].
        position_rate_mps: Its growth [m/s].
        angle_deg: Heading and tilt allowance [degrees].
        angle_rate_dps: Its growth [degrees/s].
    """

    position_m: float = 0.03
    position_rate_mps: float = 0.1
    angle_deg: float = 2.0
    angle_rate_dps: float = 2.0

    def __post_init__(self) -> None:
        for name in ("position_m", "position_rate_mps", "angle_deg", "angle_rate_dps"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0):
                raise ConfigError(f"pose guard {name} must be a positive number, got {value}")


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
        raw_topic: str = RAW_POSE_TOPIC,
    ) -> None:
        self.bus = bus
        self.config = config or PoseGuardConfig()
        self.correction = Pose.identity()  # world-frame: corrected = correction o raw
        self.jumps = 0
        self._last: PoseEstimate | None = None
        self._odometry: PlanarPose | None = None
        self._attitude: Rotation | None = None
        bus.subscribe(raw_topic, self._on_raw)
        bus.subscribe(GaitStatus.TOPIC, self._on_status, last=True)
        bus.subscribe(RobotState.TOPIC, self._on_state, last=True)

    def _on_status(self, status: GaitStatus) -> None:
        self._odometry = status.body_pose

    def _on_state(self, state: RobotState) -> None:
        self._attitude = state.orientation_body_in_world

    def _corrected(self, raw: PoseEstimate) -> PoseEstimate:
        c = self.correction
        return PoseEstimate(raw.stamp, c.compose(raw.camera_in_world), c.compose(raw.body_in_world))

    def _on_raw(self, raw: PoseEstimate) -> None:
        estimate = self._corrected(raw)
        last, odometry = self._last, self._odometry
        if last is not None and odometry is not None and raw.stamp > last.stamp:
            jump = self._residual(estimate, last, odometry, raw.stamp - last.stamp)
            if jump is not None:
                self._reregister(raw, estimate, last, odometry, jump)
                estimate = self._corrected(raw)
        self._last = estimate
        self.bus.publish(PoseEstimate.TOPIC, estimate)

    def _residual(
        self, estimate: PoseEstimate, last: PoseEstimate, odometry: PlanarPose, elapsed: float
    ) -> str | None:
        """Why ``estimate`` is a jump from what odometry predicts, or None when it is not."""
        c = self.config
        body = estimate.body_in_world
        position_limit = c.position_m + c.position_rate_mps * elapsed
        angle_limit = math.radians(c.angle_deg + c.angle_rate_dps * elapsed)
        horizontal = math.hypot(body.position[0] - odometry.x, body.position[1] - odometry.y)
        vertical = abs(float(body.position[2] - last.body_in_world.position[2]))
        turn = abs(wrap(heading(body.rotation) - odometry.yaw))
        tilt = tilt_between(body.rotation, self._attitude) if self._attitude is not None else 0.0
        if horizontal > position_limit or vertical > position_limit:
            return f"moved {horizontal:.3f} m across and {vertical:.3f} m up from odometry"
        if turn > angle_limit or tilt > angle_limit:
            return (
                f"turned {math.degrees(turn):.1f} deg from odometry, tilted "
                f"{math.degrees(tilt):.1f} deg from the IMU"
            )
        return None

    def _reregister(
        self,
        raw: PoseEstimate,
        estimate: PoseEstimate,
        last: PoseEstimate,
        odometry: PlanarPose,
        why: str,
    ) -> None:
        """Take the correction that puts ``raw`` where odometry and the IMU say it is."""
        body = estimate.body_in_world
        attitude = self._attitude if self._attitude is not None else body.rotation
        rotation = Rotation.from_euler("z", wrap(odometry.yaw - heading(attitude))) * attitude
        predicted = Pose(
            np.array([odometry.x, odometry.y, float(last.body_in_world.position[2])]), rotation
        )
        self.correction = predicted.compose(raw.body_in_world.inverse())
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
