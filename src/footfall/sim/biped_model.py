"""MuJoCo model of the biped Archie, generated from a :class:`BipedSpec` as an MJCF string.

The hip (pelvis) with the torso on it floats on a free joint; each leg is the chain of
:mod:`footfall.biped.body` (hip yaw, roll, pitch; knee; ankle pitch, roll) ending in a flat
box foot with a touch sensor in each corner. Obstacles (boxes and cylinders standing on
the floor) are their own geoms, named ``obstacle_*``, so contacts with them can be counted.
An IMU (orientation, gyro, accelerometer) sits at the hip frame and a depth camera on the
head. Servos are position actuators integrated with ``implicitfast``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from footfall.biped.body import JOINTS, SIDES, BipedSpec
from footfall.robot.spec import CameraPlacement
from footfall.sim.model import ROBOT_GEOM_GROUP, CameraMount

TIMESTEP = 0.002  # [s]
LEG_RADIUS = 0.03  # capsule radius of thigh and shank [m]
OBSTACLE_PREFIX = "obstacle_"
# The corners of a foot, in the order of its touch sensors: front left, front right, back
# right, back left (x forward, y left).
CORNERS = ((1, 1), (1, -1), (-1, -1), (-1, 1))
# Mass of the small bodies between the hip axes, taken from the thigh's [kg].
HIP_LINK_MASS = 0.05


@dataclass(frozen=True)
class Obstacle:
    """A box or an upright cylinder standing on the floor.

    Attributes:
        kind: ``"box"`` or ``"cylinder"``.
        x: Centre [m].
        y: Centre [m].
        size_x: Box length, or the cylinder's diameter [m].
        size_y: Box width (ignored for a cylinder) [m].
        height: Height above the floor [m].
        yaw: Box heading [rad].
    """

    kind: str
    x: float
    y: float
    size_x: float
    size_y: float
    height: float
    yaw: float = 0.0

    @property
    def radius(self) -> float:
        """The radius of the circle that covers its footprint [m]."""
        if self.kind == "cylinder":
            return 0.5 * self.size_x
        return 0.5 * math.hypot(self.size_x, self.size_y)

    def mjcf(self, name: str) -> str:
        """The ``<geom>`` element."""
        z = 0.5 * self.height
        if self.kind == "cylinder":
            return (
                f'<geom name="{name}" class="obstacle" type="cylinder" '
                f'pos="{self.x:.6g} {self.y:.6g} {z:.6g}" size="{0.5 * self.size_x:.6g} {z:.6g}"/>'
            )
        return (
            f'<geom name="{name}" class="obstacle" type="box" pos="{self.x:.6g} {self.y:.6g} '
            f'{z:.6g}" size="{0.5 * self.size_x:.6g} {0.5 * self.size_y:.6g} {z:.6g}" '
            f'euler="0 0 {self.yaw:.9g}"/>'
        )


def joint_names() -> list[str]:
    """MJCF joint names in actuator order: left leg then right, each in ``JOINTS`` order."""
    return [f"{side}_{j}" for side in SIDES for j in JOINTS]


def camera_mount(spec: BipedSpec, width: int = 160, height: int = 120) -> CameraMount:
    """The head camera (a RealSense-like depth camera) at the spec's mount."""
    return CameraMount(
        placement=CameraPlacement(position_in_body=spec.camera_position, pitch=spec.camera_pitch),
        width=width,
        height=height,
        max_range=4.0,
    )


def _fmt(values: object) -> str:
    return " ".join(f"{float(v):.6g}" for v in np.ravel(values))


def _leg_xml(spec: BipedSpec, side: str) -> str:
    s = spec.side_sign(side)
    lim = spec.limits
    m_thigh, m_shank, m_link, m_foot = spec.leg_masses
    m_thigh -= 2 * HIP_LINK_MASS
    off = s * spec.hip_offset
    hl, hw, t = 0.5 * spec.foot_length, 0.5 * spec.foot_width, spec.foot_thickness
    sole = -spec.ankle_height
    sites = "\n".join(
        f'              <site name="{side}_foot_{k}" pos="{cx * hl:.6g} {cy * hw:.6g} {sole:.6g}" '
        f'size="0.012"/>'
        for k, (cx, cy) in enumerate(CORNERS)
    )
    n = side

    def rng(j: str) -> str:
        return _fmt(lim[j])

    small = f'<inertial pos="0 0 0" mass="{HIP_LINK_MASS}" diaginertia="1e-4 1e-4 1e-4"/>'
    return f"""
      <body name="{n}_hip_yaw" pos="{_fmt(spec.hip_joint(side))}">
        <joint name="{n}_hip_yaw" axis="0 0 1" range="{rng("hip_yaw")}"
               actuatorfrcrange="{-spec.servo.hip_yaw_max_torque} {spec.servo.hip_yaw_max_torque}"/>
        {small}
        <body name="{n}_hip_roll">
          <joint name="{n}_hip_roll" axis="1 0 0" range="{rng("hip_roll")}"/>
          {small}
          <body name="{n}_thigh">
            <joint name="{n}_hip_pitch" axis="0 1 0" range="{rng("hip_pitch")}"/>
            <geom name="{n}_thigh" type="capsule"
                  fromto="0 {off:.6g} -0.04 0 {off:.6g} {-spec.thigh + 0.04:.6g}"
                  mass="{m_thigh:.6g}"/>
            <body name="{n}_shank" pos="0 {off:.6g} {-spec.thigh:.6g}">
              <joint name="{n}_knee" axis="0 1 0" range="{rng("knee")}"/>
              <geom name="{n}_shank" type="capsule" fromto="0 0 -0.03 0 0 {-spec.shank + 0.03:.6g}"
                    size="{0.8 * LEG_RADIUS:.6g}" mass="{m_shank:.6g}"/>
              <body name="{n}_ankle" pos="0 0 {-spec.shank:.6g}">
                <joint name="{n}_ankle_pitch" axis="0 1 0" range="{rng("ankle_pitch")}"/>
                <geom name="{n}_ankle" type="capsule"
                      fromto="0 0 -0.02 0 0 {-spec.ankle_link + 0.02:.6g}"
                      size="{0.6 * LEG_RADIUS:.6g}" mass="{m_link:.6g}"/>
                <body name="{n}_foot" pos="0 0 {-spec.ankle_link:.6g}">
                  <joint name="{n}_ankle_roll" axis="1 0 0" range="{rng("ankle_roll")}"/>
                  <geom name="{n}_foot" class="foot" type="box" pos="0 0 {sole + 0.5 * t:.6g}"
                        size="{hl:.6g} {hw:.6g} {0.5 * t:.6g}" mass="{m_foot:.6g}"/>
                  <site name="{n}_sole" pos="0 0 {sole:.6g}" size="0.005"/>
{sites}
                </body>
              </body>
            </body>
          </body>
        </body>
      </body>"""


