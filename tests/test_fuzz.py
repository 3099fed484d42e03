"""Fuzzing the readers and entry points: every input reads, runs, or raises a FootfallError
whose message names the problem; nothing else escapes (no crash, no hang, no exhausted memory).

The normal suite runs a few dozen examples per target; ``benchmarks/fuzz.py`` runs the long
version and reports the count per target (see ``fuzzing.py``).
"""

from __future__ import annotations

import math
import tomllib
from importlib import resources

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from footfall.biped.maps import load_map, map_from_dict
from footfall.biped.planner import plan_walk
from footfall.errors import FootfallError
from footfall.mapping.engine import HeightMapConfig
from footfall.mapping.height_map import HeightMap
from footfall.mapping.snapshot import MapSnapshot
from footfall.messages import DepthFrame, PoseEstimate, WalkCommand
from footfall.messages.codec import decode
from footfall.planning.footholds import FootholdConfig, FootholdSearch
from footfall.recording.reader import Recording
from footfall.recording.replay import Replayer
from footfall.recording.replay_request import ReplayRequest
from footfall.robot.spec import load_spec
from footfall.runtime.fault_spec import FaultSpec
from footfall.scoring.walkability import ScoreConfig, score_map
from footfall.sensing.camera import PinholeCamera
from footfall.sensing.pose import Pose
from fuzzing import fails_cleanly, fuzz_settings

FUZZ = fuzz_settings(30)

numbers = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True),
    st.floats(-10.0, 10.0),
    st.sampled_from([0.0, -0.0, 1e-12, -1.0, 1e300, math.nan, math.inf]),
)


def _mutate(data: bytes, draw) -> bytes:
    how = draw(st.sampled_from(["truncate", "flip", "splice", "number"]))
    b = bytearray(data)
    if how == "truncate":
        return bytes(b[: draw(st.integers(0, len(b)))])
    if how == "flip":
        for _ in range(draw(st.integers(1, 8))):
            b[draw(st.integers(0, len(b) - 1))] = draw(st.integers(0, 255))
        return bytes(b)
    if how == "number":  # a number in the text replaced by an odd one
        text = b.decode("utf-8", "replace")
        digits = [k for k, c in enumerate(text) if c.isdigit()]
        if digits:
            k = draw(st.sampled_from(digits))
            odd = draw(st.sampled_from(["nan", "inf", "-inf", "0", "-1", "1e999", "1e-9"]))
            text = text[:k] + odd + text[k + 1 :]
        return text.encode()
    k = draw(st.integers(0, len(b)))
    return bytes(b[:k]) + draw(st.binary(max_size=40)) + bytes(b[k:])


# Readers ---------------------------------------------------------------------------------
DEFAULT_TOML = resources.files("footfall.robots").joinpath("default.toml").read_bytes()


@FUZZ
@given(data=st.data())
def test_robot_descriptions(tmp_path, data):
    """A mutated robot TOML loads or raises ConfigError; a loaded spec holds only finite
    numbers."""
    path = tmp_path / "robot.toml"
    path.write_bytes(_mutate(DEFAULT_TOML, data.draw))
    spec = fails_cleanly("robot TOML", lambda: load_spec(path))
    if spec is not None:
        assert math.isfinite(spec.femur_length) and math.isfinite(spec.foot_friction)


def test_non_finite_robot_values_are_refused(tmp_path):
    """Regression: ``friction = nan`` and ``femur_length = inf`` were accepted silently."""
    text = DEFAULT_TOML.decode()
    for key, bad in (("friction", "nan"), ("femur_length", "inf")):
        data = tomllib.loads(text)
        assert any(key in table for table in data.values() if isinstance(table, dict))
        lines = [
            f"{key} = {bad}" if line.split("=")[0].strip() == key else line
            for line in text.splitlines()
        ]
        path = tmp_path / f"{key}.toml"
        path.write_text("\n".join(lines))
        with pytest.raises(FootfallError, match="finite"):
            load_spec(path)


finite = st.floats(-20.0, 20.0)
obstacle = st.one_of(
    st.fixed_dictionaries({"x": numbers, "y": numbers, "r": numbers}),
    st.fixed_dictionaries({"x": finite, "y": finite, "r": st.floats(0.0, 1.0)}),
    st.fixed_dictionaries(
        {
            "box": st.fixed_dictionaries(
                {"x": finite, "y": finite, "width": numbers, "depth": numbers, "yaw_deg": numbers}
            )
        }
    ),
)
plan_maps = st.fixed_dictionaries(
    {
        "start": st.lists(st.one_of(finite, numbers), min_size=2, max_size=2),
        "goal": st.lists(st.one_of(finite, numbers), min_size=2, max_size=2),
        "obstacles": st.lists(obstacle, max_size=40),
    },
    optional={
        "hip_width": st.one_of(numbers, st.floats(0.05, 0.4)),
        "step": st.fixed_dictionaries(
            {},
            optional={
                "max_length": st.one_of(numbers, st.floats(0.05, 0.3)),
                "width": st.one_of(numbers, st.floats(0.1, 0.3)),
                "max_turn_deg": st.one_of(numbers, st.floats(1.0, 90.0), st.just(1e-9)),
            },
        ),
    },
)


