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

import mujoco
import numpy as np
import numpy.typing as npt

from footfall.biped.body import SIDES, BipedSpec, leg_inverse, rot_x, rot_y, rot_z
from footfall.biped.gait import SUPPORT_DOUBLE, SUPPORT_LEFT, GaitPattern
from footfall.sim.biped_model import CORNERS, OBSTACLE_PREFIX, joint_names

CONTROL_PERIOD = 0.004  # [s]
# A foot carries load when its sensors read more than this [N].
LOADED_FORCE = 20.0
# The robot has fallen when its hip drops below this share of the walking height, or it
# tilts more than FALL_TILT.
FALL_HEIGHT_FRACTION = 0.6
FALL_TILT = math.radians(40.0)
# Time constant with which the COM pattern follows the standing feet [s].
ANCHOR_FILTER = 0.15


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


def convex_hull(points: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    """Counter-clockwise hull of 2-D points (monotone chain), shape (h, 2)."""
    p = np.unique(np.round(points, 12), axis=0)
    if len(p) < 3:
        return p

    def cross(o, a, b) -> float:
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    lower: list = []
    for q in p:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], q) <= 0:
            lower.pop()
        lower.append(q)
    upper: list = []
    for q in p[::-1]:
        while len(upper) >= 2 and cross(upper[-2], upper[-1], q) <= 0:
            upper.pop()
        upper.append(q)
    return np.array(lower[:-1] + upper[:-1])


def polygon_margin(hull: npt.NDArray[np.float64], point: npt.NDArray[np.float64]) -> float:
    """Signed distance from a point to a convex polygon's boundary, positive inside [m]."""
    if len(hull) < 3:
        return -math.inf
    edges = np.roll(hull, -1, axis=0) - hull
    normals = np.column_stack([edges[:, 1], -edges[:, 0]]) / np.linalg.norm(
        edges, axis=1, keepdims=True
    )
    inside = -np.sum((point - hull) * normals, axis=1)  # distance inward of each edge line
    return float(np.min(inside))


