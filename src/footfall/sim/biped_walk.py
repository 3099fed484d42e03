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

from footfall.biped.body import SIDES, BipedSpec, leg_inverse, mean_heading, rot_x, rot_y, rot_z
from footfall.biped.gait import GaitPattern
from footfall.errors import UnreachableTargetError
from footfall.sim.biped_sim import BipedSimulation, polygon_margin

CONTROL_PERIOD = 0.004  # [s]
# Time constant with which the COM pattern follows the standing feet [s].
ANCHOR_FILTER = 0.15
# After a pose it cannot reach the robot holds its last targets this long [s].
HOLD_AFTER_STOP = 1.0
# A foothold is measured this long after its foot is loaded [s].
FOOTHOLD_SETTLE = 0.1
# Corrections of the hip position that bring the body's COM over its target; warm-started
# from the previous tick, two leave it within a tenth of a millimetre.
COM_ITERATIONS = 2


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
    joints: list[npt.NDArray[np.float64]] = field(default_factory=list)
    targets: list[npt.NDArray[np.float64]] = field(default_factory=list)
    support_polygon: list[npt.NDArray[np.float64] | None] = field(default_factory=list)

    def arrays(self) -> dict[str, npt.NDArray[np.float64]]:
        """The rows as arrays."""
        return {
            k: np.asarray(getattr(self, k))
            for k in ("time", "com", "com_ref", "zmp", "zmp_ref", "zmp_margin", "joints")
        }


FootPoses = dict[str, tuple[npt.NDArray[np.float64], float]]  # side -> sole [m], heading [rad]


def leg_angles(spec: BipedSpec, hip, rotation, feet: FootPoses) -> npt.NDArray[np.float64]:
    """Both legs' joint angles for level feet at their poses under a hip pose."""
    return np.concatenate(
        [
            leg_inverse(
                spec, side, rotation.T @ (feet[side][0] - hip), rotation.T @ rot_z(feet[side][1])
            )
            for side in SIDES
        ]
    )


