"""Settings tuned on the default robot follow another robot's own dimensions."""

from __future__ import annotations

import dataclasses

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from footfall.motion.gait import GaitConfig
from footfall.planning.footholds import FootholdConfig
from footfall.planning.navigation import NavigationConfig
from footfall.planning.terrain_planner import TerrainPlanner, TerrainPlannerConfig
from footfall.robot.scale import feet_span_m, robot_scale
from footfall.robot.spec import HexapodSpec, load_spec

DEFAULT = load_spec("default")


def _scaled(spec: HexapodSpec, k: float) -> HexapodSpec:
    """The robot with every length ``k`` times its own (angles, masses and gains kept)."""
    mounts = tuple(
        dataclasses.replace(m, position_in_body=tuple(k * v for v in m.position_in_body))
        for m in spec.mounts
    )
    lengths = (
        "coxa_length",
        "femur_length",
        "tibia_length",
        "foot_radius",
        "stance_radius",
        "body_height",
        "max_step_height",
        "stride_length",
    )
    return dataclasses.replace(
        spec,
        name=f"{spec.name} x{k:g}",
        mounts=mounts,
        body_size=tuple(k * v for v in spec.body_size),
        **{name: k * getattr(spec, name) for name in lengths},
    )


def _robot_lengths(spec: HexapodSpec) -> dict[str, float]:
    """Every setting that follows the robot's size, as the walk resolves it [m]."""
    planner = TerrainPlanner(spec)
    gait = GaitConfig().for_robot(spec)
    navigation = NavigationConfig().for_robot(spec)
    return {
        "stability_margin": planner.config.footholds.stability_margin,
        "in_place": planner.in_place_travel_m,
        "stroke_margin": gait.stroke_margin,
        "polynomial_apex": gait.polynomial_apex,
        "escape_radius_m": navigation.escape_radius_m,
        "blocked_radius_m": navigation.blocked_radius_m,
        "blocked_ahead_m": navigation.blocked_ahead_m,
    }


def test_the_default_robot_keeps_the_tuned_numbers_exactly():
    """On the robot they were tuned on, the settings are those numbers to the last bit: its
    walks are the walks they were before the settings followed the robot."""
    assert dataclasses.astuple(robot_scale(DEFAULT)) == (1.0, 1.0)
    assert _robot_lengths(DEFAULT) == {
        "stability_margin": 0.02,
        "in_place": 0.02,
        "stroke_margin": 0.04,
        "polynomial_apex": 0.10,
        "escape_radius_m": 0.25,
        "blocked_radius_m": 0.15,
        "blocked_ahead_m": 0.25,
    }


@settings(max_examples=30, deadline=None)
@given(k=st.floats(0.4, 2.5))
def test_a_robot_k_times_the_size_gets_every_robot_length_k_times(k):
    """Scaling the whole default robot by k scales every setting that follows the robot's
    size by k, and no other."""
    big = _scaled(DEFAULT, k)
    scale = robot_scale(big)
    for ratio in dataclasses.astuple(scale):
        assert ratio == pytest.approx(k, rel=1e-9)
    assert feet_span_m(big) == pytest.approx(k * feet_span_m(DEFAULT), rel=1e-9)
    mine, tuned = _robot_lengths(big), _robot_lengths(DEFAULT)
    for name, value in mine.items():
        assert value == pytest.approx(k * tuned[name], rel=1e-9), name
    planner, tuned_planner = TerrainPlanner(big).config, TerrainPlannerConfig()
    assert planner.reach_margin == tuned_planner.reach_margin
    assert planner.swing_clearance == tuned_planner.swing_clearance
    assert planner.footholds.search_radius == tuned_planner.footholds.search_radius


def test_the_phantomx_settings_follow_its_lift_stride_and_span():
    """The PhantomX's lift is 0.4 of the default's and its stride 2/3: its swing apex and
    stroke margin follow, and a number set by hand wins."""
    phantomx = load_spec("phantomx")
    lengths = _robot_lengths(phantomx)
    assert robot_scale(phantomx).stride == pytest.approx(0.10 / 0.15)
    assert lengths["polynomial_apex"] == phantomx.max_step_height == 0.04
    assert lengths["stroke_margin"] == pytest.approx(0.04 * 0.10 / 0.15)
    assert lengths["stability_margin"] == pytest.approx(
        0.02 * feet_span_m(phantomx) / feet_span_m(DEFAULT)
    )
    by_hand = TerrainPlannerConfig(footholds=FootholdConfig(stability_margin=0.03))
    assert TerrainPlanner(phantomx, by_hand).config.footholds.stability_margin == 0.03
    assert GaitConfig(stroke_margin=0.05).for_robot(phantomx).stroke_margin == 0.05
    assert NavigationConfig(blocked_radius_m=0.2).for_robot(phantomx).blocked_radius_m == 0.2