def biped_mjcf(
    spec: BipedSpec,
    obstacles: tuple[Obstacle, ...] = (),
    camera: CameraMount | None = None,
    hip_position: tuple[float, float, float] | None = None,
    hip_yaw: float = 0.0,
) -> str:
    """MJCF of the biped on a flat floor among obstacles.

    Args:
        spec: The robot.
        obstacles: Boxes and cylinders on the floor.
        camera: Depth camera on the head, if any.
        hip_position: Hip frame position at load time [m]; the walking height over the
            origin when None.
        hip_yaw: Heading at load time [rad].
    """
    pos = (0.0, 0.0, spec.hip_height) if hip_position is None else hip_position
    servo = spec.servo
    actuators = "\n    ".join(f'<position name="{j}" joint="{j}"/>' for j in joint_names())
    touch = "\n    ".join(
        f'<touch name="{side}_foot_{k}" site="{side}_foot_{k}"/>'
        for side in SIDES
        for k in range(len(CORNERS))
    )
    px, py, pz = (0.5 * v for v in spec.pelvis_size)
    tx, ty, tz = (0.5 * v for v in spec.torso_size)
    walls = "\n    ".join(o.mjcf(f"{OBSTACLE_PREFIX}{k}") for k, o in enumerate(obstacles))
    half = 0.5 * hip_yaw
    quat = f"{math.cos(half):.9g} 0 0 {math.sin(half):.9g}"
    legs = "".join(_leg_xml(spec, side) for side in SIDES)
    return f"""<mujoco model="biped-{spec.name}">
  <compiler angle="radian" autolimits="true"/>
  <option timestep="{TIMESTEP}" integrator="implicitfast" cone="elliptic" impratio="10"/>
  <statistic extent="2" center="0 0 0.6"/>
  <visual>
    <headlight ambient="0.35 0.35 0.35" diffuse="0.6 0.6 0.6"/>
  </visual>
  <default>
    <joint damping="{servo.joint_damping:.6g}" armature="{servo.armature:.6g}"/>
    <position kp="{servo.kp:.6g}" kv="{servo.kv:.6g}"
              forcerange="{-servo.max_torque:.6g} {servo.max_torque:.6g}"/>
    <geom contype="2" conaffinity="1" group="{ROBOT_GEOM_GROUP}" size="{LEG_RADIUS:.6g}"
          rgba="0.25 0.3 0.35 1"/>
    <site group="3" rgba="0.9 0.2 0.2 1"/>
    <default class="foot">
      <geom friction="{spec.foot_friction:.6g} 0.02 0.001" rgba="0.1 0.1 0.1 1"/>
    </default>
    <default class="obstacle">
      <geom contype="1" conaffinity="2" group="0" rgba="0.75 0.25 0.2 1"/>
    </default>
  </default>
  <asset>
    <texture name="grid" type="2d" builtin="checker" rgb1="0.82 0.82 0.8" rgb2="0.7 0.7 0.68"
             width="512" height="512" mark="edge" markrgb="0.5 0.5 0.5"/>
    <material name="grid" texture="grid" texrepeat="1 1" texuniform="true"/>
  </asset>
  <worldbody>
    <light name="sun" pos="0 0 4" dir="0 0 -1" directional="true"/>
    <geom name="floor" type="plane" size="0 0 0.05" material="grid" contype="1" conaffinity="2"
          group="0" friction="1 0.02 0.001"/>
    {walls}
    <body name="hip" pos="{_fmt(pos)}" quat="{quat}">
      <freejoint name="root"/>
      <geom name="pelvis" type="box" size="{px:.6g} {py:.6g} {pz:.6g}" mass="{spec.pelvis_mass:.6g}"
            rgba="0.85 0.45 0.1 1"/>
      <geom name="torso" type="box" pos="0 0 {spec.torso_height:.6g}"
            size="{tx:.6g} {ty:.6g} {tz:.6g}" mass="{spec.torso_mass:.6g}" rgba="0.85 0.45 0.1 1"/>
      <site name="imu" pos="0 0 0" size="0.01"/>
      {camera.mjcf() if camera is not None else ""}
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
    {touch}
  </sensor>
</mujoco>
"""
