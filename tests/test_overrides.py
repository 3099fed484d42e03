"""Settings by name (`--set`): reading values by the field's type, applying them, studies."""

import dataclasses
import json
import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from footfall.cli import main
from footfall.errors import ConfigError
from footfall.mapping.fusion import FusionRule
from footfall.sim.overrides import (
    SECTIONS,
    apply_settings,
    combinations,
    parse_set,
    settings_json,
    walk_settings,
)
from footfall.sim.walk_request import WalkRequest, prepare_walk


def _scalar_fields(prefix: str, instance: object) -> list[tuple[str, object]]:
    """Every settable number, flag or name under ``instance``, with its value."""
    out = []
    for f in dataclasses.fields(instance):
        value = getattr(instance, f.name)
        if dataclasses.is_dataclass(value):
            out += _scalar_fields(f"{prefix}.{f.name}", value)
        elif isinstance(value, bool | int | float | str) and f"{prefix}.{f.name}" != "gait.kind":
            out.append((f"{prefix}.{f.name}", value))
    return out


def _defaults() -> list[tuple[str, object]]:
    job = prepare_walk(WalkRequest(terrain="flat"))
    out = _scalar_fields("robot", job.spec) + _scalar_fields("gait", job.settings.gait)
    for section, attribute in SECTIONS.items():
        if attribute:
            out += _scalar_fields(section, getattr(job.settings, attribute))
    return [*out, ("walk.pose_source", job.settings.pose_source)]


DEFAULTS = _defaults()


@pytest.mark.parametrize(("name", "value"), DEFAULTS, ids=[n for n, _ in DEFAULTS])
def test_every_field_set_to_its_own_value_walks_as_configured(name, value):
    """Each number, flag and name of every section reads back from its text as the same
    value, and a walk set up with it is the walk set up without it."""
    text = str(value).lower() if isinstance(value, bool) else str(value)
    assert parse_set(f"{name}={text}") == (name, (value,))
    plain = prepare_walk(WalkRequest(terrain="flat"))
    same = prepare_walk(WalkRequest(terrain="flat", overrides=((name, value),)))
    assert (same.spec, same.settings) == (plain.spec, plain.settings)


def test_values_reach_the_walk_where_they_are_named():
    """A setting changes its field and nothing else, at any depth."""
    chosen = walk_settings(
        [
            "scoring.threshold=0.4",
            "planner.footholds.search_radius=0.12",
            "mapping.drift.enabled=false",
            "mapping.fusion=variance",
            "robot.body_height=0.1",
            "robot.limits.femur=-1.5:1.8",
            "gait.flow.rise=10",
            "navigation.traversability.span_radius_m=none",
        ]
    )
    plain = prepare_walk(WalkRequest(terrain="flat"))
    job = prepare_walk(WalkRequest(terrain="flat", overrides=chosen))
    assert job.settings.score == dataclasses.replace(plain.settings.score, threshold=0.4)
    assert job.settings.planner.footholds.search_radius == 0.12
    assert job.settings.planner.reach_margin == plain.settings.planner.reach_margin
    assert job.settings.map.drift.enabled is False
    assert job.settings.map.fusion is FusionRule.VARIANCE
    assert job.spec.body_height == 0.1
    assert job.settings.command.body_height == 0.1  # the robot's height is the walk's
    assert job.spec.limits.femur == (-1.5, 1.8)
    assert job.settings.gait.flow.rise == 10.0
    assert job.settings.navigation.traversability.span_radius_m is None
    assert settings_json(chosen)["mapping.fusion"] == "variance"
    assert settings_json(chosen)["robot.limits.femur"] == [-1.5, 1.8]


@pytest.mark.parametrize(
    ("text", "named"),
    [
        ("scoring.thresold=0.4", "thresold"),
        ("scorer.threshold=0.4", "scorer"),
        ("scoring.threshold=high", "high"),
        ("scoring.threshold=nan", "nan"),
        ("scoring.kernel_size=2.5", "2.5"),
        ("mapping.drift.enabled=maybe", "maybe"),
        ("mapping.fusion=average", "average"),
        ("robot.servo=1", "kp"),
        ("robot.limits.femur=1", "A:B"),
        ("robot.mounts=1:2", "LegMount"),
        ("gait.kind=wave", "--gait"),
        ("walk.seconds=3", "pose_source"),
        ("scoring.threshold", "NAME=VALUE"),
        ("scoring.threshold=0.4,", "missing"),
        ("scoring.threshold=0.4,0.4", "twice"),
    ],
)
def test_a_bad_name_or_value_is_named(text, named):
    """An unknown section or field, a value of the wrong kind, a nested section named
    without a field: a ConfigError naming what is wrong."""
    with pytest.raises(ConfigError, match=named):
        parse_set(text)


def test_the_dataclass_checks_every_value():
    """A value of the right kind that the configuration refuses fails when applied, named."""
    with pytest.raises(ConfigError, match=r"scoring\.threshold=-1"):
        prepare_walk(WalkRequest(overrides=(("scoring.threshold", -1.0),)))
    with pytest.raises(ConfigError, match=r"cannot stand at body height 0\.5"):
        prepare_walk(WalkRequest(overrides=(("robot.body_height", 0.5),)))
    with pytest.raises(ConfigError, match="unknown pose source 'slam'"):
        prepare_walk(WalkRequest(overrides=(("walk.pose_source", "slam"),)))


