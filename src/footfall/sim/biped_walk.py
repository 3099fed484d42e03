"""Archie walks a gait pattern in MuJoCo: joint targets, stabiliser, measurements.

Each control tick takes the pattern's COM and feet at that time, corrects them with the
stabiliser, and turns them into joint targets with the legs' closed-form inverse
kinematics (:func:`footfall.biped.body.leg_inverse`). The hip frame is placed so the whole
body's COM (the model's own, from the commanded joint angles) lies over the pattern's COM,
at the walking hip height, heading between the feet.

Stabiliser (dissertation §4.3): the ZMP measured by the foot corner force sensors is
compared with the pattern's ZMP and the COM is shifted against the error in the
cart-table sense (Kajita's COM-ZMP control: ``d/dt dx = k_zmp (p - p_ref) - k_com dx``,
stable for ``k_com > k_zmp``); the hip IMU's roll and pitch are fed back to the hip so the
trunk stays upright (the attitude control of Hashimoto et al., §4.3).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from footfall.biped.body import SIDES, leg_inverse, rot_x, rot_y, rot_z
from footfall.biped.gait import SUPPORT_DOUBLE, SUPPORT_LEFT, GaitPattern
from footfall.errors import UnreachableTargetError
from footfall.sim.biped_sim import BipedSimulation, polygon_margin

CONTROL_PERIOD = 0.004  # [s]
# Time constant with which the COM pattern follows the standing feet [s].
ANCHOR_FILTER = 0.15
# After a pose it cannot reach the robot holds its last targets this long [s].
HOLD_AFTER_STOP = 1.0


@dataclass(frozen=True)
class StabiliserConfig:
    """Gains of the stabiliser; zero gains switch it off.

    Attributes:
        zmp_gain: ``k_zmp`` [1/s].
        com_gain: ``k_com`` [1/s], leak of the COM shift.
        max_shift: Largest COM shift [m].
        attitude_gain: Share of the measured trunk tilt commanded back at the hip.
        zmp_filter: Time constant of the measured ZMP's low-pass filter [s].
    """

    zmp_gain: float = 1.5
    com_gain: float = 4.0
    max_shift: float = 0.03
    attitude_gain: float = 0.5
    zmp_filter: float = 0.02


@dataclass
class BipedLog:
    """What a walk measured, one row per control tick."""

    time: list[float] = field(default_factory=list)
    com: list[npt.NDArray[np.float64]] = field(default_factory=list)
    com_ref: list[npt.NDArray[np.float64]] = field(default_factory=list)
    zmp: list[npt.NDArray[np.float64]] = field(default_factory=list)
    zmp_ref: list[npt.NDArray[np.float64]] = field(default_factory=list)
    zmp_margin: list[float] = field(default_factory=list)
    feet: list[npt.NDArray[np.float64]] = field(default_factory=list)
    joints: list[npt.NDArray[np.float64]] = field(default_factory=list)
    targets: list[npt.NDArray[np.float64]] = field(default_factory=list)
    support_polygon: list[npt.NDArray[np.float64] | None] = field(default_factory=list)

    def arrays(self) -> dict[str, npt.NDArray[np.float64]]:
        """The rows as arrays."""
        return {
            k: np.asarray(getattr(self, k))
            for k in ("time", "com", "com_ref", "zmp", "zmp_ref", "zmp_margin", "feet", "joints")
        }


def _mean_angle(a: float, b: float) -> float:
    return math.atan2(math.sin(a) + math.sin(b), math.cos(a) + math.cos(b))


class GaitController:
    """Pattern + stabiliser -> joint targets."""

    def __init__(
        self,
        sim: BipedSimulation,
        pattern: GaitPattern,
        stabiliser: StabiliserConfig | None = None,
    ) -> None:
        self.sim = sim
        self.pattern = pattern
        self.config = stabiliser or StabiliserConfig()
        self.shift = np.zeros(2)
        self.zmp_filtered: npt.NDArray[np.float64] | None = None
        self._hip_offset = np.zeros(2)  # hip frame minus body COM, learnt tick by tick
        # Where each foot really is against the pattern (x, y, yaw), and the same at lift-off.
        self.foot_offset = {side: np.zeros(3) for side in SIDES}
        self._lift_off: dict[str, npt.NDArray[np.float64] | None] = dict.fromkeys(SIDES)
        self.anchor = np.zeros(2)  # the pattern's COM and ZMP shift to the feet's offsets

    def pose_at(self, i: int, tilt: tuple[float, float] = (0.0, 0.0)):
        """Hip pose and joint targets for pattern sample ``i`` plus the COM shift."""
        p, spec = self.pattern, self.sim.spec
        yaw = _mean_angle(p.foot_yaw["left"][i], p.foot_yaw["right"][i])
        rotation = rot_z(yaw) @ rot_x(tilt[0]) @ rot_y(tilt[1])
        com_target = p.com[i] + self.anchor + self.shift
        hip = np.array([*(com_target + self._hip_offset), spec.hip_height])
        for _ in range(2):
            joints = self.joint_targets(hip, rotation, i)
            com = self.sim.body_com(hip, rotation, joints)
            hip[:2] += com_target - com[:2]
        self._hip_offset = hip[:2] - com_target
        return hip, rotation, self.joint_targets(hip, rotation, i)

    def joint_targets(self, hip, rotation, i: int) -> npt.NDArray[np.float64]:
        """Both legs' angles for the feet of sample ``i`` under a hip pose."""
        p = self.pattern
        q = []
        for side in SIDES:
            off = self.foot_offset[side]
            foot = p.feet[side][i] + np.array([off[0], off[1], 0.0])
            r_foot = rot_z(p.foot_yaw[side][i] + off[2])
            q.append(
                leg_inverse(self.sim.spec, side, rotation.T @ (foot - hip), rotation.T @ r_foot)
            )
        return np.concatenate(q)

    def track_feet(self, i: int, dt: float) -> None:
        """Follow the feet where they stand, and carry each swing back onto the plan.

        A standing foot is commanded where it is (no leg pushes it across the floor); a
        swing starts from where its foot stood and ends on the planned foothold, so slips
        do not add up from step to step; the COM pattern moves with the standing feet.
        """
        p = self.pattern
        standing = []
        for side in SIDES:
            progress = p.swing[side][i]
            if math.isnan(progress):
                actual = self.sim.sole(side)
                r = self.sim.sole_rotation(side)
                planned = p.feet[side][i]
                yaw = math.atan2(r[1, 0], r[0, 0]) - p.foot_yaw[side][i]
                self.foot_offset[side] = np.array(
                    [
                        actual[0] - planned[0],
                        actual[1] - planned[1],
                        math.atan2(math.sin(yaw), math.cos(yaw)),
                    ]
                )
                self._lift_off[side] = None
                standing.append(self.foot_offset[side][:2])
            else:
                if self._lift_off[side] is None:
                    self._lift_off[side] = self.foot_offset[side].copy()
                self.foot_offset[side] = self._lift_off[side] * (1.0 - progress)
        target = np.mean(standing, axis=0) if standing else self.anchor
        a = dt / (ANCHOR_FILTER + dt)
        self.anchor = self.anchor + a * (target - self.anchor)

    def update(self, i: int, dt: float) -> npt.NDArray[np.float64]:
        """One tick: read the sensors, update the stabiliser, return joint targets."""
        c = self.config
        self.track_feet(i, dt)
        zmp, _ = self.sim.measured_zmp()
        if zmp is not None:
            if self.zmp_filtered is None:
                self.zmp_filtered = zmp
            a = dt / (c.zmp_filter + dt)
            self.zmp_filtered = self.zmp_filtered + a * (zmp - self.zmp_filtered)
            error = self.zmp_filtered - (self.pattern.zmp[i] + self.anchor)
            self.shift += dt * (c.zmp_gain * error - c.com_gain * self.shift)
            self.shift = np.clip(self.shift, -c.max_shift, c.max_shift)
        roll, pitch, _ = self.sim.attitude()
        tilt = (-c.attitude_gain * roll, -c.attitude_gain * pitch)
        _, _, joints = self.pose_at(i, tilt)
        return joints


