"""Archie's body: spec, closed-form leg kinematics against the model and §4.4, the gait."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from footfall.biped.archie import support_leg_angles, swing_leg_angles
from footfall.biped.body import SIDES, leg_forward, leg_inverse, load_biped_spec
from footfall.biped.footsteps import footsteps_from_parameters
from footfall.biped.gait import SUPPORT_DOUBLE, gait_pattern
from footfall.biped.lipm import GRAVITY, WalkParameter
from footfall.errors import ConfigError, UnreachableTargetError
from footfall.sim.biped_model import biped_mjcf

SPEC = load_biped_spec()
ANGLES = st.tuples(
    st.floats(-0.5, 0.5),
    st.floats(-0.35, 0.35),
    st.floats(-1.2, 0.5),
    st.floats(0.05, 1.8),
    st.floats(-0.8, 0.8),
    st.floats(-0.4, 0.4),
)


def test_the_spec_adds_up_to_archie():
    """Appendix A's leg (68.6 cm in the text) and the dissertation's 20 kg."""
    assert SPEC.mass == pytest.approx(20.0)
    assert SPEC.ankle_link + SPEC.shank + SPEC.thigh == pytest.approx(0.69)


@given(ANGLES, st.sampled_from(SIDES))
@settings(max_examples=300, deadline=None)
def test_inverse_kinematics_returns_the_angles_forward_kinematics_started_from(q, side):
    """Round trip: angles -> sole pose -> angles, for poses with the knee bent back."""
    sole, rotation = leg_forward(SPEC, side, q)
    np.testing.assert_allclose(leg_inverse(SPEC, side, sole, rotation), q, atol=1e-9)


@given(st.lists(ANGLES, min_size=2, max_size=2))
@settings(max_examples=30, deadline=None)
def test_the_generated_model_has_the_kinematics_of_the_module(angles):
    """MuJoCo's sole sites sit where leg_forward puts them, in the hip frame."""
    model = mujoco.MjModel.from_xml_string(biped_mjcf(SPEC))
    data = mujoco.MjData(model)
    q = np.concatenate(angles)
    data.qpos[7:] = q
    mujoco.mj_kinematics(model, data)
    hip = model.body("hip").id
    r_hip = data.xmat[hip].reshape(3, 3)
    for k, side in enumerate(SIDES):
        site = model.site(f"{side}_sole").id
        sole, rotation = leg_forward(SPEC, side, q[6 * k : 6 * k + 6])
        np.testing.assert_allclose(
            r_hip.T @ (data.site_xpos[site] - data.xpos[hip]), sole, atol=1e-9
        )
        np.testing.assert_allclose(
            r_hip.T @ data.site_xmat[site].reshape(3, 3), rotation, atol=1e-9
        )


@given(st.floats(-0.15, 0.15), st.floats(0.02, 0.2))
@settings(max_examples=200, deadline=None)
def test_support_leg_relations_of_section_4_4_are_a_case_of_the_inverse(x_com, y_com):
    """Eqs. 41-43 and 54: with the knee straight and the trunk upright, the hip centre over
    the right foot at (x_com, y_com) needs ankle roll theta0, ankle pitch theta1, hip roll
    -theta0 and hip pitch -theta1 (in the model's signs: pitch about +y)."""
    theta = support_leg_angles(x_com, y_com)
    q = np.array([0.0, -theta[0], theta[1], 0.0, -theta[1], theta[0]])
    sole, rotation = leg_forward(SPEC, "right", q)
    np.testing.assert_allclose(-sole[:2], (x_com, y_com), atol=1e-9)  # the hip over the foot
    np.testing.assert_allclose(rotation, np.eye(3), atol=1e-9)  # foot flat, trunk upright
    np.testing.assert_allclose(leg_inverse(SPEC, "right", sole), q, atol=1e-7)


@given(st.floats(-0.2, 0.2), st.floats(0.3, 0.55))
@settings(max_examples=200, deadline=None)
def test_swing_leg_relations_of_section_4_4_are_a_case_of_the_inverse(advance, height):
    """Eqs. 46-52: a level swing foot ``advance`` ahead of and ``height`` below the hip."""
    if not abs(SPEC.thigh - SPEC.shank) < math.hypot(advance, height) < SPEC.shank + SPEC.thigh:
        return
    hip, knee, ankle = swing_leg_angles(advance, height)
    sole = SPEC.hip_joint("left") + np.array(
        [advance, SPEC.hip_offset, -height - SPEC.ankle_link - SPEC.ankle_height]
    )
    q = leg_inverse(SPEC, "left", sole)
    np.testing.assert_allclose(q, [0.0, 0.0, -hip, knee, -ankle, 0.0], atol=1e-9)


def test_an_out_of_reach_foot_is_refused_by_name():
    with pytest.raises(UnreachableTargetError, match=r"leg left.*reaches"):
        leg_inverse(SPEC, "left", [0.0, 0.1, -1.2])


def test_a_spec_without_a_section_names_it(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text('name = "x"\n[leg]\nthigh = 0.3\n')
    with pytest.raises(ConfigError, match="lacks the key"):
        load_biped_spec(bad)


KAJITA = [WalkParameter(sx, 0.2) for sx in (0.0, 0.3, 0.3, 0.3, 0.0)]
FEET = {"left": (0.0, 0.1, 0.0), "right": (0.0, -0.1, 0.0)}


def test_the_gait_com_makes_the_planned_zmp_through_the_cart_table():
    """The COM pattern's cart-table ZMP, p = x - (z_c / g) x'', follows the reference,
    which stays on the support foot in single support; every swing ends on its foothold."""
    steps = footsteps_from_parameters(KAJITA, (0.0, 0.0), first_step_left=False)
    g = gait_pattern(steps, FEET, 0.62)
    dt = g.time[1] - g.time[0]
    accel = (g.com[2:] - 2 * g.com[1:-1] + g.com[:-2]) / dt**2
    zmp = g.com[1:-1] - g.com_height / GRAVITY * accel
    error = np.linalg.norm(zmp - g.zmp[1:-1], axis=1)
    assert np.percentile(error, 99) < 0.005 and error.max() < 0.03
    single = g.support != SUPPORT_DOUBLE
    assert single.any()
    for n, side in enumerate(g.foothold_sides[1:], start=1):
        landed = g.feet[side][g.index(g.landing_time[n] + 0.01)]
        np.testing.assert_allclose(landed[:2], g.footholds[n], atol=1e-9)
        assert landed[2] == 0.0
    assert np.max(g.feet["left"][:, 2]) == pytest.approx(0.05, abs=1e-3)


def test_a_spec_that_is_not_text_or_not_there_is_refused(tmp_path):
    binary = tmp_path / "archie.toml"
    binary.write_bytes(b"\xff\xfe\x00name")
    with pytest.raises(ConfigError, match="not UTF-8"):
        load_biped_spec(binary)
    with pytest.raises(ConfigError, match="neither a built-in robot"):
        load_biped_spec(tmp_path / "missing.toml")