@FUZZ
@given(layout=plan_maps)
def test_biped_maps_and_plans(layout):
    """Any map layout loads and plans, or raises ConfigError/PlanningError; a plan's path
    stays out of the inflated obstacles."""
    plan_map = fails_cleanly("biped map", lambda: map_from_dict(layout))
    if plan_map is None:
        return
    plan = fails_cleanly("biped planner", lambda: plan_walk(plan_map))
    if plan is not None:
        assert plan.collisions == 0


plannable = st.fixed_dictionaries(
    {
        "start": st.tuples(st.floats(-4, 4), st.floats(-4, 4)),
        "goal": st.tuples(st.floats(-4, 4), st.floats(-4, 4)),
        "obstacles": st.lists(
            st.fixed_dictionaries(
                {"x": st.floats(-5, 5), "y": st.floats(-5, 5), "r": st.floats(0.0, 0.8)}
            ),
            max_size=200,
        ),
    },
    optional={"step": st.fixed_dictionaries({"max_turn_deg": st.floats(0.1, 180.0)})},
)


@FUZZ
@given(layout=plannable)
def test_biped_plans_among_many_obstacles(layout):
    """Overlapping, zero-radius or hundreds of obstacles: a plan that touches none, or a
    PlanningError (start or goal blocked, no way through)."""
    plan_map = fails_cleanly("biped map", lambda: map_from_dict(layout))
    plan = plan_map and fails_cleanly("biped planner", lambda: plan_walk(plan_map))
    if plan is not None:
        assert plan.collisions == 0


@FUZZ
@given(
    text=st.one_of(
        st.text(max_size=200), st.binary(max_size=200).map(lambda b: b.decode("latin-1"))
    )
)
def test_biped_map_files(tmp_path, text):
    """A map file of arbitrary text reads or raises ConfigError."""
    path = tmp_path / "map.json"
    path.write_text(text, encoding="utf-8", errors="surrogateescape")
    fails_cleanly("biped map file", lambda: load_map(path))


def test_a_vanishing_turn_limit_is_refused_not_planned():
    """Regression: ``max_turn_deg: 1e-9`` planned billions of turning steps (memory)."""
    layout = {"start": [0, 0], "goal": [2, 1], "obstacles": [], "step": {"max_turn_deg": 1e-9}}
    with pytest.raises(FootfallError, match="max_turn"):
        map_from_dict(layout)


def test_hundreds_of_overlapping_and_tiny_obstacles_plan_or_refuse():
    """300 obstacles, overlapping and down to a millimetre, plan without touching one."""
    rng = np.random.default_rng(5)
    obstacles = [
        {"x": float(x), "y": float(y), "r": float(r)}
        for x, y, r in zip(
            rng.uniform(0.5, 6.0, 300),
            rng.uniform(-3, 3, 300),
            rng.uniform(1e-3, 0.15, 300),
            strict=True,
        )
    ]
    layout = {"start": [0, 0], "goal": [7, 0], "obstacles": obstacles}
    plan = fails_cleanly("biped planner", lambda: plan_walk(map_from_dict(layout)))
    if plan is not None:
        assert plan.collisions == 0


@pytest.fixture(scope="module")
def small_recording(tmp_path_factory):
    """A 1 s recorded walk on stairs, for mutation."""
    from footfall.recording.session import Recorders
    from footfall.runtime.bus import InProcessBus
    from footfall.sim.walk import simulate_walk
    from footfall.sim.walk_request import WalkRequest, prepare_walk

    path = tmp_path_factory.mktemp("fuzzrec") / "walk.mcap"
    job = prepare_walk(WalkRequest(terrain="stairs", seconds=0.4, image_size=(64, 48)))
    with Recorders(path) as recorders:
        bus = recorders.attach(InProcessBus())
        simulate_walk(
            job.spec,
            job.settings,
            terrain=job.terrain,
            bus=bus,
            on_build=lambda robot: recorders.mapping_started(robot.mapping),
        )
    return path.read_bytes()