def test_combinations_are_the_product_first_option_outermost():
    """Every combination once, in order; no option is the walk as configured; a walk takes
    one value a name."""
    study = combinations(["scoring.threshold=0.3,0.5", "gait.stroke_margin=0.02,0.03,0.04"])
    assert [tuple(v for _, v in c) for c in study] == [
        (t, m) for t in (0.3, 0.5) for m in (0.02, 0.03, 0.04)
    ]
    assert combinations(None) == ((),)
    with pytest.raises(ConfigError, match="more than once"):
        combinations(["scoring.threshold=0.3", "scoring.threshold=0.5"])
    with pytest.raises(ConfigError, match="one value"):
        walk_settings(["scoring.threshold=0.3,0.5"])


@given(st.floats(allow_nan=False, allow_infinity=False), st.floats(0.01, 10.0))
def test_numbers_read_back_exactly(value, positive):
    """Any finite number reads back bit for bit from its text; applied where the
    configuration takes it, the field holds it."""
    assert parse_set(f"feedback.tilt_gain={value!r}")[1] == (value,)
    config = prepare_walk(WalkRequest(terrain="flat")).settings.score
    applied = apply_settings(config, "scoring", (("scoring.threshold", positive),))
    assert applied.threshold == positive


def test_bench_terrain_compares_every_combination(tmp_path, monkeypatch, capsys):
    """`--set scoring.threshold=A,B` over two terrains: a row per combination and terrain,
    success, falls, invalid footholds and walking medians per combination; an unknown name
    or a bad value fails before any walk, naming it."""
    from footfall.sim.terrain import Stairs

    monkeypatch.setattr(Stairs, "sweep", (0.04,))
    out = tmp_path / "study"
    args = ["bench", "terrain", "--seeds", "1", "--seconds", "1", "--modes", "planned"]
    args += ["--terrains", "stairs,dead_end", "--set", "scoring.threshold=0.3,0.6"]
    assert main([*args, "--out", str(out)]) == 0
    bench = json.loads((out / "bench.json").read_text())
    assert [(r["terrain"], r["settings"]) for r in bench["results"]] == [
        (t, {"scoring.threshold": v}) for v in (0.3, 0.6) for t in ("stairs", "dead_end")
    ]
    assert bench["settings"] == ["scoring.threshold"]
    assert [v["variant"] for v in bench["variants"]] == [
        "default tripod scoring.threshold=0.3",
        "default tripod scoring.threshold=0.6",
    ]
    for v in bench["variants"]:
        assert v["runs"] == 2 and {"successes", "falls", "invalid_footholds"} <= v.keys()
        assert v["median_speed_mps"] >= 0.0 and math.isfinite(v["median_tilt_max_deg"])
    assert (out / "bench.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # Each walk walks with its combination's settings, not only the rows that name them.
    from footfall.reliability.variants import Variant, walk_variant

    lower = Variant("default", "tripod", (("robot.body_height", 0.08),))
    walked = walk_variant(lower, "flat", seed=0, seconds=0.5).metrics
    assert walked.setup.commanded_body_height_m == 0.08
    capsys.readouterr()
    for bad, named in (("scoring.thresold=0.3", "thresold"), ("scoring.threshold=0.3,-1", "-1")):
        failed = tmp_path / "failed"
        assert main([*args[:-1], bad, "--out", str(failed)]) == 2
        assert named in capsys.readouterr().out
        assert not failed.exists()


def test_bench_terrain_compares_pose_sources(tmp_path, monkeypatch):
    """`--pose sim,estimator`: each pose source a row dimension, as the setting it stands for;
    the estimator's rows give its drift per metre walked, the truth's do not."""
    from footfall.sim.terrain import Stairs

    monkeypatch.setattr(Stairs, "sweep", (0.04,))
    out = tmp_path / "poses"
    args = ["bench", "terrain", "--seeds", "1", "--seconds", "4", "--modes", "planned"]
    args += ["--terrains", "stairs", "--pose", "sim,estimator", "--out", str(out)]
    assert main(args) == 0
    bench = json.loads((out / "bench.json").read_text())
    rows = {r["settings"]["walk.pose_source"]: r for r in bench["results"]}
    assert sorted(rows) == ["estimator", "sim"]
    assert "median_estimator_drift_per_m" not in rows["sim"]
    assert 0.0 <= rows["estimator"]["median_estimator_drift_per_m"] < 0.05
    assert 0.0 <= rows["estimator"]["median_estimator_heading_drift_deg_per_m"] < 2.0


def test_a_row_no_gait_can_cross_is_declared_and_left_out_of_the_rates(tmp_path, monkeypatch):
    """Feet of friction 0.3 hold no 20 degree ramp: that row is walked, reported
    `impassable` with the rule's reason, and the success rates count only the 10 degree row
    (the robot may cross it)."""
    from footfall.sim.terrain_relief import Ramps

    monkeypatch.setattr(Ramps, "sweep", (10.0, 20.0))
    out = tmp_path / "slippery"
    args = ["bench", "terrain", "--seeds", "1", "--seconds", "1", "--modes", "planned"]
    args += ["--terrains", "ramps", "--set", "robot.foot_friction=0.3", "--out", str(out)]
    assert main(args) == 0
    bench = json.loads((out / "bench.json").read_text())
    gentle, steep = bench["results"]
    assert (gentle["value"], gentle["impassable"], gentle["impassable_reason"]) == (10.0, False, "")
    assert steep["value"] == 20.0 and steep["impassable"] and steep["runs"] == 1
    assert "friction 0.3" in steep["impassable_reason"]
    assert bench["impassable_rows"] == 1
    assert bench["planned_success_rate"] == gentle["successes"] / gentle["runs"]
    assert bench["variants"][0]["runs"] == 1
