"""The robots and gaits a benchmark walks: each (robot, gait) pair is a row dimension.

``footfall bench terrain`` and ``bench faults`` take ``--robot`` and ``--gait`` lists; every
pair walks the whole suite, and each walk is set up the way ``footfall walk`` sets it up
(:func:`footfall.sim.walk_request.prepare_walk`): the robot's nominal height and stride, the
gait's default speed (0.1 m/s, or 3/4 of the gait's top speed where that is less).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, NamedTuple

from footfall.errors import ConfigError

if TYPE_CHECKING:
    from footfall.sim.walk_settings import WalkResult

DEFAULT_ROBOTS = ("default",)
DEFAULT_GAITS = ("tripod",)


class Variant(NamedTuple):
    """One robot walking one gait.

    Attributes:
        robot: A built-in robot's name or a robot description TOML file.
        gait: A gait's name (``footfall.motion.gait.GAITS``).
    """

    robot: str
    gait: str


def parse_variants(
    robots: Sequence[str] | None = None, gaits: Sequence[str] | None = None
) -> tuple[Variant, ...]:
    """Every robot with every gait, robots outermost; each checked now.

    Raises:
        ConfigError: An empty list, a name given twice, an unknown gait or a robot that
            does not load (the error names it).
    """
    from footfall.motion.gait import GAITS
    from footfall.robot.spec import load_spec

    robots = DEFAULT_ROBOTS if robots is None else tuple(robots)
    gaits = DEFAULT_GAITS if gaits is None else tuple(gaits)
    for option, names in (("--robot", robots), ("--gait", gaits)):
        if not names:
            raise ConfigError(f"{option} names nothing")
        twice = sorted({n for n in names if names.count(n) > 1})
        if twice:
            raise ConfigError(f"{option} names {', '.join(map(repr, twice))} more than once")
    for gait in gaits:
        GAITS.check(gait)
    for robot in robots:
        load_spec(robot)
    return tuple(Variant(robot, gait) for robot in robots for gait in gaits)


def walk_variant(
    variant: Variant,
    terrain: str,
    seed: int,
    seconds: float,
    difficulty: float | None = None,
    blind: bool = False,
    straight: bool = False,
    faults: str = "",
) -> WalkResult:
    """The robot walking its gait across ``terrain`` to the goal, as ``footfall walk`` does."""
    from footfall.sim.walk import simulate_walk
    from footfall.sim.walk_request import WalkRequest, prepare_walk

    job = prepare_walk(
        WalkRequest(
            terrain=terrain,
            seconds=seconds,
            gait=variant.gait,
            robot=variant.robot,
            blind=blind,
            straight=straight,
            seed=seed,
            difficulty=difficulty,
            faults=faults,
        )
    )
    return simulate_walk(job.spec, job.settings, terrain=job.terrain)


def variant_rates(
    rows: Sequence[dict], variants: Sequence[Variant], modes: Sequence[str]
) -> list[dict[str, object]]:
    """Success rate per robot and gait (and per mode, where rows have one).

    Returns:
        One dict per variant: ``robot``, ``gait``, ``runs``, ``successes``, ``falls``,
        ``invalid_footholds`` and ``success_rate``, and ``{mode}_success_rate`` for each
        of ``modes``.
    """
    out = []
    for robot, gait in variants:
        mine = [r for r in rows if r["robot"] == robot and r["gait"] == gait]
        runs = sum(r["runs"] for r in mine)
        entry: dict[str, object] = {
            "robot": robot,
            "gait": gait,
            "runs": runs,
            "successes": sum(r["successes"] for r in mine),
            "falls": sum(r["falls"] for r in mine),
            "invalid_footholds": sum(r["invalid_footholds"] for r in mine),
            "success_rate": sum(r["successes"] for r in mine) / runs if runs else float("nan"),
        }
        for mode in modes:
            of_mode = [r for r in mine if r.get("mode") == mode]
            n = sum(r["runs"] for r in of_mode)
            entry[f"{mode}_success_rate"] = (
                sum(r["successes"] for r in of_mode) / n if n else float("nan")
            )
        out.append(entry)
    return out


def variant_lines(bench: dict) -> list[str]:
    """Each robot and gait's success as a line, where a benchmark walked more than one."""
    if len(bench["variants"]) < 2:
        return []
    return [
        f"{v['robot']} {v['gait']}: {v['successes']}/{v['runs']} ({v['success_rate']:.0%}), "
        f"{v['falls']} falls, {v['invalid_footholds']} invalid footholds"
        for v in bench["variants"]
    ]


def tally(outcomes: Sequence[dict], seeds: Sequence[int]) -> dict[str, object]:
    """What a results row counts over its walks, one walk per seed.

    Returns:
        ``runs``, ``successes``, ``falls``, ``invalid_footholds``, ``frozen`` and the
        ``failed_seeds``.
    """
    return {
        "runs": len(outcomes),
        "successes": sum(bool(o["success"]) for o in outcomes),
        "falls": sum(bool(o["fell"]) for o in outcomes),
        "invalid_footholds": sum(int(o["invalid_footholds"]) for o in outcomes),
        "frozen": sum(bool(o["frozen"]) for o in outcomes),
        "failed_seeds": [s for s, o in zip(seeds, outcomes, strict=True) if not o["success"]],
    }
