"""The robots, gaits and settings a benchmark walks: each variant is a row dimension.

``footfall bench terrain`` and ``bench faults`` take ``--robot`` and ``--gait`` lists and
``--set NAME=V1,V2,...`` options (:mod:`footfall.sim.overrides`); every robot walks every gait
with every combination of the settings over the whole suite, and each walk is set up the way
``footfall walk`` sets it up (:func:`footfall.sim.walk_request.prepare_walk`): the robot's
nominal height and stride, the gait's default speed (0.1 m/s, or 3/4 of the gait's top speed
where that is less).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, NamedTuple

from footfall.errors import ConfigError
from footfall.sim.overrides import Setting, combinations, settings_json

if TYPE_CHECKING:
    from footfall.sim.walk_settings import WalkResult

DEFAULT_ROBOTS = ("default",)
DEFAULT_GAITS = ("tripod",)


class Variant(NamedTuple):
    """One robot walking one gait with one combination of settings.

    Attributes:
        robot: A built-in robot's name or a robot description TOML file.
        gait: A gait's name (``footfall.motion.gait.GAITS``).
        overrides: Configuration fields set by name, as ``(name, value)`` pairs.
    """

    robot: str
    gait: str
    overrides: tuple[Setting, ...] = ()

    @property
    def label(self) -> str:
        """The robot, gait and settings in a line: ``default tripod scoring.threshold=0.4``."""
        shown = " ".join(f"{name}={value}" for name, value in settings_json(self.overrides).items())
        return " ".join(filter(None, (self.robot, self.gait, shown)))


def parse_variants(
    robots: Sequence[str] | None = None,
    gaits: Sequence[str] | None = None,
    sets: Sequence[str] | None = None,
) -> tuple[Variant, ...]:
    """Every robot with every gait and every combination of ``sets``; each checked now.

    Robots are outermost, then gaits, then the settings (the first ``--set`` outermost).
    Every variant is set up as a walk before anything walks, so a setting the robot or the
    walk refuses fails here.

    Raises:
        ConfigError: An empty list, a name given twice, an unknown gait, a robot that
            does not load, an unknown setting or a value it refuses (the error names it).
    """
    from footfall.motion.gait import GAITS
    from footfall.robot.spec import load_spec
    from footfall.sim.walk_request import WalkRequest, prepare_walk

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
    studied = combinations(sets)
    variants = tuple(
        Variant(robot, gait, chosen) for robot in robots for gait in gaits for chosen in studied
    )
    if sets:
        for variant in variants:
            prepare_walk(
                WalkRequest(
                    terrain="flat",
                    robot=variant.robot,
                    gait=variant.gait,
                    overrides=variant.overrides,
                )
            )
    return variants


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
            overrides=variant.overrides,
        )
    )
    return simulate_walk(job.spec, job.settings, terrain=job.terrain)


def variant_rates(
    rows: Sequence[dict], variants: Sequence[Variant], modes: Sequence[str]
) -> list[dict[str, object]]:
    """Success rate per robot, gait and settings (and per mode, where rows have one).

    Rows declared ``impassable`` (terrain the robot cannot cross) are left out.

    Returns:
        One dict per variant: ``robot``, ``gait``, ``settings``, ``runs``, ``successes``,
        ``falls``, ``invalid_footholds`` and ``success_rate``, and ``{mode}_success_rate``
        for each of ``modes``.
    """
    out = []
    for variant in variants:
        mine = [r for r in rows if r["variant"] == variant.label and not r.get("impassable")]
        runs = sum(r["runs"] for r in mine)
        entry: dict[str, object] = {
            **variant_row(variant),
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
    """Each variant's success as a line, where a benchmark walked more than one."""
    if len(bench["variants"]) < 2:
        return []
    return [
        f"{v['variant']}: {v['successes']}/{v['runs']} ({v['success_rate']:.0%}), "
        f"{v['falls']} falls, {v['invalid_footholds']} invalid footholds"
        for v in bench["variants"]
    ]


def variant_row(variant: Variant) -> dict[str, object]:
    """A ``results`` row's variant: ``robot``, ``gait``, ``settings`` and ``variant``.

    ``variant`` is the three in a line, as charts and tables name it.
    """
    return {
        "robot": variant.robot,
        "gait": variant.gait,
        "settings": settings_json(variant.overrides),
        "variant": variant.label,
    }


def tally(outcomes: Sequence[dict], seeds: Sequence[int]) -> dict[str, object]:
    """What a results row counts over its walks, one walk per seed.

    Returns:
        ``runs``, ``successes``, ``falls``, ``invalid_footholds``, ``frozen``,
        ``foothold_region_jumps`` (re-plans that moved a foot to another steppable region
        needlessly) and the ``failed_seeds``.
    """
    return {
        "runs": len(outcomes),
        "successes": sum(bool(o["success"]) for o in outcomes),
        "falls": sum(bool(o["fell"]) for o in outcomes),
        "invalid_footholds": sum(int(o["invalid_footholds"]) for o in outcomes),
        "frozen": sum(bool(o["frozen"]) for o in outcomes),
        "foothold_region_jumps": sum(int(o["foothold_region_jumps"]) for o in outcomes),
        "failed_seeds": [s for s, o in zip(seeds, outcomes, strict=True) if not o["success"]],
    }
