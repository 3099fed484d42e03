"""Settings named on the command line: ``--set scoring.threshold=0.4``.

A name is a section and a field of that section's configuration dataclass, as the field is
named there (a field of a nested dataclass through more dots):

======================  ==================================================================
section                 configuration
======================  ==================================================================
``robot``               the robot description (:class:`~footfall.robot.spec.HexapodSpec`):
                        ``robot.body_height``, ``robot.stride_length``, ``robot.servo.kp``
``gait``                :class:`~footfall.motion.gait.GaitConfig`: ``gait.stroke_margin``,
                        ``gait.swing``, ``gait.flow.rise``
``scoring``             :class:`~footfall.scoring.walkability.ScoreConfig`
``mapping``             :class:`~footfall.mapping.engine.HeightMapConfig`:
                        ``mapping.resolution``, ``mapping.drift.enabled``
``planner``             :class:`~footfall.planning.terrain_planner.TerrainPlannerConfig`:
                        ``planner.footholds.search_radius``
``navigation``          :class:`~footfall.planning.navigation.NavigationConfig`
``feedback``            :class:`~footfall.motion.feedback.FeedbackConfig`
``walk``                the walk itself (:class:`~footfall.sim.walk_settings.WalkSettings`),
                        of which only ``walk.pose_source`` (the pose source by name: a
                        benchmark's ``--pose``); its other fields have options of their own
======================  ==================================================================

Values are read by the field's type: numbers (finite), ``true``/``false``, names, an enum's
value, ``none`` where the field may be None, and tuples of numbers as ``A:B``. Units are the
dataclasses' own: metres, radians, seconds. Every value is checked by the dataclass itself
when applied, so a setting the robot or the walk cannot take fails before anything walks.
"""

from __future__ import annotations

import dataclasses
import enum
import itertools
import math
import types
import typing
from collections.abc import Sequence
from typing import Any, TypeVar

from footfall.errors import ConfigError

D = TypeVar("D")

# Sections and the attribute of WalkSettings each lives in (robot and gait are set up before
# the walk's settings: the robot's height and stride and the gait's top speed depend on them).
SECTIONS = {
    "robot": None,
    "gait": None,
    "scoring": "score",
    "mapping": "map",
    "planner": "planner",
    "navigation": "navigation",
    "feedback": "feedback",
    "walk": "",  # the walk's settings themselves
}
# The walk's own fields that are set by name.
WALK_FIELDS = ("pose_source",)
# Fields with options of their own, which say what the walk is rather than tune it.
OWN_OPTIONS = {"gait.kind": "--gait"}

Setting = tuple[str, object]
"""A field's name and its value."""


def _section_defaults() -> dict[str, object]:
    """A default instance of every section's dataclass, to read field types from."""
    from footfall.motion.gait import GaitConfig
    from footfall.robot.spec import load_spec
    from footfall.sim.walk_settings import WalkSettings

    walk = WalkSettings()
    defaults: dict[str, object] = {"robot": load_spec("default"), "gait": GaitConfig()}
    for section, attribute in SECTIONS.items():
        if attribute is not None:
            defaults[section] = getattr(walk, attribute) if attribute else walk
    return defaults


def _field_type(owner: type, name: str) -> Any:
    """The resolved annotation of dataclass ``owner``'s field ``name``."""
    return typing.get_type_hints(owner)[name]


def _parse_scalar(kind: Any, text: str, name: str) -> object:
    """``text`` as a value of type ``kind`` (bool, int, float, str or an Enum)."""
    if kind is bool:
        lowered = text.strip().lower()
        if lowered in ("true", "yes", "on", "1"):
            return True
        if lowered in ("false", "no", "off", "0"):
            return False
        raise ConfigError(f"--set {name}: {text!r} is not true or false")
    if kind is int:
        try:
            return int(text)
        except ValueError:
            raise ConfigError(f"--set {name}: {text!r} is not a whole number") from None
    if kind is float:
        try:
            value = float(text)
        except ValueError:
            raise ConfigError(f"--set {name}: {text!r} is not a number") from None
        if not math.isfinite(value):
            raise ConfigError(f"--set {name}: {text!r} is not a finite number")
        return value
    if kind is str:
        if not text.strip():
            raise ConfigError(f"--set {name}: an empty name")
        return text.strip()
    if isinstance(kind, type) and issubclass(kind, enum.Enum):
        for member in kind:
            if text.strip() in (str(member.value), member.name, member.name.lower()):
                return member
        choices = ", ".join(str(m.value) for m in kind)
        raise ConfigError(f"--set {name}: {text!r} is not one of {choices}")
    raise ConfigError(f"--set {name}: a field of type {kind} cannot be set by name")


def _parse_value(kind: Any, text: str, name: str) -> object:
    """``text`` as a value of the annotated type ``kind``."""
    args = typing.get_args(kind)
    origin = typing.get_origin(kind)
    if origin in (typing.Union, types.UnionType):
        if text.strip().lower() == "none" and type(None) in args:
            return None
        others = [a for a in args if a is not type(None)]
        if len(others) != 1:
            raise ConfigError(f"--set {name}: a field of type {kind} cannot be set by name")
        return _parse_value(others[0], text, name)
    if origin is tuple:
        parts = text.split(":")
        if len(args) == 2 and args[1] is Ellipsis:
            kinds = [args[0]] * len(parts)
        elif len(args) == len(parts):
            kinds = list(args)
        else:
            raise ConfigError(
                f"--set {name}: {text!r} gives {len(parts)} values; the field takes "
                f"{len(args)}, written A:B"
            )
        if any(dataclasses.is_dataclass(k) for k in kinds):
            raise ConfigError(f"--set {name}: a tuple of {kinds[0].__name__} cannot be set by name")
        return tuple(_parse_scalar(k, part, name) for k, part in zip(kinds, parts, strict=True))
    return _parse_scalar(kind, text, name)


