"""Robot descriptions: loading, validation and derived values."""

from __future__ import annotations

import math
import re
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from footfall.errors import ConfigError
from footfall.robot.spec import CameraPlacement, load_spec

PHANTOMX_URDF = (
    Path(__file__).parents[2] / "shared/data/robots/phantomx_mark4/urdf/pxmark4.urdf.xacro"
)


def test_builtin_robots_load(any_spec):
    """Both built-in robots load with six counter-clockwise legs and positive geometry."""
    assert len(any_spec.mounts) == 6
    assert any_spec.leg_names == ("LF", "LM", "LB", "RB", "RM", "RF")
    assert any_spec.mass > any_spec.body_mass


def test_phantomx_geometry_matches_urdf():
    """The PhantomX file carries the Mark-4's effective link lengths and mount layout."""
    spec = load_spec("phantomx")
    assert spec.coxa_length == pytest.approx(0.05291)
    assert spec.femur_length == pytest.approx(math.hypot(0.06, 0.015), abs=1e-5)
    assert spec.tibia_length == pytest.approx(math.hypot(0.095, 0.09), abs=1e-5)
    rf = spec.mounts[spec.leg_names.index("RF")]
    assert rf.position_in_body[:2] == pytest.approx((0.125, -0.065))
    assert math.degrees(rf.yaw) == pytest.approx(-45.0)


@pytest.mark.skipif(not PHANTOMX_URDF.exists(), reason="shared reference data not present")
def test_phantomx_limits_convert_urdf_limits():
    """Femur and tibia limits are the URDF's, moved into footfall's angle convention."""
    spec = load_spec("phantomx")
    femur_zero = math.degrees(math.atan2(-0.015, 0.06))
    tibia_zero = math.degrees(math.atan2(-0.09, 0.095)) - femur_zero
    lower, upper = (math.degrees(v) for v in spec.limits.femur)
    assert (lower, upper) == pytest.approx((-90 + femur_zero, 98 + femur_zero), abs=0.01)
    lower, upper = (math.degrees(v) for v in spec.limits.tibia)
    assert (lower, upper) == pytest.approx((-125 + tibia_zero, 45 + tibia_zero), abs=0.01)


def test_rest_feet_lie_on_mount_yaw_at_stance_radius(any_spec):
    """Rest feet sit stance_radius out along each leg's yaw, body_height below the body."""
    feet = any_spec.rest_feet_in_body()
    offset = feet[:, :2] - any_spec.mount_positions_in_body[:, :2]
    np.testing.assert_allclose(np.hypot(offset[:, 0], offset[:, 1]), any_spec.stance_radius)
    np.testing.assert_allclose(
        np.arctan2(offset[:, 1], offset[:, 0]), any_spec.mount_yaws, atol=1e-12
    )
    np.testing.assert_allclose(feet[:, 2], -any_spec.body_height)


def test_toml_file_round_trip(tmp_path, default_spec):
    """A robot file outside the package loads like the built-in one."""
    text = (Path(__file__).parents[1] / "src/footfall/robots/default.toml").read_text()
    path = tmp_path / "robot.toml"
    path.write_text(text.replace('name = "default"', 'name = "copy"'))
    spec = load_spec(path)
    assert spec.name == "copy"
    assert replace(spec, name="default") == default_spec


def test_clockwise_legs_are_rejected(default_spec):
    """Legs listed clockwise break the tripod rule, so the spec refuses them."""
    with pytest.raises(ConfigError, match="counter-clockwise"):
        replace(default_spec, mounts=tuple(reversed(default_spec.mounts)))


def test_five_legs_are_rejected(default_spec):
    """A hexapod has six legs."""
    with pytest.raises(ConfigError, match="6 legs"):
        replace(default_spec, mounts=default_spec.mounts[:5])


def test_unknown_robot_names_the_choices():
    """An unknown robot name says which robots exist."""
    with pytest.raises(ConfigError, match="default, phantomx"):
        load_spec("spider")


def test_missing_key_is_named(tmp_path):
    """A robot file without a required table names the missing key."""
    path = tmp_path / "bad.toml"
    path.write_text('name = "x"\n[body]\nsize = [0.1, 0.1, 0.1]\nmass = 1.0\n')
    with pytest.raises(ConfigError, match="'leg'"):
        load_spec(path)


def test_bad_toml_syntax_is_reported(tmp_path):
    """A file that is not TOML gives a ConfigError naming the file."""
    path = tmp_path / "broken.toml"
    path.write_text("name = \n")
    with pytest.raises(ConfigError, match=r"broken\.toml"):
        load_spec(path)


def test_the_camera_table_places_the_robots_camera(tmp_path, default_spec):
    """A robot file's [camera] table is its camera's place (degrees in the file, radians in
    the spec); without one the camera sits where the default robot's does; a key it does not
    know or a position of two numbers is named."""
    text = (Path(__file__).parents[1] / "src/footfall/robots/default.toml").read_text()
    text = re.sub(r"(?ms)^\[camera\].*?(?=^\[)", "", text)  # the default robot's own table
    path = tmp_path / "robot.toml"
    path.write_text(text + "\n[camera]\nposition = [0.1, 0.02, 0.12]\npitch_deg = 45.0\n")
    camera = load_spec(path).camera
    assert camera.position_in_body == (0.1, 0.02, 0.12)
    assert camera.pitch == pytest.approx(np.radians(45.0)) and camera.roll == camera.yaw == 0.0
    assert default_spec.camera == CameraPlacement()
    for table, message in (("tilt_deg = 3.0", "tilt_deg"), ("position = [0.1, 0.0]", "three")):
        path.write_text(text + f"\n[camera]\n{table}\n")
        with pytest.raises(ConfigError, match=message):
            load_spec(path)