class BipedSimulation:
    """The compiled model and its state, with Archie's sensors read the way a robot would."""

    def __init__(self, spec: BipedSpec, model: mujoco.MjModel) -> None:
        self.spec = spec
        self.model = model
        self.data = mujoco.MjData(model)
        self._scratch = mujoco.MjData(model)
        names = joint_names()
        self._qadr = np.array([model.joint(n).qposadr[0] for n in names])
        self._act = np.array([model.actuator(n).id for n in names])
        self._hip = model.body("hip").id
        self._sites = {
            side: [model.site(f"{side}_foot_{k}").id for k in range(len(CORNERS))] for side in SIDES
        }
        self._touch = {
            side: [model.sensor(f"{side}_foot_{k}").adr[0] for k in range(len(CORNERS))]
            for side in SIDES
        }
        self._quat = model.sensor("imu_quat").adr[0]
        self._sole = {side: model.site(f"{side}_sole").id for side in SIDES}
        self._robot_geoms = set(np.flatnonzero(model.geom_bodyid > 0).tolist())
        self._obstacles = {
            g for g in range(model.ngeom) if (model.geom(g).name or "").startswith(OBSTACLE_PREFIX)
        }
        self.touching: set[tuple[int, int]] = set()
        self.collisions = 0
        self.warnings_seen = 0

    def set_pose(self, hip_position, hip_yaw: float, joints: npt.ArrayLike) -> None:
        """Place the robot (no velocity) and hold the joints there."""
        d = self.data
        d.qpos[:3] = hip_position
        d.qpos[3:7] = [math.cos(0.5 * hip_yaw), 0.0, 0.0, math.sin(0.5 * hip_yaw)]
        d.qpos[self._qadr] = joints
        d.qvel[:] = 0.0
        d.ctrl[self._act] = joints
        mujoco.mj_forward(self.model, d)

    def body_com(self, hip_position, hip_rotation, joints) -> npt.NDArray[np.float64]:
        """The whole body's COM for a hip pose and joint angles (kinematics only) [m]."""
        s = self._scratch
        s.qpos[:3] = hip_position
        quat = np.empty(4)
        mujoco.mju_mat2Quat(quat, np.asarray(hip_rotation, dtype=np.float64).ravel())
        s.qpos[3:7] = quat
        s.qpos[self._qadr] = joints
        mujoco.mj_kinematics(self.model, s)
        mujoco.mj_comPos(self.model, s)
        return s.subtree_com[self._hip].copy()

    def command(self, joints: npt.ArrayLike) -> None:
        """Set the servos' targets [rad]."""
        self.data.ctrl[self._act] = joints

    def step(self, duration: float) -> None:
        """Advance the physics and track contacts with obstacles."""
        n = max(1, round(duration / self.model.opt.timestep))
        for _ in range(n):
            mujoco.mj_step(self.model, self.data)
        now = set()
        for c in self.data.contact[: self.data.ncon]:
            g1, g2 = int(c.geom1), int(c.geom2)
            if g1 in self._obstacles and g2 in self._robot_geoms:
                now.add((g2, g1))
            elif g2 in self._obstacles and g1 in self._robot_geoms:
                now.add((g1, g2))
        self.collisions += len(now - self.touching)
        self.touching = now
        self.warnings_seen = int(sum(w.number for w in self.data.warning))

    @property
    def joints(self) -> npt.NDArray[np.float64]:
        """Measured joint angles [rad]."""
        return self.data.qpos[self._qadr].copy()

    @property
    def hip_height(self) -> float:
        """Hip frame height [m]."""
        return float(self.data.qpos[2])

    def attitude(self) -> tuple[float, float, float]:
        """Roll, pitch, yaw of the hip from the IMU [rad]."""
        w, x, y, z = self.data.sensordata[self._quat : self._quat + 4]
        roll = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
        pitch = math.asin(max(-1.0, min(1.0, 2 * (w * y - z * x))))
        yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
        return roll, pitch, yaw

    def com(self) -> npt.NDArray[np.float64]:
        """Measured whole-body COM [m]."""
        return self.data.subtree_com[self._hip].copy()

    def sole_rotation(self, side: str) -> npt.NDArray[np.float64]:
        """Orientation of a foot in the world, shape (3, 3)."""
        return self.data.site_xmat[self._sole[side]].reshape(3, 3).copy()

    def sole(self, side: str) -> npt.NDArray[np.float64]:
        """Sole centre of a foot in the world [m]."""
        return self.data.site_xpos[self._sole[side]].copy()

    def foot_forces(self) -> dict[str, tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]]:
        """Per side, the corner sensors' normal forces [N] and the corners' positions [m]."""
        out = {}
        for side in SIDES:
            f = self.data.sensordata[self._touch[side]].copy()
            out[side] = (f, self.data.site_xpos[self._sites[side]][:, :2].copy())
        return out

    def measured_zmp(self) -> tuple[npt.NDArray[np.float64] | None, npt.NDArray[np.float64]]:
        """ZMP from the foot sensors, and the support polygon of the loaded feet.

        Returns:
            ``(zmp, hull)``: the centre of pressure [m] (None in the air) and the hull of
            the corners of every loaded foot (empty when none is).
        """
        forces = self.foot_forces()
        total = sum(float(f.sum()) for f, _ in forces.values())
        if total < LOADED_FORCE:
            return None, np.empty((0, 2))
        zmp = sum(f @ p for f, p in forces.values()) / total
        corners = [p for f, p in forces.values() if f.sum() > LOADED_FORCE]
        hull = convex_hull(np.vstack(corners)) if corners else np.empty((0, 2))
        return zmp, hull

    def fallen(self) -> bool:
        """Hip too low or trunk tipped over."""
        roll, pitch, _ = self.attitude()
        low = self.hip_height < FALL_HEIGHT_FRACTION * self.spec.hip_height
        return low or abs(roll) > FALL_TILT or abs(pitch) > FALL_TILT


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
    while t <= pattern.duration:
        i = pattern.index(t)
        joints = controller.update(i, CONTROL_PERIOD)
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
    )


def support_of(pattern: GaitPattern, i: int) -> str:
    """``"double"``, ``"left"`` or ``"right"`` at sample ``i``."""
    s = int(pattern.support[i])
    return "double" if s == SUPPORT_DOUBLE else ("left" if s == SUPPORT_LEFT else "right")
