"""The generated MuJoCo model: healthy physics and the same kinematics as the library."""

from __future__ import annotations

import dataclasses

import mujoco
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from footfall.errors import ConfigError
from footfall.messages import JointTargets
from footfall.robot.kinematics import LegKinematics
from footfall.robot.spec import CameraPlacement, load_spec
from footfall.sim.hexapod import MujocoHexapod
from footfall.sim.model import CameraMount, hexapod_mjcf


def test_every_generated_model_steps_without_warnings(any_spec):
    """Each robot's model stands for 1 s of physics with no MuJoCo warning."""
    sim = MujocoHexapod(any_spec)
    hold = sim.read().joint_positions
    sim.command(JointTargets(hold, np.zeros((6, 3))))
    sim.advance(1.0)
    assert sim.warnings() == {}
    assert sim.model.opt.integrator == mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    state = sim.read()
    assert np.degrees(state.tilt) < 0.5
    assert state.feet_in_contact.all()
    assert sim.body_height_above() == pytest.approx(any_spec.body_height, abs=0.01)


def test_model_compiles_from_xml(default_spec):
    """The MJCF string is a complete model with 18 hinge joints and 18 actuators."""
    model = mujoco.MjModel.from_xml_string(hexapod_mjcf(default_spec))
    assert model.nu == 18
    assert int(np.sum(model.jnt_type == mujoco.mjtJoint.mjJNT_HINGE)) == 18


SIMS = {name: MujocoHexapod(load_spec(name)) for name in ("default", "phantomx")}


@given(st.sampled_from(sorted(SIMS)), st.lists(st.floats(0.0, 1.0), min_size=18, max_size=18))
@settings(max_examples=50, deadline=None)
def test_simulator_and_library_agree_on_forward_kinematics(name, unit):
    """Joint angles put the simulated feet exactly where LegKinematics says (angle convention)."""
    sim = SIMS[name]
    kin = LegKinematics(sim.spec)
    angles = kin.lower + np.array(unit).reshape(6, 3) * (kin.upper - kin.lower)
    data = mujoco.MjData(sim.model)
    data.qpos[2] = 1.0
    data.qpos[3] = 1.0  # identity quaternion, body at (0, 0, 1)
    data.qpos[sim._qpos_index] = angles.ravel()
    mujoco.mj_kinematics(sim.model, data)
    feet_in_world = data.site_xpos[sim._foot_sites]
    np.testing.assert_allclose(
        feet_in_world - [0.0, 0.0, 1.0], kin.forward_in_body(angles), atol=1e-9
    )


@given(
    st.tuples(*[st.floats(-0.2, 0.2)] * 3),
    st.floats(-1.3, 1.3),
    st.floats(-np.pi, np.pi),
    st.floats(-np.pi, np.pi),
)
@settings(max_examples=25, deadline=None)
def test_the_simulated_camera_sits_where_the_robot_description_puts_it(position, pitch, roll, yaw):
    """The robot's [camera] placement is the simulated camera's optical frame on the body, in
    position and in every axis (the image's right, down and the optical axis)."""
    spec = dataclasses.replace(
        SIMS["phantomx"].spec, camera=CameraPlacement(position, pitch, roll, yaw)
    )
    model = mujoco.MjModel.from_xml_string(
        hexapod_mjcf(spec, camera=CameraMount(width=8, height=6))
    )
    data = mujoco.MjData(model)
    data.qpos[2] = 1.0
    data.qpos[3] = 1.0  # identity quaternion, body at (0, 0, 1)
    mujoco.mj_kinematics(model, data)
    mujoco.mj_camlight(model, data)
    optical = spec.camera.optical_in_body()
    camera = model.camera("depth").id
    np.testing.assert_allclose(data.cam_xpos[camera] - [0.0, 0.0, 1.0], position, atol=1e-6)
    # MuJoCo's camera looks along its -z with its y up: the optical z and -y.
    mujoco_axes = data.cam_xmat[camera].reshape(3, 3)
    optical_axes = optical.rotation.as_matrix()
    np.testing.assert_allclose(mujoco_axes[:, 0], optical_axes[:, 0], atol=1e-7)
    np.testing.assert_allclose(mujoco_axes[:, 1], -optical_axes[:, 1], atol=1e-7)
    np.testing.assert_allclose(mujoco_axes[:, 2], -optical_axes[:, 2], atol=1e-7)
    forward = optical_axes[:, 2]
    assert np.degrees(np.arcsin(-forward[2])) == pytest.approx(np.degrees(pitch), abs=1e-6)


def test_a_camera_of_its_own_is_not_moved_to_the_robots_place():
    """A mount with a placement keeps it; one without takes the robot's."""
    spec = SIMS["phantomx"].spec
    own = CameraPlacement((0.1, 0.0, 0.2), 0.9)
    assert CameraMount(placement=own).on(spec.camera).placement == own
    assert CameraMount().on(spec.camera).placement == spec.camera
    with pytest.raises(ConfigError, match="place on the body"):
        CameraMount().mjcf()
