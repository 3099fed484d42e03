"""Gaits: groups and duty factors, the sextant rule, commands and step timing."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from footfall.errors import ConfigError
from footfall.messages import WalkCommand
from footfall.motion.gait import (
    GAITS,
    GaitConfig,
    active_sextant,
    duty_factor,
    swing_groups,
    tripod_swing_set,
)
from footfall.robot.spec import load_spec


@pytest.mark.parametrize(("kind", "duty"), [("tripod", 1 / 2), ("ripple", 2 / 3), ("wave", 5 / 6)])
def test_groups_partition_the_legs_with_thesis_duty_factors(kind, duty):
    """Every leg swings exactly once per cycle; duty factors are those of thesis §5.3."""
    groups = swing_groups(kind)
    assert sorted(leg for g in groups for leg in g) == list(range(6))
    assert duty_factor(kind) == pytest.approx(duty)


def test_tripods_are_every_other_leg():
    """Eq. 5.15: legs xi, xi+2, xi+4 swing together."""
    assert swing_groups("tripod") == ((0, 2, 4), (1, 3, 5))


def test_ripple_never_lifts_neighbours_together(default_spec):
    """Ripple swings two legs on opposite sides that are not neighbours around the body."""
    for a, b in swing_groups("ripple"):
        assert (a - b) % 6 not in (1, 5)
        assert {default_spec.leg_names[a][0], default_spec.leg_names[b][0]} == {"L", "R"}


def test_sextant_of_forward_and_sideways_walks(default_spec):
    """The active sextant is the leg whose rest foot lies nearest the walk direction."""
    rest = default_spec.rest_feet_in_body()
    names = default_spec.leg_names
    assert names[active_sextant([0.0, 1.0], rest)] == "LM"
    assert names[active_sextant([0.0, -1.0], rest)] == "RM"
    assert names[active_sextant([-1.0, 0.3], rest)] == "LB"
    assert names[active_sextant([1.0, -0.2], rest)] == "RF"


def test_tripod_set_inverts_when_the_leading_leg_is_extended(default_spec):
    """Eq. 5.16: with leg xi's foot beyond its rest length, the other tripod swings."""
    rest = default_spec.rest_feet_in_body()
    mounts = default_spec.mount_positions_in_body
    direction = np.array([0.0, 1.0])  # sextant of LM (index 1)
    at_rest = tripod_swing_set(direction, rest, rest, mounts)
    assert at_rest.tolist() == [False, True, False, True, False, True]
    extended = rest.copy()
    extended[1, 1] += 0.03  # LM's foot pushed outwards
    assert tripod_swing_set(direction, rest, extended, mounts).tolist() == (~at_rest).tolist()


@given(st.sampled_from(GAITS.names()), st.floats(0.0, 1.0))
@settings(max_examples=100, deadline=None)
def test_step_duration_keeps_speed_and_bounds(kind, fraction):
    """Below the top speed the step timing delivers the speed: stride <= the robot's."""
    config = GaitConfig(kind=kind).for_robot(load_spec("default"))
    speed = fraction * config.max_speed
    duration = config.step_duration(speed)
    assert config.min_step_duration <= duration <= config.max_step_duration
    if speed > 1e-6:
        stride = len(config.groups) * duration * speed
        assert stride <= config.stride + 1e-12


def test_top_speed_follows_eq_5_14():
    """V = S / (D tau) with the body-frame stroke D*S: the tripod's top speed."""
    config = GaitConfig(kind="tripod", min_step_duration=0.3).for_robot(load_spec("default"))
    tau = 2 * 0.3
    stroke = config.duty_factor * 0.15
    assert config.max_speed == pytest.approx(stroke / (config.duty_factor * tau))


def test_command_validation():
    """Non-finite, negative or directionless commands are refused with a clear error."""
    with pytest.raises(ConfigError, match="non-finite"):
        WalkCommand(speed=math.nan)
    with pytest.raises(ConfigError, match="speed must be >= 0"):
        WalkCommand(speed=-0.1)
    with pytest.raises(ConfigError, match="zero length"):
        WalkCommand(direction=(0.0, 0.0), speed=0.1)
    with pytest.raises(ConfigError, match="body height"):
        WalkCommand(body_height=0.0)
    assert WalkCommand(direction=(3.0, 4.0), speed=0.5).velocity_in_body == pytest.approx(
        (0.3, 0.4)
    )


def test_unknown_gait_is_rejected():
    """A gait name outside tripod/ripple/wave raises."""
    with pytest.raises(ValueError, match="gallop"):
        GaitConfig(kind="gallop")