@FUZZ
@given(data=st.data())
def test_recordings(tmp_path, small_recording, data):
    """A truncated, bit-flipped or spliced recording opens and replays, or raises
    DatasetError."""
    path = tmp_path / "m.mcap"
    path.write_bytes(_mutate(small_recording, data.draw))

    def replay():
        Recording(path)
        return Replayer(ReplayRequest(path, fast=True)).run()

    fails_cleanly("recording", replay)


# Messages --------------------------------------------------------------------------------
def _encoded_messages() -> list[bytes]:
    camera = PinholeCamera(40, 40, 15.5, 11.5, 32, 24)
    pose = Pose(np.array([0.1, 0.2, 0.3]), Rotation.from_euler("xyz", [0.1, 0.2, 0.3]))
    return [
        DepthFrame(1.0, np.ones((24, 32), np.float32), camera, pose, sequence=3).encode(),
        PoseEstimate(1.0, pose, pose).encode(),
        WalkCommand(speed=0.1).encode(),
    ]


ENCODED = _encoded_messages()


@FUZZ
@given(data=st.data(), k=st.integers(0, len(ENCODED) - 1))
def test_messages(data, k):
    """Mutated message bytes decode or raise MessageError."""
    fails_cleanly("message decode", lambda: decode(_mutate(ENCODED[k], data.draw)))


# Entry points ----------------------------------------------------------------------------
@FUZZ
@given(fx=numbers, fy=numbers, cx=numbers, cy=numbers, w=st.integers(-2, 50), h=st.integers(-2, 50))
def test_camera_models(fx, fy, cx, cy, w, h):
    """Intrinsics with any numbers build a camera or raise ConfigError (NaN included)."""
    camera = fails_cleanly("camera model", lambda: PinholeCamera(fx, fy, cx, cy, w, h))
    if camera is not None:
        assert all(math.isfinite(v) for v in (camera.fx, camera.fy, camera.cx, camera.cy))


def test_a_nan_principal_point_is_refused():
    """Regression: ``cx = nan`` was accepted and turned every point into NaN."""
    with pytest.raises(FootfallError, match="cx"):
        PinholeCamera(100.0, 100.0, math.nan, 50.0, 100, 100)


@FUZZ
@given(
    position=st.lists(numbers, min_size=3, max_size=3), q=st.lists(numbers, min_size=4, max_size=4)
)
def test_poses(position, q):
    """Any position and quaternion make a pose or raise InvalidPoseError."""
    pose = fails_cleanly("pose", lambda: Pose.from_quaternion(position, q))
    if pose is not None:
        assert np.all(np.isfinite(pose.rotation.as_quat()))


depth_images = st.one_of(
    st.builds(
        lambda v, shape: np.full(shape, v, dtype=np.float32),
        numbers,
        st.tuples(st.integers(0, 30), st.integers(0, 30)),
    ),
    st.builds(
        lambda seed, dtype: np.random.default_rng(seed).uniform(-1, 5, (24, 32)).astype(dtype),
        st.integers(0, 99),
        st.sampled_from([np.float32, np.float64, np.uint16, np.int32, np.uint8, np.bool_]),
    ),
    st.builds(lambda: np.zeros((3, 4, 5), np.float32)),
)


@FUZZ
@given(
    depth=depth_images,
    position=st.lists(st.floats(-1e9, 1e9), min_size=3, max_size=3),
    angles=st.lists(st.floats(-7.0, 7.0), min_size=3, max_size=3),
    scale=st.one_of(st.none(), numbers),
    stride=st.integers(-1, 5),
)
def test_map_updates(depth, position, angles, scale, stride):
    """Any depth image from any pose updates the map or raises; known cells stay finite."""
    height_map = HeightMap(HeightMapConfig(size=32, resolution=0.05))
    camera = PinholeCamera(30.0, 30.0, 15.5, 11.5, 32, 24)
    pose = Pose(np.asarray(position), Rotation.from_euler("xyz", angles))
    fails_cleanly(
        "map update",
        lambda: height_map.integrate_depth(depth, camera, pose, depth_scale=scale, stride=stride),
    )
    assert np.all(np.isfinite(height_map.heights[height_map.known]))


@FUZZ
@given(centre=st.tuples(numbers, numbers), size=st.integers(-1, 40), res=numbers)
def test_map_windows(centre, size, res):
    """A map window centred anywhere with any size and resolution builds or raises."""
    fails_cleanly(
        "map window", lambda: HeightMap(HeightMapConfig(size=size, resolution=res), centre)
    )


