"""Leg kinematics: IK/FK round trips, the Jacobian against finite differences, errors."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from footfall.errors import SingularConfigurationError, UnreachableTargetError
from footfall.robot.kinematics import LegKinematics
from footfall.robot.spec import load_spec

SPECS = {name: load_spec(name) for name in ("default", "phantomx")}
KINEMATICS = {name: LegKinematics(spec) for name, spec in SPECS.items()}


def _leg_angles(kin: LegKinematics, margin: float = 0.02) -> st.SearchStrategy[np.ndarray]:
    """One leg's joint angles in the workspace of a hexapod leg.

    Inside the limits, knee bent by at least ``margin`` rad, foot out from the coxa axis.
    """
    lower, upper = kin.lower + margin, kin.upper - margin
    upper[2] = min(upper[2], -margin)  # knee-up branch: theta3 < 0

    def reach(q: np.ndarray) -> float:
        return kin.L1 + kin.L2 * np.cos(q[1]) + kin.L3 * np.cos(q[1] + q[2])

    return (
        st.tuples(*(st.floats(float(lo), float(hi)) for lo, hi in zip(lower, upper, strict=True)))
        .map(np.array)
        .filter(lambda q: reach(q) > 0.01)
    )


@st.composite
def robot_and_angles(draw):
    name = draw(st.sampled_from(sorted(KINEMATICS)))
    kin = KINEMATICS[name]
    legs = draw(st.lists(_leg_angles(kin), min_size=6, max_size=6))
    return kin, np.stack(legs)


@given(robot_and_angles())
@settings(max_examples=300, deadline=None)
def test_fk_of_ik_returns_the_target(case):
    """FK(IK(p)) = p for every reachable foot position (reachable = FK of in-range angles)."""
    kin, angles = case
    feet = kin.forward(angles)
    np.testing.assert_allclose(kin.forward(kin.inverse(feet)), feet, atol=1e-9)


@given(robot_and_angles())
@settings(max_examples=300, deadline=None)
def test_ik_of_fk_returns_the_angles(case):
    """IK recovers knee-up joint angles exactly (the branch is unique with theta3 < 0)."""
    kin, angles = case
    np.testing.assert_allclose(kin.inverse(kin.forward(angles)), angles, atol=1e-7)


@given(robot_and_angles())
@settings(max_examples=200, deadline=None)
def test_body_frame_round_trip(case):
    """Targets given in the body frame go through body -> leg -> IK -> FK -> body unchanged."""
    kin, angles = case
    feet_in_body = kin.forward_in_body(angles)
    np.testing.assert_allclose(
        kin.forward_in_body(kin.inverse_in_body(feet_in_body)), feet_in_body, atol=1e-9
    )
    np.testing.assert_allclose(
        kin.leg_to_body(kin.body_to_leg(feet_in_body)), feet_in_body, atol=1e-12
    )


@given(robot_and_angles())
@settings(max_examples=200, deadline=None)
def test_knee_lies_a_femur_from_the_femur_joint_and_a_tibia_from_the_foot(case):
    """The knee found from a foot target is where forward kinematics of its angles puts it."""
    kin, angles = case
    feet_in_body = kin.forward_in_body(angles)
    knees_in_leg = kin.forward(np.column_stack([angles[:, 0], angles[:, 1], np.zeros(6)]))
    # The femur alone (tibia straight) ends L3 beyond the knee along the femur.
    femur_dir = np.column_stack(
        [
            np.cos(angles[:, 1]) * np.cos(angles[:, 0]),
            np.cos(angles[:, 1]) * np.sin(angles[:, 0]),
            np.sin(angles[:, 1]),
        ]
    )
    expected = kin.leg_to_body(knees_in_leg - kin.L3 * femur_dir)
    for leg in range(6):
        knee = kin.knees_in_body(leg, feet_in_body[leg])
        np.testing.assert_allclose(knee, expected[leg], atol=1e-7)
        assert np.linalg.norm(feet_in_body[leg] - knee) == pytest.approx(kin.L3, abs=1e-7)


@given(robot_and_angles(), st.lists(st.floats(-1.0, 1.0), min_size=18, max_size=18))
@settings(max_examples=200, deadline=None)
def test_jacobian_matches_finite_differences(case, direction):
    """Each Jacobian column equals the central difference of FK along that joint."""
    kin, angles = case
    eps = 1e-6
    J = kin.jacobian(angles)
    for j in range(3):
        step = np.zeros(3)
        step[j] = eps
        numeric = (kin.forward(angles + step) - kin.forward(angles - step)) / (2 * eps)
        np.testing.assert_allclose(J[:, :, j], numeric, atol=1e-8)


@given(robot_and_angles(), st.lists(st.floats(-1.0, 1.0), min_size=18, max_size=18))
@settings(max_examples=200, deadline=None)
def test_joint_rates_reproduce_the_foot_velocity(case, rates):
    """Joint rates from a foot velocity equal the finite-difference rates of IK along it."""
    kin, angles = case
    q_dot = np.array(rates).reshape(6, 3)
    feet = kin.forward(angles)
    dt = 1e-6
    foot_velocity = (kin.forward(angles + q_dot * dt) - kin.forward(angles - q_dot * dt)) / (2 * dt)
    sin_knee = np.abs(np.sin(angles[:, 2]))
    if sin_knee.min() < 0.05 or np.hypot(feet[:, 0], feet[:, 1]).min() < 0.02:
        return  # near-singular: covered by the singularity test
    np.testing.assert_allclose(kin.joint_rates(angles, foot_velocity), q_dot, atol=1e-4)


@given(
    st.sampled_from(sorted(SPECS)),
    st.integers(0, 5),
    st.floats(0.001, 0.5),
    st.floats(-np.pi, np.pi),
    st.floats(-np.pi / 2, np.pi / 2),
)
@settings(max_examples=200, deadline=None)
def test_out_of_reach_targets_raise_with_leg_and_excess(name, leg, excess, azimuth, elevation):
    """A target beyond the stretched leg raises UnreachableTargetError naming leg and excess."""
    kin = KINEMATICS[name]
    reach = kin.L2 + kin.L3 + excess
    feet = kin.forward(np.tile([0.0, 0.3, -1.2], (6, 1)))
    r, z = reach * np.cos(elevation), reach * np.sin(elevation)
    d = kin.L1 + abs(r)
    feet[leg] = [d * np.cos(azimuth), d * np.sin(azimuth), z]
    with pytest.raises(UnreachableTargetError) as info:
        kin.inverse(feet, check_limits=False)
    assert info.value.leg == kin.names[leg]
    assert info.value.excess_m == pytest.approx(excess, rel=1e-6, abs=1e-9)
    assert kin.names[leg] in str(info.value) and "out of reach" in str(info.value)


def test_too_close_target_raises():
    """A target nearer than the folded leg can reach raises, with the shortfall."""
    kin = KINEMATICS["phantomx"]
    feet = kin.forward(np.tile([0.0, 0.3, -1.2], (6, 1)))
    feet[2] = [kin.L1 + 0.01, 0.0, 0.0]  # 1 cm from the femur axis
    with pytest.raises(UnreachableTargetError, match="closer than the folded leg") as info:
        kin.inverse(feet)
    assert info.value.leg == "LB"
    assert info.value.excess_m == pytest.approx(abs(kin.L2 - kin.L3) - 0.01)


def test_joint_limit_violation_names_the_joint():
    """A reachable target that needs a joint beyond its limit names the leg and the joint."""
    kin = KINEMATICS["default"]
    feet = kin.forward(np.tile([0.0, 0.3, -1.2], (6, 1)))
    feet[4] = kin.forward(np.array([[np.radians(80.0), 0.3, -1.2]]))[0]  # coxa beyond 60 deg
    with pytest.raises(UnreachableTargetError, match=r"leg RM: .*coxa angle 80\.0 deg"):
        kin.inverse(feet)


def test_stretched_leg_is_singular():
    """Joint rates at a straight knee raise SingularConfigurationError naming the leg."""
    kin = KINEMATICS["default"]
    angles = np.tile([0.0, 0.3, -1.2], (6, 1))
    angles[1, 2] = 0.0
    with pytest.raises(SingularConfigurationError, match="leg LM"):
        kin.joint_rates(angles, np.ones((6, 3)))


def test_rest_stance_is_reachable_for_every_robot():
    """Every built-in robot can stand on its rest stance at its nominal height."""
    for name, spec in SPECS.items():
        feet = spec.rest_feet_in_body()
        feet[:, 2] += spec.foot_radius
        KINEMATICS[name].inverse_in_body(feet)


@settings(max_examples=100, deadline=None)
@given(
    offsets=arrays(np.float64, (6, 3), elements=st.floats(-0.15, 0.15)),
    margin=st.floats(0.0, 0.03),
)
def test_reachable_all_agrees_with_each_leg(default_spec, offsets, margin):
    """The six-leg reach test gives each leg's own answer."""
    kin = LegKinematics(default_spec)
    feet = default_spec.rest_feet_in_body() + offsets
    expected = [kin.reachable(leg, feet[leg], margin) for leg in range(6)]
    assert kin.reachable_all(feet, margin).tolist() == expected


