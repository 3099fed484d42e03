"""Messages: every type round-trips through bytes exactly; malformed bytes are refused."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from footfall.errors import MessageError
from footfall.messages import (
    Ack,
    BipedPlan,
    BipedStatus,
    ColorImage,
    DepthFrame,
    EffectorTargets,
    GaitState,
    GaitStatus,
    GroundPrior,
    ImuReading,
    JointTargets,
    LogLine,
    MapUpdate,
    Mode,
    ModeCommand,
    NewMap,
    Obstacles,
    OdometryEstimate,
    PlanningGoal,
    PoseEstimate,
    Posture,
    RobotState,
    ServoStatus,
    Touchdown,
    Trigger,
    WalkCommand,
    decode,
    message_types,
)
from footfall.messages.wire import LinkAck, PackedColor, PackedDepth, PackedMap, WholeMapRequest
from footfall.robot.planar import PlanarPose
from footfall.sensing.camera import PinholeCamera
from footfall.sensing.pose import Pose

finite = st.floats(-1e6, 1e6, allow_nan=False)


def _pose(rng: np.random.Generator) -> Pose:
    return Pose(rng.normal(size=3), Rotation.from_quat(rng.normal(size=4)))


def b_(rng: np.random.Generator) -> np.ndarray:
    """Packed bytes: a uint8 array."""
    return rng.integers(0, 256, 37, dtype=np.uint8)


def examples(rng: np.random.Generator) -> list:
    """One message of every type, with random contents."""
    n = 16
    heights = rng.normal(size=(n, n))
    heights[0, 0] = np.nan
    camera = PinholeCamera(100.0, 101.0, 31.5, 23.5, 64, 48, 0.1, 4.0)
    return [
        WalkCommand((0.6, -0.8), 0.12, 0.09, 0.2, stamp=1.5),
        ModeCommand(Mode.WALKING, 2.0),
        DepthFrame(
            0.25,
            rng.uniform(0, 3, (48, 64)).astype(np.float32),
            camera,
            _pose(rng),
            None,
            7,
            rng.integers(0, 255, (48, 64, 3), dtype=np.uint8),
        ),
        DepthFrame(0.5, rng.integers(0, 9000, (48, 64), dtype=np.uint16), camera, _pose(rng), 2e-4),
        PoseEstimate(0.25, _pose(rng), _pose(rng)),
        OdometryEstimate(0.26, _pose(rng), rng.normal(size=3), rng.uniform(0, 1, 6), True),
        GroundPrior(0.0, rng.normal(size=3), -0.01, 0.6),
        MapUpdate(
            3.0,
            4,
            heights,
            np.isfinite(heights),
            np.abs(rng.normal(size=(n, n))),
            rng.normal(size=(n, n)),
            rng.normal(size=(n, n)),
            rng.normal(size=(n, n)),
            rng.normal(size=(n, n)) > 0,
            (-2.56, 1.28),
            0.02,
        ),
        MapUpdate(
            3.0,
            5,
            heights,
            heights > 0,
            None,
            heights,
            heights,
            heights,
            heights > 0,
            (0.0, 0.0),
            0.02,
        ),
        EffectorTargets(
            1.0,
            rng.normal(size=(6, 3)),
            rng.normal(size=(6, 3)),
            rng.normal(size=6) > 0,
            rng.normal(size=(6, 3)),
        ),
        JointTargets(rng.normal(size=(6, 3)), rng.normal(size=(6, 3)), 1.0),
        RobotState(
            2.0,
            rng.normal(size=(6, 3)),
            rng.normal(size=(6, 3)),
            Rotation.from_quat(rng.normal(size=4)),
            rng.normal(size=3),
            rng.normal(size=3),
            rng.normal(size=(6, 3)),
            rng.normal(size=6) > 0,
            rng.normal(size=(6, 3, 3)),
        ),
        RobotState(2.0, np.zeros((6, 3)), np.zeros((6, 3)), Rotation.identity(), np.zeros(3)),
        GaitStatus(
            4.0,
            Mode.WALKING,
            GaitState.FROZEN,
            "leg LF: no foothold",
            "LF",
            PlanarPose(1.0, -0.5, 0.3),
            0.11,
            12,
            3,
            math.inf,
        ),
        Touchdown(4.5, 2, rng.normal(size=3), rng.normal(size=3)),
        LogLine(5.0, "mapping", "warning", "depth frame 3: skipped — no pose ✓"),
        ServoStatus(
            5.5, Posture.HALTED, "servo 5 (LM femur): overheating", *rng.normal(size=(3, 18))
        ),
        ServoStatus(5.6, Posture.RISING),
        Obstacles(1.0, rng.normal(size=4), rng.normal(size=4), rng.uniform(0.1, 1, 4)),
        BipedPlan(
            2.0,
            rng.normal(size=(3, 2)),
            rng.normal(size=(7, 3)),
            rng.normal(size=7) > 0,
            rng.normal(size=(50, 2)),
            4.2,
            0,
        ),
        PlanningGoal(3.0, -1.0),
        NewMap(rng.normal(size=3), rng.normal(size=3), 0.25),
        Trigger(1.0),
        ColorImage(0.25, rng.integers(0, 255, (48, 64, 3), dtype=np.uint8), 7),
        Ack(False, "the goal lies inside an obstacle"),
        ImuReading(0.25, rng.normal(size=3), np.array([0.1, -0.2, 9.81])),
        PackedMap(3.0, 6, 0, (-2.56, 1.28), 0.02, 16, 16, -120, True, b_(rng)),
        PackedMap(3.2, 7, 6, (-2.5, 1.3), 0.02, 16, 16, -120, False, b_(rng), 41, 1.7e9),
        PackedDepth(0.5, 9, camera, _pose(rng), b_(rng), 42, 1.7e9),
        PackedColor(0.5, 9, b_(rng)),
        LinkAck(np.array([41, 42], np.int64), 1.7e9, "a0f3"),
        WholeMapRequest(1.7e9, "a0f3"),
        MapUpdate(
            3.0, 5, heights, heights > 0, None, None, None, heights, heights > 0, (0.0, 0.0), 0.02
        ),
        BipedStatus(
            3.5,
            "stopping",
            rng.normal(size=2),
            0.3,
            rng.normal(size=(2, 3)),
            np.array([np.nan, np.nan]),
            12,
            0,
            "no heartbeat from the station for 0.6 s",
        ),
    ]


def assert_same(a, b) -> None:
    """Field-by-field equality, arrays bit for bit (NaN equal to NaN)."""
    assert type(a) is type(b)
    for name in a.__dataclass_fields__:
        x, y = getattr(a, name), getattr(b, name)
        if isinstance(x, np.ndarray):
            assert x.dtype == y.dtype and x.shape == y.shape, name
            np.testing.assert_array_equal(x, y, err_msg=name)
        elif isinstance(x, Rotation):
            np.testing.assert_array_equal(x.as_quat(), y.as_quat(), err_msg=name)
        elif isinstance(x, Pose):
            np.testing.assert_array_equal(x.position, y.position)
            np.testing.assert_array_equal(x.rotation.as_quat(), y.rotation.as_quat())
            np.testing.assert_array_equal(x.rotation.as_matrix(), y.rotation.as_matrix())
        else:
            assert x == y, name


def test_every_message_type_has_an_example_and_a_topic():
    """The round-trip examples cover every registered message type, each with a topic."""
    covered = {type(m).__name__ for m in examples(np.random.default_rng(0))}
    assert covered == set(message_types())
    assert all(cls.TOPIC for cls in message_types().values())


@pytest.mark.parametrize("seed", range(3))
def test_every_message_round_trips_exactly(seed):
    """decode(encode(m)) gives m back, arrays bit for bit, with dtype and shape."""
    for message in examples(np.random.default_rng(seed)):
        data = message.encode()
        assert_same(message, type(message).decode(data))
        assert_same(message, decode(bytearray(data)))


def test_decoded_arrays_are_views_of_the_bytes():
    """Decoding copies no array: the array shares memory with the encoded bytes."""
    update = next(m for m in examples(np.random.default_rng(1)) if isinstance(m, MapUpdate))
    data = update.encode()
    back = MapUpdate.decode(data)
    assert not back.heights.flags.owndata
    assert not back.heights.flags.writeable
    assert np.shares_memory(back.heights, np.frombuffer(data, dtype=np.uint8))


@settings(max_examples=60, deadline=None)
@given(
    direction=st.tuples(finite, finite).filter(lambda d: math.hypot(*d) > 1e-6),
    speed=st.floats(0, 10),
    height=st.floats(1e-3, 1.0),
    yaw=finite,
    stamp=finite,
)
def test_walk_commands_round_trip(direction, speed, height, yaw, stamp):
    """Any valid walk command survives the trip through bytes."""
    command = WalkCommand(direction, speed, height, yaw, stamp)
    assert WalkCommand.decode(command.encode()) == command


@settings(max_examples=60, deadline=None)
@given(
    shape=st.lists(st.integers(0, 5), min_size=2, max_size=2),
    dtype=st.sampled_from(["<f4", "<f8", "<u2"]),
    seed=st.integers(0, 1000),
)
def test_depth_images_of_any_size_and_type_round_trip(shape, dtype, seed):
    """Depth images of any shape (empty included) and element type round-trip."""
    rng = np.random.default_rng(seed)
    depth = (rng.uniform(0, 100, shape)).astype(dtype)
    camera = PinholeCamera(10.0, 10.0, 1.0, 1.0, 4, 4)
    frame = DepthFrame(0.0, depth, camera, _pose(rng), 1e-3 if dtype == "<u2" else None)
    assert_same(frame, DepthFrame.decode(frame.encode()))


@settings(max_examples=300, deadline=None)
@given(data=st.data())
def test_corrupt_or_truncated_bytes_raise_message_error(data):
    """Any truncation or byte flip of a message is either decoded or refused with a
    MessageError: never another exception."""
    message = data.draw(st.sampled_from(examples(np.random.default_rng(2))))
    raw = bytearray(message.encode())
    if data.draw(st.booleans()):
        raw = raw[: data.draw(st.integers(0, len(raw) - 1))]
    else:
        for _ in range(data.draw(st.integers(1, 4))):
            raw[data.draw(st.integers(0, len(raw) - 1))] = data.draw(st.integers(0, 255))
    try:
        decode(bytes(raw))
    except MessageError:
        pass


def test_refusals_name_the_problem():
    """A wrong type, an old version, trailing bytes and junk each get their own message."""
    command = WalkCommand(speed=0.1).encode()
    with pytest.raises(MessageError, match="expected a ModeCommand"):
        ModeCommand.decode(command)
    with pytest.raises(MessageError, match="trailing"):
        decode(command + b"\0")
    with pytest.raises(MessageError, match="truncated"):
        decode(command[:-3])
    with pytest.raises(MessageError, match="magic"):
        decode(b"hello world")
    old = bytearray(command)
    name_end = 4 + 2 + len("WalkCommand")
    old[name_end : name_end + 2] = (99).to_bytes(2, "little")
    with pytest.raises(MessageError, match="version 99"):
        decode(bytes(old))
    with pytest.raises(MessageError, match="shape"):
        EffectorTargets(0.0, np.zeros((5, 3)), np.zeros((6, 3)), np.zeros(6), np.zeros((6, 3)))
