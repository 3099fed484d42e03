"""The compiled leg checks of the foothold planner answer as their NumPy forms did."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

import leg_clearance_reference as reference
from footfall.planning import clearance_kernels, leg_clearance
from footfall.planning.leg_clearance import (
    SWING_END_RADIUS_M,
    SWING_SAMPLES,
    TIBIA_FRACTIONS,
    FootholdChecks,
    MapTerrain,
    foothold_heights,
    pose_rows,
)
from footfall.planning.plan_kernels import foot_ring
from footfall.robot.kinematics import LegKinematics
from footfall.robot.planar import PlanarPose
from footfall.robot.spec import load_spec

SPECS = {name: load_spec(name) for name in ("default", "phantomx")}
KINEMATICS = {name: LegKinematics(spec) for name, spec in SPECS.items()}


@st.composite
def scenes(draw):
    """A robot and a leg, a rough map around it, poses, candidate feet and body heights."""
    name = draw(st.sampled_from(sorted(SPECS)))
    spec, kin = SPECS[name], KINEMATICS[name]
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    leg = draw(st.integers(0, 5))
    n, res = 40, 0.02
    heights = rng.normal(0.0, draw(st.sampled_from([0.005, 0.03, 0.08])), (n, n))
    heights[rng.random((n, n)) < draw(st.sampled_from([0.0, 0.2]))] = np.nan
    terrain = MapTerrain(foot_ring(spec.foot_radius), heights, -0.4, -0.4, res)
    poses = tuple(
        PlanarPose(*rng.uniform(-0.03, 0.03, 2), rng.uniform(-0.3, 0.3)) for _ in range(3)
    )
    inclines = tuple(draw(st.sampled_from([(0.0,) * 3, tuple(rng.uniform(-0.3, 0.3, 3))])))
    rest = spec.rest_feet_in_body()[leg]
    feet = rest + rng.normal(0.0, 0.04, (draw(st.integers(1, 30)), 3))
    feet[:, 2] = rng.normal(0.0, 0.04, len(feet))
    body_z = np.sort(rng.uniform(0.0, 0.25, draw(st.integers(1, 12))))
    return kin, terrain, leg, feet, poses, inclines, body_z


@settings(max_examples=150, deadline=None)
@given(scene=scenes(), margin=st.sampled_from([0.0, 0.02]))
def test_the_compiled_reach_over_poses_answers_as_numpy(scene, margin):
    kin, _, leg, feet, poses, inclines, body_z = scene
    ours = leg_clearance.reach_heights(kin, leg, feet, poses, body_z, margin, inclines)
    expected = reference.reach_heights(kin, leg, feet, poses, body_z, margin, inclines)
    np.testing.assert_array_equal(ours, expected)
    one = leg_clearance.reach_heights(kin, leg, feet[0], poses, body_z, margin, inclines)
    np.testing.assert_array_equal(one, expected[0])


def _clear(kin, terrain, leg, feet, poses, body_z, clearance, inclines):
    """The compiled knee and tibia check alone."""
    out = np.ones((len(feet), len(body_z)), dtype=bool)
    clearance_kernels.legs_clear_heights(
        np.ascontiguousarray(feet),
        pose_rows(poses, inclines),
        body_z,
        TIBIA_FRACTIONS,
        clearance,
        terrain,
        np.ascontiguousarray(kin.mounts_in_body[leg]),
        kin.reach_arrays[1],
        out,
    )
    return out


def _swing(kin, terrain, leg, start, ends, poses, body_z, lift, inclines):
    """The compiled swing-way check alone."""
    out = np.ones((len(ends), len(body_z)), dtype=bool)
    clearance_kernels.swing_reach_heights(
        start,
        np.ascontiguousarray(ends),
        pose_rows(poses, inclines),
        body_z,
        lift,
        np.linspace(0.0, 1.0, SWING_SAMPLES),
        SWING_END_RADIUS_M,
        terrain,
        leg,
        *kin.reach_arrays,
        out,
    )
    return out


@settings(max_examples=150, deadline=None)
@given(scene=scenes(), clearance=st.sampled_from([0.0, 0.03]))
def test_the_compiled_knee_and_tibia_clearance_answers_as_numpy(scene, clearance):
    kin, terrain, leg, feet, poses, inclines, body_z = scene
    args = (kin, terrain, leg, feet, poses, body_z, clearance, inclines)
    np.testing.assert_array_equal(_clear(*args), reference.legs_clear_heights(*args))


@settings(max_examples=150, deadline=None)
@given(scene=scenes(), lift=st.sampled_from([0.03, 0.06, 0.12]))
def test_the_compiled_swing_way_answers_as_numpy(scene, lift):
    kin, terrain, leg, feet, poses, inclines, body_z = scene
    start = feet[-1] + np.array([-0.08, 0.0, 0.0])
    args = (kin, terrain, leg, start, feet, poses[:2], body_z, lift, inclines[:2])
    np.testing.assert_array_equal(_swing(*args), reference.swing_reach_heights(*args))


@settings(max_examples=100, deadline=None)
@given(scene=scenes())
def test_a_foothold_passes_when_it_passes_every_check(scene):
    kin, terrain, leg, feet, poses, inclines, body_z = scene
    start = feet[-1] + np.array([-0.08, 0.0, 0.0])
    checks = FootholdChecks(
        pose_rows(poses, inclines), 0.02, pose_rows(poses[:2], inclines[:2]), 0.05,
        pose_rows(poses[::-1], inclines[::-1]), 0.02,
    )  # fmt: skip
    expected = (
        reference.reach_heights(kin, leg, feet, poses, body_z, 0.02, inclines)
        & reference.swing_reach_heights(
            kin, terrain, leg, start, feet, poses[:2], body_z, 0.05, inclines[:2]
        )
        & reference.legs_clear_heights(
            kin, terrain, leg, feet, poses[::-1], body_z, 0.02, inclines[::-1]
        )
    )
    ours = foothold_heights(kin, terrain, leg, feet, start, body_z, checks)
    np.testing.assert_array_equal(ours, expected)


def test_the_checks_refuse_what_the_terrain_or_the_leg_rules_out():
    """Not only equal to the reference: a wall over the knee, a riser too high to lift the
    foot over and a foothold beyond the leg each refuse, and the flat ground accepts."""
    spec, kin = SPECS["default"], KINEMATICS["default"]
    leg = spec.leg_names.index("LF")
    flat = np.zeros((40, 40))
    terrain = MapTerrain(foot_ring(spec.foot_radius), flat, -0.4, -0.4, 0.02)
    pose = (PlanarPose(),)
    rest = spec.rest_feet_in_body()[leg]
    foot = np.array([[rest[0], rest[1], spec.foot_radius]])
    body_z = np.array([spec.body_height])
    assert leg_clearance.reach_heights(kin, leg, foot, pose, body_z, 0.0).all()
    assert _clear(kin, terrain, leg, foot, pose, body_z, 0.01, None).all()
    walled = MapTerrain(terrain.offsets, np.full((40, 40), 0.5), -0.4, -0.4, 0.02)
    assert not _clear(kin, walled, leg, foot, pose, body_z, 0.01, None).any()
    far = foot + [1.0, 0.0, 0.0]
    assert not leg_clearance.reach_heights(kin, leg, far, pose, body_z, 0.0).any()
    riser = flat.copy()
    x0 = int((foot[0, 0] + 0.05 + 0.4) / 0.02)
    riser[x0 : x0 + 2, :] = 0.4  # a tall thin wall between the foot and its target
    high = MapTerrain(terrain.offsets, riser, -0.4, -0.4, 0.02)
    start, end = foot[0], foot + [0.1, 0.0, 0.0]
    assert _swing(kin, terrain, leg, start, end, pose, body_z, 0.03, None).all()
    assert not _swing(kin, high, leg, start, end, pose, body_z, 0.03, None).any()