def _reference_reached(kin: LegKinematics, leg: int, feet: np.ndarray, margin: float):
    """The reach test written out in NumPy, from the leg's own inverse kinematics."""
    p = feet - kin.mounts_in_body[leg]
    yaw = kin.spec.mount_yaws[leg]
    x = np.cos(yaw) * p[..., 0] + np.sin(yaw) * p[..., 1]
    y = -np.sin(yaw) * p[..., 0] + np.cos(yaw) * p[..., 1]
    r = np.hypot(x, y) - kin.L1
    reach = np.hypot(r, p[..., 2])
    ok = (abs(kin.L2 - kin.L3) + margin <= reach) & (reach <= kin.L2 + kin.L3 - margin)
    femur, tibia = kin._femur_tibia(r, p[..., 2])
    slack = margin / kin.L3
    for angle, axis in ((np.arctan2(y, x), 0), (femur, 1), (tibia, 2)):
        ok &= (angle >= kin.lower[axis] + slack) & (angle <= kin.upper[axis] - slack)
    return ok


@settings(max_examples=200, deadline=None)
@given(
    name=st.sampled_from(sorted(KINEMATICS)),
    offsets=arrays(np.float64, (7, 6, 3), elements=st.floats(-0.3, 0.3)),
    margin=st.floats(0.0, 0.03),
)
def test_the_compiled_reach_test_answers_as_numpy(name, offsets, margin):
    """The compiled reach test gives the NumPy reference's answer for every leg and point,
    one leg at a time and all six at once, in any leading shape."""
    kin = KINEMATICS[name]
    feet = kin.mounts_in_body + offsets
    expected = np.stack([_reference_reached(kin, leg, feet[:, leg], margin) for leg in range(6)])
    assert (kin.reachable_all(feet, margin) == expected.T).all()
    for leg in range(6):
        assert (kin.reachable(leg, feet[:, leg], margin) == expected[leg]).all()
        assert kin.reachable(leg, feet[0, leg], margin) is bool(expected[leg, 0])
    with pytest.raises(ValueError, match="shape"):
        kin.reachable_all(feet[:, :3], margin)