@dataclass
class BipedRun:
    """A finished walk."""

    log: BipedLog
    pattern: GaitPattern
    fell: bool
    collisions: int
    actual_footholds: npt.NDArray[np.float64]
    wall_seconds: float
    sim_seconds: float
    warnings: int
    stopped: str | None = None


def start_pose(sim: BipedSimulation, pattern: GaitPattern) -> None:
    """Stand the robot on the pattern's first sample, feet on the floor."""
    controller = GaitController(sim, pattern, StabiliserConfig(0.0, 1.0, 0.0, 0.0))
    hip, rotation, joints = controller.pose_at(0)
    yaw = math.atan2(rotation[1, 0], rotation[0, 0])
    sim.set_pose(hip, yaw, joints)


def run_pattern(
    sim: BipedSimulation,
    pattern: GaitPattern,
    stabiliser: StabiliserConfig | None = None,
    on_tick=None,
) -> BipedRun:
    """Walk a pattern from its standing start; stop early on a fall.

    Args:
        sim: The simulation, its robot placed with :func:`start_pose`.
        pattern: The gait.
        stabiliser: Gains (defaults when None).
        on_tick: Called with ``(sim, time)`` after each control tick (a camera, a viewer).
    """
    controller = GaitController(sim, pattern, stabiliser)
    log = BipedLog()
    fell = False
    started = time.perf_counter()
    t = 0.0
    landed: list[npt.NDArray[np.float64]] = []
    next_landing = 1
    settle = 0.5 * (1.0 - 0.0) * 0.2  # sample a foothold a moment after it is loaded
    stopped = None
    joints = sim.data.ctrl.copy()
    while t <= pattern.duration:
        i = pattern.index(t)
        if stopped is None:
            try:
                joints = controller.update(i, CONTROL_PERIOD)
            except UnreachableTargetError as exc:
                # Freeze: hold the last targets and watch whether it stays up.
                stopped = str(exc)
                hold_until = t + HOLD_AFTER_STOP
        elif t >= hold_until:
            break
        sim.command(joints)
        sim.step(CONTROL_PERIOD)
        t += CONTROL_PERIOD
        zmp, hull = sim.measured_zmp()
        log.time.append(t)
        log.com.append(sim.com()[:2])
        log.com_ref.append(pattern.com[i] + controller.anchor)
        log.zmp.append(np.full(2, np.nan) if zmp is None else zmp)
        log.zmp_ref.append(pattern.zmp[i] + controller.anchor)
        log.zmp_margin.append(np.nan if zmp is None else polygon_margin(hull, zmp))
        log.feet.append(np.concatenate([sim.sole(s)[:2] for s in SIDES]))
        log.joints.append(sim.joints)
        log.targets.append(joints)
        log.support_polygon.append(hull if len(hull) else None)
        while next_landing < len(pattern.landing_time) and t >= (
            pattern.landing_time[next_landing] + settle
        ):
            landed.append(sim.sole(pattern.foothold_sides[next_landing])[:2])
            next_landing += 1
        if on_tick is not None:
            on_tick(sim, t)
        if sim.fallen():
            fell = True
            break
    return BipedRun(
        log=log,
        pattern=pattern,
        fell=fell,
        collisions=sim.collisions,
        actual_footholds=np.array(landed).reshape(-1, 2),
        wall_seconds=time.perf_counter() - started,
        sim_seconds=t,
        warnings=sim.warnings_seen,
        stopped=stopped,
    )


def support_of(pattern: GaitPattern, i: int) -> str:
    """``"double"``, ``"left"`` or ``"right"`` at sample ``i``."""
    s = int(pattern.support[i])
    return "double" if s == SUPPORT_DOUBLE else ("left" if s == SUPPORT_LEFT else "right")