def place_hip(
    sim: BipedSimulation, com_xy, rotation, feet: FootPoses, hip_xy
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """The hip position (at the walking height) that puts the body's COM over ``com_xy``.

    Starting from ``hip_xy``, the hip moves by the COM's miss, the legs re-solved each time.

    Returns:
        ``(hip, joints, com)``: hip position [m], joint angles [rad], the COM before the
        last correction [m].
    """
    hip = np.array([*hip_xy, sim.spec.hip_height])
    com = np.zeros(3)
    for _ in range(COM_ITERATIONS):
        com = sim.body_com(hip, rotation, leg_angles(sim.spec, hip, rotation, feet))
        hip[:2] += np.asarray(com_xy) - com[:2]
    return hip, leg_angles(sim.spec, hip, rotation, feet), com


def stand(sim: BipedSimulation, feet: dict[str, tuple[float, float, float]]) -> float:
    """Stand the robot still on level feet ``(x, y, heading)``, its COM between them.

    Returns:
        The COM's height [m], ``z_c`` of the cart-table model.
    """
    yaw = mean_heading(feet["left"][2], feet["right"][2])
    poses = {s: (np.array([f[0], f[1], 0.0]), f[2]) for s, f in feet.items()}
    mid = 0.5 * (poses["left"][0][:2] + poses["right"][0][:2])
    hip, joints, com = place_hip(sim, mid, rot_z(yaw), poses, mid)
    sim.set_pose(hip, yaw, joints)
    return float(com[2])


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
        p = self.pattern
        yaw = mean_heading(p.foot_yaw["left"][i], p.foot_yaw["right"][i])
        rotation = rot_z(yaw) @ rot_x(tilt[0]) @ rot_y(tilt[1])
        com_target = p.com[i] + self.anchor + self.shift
        feet = {}
        for side in SIDES:
            off = self.foot_offset[side]
            feet[side] = (p.feet[side][i] + (off[0], off[1], 0.0), p.foot_yaw[side][i] + off[2])
        hip, joints, _ = place_hip(
            self.sim, com_target, rotation, feet, com_target + self._hip_offset
        )
        self._hip_offset = hip[:2] - com_target
        return hip, rotation, joints

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

    def update(
        self, i: int, dt: float, zmp: npt.NDArray[np.float64] | None
    ) -> npt.NDArray[np.float64]:
        """One tick: given the measured ZMP (None in the air), return joint targets."""
        c = self.config
        self.track_feet(i, dt)
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


def start_pose(sim: BipedSimulation, pattern: GaitPattern) -> float:
    """Stand the robot on the pattern's first feet; returns the COM height [m]."""
    return stand(
        sim,
        {s: (*pattern.feet[s][0][:2], float(pattern.foot_yaw[s][0])) for s in SIDES},
    )


class PatternRunner:
    """Walks a pattern one control tick at a time, from its standing start.

    Args:
        sim: The simulation, its robot placed with :func:`start_pose`.
        pattern: The gait.
        stabiliser: Gains (defaults when None).

    Attributes:
        t: Time into the pattern [s].
        finished: The pattern ended, the robot fell, or it held still after a pose it
            could not reach.
    """

    def __init__(
        self,
        sim: BipedSimulation,
        pattern: GaitPattern,
        stabiliser: StabiliserConfig | None = None,
    ) -> None:
        self.sim = sim
        self.pattern = pattern
        self.controller = GaitController(sim, pattern, stabiliser)
        self.log = BipedLog()
        self.fell = False
        self.finished = False
        self.stopped: str | None = None
        self.t = 0.0
        self.landed: list[npt.NDArray[np.float64]] = []
        self._next_landing = 1
        self._hold_until = math.inf
        self._joints = sim.data.ctrl.copy()
        self._zmp, _ = sim.measured_zmp()
        self._started = time.perf_counter()

    def switch(self, pattern: GaitPattern) -> None:
        """Walk on with another pattern on the same time line (one that ends sooner)."""
        self.pattern = pattern
        self.controller.pattern = pattern

    def tick(self) -> bool:
        """One control period; returns whether the walk goes on."""
        pattern, sim = self.pattern, self.sim
        if self.finished or self.t > pattern.duration:
            self.finished = True
            return False
        i = pattern.index(self.t)
        if self.stopped is None:
            try:
                self._joints = self.controller.update(i, CONTROL_PERIOD, self._zmp)
            except UnreachableTargetError as exc:
                # Freeze: hold the last targets and watch whether it stays up.
                self.stopped = str(exc)
                self._hold_until = self.t + HOLD_AFTER_STOP
        elif self.t >= self._hold_until:
            self.finished = True
            return False
        sim.command(self._joints)
        sim.step(CONTROL_PERIOD)
        self.t += CONTROL_PERIOD
        zmp, hull = sim.measured_zmp()
        self._zmp = zmp
        log, anchor = self.log, self.controller.anchor
        log.time.append(self.t)
        log.com.append(sim.com()[:2])
        log.com_ref.append(pattern.com[i] + anchor)
        log.zmp.append(np.full(2, np.nan) if zmp is None else zmp)
        log.zmp_ref.append(pattern.zmp[i] + anchor)
        log.zmp_margin.append(np.nan if zmp is None else polygon_margin(hull, zmp))
        log.joints.append(sim.joints)
        log.targets.append(self._joints)
        log.support_polygon.append(hull if len(hull) else None)
        while self._next_landing < len(pattern.landing_time) and self.t >= (
            pattern.landing_time[self._next_landing] + FOOTHOLD_SETTLE
        ):
            side = pattern.foothold_sides[self._next_landing]
            self.landed.append(sim.sole(side)[:2])
            self._next_landing += 1
        if sim.fallen():
            self.fell = self.finished = True
            return False
        return True

    def result(self) -> BipedRun:
        """The walk so far."""
        return BipedRun(
            log=self.log,
            pattern=self.pattern,
            fell=self.fell,
            collisions=self.sim.collisions,
            actual_footholds=np.array(self.landed).reshape(-1, 2),
            wall_seconds=time.perf_counter() - self._started,
            sim_seconds=self.t,
            warnings=self.sim.warnings_seen,
            stopped=self.stopped,
        )


def run_pattern(
    sim: BipedSimulation,
    pattern: GaitPattern,
    stabiliser: StabiliserConfig | None = None,
) -> BipedRun:
    """Walk a pattern from its standing start; stop early on a fall.

    Args:
        sim: The simulation, its robot placed with :func:`start_pose`.
        pattern: The gait.
        stabiliser: Gains (defaults when None).
    """
    runner = PatternRunner(sim, pattern, stabiliser)
    while runner.tick():
        pass
    return runner.result()
