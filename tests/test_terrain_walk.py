"""Terrain-aware walking in simulation: the full loop from camera to joints."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import numpy.typing as npt
import pytest

from footfall.messages import WalkCommand
from footfall.robot.spec import load_spec
from footfall.sim.terrain import Terrain, TerrainXml
from footfall.sim.terrains import make_terrain
from footfall.sim.walk import simulate_walk
from footfall.sim.walk_settings import WalkSettings

SPEC = load_spec("default")


def _walk(terrain: str, blind: bool = False, seed: int = 0, seconds: float = 90.0, **kwargs):
    settings = WalkSettings(
        terrain=terrain, seconds=seconds, blind=blind, seed=seed, stop_at_goal=True, **kwargs
    )
    return simulate_walk(SPEC, settings)


@pytest.fixture(scope="module")
def stairs_walk():
    return _walk("stairs")


def test_planned_walk_climbs_and_descends_the_staircase(stairs_walk):
    """4 steps of 4 cm up and down: goal reached, no fall, no invalid foothold, tilt < 2 deg."""
    m = stairs_walk.metrics.to_json()
    assert m["reached_goal"] and not m["fell"] and not m["frozen"], m["frozen_reason"]
    assert m["invalid_footholds"] == 0
    assert m["tilt_max_deg"] < 2.0
    assert stairs_walk.warnings == {}


def test_body_rises_with_the_stairs_in_small_steps(stairs_walk):
    """Thesis Fig. 8.4: the body's height follows the floor of the footholds, so it rises
    by about the staircase's height, without jumps."""
    z = stairs_walk.log.array("reference_body_z")
    assert z.max() - z[0] == pytest.approx(4 * 0.04, abs=0.03)
    assert np.max(np.abs(np.diff(z))) < 0.002  # at most 2 mm per 10 ms tick


def test_footholds_land_where_planned(stairs_walk):
    """Every planned foothold is on a cell the robot's map scored valid (checked via the
    ground truth): none of the chosen footholds is on an invalid true cell."""
    assert stairs_walk.metrics.footholds.touchdowns > 60
    assert all(np.isfinite(t.chosen_in_world).all() for t in stairs_walk.touchdowns)


@pytest.mark.slow
def test_eight_centimetre_stairs_are_climbed_and_descended():
    """Stairs nearly as high as the body: the body height is planned with the footholds,
    so it rises over each step and lowers itself to step down, keeping every foot in
    reach; no fall, no invalid foothold, the body a centimetre clear of the edges."""
    terrain = make_terrain("stairs", seed=3, rise=0.08)
    settings = WalkSettings(terrain="stairs", seconds=90.0, blind=False, seed=3, stop_at_goal=True)
    result = simulate_walk(SPEC, settings, terrain=terrain)
    m = result.metrics.to_json()
    assert m["reached_goal"] and not m["fell"] and not m["frozen"]
    assert m["invalid_footholds"] == 0
    body = result.log.array("body_position_in_world")
    under = terrain.height(body[:, 0], body[:, 1])
    assert np.min(body[:, 2] - under) > 0.5 * SPEC.body_size[2]  # the belly never touches
    assert abs(m["body_z_tracking_error_mean_m"]) < 0.01


@pytest.mark.slow
def test_planning_beats_the_blind_baseline_on_cobblestones():
    """Cobblestones: planned walking reaches the goal without falling, tilting under 2 deg,
    with far fewer invalid footholds than the blind baseline."""
    planned = _walk("cobblestones", seed=5).metrics.to_json()
    blind = _walk("cobblestones", blind=True, seed=5, seconds=40.0).metrics.to_json()
    assert planned["reached_goal"] and not planned["fell"]
    assert planned["tilt_max_deg"] < 2.0
    assert planned["invalid_footholds"] < 0.3 * blind["invalid_footholds"]
    assert blind["invalid_footholds"] > 20


@dataclass(frozen=True)
class Wall(Terrain):
    """A 30 cm wall across the way: impassable."""

    name: ClassVar[str] = "wall"

    @property
    def goal(self) -> tuple[float, float]:  # type: ignore[override]
        """Beyond the wall."""
        return (2.0, 0.0)

    def height(self, x: npt.ArrayLike, y: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """The wall's top, else the floor."""
        xa, ya = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(y, dtype=float))
        return np.where((xa >= 0.7) & (xa <= 0.9) & (np.abs(ya) <= 1.0), 0.3, 0.0)

    def mjcf(self) -> TerrainXml:
        """One box."""
        box = '<geom name="wall" class="terrain" type="box" pos="0.8 0 0.15" size="0.1 1 0.15"/>'
        return TerrainXml(worldbody=box)


def test_walking_into_an_impassable_wall_freezes_safely():
    """Held to the straight line (the thesis' behaviour), a walk into a wall ends frozen in
    front of it, standing, with the leg and the reason named, and no foot on an invalid
    cell."""
    settings = WalkSettings(
        terrain="flat", seconds=25.0, blind=False, command=WalkCommand(speed=0.1), straight=True
    )
    result = simulate_walk(SPEC, settings, terrain=Wall())
    m = result.metrics.to_json()
    assert m["frozen"] and not m["fell"]
    assert "no valid" in m["frozen_reason"]
    assert any(m["frozen_reason"].startswith(f"leg {n}") for n in SPEC.leg_names)
    assert m["invalid_footholds"] == 0
    body = result.log.array("body_position_in_world")[-1]
    assert body[0] < 0.7  # stopped in front of the wall
    assert not result.log.array("swinging")[-1].any()  # all feet down


def test_a_navigating_robot_goes_round_the_wall_to_the_goal():
    """With route planning the same wall is gone round: the goal beyond it is reached, no
    fall, no foot on an invalid cell, and the body never came within the legs' span of the
    wall."""
    settings = WalkSettings(
        terrain="flat", seconds=90.0, blind=False, command=WalkCommand(speed=0.1), stop_at_goal=True
    )
    result = simulate_walk(SPEC, settings, terrain=Wall())
    m = result.metrics.to_json()
    assert m["reached_goal"] and not m["fell"], m
    assert m["invalid_footholds"] == 0
    body = result.log.array("body_position_in_world")[:, :2]
    beside = np.hypot(
        np.maximum(np.abs(body[:, 0] - 0.8) - 0.1, 0.0), np.maximum(np.abs(body[:, 1]) - 1.0, 0.0)
    )
    assert beside.min() > 0.25
