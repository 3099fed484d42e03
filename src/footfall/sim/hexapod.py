"""The simulated hexapod: a MuJoCo model behind the :class:`HexapodBackend` interface."""

from __future__ import annotations

import mujoco
import numpy as np
import numpy.typing as npt
from scipy.spatial.transform import Rotation

from footfall.backends import BackendSetup
from footfall.errors import ConfigError
from footfall.messages import JointTargets, RobotState
from footfall.robot.kinematics import LegKinematics
from footfall.robot.spec import HexapodSpec
from footfall.sim.model import CameraMount, hexapod_mjcf, joint_names
from footfall.sim.terrain import Flat, Terrain


class MujocoHexapod:
    """A hexapod simulated in MuJoCo, standing on its rest stance at the terrain's start.

    Args:
        spec: The robot.
        terrain: The ground; flat when None.
        camera: A depth camera on the body (see :class:`footfall.sim.camera.SimDepthCamera`).
        body_height: Initial body height above the ground [m]; the spec's by default.
    """

    realtime = False

    def __init__(
        self,
        spec: HexapodSpec,
        terrain: Terrain | None = None,
        camera: CameraMount | None = None,
        body_height: float | None = None,
    ) -> None:
        self.spec = spec
        self.terrain = terrain or Flat()
        self.camera_mount = None if camera is None else camera.on(spec.camera)
        height = spec.body_height if body_height is None else body_height
        x0, y0 = self.terrain.start
        ground = float(self.terrain.height(x0, y0))
        pieces = self.terrain.mjcf()
        self.xml = hexapod_mjcf(
            spec, pieces, self.camera_mount, initial_position=(x0, y0, ground + height)
        )
        self.model = mujoco.MjModel.from_xml_string(self.xml)
        for field in pieces.height_fields:
            hfield = self.model.hfield(field.name)
            start = int(hfield.adr[0])
            self.model.hfield_data[start : start + field.elevation.size] = field.elevation.ravel()
        self.data = mujoco.MjData(self.model)
        names = joint_names(spec)
        self._qpos_index = np.array([self.model.joint(n).qposadr[0] for n in names])
        self._qvel_index = np.array([self.model.joint(n).dofadr[0] for n in names])
        self._foot_sites = np.array([self.model.site(f"{n}_foot").id for n in spec.leg_names])
        self._touch = [self.model.sensor(f"{n}_touch") for n in spec.leg_names]
        self._quat = self.model.sensor("imu_quat")
        self._gyro = self.model.sensor("imu_gyro")
        self._torso = self.model.body("torso").id
        servo = spec.servo
        self._feedforward_gain = servo.kv / servo.kp
        kinematics = LegKinematics(spec)
        feet = spec.rest_feet_in_body(height)
        feet[:, 2] += spec.foot_radius
        angles = kinematics.inverse_in_body(feet)
        self.data.qpos[self._qpos_index] = angles.ravel()
        self.data.ctrl[:] = angles.ravel()
        mujoco.mj_forward(self.model, self.data)
        self._servo_gains = self.model.actuator_gainprm[:, 0].copy()
        self._servo_bias = self.model.actuator_biasprm[:, 1:3].copy()
        self.torque = True

    @classmethod
    def open(cls, setup: BackendSetup) -> MujocoHexapod:
        """The simulated robot on ``setup.world`` (a terrain; flat when None).

        ``setup.camera`` (a :class:`~footfall.sim.model.CameraMount`) goes on its body.
        """
        if setup.world is not None and not isinstance(setup.world, Terrain):
            raise ConfigError(f"the simulator stands on a terrain, not {setup.world!r}")
        if setup.camera is not None and not isinstance(setup.camera, CameraMount):
            raise ConfigError(f"the simulator's camera is a CameraMount, not {setup.camera!r}")
        return cls(setup.spec, setup.world, setup.camera, body_height=setup.body_height)

    @property
    def timestep(self) -> float:
        """Physics time step [s]."""
        return float(self.model.opt.timestep)

    def read(self) -> RobotState:
        """Joint encoders, IMU attitude and gyro, and the simulator's ground truth."""
        d = self.data
        w, x, y, z = d.sensordata[self._quat.adr[0] : self._quat.adr[0] + 4]
        touch = np.array([d.sensordata[s.adr[0]] for s in self._touch])
        return RobotState(
            time=float(d.time),
            joint_positions=d.qpos[self._qpos_index].reshape(6, 3).copy(),
            joint_velocities=d.qvel[self._qvel_index].reshape(6, 3).copy(),
            orientation_body_in_world=Rotation.from_quat([x, y, z, w]),
            angular_velocity_body_in_body=d.sensordata[
                self._gyro.adr[0] : self._gyro.adr[0] + 3
            ].copy(),
            position_body_in_world=d.xpos[self._torso].copy(),
            feet_in_world=d.site_xpos[self._foot_sites].copy(),
            feet_in_contact=touch > 1e-6,
            foot_orientations_in_world=d.site_xmat[self._foot_sites].reshape(6, 3, 3).copy(),
        )

    def command(self, targets: JointTargets) -> None:
        """Set the servo targets; the rate feed-forward cancels the servo damping's lag."""
        ctrl = targets.positions + self._feedforward_gain * targets.velocities
        self.data.ctrl[:] = ctrl.ravel()

    def set_torque(self, enabled: bool) -> None:
        """Servos on (position control) where the joints are, or off: the legs go limp."""
        if enabled and not self.torque:
            self.data.ctrl[:] = self.data.qpos[self._qpos_index]  # nothing jumps
        self.torque = bool(enabled)
        on = 1.0 if self.torque else 0.0
        self.model.actuator_gainprm[:, 0] = on * self._servo_gains
        self.model.actuator_biasprm[:, 1:3] = on * self._servo_bias

    def drive(
        self,
        positions: npt.ArrayLike,
        rates: npt.ArrayLike,
        torque: npt.ArrayLike,
    ) -> None:
        """Per-joint servo set-points [rad], their rates [rad/s] and torque on or off.

        For servos emulated joint by joint (:mod:`footfall.hardware.servo_bus`): a joint
        whose torque is off goes limp.
        """
        on = np.asarray(torque, dtype=float).ravel()
        self.data.ctrl[:] = np.ravel(positions) + self._feedforward_gain * np.ravel(rates)
        self.model.actuator_gainprm[:, 0] = on * self._servo_gains
        self.model.actuator_biasprm[:, 1:3] = on[:, None] * self._servo_bias
        self.torque = bool(on.any())

    def joints(self) -> tuple[npt.NDArray[np.float64], ...]:
        """Joint angles [rad], rates [rad/s] and servo torques [N m], shape (18,) each."""
        d = self.data
        return (
            d.qpos[self._qpos_index].copy(),
            d.qvel[self._qvel_index].copy(),
            d.actuator_force.copy(),
        )

    def advance(self, duration: float) -> None:
        """Step the physics for ``duration`` seconds (rounded to whole time steps)."""
        steps = max(1, round(duration / self.timestep))
        mujoco.mj_step(self.model, self.data, nstep=steps)

    def warnings(self) -> dict[str, int]:
        """MuJoCo warnings raised so far, by name (empty when the simulation is healthy)."""
        return {
            mujoco.mjtWarning(i).name: int(w.number)
            for i, w in enumerate(self.data.warning)
            if w.number > 0
        }

    def body_height_above(self, ground_height: float = 0.0) -> float:
        """Body frame height above a ground level [m] (ground truth)."""
        return float(self.data.xpos[self._torso][2] - ground_height)


def simulated_robot(backend: object) -> MujocoHexapod | None:
    """The MuJoCo robot behind a backend: itself, or the one it wraps (``.simulator``)."""
    if isinstance(backend, MujocoHexapod):
        return backend
    simulator = getattr(backend, "simulator", None)
    return simulator if isinstance(simulator, MujocoHexapod) else None
