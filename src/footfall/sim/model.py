"""MuJoCo model of a hexapod, generated from a :class:`HexapodSpec` as an MJCF string.

The body is a box on a free joint; each leg is a chain coxa (yaw) -> femur (pitch) ->
tibia (pitch) with a spherical foot. Joint zero angles and signs follow ``docs/frames.md``,
so the angles the kinematics module computes are the simulator's joint positions. Servos
are position actuators with high gain and high damping (thesis §3.3), integrated with
``implicitfast`` so the damping stays stable at a 2 ms step.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from footfall.checks import require_positive
from footfall.errors import ConfigError
from footfall.robot.spec import CameraPlacement, HexapodSpec
from footfall.sim.terrain import TerrainXml

TIMESTEP = 0.002  # [s]
ROBOT_GEOM_GROUP = 1  # robot geoms; terrain geoms stay in group 0
LEG_RADIUS = 0.008  # capsule radius of the leg segments [m]


@dataclass(frozen=True)
class CameraMount:
    """A depth camera on the body, looking ahead and down (a RealSense D435i by default).

    Where it sits is the robot's (:attr:`HexapodSpec.camera`, the ``[camera]`` table of its
    TOML) unless ``placement`` says otherwise. The default robot's puts it at the front of the
    body on a short mast, 8 cm above the body frame, tilted 30 degrees down: from there it
    sees the ground from just ahead of the front feet to about 1.5 m, and about as wide.

    Attributes:
        placement: Where it sits on the body; None: where the robot's description puts it.
        horizontal_fov: Horizontal field of view [rad].
        vertical_fov: Vertical field of view [rad].
        width: Image width [px].
        height: Image height [px].
        rate_hz: Frame rate [Hz].
        max_range: Farthest usable depth [m].
    """

    placement: CameraPlacement | None = None
    horizontal_fov: float = math.radians(87.0)
    vertical_fov: float = math.radians(58.0)
    width: int = 640
    height: int = 480
    rate_hz: float = 15.0
    max_range: float = 3.0

    def __post_init__(self) -> None:
        if not (0 < self.horizontal_fov < math.pi and 0 < self.vertical_fov < math.pi):
            raise ConfigError("camera fields of view must lie between 0 and pi")
        require_positive(
            "camera",
            width=self.width,
            height=self.height,
            rate_hz=self.rate_hz,
            max_range=self.max_range,
        )

    @property
    def focal_lengths(self) -> tuple[float, float]:
        """``(fx, fy)`` [px]."""
        return (
            0.5 * self.width / math.tan(0.5 * self.horizontal_fov),
            0.5 * self.height / math.tan(0.5 * self.vertical_fov),
        )

    def on(self, robot: CameraPlacement) -> CameraMount:
        """This camera, placed where ``robot`` puts it unless it has a placement of its own."""
        return self if self.placement is not None else replace(self, placement=robot)

    def mjcf(self) -> str:
        """The ``<camera>`` element (MuJoCo cameras look along -z with y up).

        Raises:
            ConfigError: The camera has no placement (see :meth:`on`).
        """
        if self.placement is None:
            raise ConfigError("a camera needs a place on the body: CameraMount.on(spec.camera)")
        optical = self.placement.optical_in_body()
        # MuJoCo's camera x is the image's right, its y the image's up (the optical -y).
        x_axis, down = optical.rotation.as_matrix()[:, 0], optical.rotation.as_matrix()[:, 1]
        fx, fy = self.focal_lengths
        # Pixel size is arbitrary for MuJoCo; 1 um makes focal lengths in pixels exact.
        pixel = 1e-6
        return (
            f'<camera name="depth" pos="{_fmt(self.placement.position_in_body)}" '
            f'xyaxes="{_fmt9(x_axis)} {_fmt9(-down)}" resolution="{self.width} {self.height}" '
            f'sensorsize="{self.width * pixel:.9g} {self.height * pixel:.9g}" '
            f'focalpixel="{fx:.9g} {fy:.9g}" principalpixel="0 0"/>'
        )


def joint_names(spec: HexapodSpec) -> list[str]:
    """MJCF joint names in actuator order: for each leg, coxa, femur, tibia."""
    return [f"{leg}_{part}" for leg in spec.leg_names for part in ("coxa", "femur", "tibia")]


def _fmt(values: object) -> str:
    return " ".join(f"{float(v):.6g}" for v in np.ravel(values))


def _fmt9(values: object) -> str:
    """Nine digits; a rotation's rounding noise (1e-17 for an exact 0) written as 0."""
    return " ".join(f"{float(v) + 0.0:.9g}" for v in np.round(np.ravel(values), 12))


