"""The public API and the examples."""

from __future__ import annotations

import runpy
import sys
from pathlib import Path

import pytest

import footfall

EXAMPLES = sorted((Path(__file__).parents[1] / "examples").glob("*.py"))


def test_every_exported_name_resolves():
    """Each name in footfall.__all__ is importable from the package."""
    for name in footfall.__all__:
        assert getattr(footfall, name) is not None, name


def test_library_never_imports_mujoco_outside_the_simulator():
    """Planning and motion code stay free of the simulator (it is one backend among others)."""
    root = Path(footfall.__file__).parent
    for path in root.rglob("*.py"):
        if path.parent.name == "sim":
            continue
        assert "import mujoco" not in path.read_text(), path


@pytest.mark.parametrize("example", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_examples_run(example, monkeypatch, tmp_path):
    """Every example runs headless to completion."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(sys, "argv", [str(example)])
    runpy.run_path(str(example), run_name="__main__")