def _resolve(name: str, defaults: dict[str, object]) -> tuple[object, Any]:
    """The dataclass instance holding ``name``'s field and the field's type.

    Raises:
        ConfigError: An unknown section or field (naming the known ones), a section or a
            nested dataclass named without a field, or a field with an option of its own.
    """
    section, _, path = name.partition(".")
    if section not in SECTIONS:
        raise ConfigError(
            f"--set {name}: no section {section!r}; a name starts with one of {', '.join(SECTIONS)}"
        )
    if name in OWN_OPTIONS:
        raise ConfigError(f"--set {name}: walk another one with {OWN_OPTIONS[name]}")
    if section == "walk" and path and path not in WALK_FIELDS:
        raise ConfigError(
            f"--set {name}: of the walk's own settings only {', '.join(WALK_FIELDS)} is set "
            "by name; the others have options of their own"
        )
    owner = defaults[section]
    parts = path.split(".") if path else []
    if not parts:
        raise ConfigError(f"--set {name}: name a field of {section}, as {section}.FIELD")
    for k, part in enumerate(parts):
        fields = {f.name for f in dataclasses.fields(owner)}
        if part not in fields:
            where = ".".join([section, *parts[:k]])
            raise ConfigError(
                f"--set {name}: {where} has no field {part!r}; its fields: "
                f"{', '.join(sorted(fields))}"
            )
        kind = _field_type(type(owner), part)
        value = getattr(owner, part)
        if dataclasses.is_dataclass(value):
            if k == len(parts) - 1:
                inner = ", ".join(f.name for f in dataclasses.fields(value))
                raise ConfigError(f"--set {name}: name one of its fields: {inner}")
            owner = value
        elif k < len(parts) - 1:
            raise ConfigError(f"--set {name}: {part} has no fields")
    return owner, kind


def parse_set(text: str) -> tuple[str, tuple[object, ...]]:
    """``NAME=V1,V2,...`` as the name and its values, each read by the field's type.

    Raises:
        ConfigError: No ``=``, no value, a value given twice, an unknown name or a value of
            the wrong kind (the message names it).
    """
    name, equals, values = text.partition("=")
    name = name.strip()
    if not equals or not name:
        raise ConfigError(f"--set {text!r}: write NAME=VALUE (or NAME=V1,V2,... to compare)")
    _, kind = _resolve(name, _section_defaults())
    texts = [v.strip() for v in values.split(",")]
    if not values.strip() or any(not v for v in texts):
        raise ConfigError(f"--set {text!r}: a value is missing")
    parsed = tuple(_parse_value(kind, v, name) for v in texts)
    if len(set(parsed)) != len(parsed):
        raise ConfigError(f"--set {text!r}: a value is given twice")
    return name, parsed


def combinations(sets: Sequence[str] | None) -> tuple[tuple[Setting, ...], ...]:
    """Every combination of the ``--set`` options' values, the first option outermost.

    No options give one empty combination (the walk as configured).

    Raises:
        ConfigError: As :func:`parse_set`, or a name set twice.
    """
    studied = [parse_set(text) for text in sets or ()]
    names = [name for name, _ in studied]
    twice = sorted({n for n in names if names.count(n) > 1})
    if twice:
        raise ConfigError(f"--set {', '.join(twice)} is given more than once")
    return tuple(
        tuple(zip(names, values, strict=True))
        for values in itertools.product(*(values for _, values in studied))
    )


def walk_settings(sets: Sequence[str] | None) -> tuple[Setting, ...]:
    """The settings of one walk: every ``--set`` with one value.

    Raises:
        ConfigError: As :func:`combinations`, or a name given several values.
    """
    chosen = combinations(sets)
    if len(chosen) != 1:
        raise ConfigError(
            "--set on a walk takes one value a name; `footfall bench terrain --set "
            "NAME=V1,V2` walks several"
        )
    return chosen[0]


def _replace_path(instance: D, path: Sequence[str], value: object) -> D:
    """``instance`` with the field at ``path`` (through nested dataclasses) set to ``value``."""
    head, *rest = path
    if rest:
        value = _replace_path(getattr(instance, head), rest, value)
    return dataclasses.replace(instance, **{head: value})  # type: ignore[type-var]


def apply_settings(instance: D, section: str, settings: Sequence[Setting]) -> D:
    """``instance`` (the section's configuration) with the settings of ``section`` applied.

    Raises:
        ConfigError: A value the dataclass refuses, naming the setting.
    """
    for name, value in settings:
        own, _, path = name.partition(".")
        if own == section:
            try:
                instance = _replace_path(instance, path.split("."), value)
            except ConfigError as exc:
                raise ConfigError(f"--set {name}={as_json(value)}: {exc}") from exc
    return instance


def apply_walk_settings(settings: D, chosen: Sequence[Setting]) -> D:
    """A walk's settings with its sections' fields and its own (``walk.*``) set."""
    for section, attribute in SECTIONS.items():
        if attribute:
            part = apply_settings(getattr(settings, attribute), section, chosen)
            settings = dataclasses.replace(settings, **{attribute: part})  # type: ignore[type-var]
    return apply_settings(settings, "walk", chosen)


def as_json(value: object) -> object:
    """A setting's value as JSON holds it (an enum by its value, a tuple as a list)."""
    if isinstance(value, enum.Enum):
        return value.value
    if isinstance(value, tuple):
        return [as_json(v) for v in value]
    return value


def settings_json(chosen: Sequence[Setting]) -> dict[str, object]:
    """Settings as a ``bench.json`` object: name to value."""
    return {name: as_json(value) for name, value in chosen}