def _leg_xml(spec: HexapodSpec, index: int) -> str:
    mount = spec.mounts[index]
    name = mount.name
    lim = spec.limits
    m_coxa, m_femur, m_tibia = spec.segment_masses
    L1, L2, L3 = spec.coxa_length, spec.femur_length, spec.tibia_length
    return f"""
      <body name="{name}_coxa" pos="{_fmt(mount.position_in_body)}" euler="0 0 {mount.yaw:.9g}">
        <joint name="{name}_coxa" axis="0 0 1" range="{_fmt(lim.coxa)}"/>
        <geom name="{name}_coxa" type="capsule" fromto="0 0 0 {L1:.6g} 0 0" mass="{m_coxa:.6g}"/>
        <body name="{name}_femur" pos="{L1:.6g} 0 0">
          <joint name="{name}_femur" axis="0 -1 0" range="{_fmt(lim.femur)}"/>
          <geom name="{name}_femur" type="capsule" fromto="0 0 0 {L2:.6g} 0 0"
                mass="{m_femur:.6g}"/>
          <body name="{name}_tibia" pos="{L2:.6g} 0 0">
            <joint name="{name}_tibia" axis="0 -1 0" range="{_fmt(lim.tibia)}"/>
            <geom name="{name}_tibia" type="capsule" fromto="0 0 0 {L3 - spec.foot_radius:.6g} 0 0"
                  mass="{m_tibia:.6g}"/>
            <geom name="{name}_foot" class="foot" pos="{L3:.6g} 0 0" size="{spec.foot_radius:.6g}"/>
            <site name="{name}_foot" pos="{L3:.6g} 0 0" size="{1.25 * spec.foot_radius:.6g}"/>
          </body>
        </body>
      </body>"""


def hexapod_mjcf(
    spec: HexapodSpec,
    terrain: TerrainXml | None = None,
    camera: CameraMount | None = None,
    initial_position: tuple[float, float, float] | None = None,
) -> str:
    """MJCF of the robot on a terrain.

    Args:
        spec: The robot.
        terrain: Terrain pieces; the bare floor when None.
        camera: Depth camera on the body, if any.
        initial_position: Body position at load time [m]; above the origin at the nominal
            height when None.

    Returns:
        The model as an MJCF string.
    """
    terrain = terrain or TerrainXml()
    position = (0.0, 0.0, spec.body_height) if initial_position is None else initial_position
    height = position[2]
    sx, sy, sz = (0.5 * s for s in spec.body_size)
    servo = spec.servo
    legs = "".join(_leg_xml(spec, i) for i in range(len(spec.mounts)))
    actuators = "\n    ".join(f'<position name="{j}" joint="{j}"/>' for j in joint_names(spec))
    sensors = "\n    ".join(f'<touch name="{n}_touch" site="{n}_foot"/>' for n in spec.leg_names)
    # Without its own floor a terrain still gets a plane far below, so a robot that walks
    # off it falls onto something.
    floor_z = 0.0 if terrain.floor else -1.0
    floor = (
        f'<geom name="floor" class="terrain" type="plane" pos="0 0 {floor_z}" size="0 0 0.05" '
        'material="grid"/>'
    )
    extent = max(spec.body_size) + 2 * (spec.coxa_length + spec.femur_length + spec.tibia_length)
    return f"""<mujoco model="hexapod-{spec.name}">
  <compiler angle="radian" autolimits="true"/>
  <option timestep="{TIMESTEP}" integrator="implicitfast" cone="elliptic" impratio="10"/>
  <statistic extent="{extent:.4g}" center="0 0 {height:.4g}"/>
  <visual>
    <headlight ambient="0.35 0.35 0.35" diffuse="0.6 0.6 0.6"/>
  </visual>
  <default>
    <joint damping="{servo.joint_damping:.6g}" armature="{servo.armature:.6g}"/>
    <position kp="{servo.kp:.6g}" kv="{servo.kv:.6g}"
              forcerange="{-servo.max_torque:.6g} {servo.max_torque:.6g}"/>
    <geom contype="2" conaffinity="1" group="1" size="{LEG_RADIUS:.6g}" rgba="0.25 0.3 0.35 1"/>
    <default class="foot">
      <geom type="sphere" friction="{spec.foot_friction:.6g} 0.02 0.001" mass="0.005"
            rgba="0.1 0.1 0.1 1"/>
    </default>
    <default class="terrain">
      <geom contype="1" conaffinity="2" group="0" rgba="0.62 0.58 0.52 1" friction="1 0.02 0.001"/>
    </default>
  </default>
  <asset>
    <texture name="grid" type="2d" builtin="checker" rgb1="0.82 0.82 0.8" rgb2="0.7 0.7 0.68"
             width="512" height="512" mark="edge" markrgb="0.5 0.5 0.5"/>
    <material name="grid" texture="grid" texrepeat="1 1" texuniform="true"/>
    {terrain.assets}
  </asset>
  <worldbody>
    <light name="sun" pos="0 0 4" dir="0 0 -1" directional="true"/>
    {floor}
    {terrain.worldbody}
    <body name="torso" pos="{_fmt(position)}">
      <freejoint name="root"/>
      <geom name="torso" type="box" size="{sx:.6g} {sy:.6g} {sz:.6g}" mass="{spec.body_mass:.6g}"
            rgba="0.85 0.45 0.1 1"/>
      <site name="imu" pos="0 0 0" size="0.01"/>
      {camera.on(spec.camera).mjcf() if camera is not None else ""}
      {legs}
    </body>
  </worldbody>
  <actuator>
    {actuators}
  </actuator>
  <sensor>
    <framequat name="imu_quat" objtype="site" objname="imu"/>
    <gyro name="imu_gyro" site="imu"/>
    <accelerometer name="imu_accel" site="imu"/>
    {sensors}
  </sensor>
</mujoco>
"""
