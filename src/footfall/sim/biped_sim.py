"""Archie's simulated body: the compiled model, its sensors read as the robot reads them.

The foot corner touch sensors give each foot's load and centre of pressure, and together
the measured ZMP; the IMU gives the hip's attitude. Contacts of the body with obstacle
geoms are counted as collisions (each new body-obstacle contact once).
"""

from __future__ import annotations

import math

import mujoco
import numpy as np
import numpy.typing as npt

from footfall.biped.body import SIDES, BipedSpec
from footfall.sim.biped_model import CORNERS, OBSTACLE_PREFIX, joint_names

# A foot carries load when its sensors read more than this [N].
LOADED_FORCE = 20.0
# The robot has fallen when its hip drops below this share of the walking height, or it
# tilts more than FALL_TILT.
FALL_HEIGHT_FRACTION = 0.6
FALL_TILT = math.radians(40.0)


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
