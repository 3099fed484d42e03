"""Shared fixtures."""

from __future__ import annotations

import os

import pytest

os.environ.setdefault("MUJOCO_GL", "egl")

from footfall.robot.spec import HexapodSpec, load_spec


@pytest.fixture(scope="session")
def default_spec() -> HexapodSpec:
    return load_spec("default")


@pytest.fixture(scope="session", params=["default", "phantomx"])
def any_spec(request: pytest.FixtureRequest) -> HexapodSpec:
    return load_spec(request.param)
