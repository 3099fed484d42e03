"""MuJoCo model of a hexapod, generated from a :class:`HexapodSpec` as an MJCF string.

The body is a box on a free joint; each leg is a chain coxa (yaw) -> femur (pitch) ->
tibia (pitch) with a spherical foot. Joint zero angles and signs follow ``docs/frames.md``,
so the angles the kinematics module computes are the simulator's joint positions. Servos
are position actuators with high gain and high damping (thesis §3.3), integrated with
``implicitfast`` so the damping stays stable at a 2 ms step.
"""

from __future__ import annotations

import numpy as np

from footfall.robot.spec import HexapodSpec

TIMESTEP = 0.002  # [s]
LEG_RADIUS = 0.008  # capsule radius of the leg segments [m]


def joint_names(spec: HexapodSpec) -> list[str]:
    """MJCF joint names in actuator order: for each leg, coxa, femur, tibia."""
    return [f"{leg}_{part}" for leg in spec.leg_names for part in ("coxa", "femur", "tibia")]


def _fmt(values: object) -> str:
    return " ".join(f"{float(v):.6g}" for v in np.ravel(values))


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
    spec: HexapodSpec, terrain_xml: str = "", initial_height: float | None = None
) -> str:
    """MJCF of the robot standing over a floor.

    Args:
        spec: The robot.
        terrain_xml: Extra ``<worldbody>`` elements (terrain geoms) placed beside the floor.
        initial_height: Height of the body frame at load time [m]; the nominal height if None.

    Returns:
        The model as an MJCF string.
    """
    height = spec.body_height if initial_height is None else initial_height
    sx, sy, sz = (0.5 * s for s in spec.body_size)
    servo = spec.servo
    legs = "".join(_leg_xml(spec, i) for i in range(len(spec.mounts)))
    actuators = "\n    ".join(f'<position name="{j}" joint="{j}"/>' for j in joint_names(spec))
    sensors = "\n    ".join(f'<touch name="{n}_touch" site="{n}_foot"/>' for n in spec.leg_names)
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
    <geom contype="2" conaffinity="1" size="{LEG_RADIUS:.6g}" rgba="0.25 0.3 0.35 1"/>
    <default class="foot">
      <geom type="sphere" friction="{spec.foot_friction:.6g} 0.02 0.001" mass="0.005"
            rgba="0.1 0.1 0.1 1"/>
    </default>
    <default class="terrain">
      <geom contype="1" conaffinity="2" rgba="0.62 0.58 0.52 1" friction="1 0.02 0.001"/>
    </default>
  </default>
  <asset>
    <texture name="grid" type="2d" builtin="checker" rgb1="0.82 0.82 0.8" rgb2="0.7 0.7 0.68"
             width="512" height="512" mark="edge" markrgb="0.5 0.5 0.5"/>
    <material name="grid" texture="grid" texrepeat="1 1" texuniform="true"/>
  </asset>
  <worldbody>
    <light name="sun" pos="0 0 4" dir="0 0 -1" directional="true"/>
    <geom name="floor" class="terrain" type="plane" size="0 0 0.05" material="grid"/>
    {terrain_xml}
    <body name="torso" pos="0 0 {height:.6g}">
      <freejoint name="root"/>
      <geom name="torso" type="box" size="{sx:.6g} {sy:.6g} {sz:.6g}" mass="{spec.body_mass:.6g}"
            rgba="0.85 0.45 0.1 1"/>
      <site name="imu" pos="0 0 0" size="0.01"/>
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
