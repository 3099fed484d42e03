"""The terrains a walk, a mapping run or a benchmark can name: one registration line each.

``footfall walk --terrain``, ``footfall map --terrain``, ``footfall robot --sim`` and the
sweep of ``footfall bench terrain`` read :data:`TERRAINS`. A terrain declares its name, its
difficulty parameter, the values the benchmark sweeps and whether a route to its goal
exists on its own class (see :class:`~footfall.sim.terrain.Terrain`); its ground truth is
its ``height``.
"""

from __future__ import annotations

from footfall.registry import Registry
from footfall.sim import terrain_obstacles as obstacles
from footfall.sim import terrain_relief as relief
from footfall.sim.terrain import Cobblestones, Course, Flat, Stairs, Terrain

TERRAINS: Registry[type[Terrain]] = Registry("terrain")


def register_terrain(kind: type[Terrain]) -> type[Terrain]:
    """Register a terrain class under its ``name`` (usable as a class decorator)."""
    TERRAINS.register(kind.name, kind)
    return kind


register_terrain(Flat)
register_terrain(Stairs)
register_terrain(Cobblestones)
register_terrain(Course)
register_terrain(relief.SteppingStones)
register_terrain(relief.Gaps)
register_terrain(obstacles.Boxes)
register_terrain(relief.Ramps)
register_terrain(relief.Pits)
register_terrain(obstacles.ObstacleField)
register_terrain(obstacles.DeadEnd)


def make_terrain(name: str, seed: int = 0, **params: float) -> Terrain:
    """A registered terrain by name, laid out by ``seed``, with optional parameters.

    Raises:
        ConfigError: On an unknown name or parameter.
    """
    return TERRAINS.get(name).seeded(seed, **params)


def difficulty_parameters() -> dict[str, str]:
    """Each registered terrain that has a difficulty parameter, with its name."""
    return {
        name: kind.difficulty
        for name in TERRAINS
        if (kind := TERRAINS.get(name)).difficulty is not None
    }
