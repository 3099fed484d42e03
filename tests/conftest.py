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


SHARED_DATA = __import__("pathlib").Path(__file__).resolve().parents[2] / "shared" / "data"


def shared_data(relative: str):
    """Path of a file in the shared reference data, skipping the test when it is absent."""
    path = SHARED_DATA / relative
    if not path.exists():
        pytest.skip(f"shared reference data not present: {relative}")
    return path


def pytest_sessionfinish(session, exitstatus):
    """Write the fuzz tests' example counts when a report file is asked for."""
    from fuzzing import write_report

    write_report()