grids = st.builds(
    lambda seed, n, kind: {
        "random": np.random.default_rng(seed).normal(0, 0.05, (n, n)),
        "nan": np.full((n, n), np.nan),
        "inf": np.where(np.random.default_rng(seed).random((n, n)) < 0.3, np.inf, 0.0),
        "steps": np.floor(np.random.default_rng(seed).random((n, n)) * 4) * 0.05,
    }[kind],
    st.integers(0, 999),
    st.integers(1, 24),
    st.sampled_from(["random", "nan", "inf", "steps"]),
)


@FUZZ
@given(heights=grids, res=numbers, nominal=st.tuples(numbers, numbers))
def test_scoring_and_foothold_search(heights, res, nominal):
    """Scoring any grid, then searching it from any nominal point: a foothold is on a valid
    cell, or there is none, or a FootfallError says why."""
    known = np.isfinite(heights)
    snapshot = fails_cleanly(
        "scoring", lambda: MapSnapshot(np.where(known, heights, np.nan), known, (0.0, 0.0), res)
    )
    if snapshot is None:
        return
    scores = fails_cleanly("scoring", lambda: score_map(snapshot, ScoreConfig()))
    if scores is None:
        return
    search = fails_cleanly(
        "foothold search", lambda: FootholdSearch(FootholdConfig(), scores.resolution)
    )
    if search is None:
        return
    foothold = fails_cleanly(
        "foothold search", lambda: search.search(nominal, scores, snapshot.heights)
    )
    if foothold is not None:
        assert scores.valid[foothold.cell]


@FUZZ
@given(text=st.text(max_size=80))
def test_fault_specs(text):
    """Any --faults text parses or raises ConfigError."""
    fails_cleanly("fault spec", lambda: FaultSpec.parse(text))


# Regressions: each defect the fuzzing found --------------------------------------------
def test_a_crafted_lzf_stream_never_reads_past_its_end():
    """A back reference whose length byte is cut off, and one pointing before the output."""
    from footfall.io.pcd import lzf_decompress

    for stream in ([0xE0], [0x20], [0x00, 0x41, 0x3F, 0x10]):
        with pytest.raises(ValueError, match="corrupt LZF stream"):
            lzf_decompress(np.array(stream, dtype=np.uint8), 16)


@pytest.mark.parametrize(
    ("build", "says"),
    [
        (lambda: HeightMap(HeightMapConfig(size=16), centre=(math.nan, 0.0)), "map centre"),
        (lambda: HeightMapConfig(resolution=1e-300), "resolution"),
        (
            lambda: MapSnapshot(np.zeros((2, 2)), np.ones((2, 2), bool), (0.0, 0.0), 0.0),
            "resolution",
        ),
        (lambda: FootholdSearch(FootholdConfig(), 1e-38), "search radius"),
        (lambda: map_from_dict([1, 2]), "JSON object"),
        (lambda: map_from_dict({"start": [0, 0], "goal": [1e300, 0]}), "goal"),
        (
            lambda: map_from_dict(
                {"start": [0, 0], "goal": [1, 0], "obstacles": [{"x": 1, "y": math.inf, "r": 1}]}
            ),
            "finite",
        ),
    ],
)
def test_values_the_fuzzing_found_are_refused_by_name(build, says):
    with pytest.raises(FootfallError, match=says):
        build()


def test_malformed_recording_metadata_is_a_dataset_error(tmp_path):
    """Regression: a garbled footfall/mapping record raised ValueError from float()."""
    from footfall.errors import DatasetError
    from footfall.recording.session import Recorders
    from footfall.runtime.bus import InProcessBus
    from footfall.sim.walk import simulate_walk
    from footfall.sim.walk_request import WalkRequest, prepare_walk

    path = tmp_path / "bad.mcap"
    job = prepare_walk(WalkRequest(terrain="flat", seconds=0.3, image_size=(64, 48)))
    garbled = {"footfall/mapping": {"map.resolution": "\x00.0", "centre_x": "0", "centre_y": "0"}}
    with Recorders(path, metadata=garbled) as recorders:
        simulate_walk(job.spec, job.settings, bus=recorders.attach(InProcessBus()))
    with pytest.raises(DatasetError, match="malformed footfall/mapping metadata"):
        Replayer(ReplayRequest(path, fast=True)).run()


def test_a_robot_description_that_is_not_text_is_refused(tmp_path):
    path = tmp_path / "robot.toml"
    path.write_bytes(b"\xff\xfe name = 1")
    with pytest.raises(FootfallError, match="not UTF-8"):
        load_spec(path)


def test_scoring_a_grid_of_zero_resolution_is_refused():
    from footfall.scoring.walkability import score_heights

    with pytest.raises(FootfallError, match="resolution"):
        score_heights(np.zeros((4, 4)), 0.0)
