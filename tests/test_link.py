"""The radio link: packed maps, depth and colour, and a sender paced by acknowledgements."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from footfall.errors import MessageError
from footfall.messages import ColorImage, DepthFrame, MapUpdate, decode
from footfall.messages.wire import LinkAck, PackedColor, WholeMapRequest
from footfall.runtime.bridge import Bridge
from footfall.runtime.bus import InProcessBus
from footfall.runtime.link import MIN_WINDOW_BYTES, LinkReceiver, LinkSender
from footfall.runtime.wire import (
    SCORE_FULL_SCALE,
    SCORE_STEP,
    MapPacker,
    MapUnpacker,
    pack_color,
    pack_depth,
    unpack_color,
    unpack_depth,
)
from footfall.sensing.camera import PinholeCamera
from footfall.sensing.pose import Pose

RESOLUTION = 0.02


def random_map(rng: np.random.Generator, n: int, corner: tuple[int, int], sequence: int):
    """A map window with unknown cells, steps, large scores and a spread layer."""
    heights = rng.uniform(-0.3, 0.5, (n, n)) + rng.choice([0.0, 0.08], (n, n))
    known = rng.random((n, n)) > 0.3
    heights[~known] = np.nan
    spread = np.where(known, rng.uniform(0, 0.05, (n, n)), np.nan)
    score = np.where(known, rng.exponential(0.3, (n, n)), np.nan)
    valid = known & (score < 0.5)
    return MapUpdate(
        stamp=0.1 * sequence,
        sequence=sequence,
        heights=heights,
        known=known,
        spread=spread,
        slope=np.zeros((n, n)),
        proximity=np.zeros((n, n)),
        score=score,
        valid=valid,
        origin=(corner[0] * RESOLUTION, corner[1] * RESOLUTION),
        resolution=RESOLUTION,
    )


def assert_within_quantisation(got: MapUpdate, sent: MapUpdate) -> None:
    """The station's map equals the robot's within the link's quantisation."""
    assert got is not None and got.sequence == sent.sequence and got.origin == sent.origin
    np.testing.assert_array_equal(got.known, sent.known)
    np.testing.assert_array_equal(got.valid, sent.valid)
    k = sent.known
    assert np.all(np.isnan(got.heights[~k]))
    assert np.max(np.abs(got.heights[k] - sent.heights[k]), initial=0) <= 0.0005 + 1e-9
    assert np.max(np.abs(got.spread[k] - sent.spread[k]), initial=0) <= 0.0005 + 1e-9
    scored = np.isfinite(sent.score)
    np.testing.assert_array_equal(np.isfinite(got.score), scored)
    low = scored & (sent.score <= SCORE_FULL_SCALE)
    high = scored & ~low
    assert np.max(np.abs(got.score[low] - sent.score[low]), initial=0) <= SCORE_STEP / 2 + 1e-12
    assert np.all(got.score[high] >= SCORE_FULL_SCALE - SCORE_STEP / 2)


@settings(max_examples=40, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    n=st.integers(4, 40),
    shift=st.tuples(st.integers(-12, 12), st.integers(-12, 12)),
    changed=st.floats(0.0, 1.0),
)
def test_a_map_crosses_the_link_whole_and_as_changes_within_its_quantisation(
    seed, n, shift, changed
):
    """A whole map, then the same window scrolled and partly re-measured, sent as the cells
    that changed since the whole map: each arrives equal to the robot's map within the
    quantisation (1 mm heights and spread, the score's step), unknown cells unknown."""
    rng = np.random.default_rng(seed)
    clock = [0.0]
    packer, unpacker = MapPacker(clock=lambda: clock[0]), MapUnpacker()
    first = random_map(rng, n, (100, -40), 1)
    whole = packer.pack(first)
    assert whole.base == 0
    assert_within_quantisation(unpacker.unpack(decode(whole.encode())), first)

    second = random_map(rng, n, (100 + shift[0], -40 + shift[1]), 2)
    # Where the windows overlap and the cell was not re-measured, the map is as before.
    keep = rng.random((n, n)) > changed
    di, dj = shift
    fields = {}
    for name in ("heights", "known", "spread", "score", "valid"):
        new, old = getattr(second, name).copy(), getattr(first, name)
        for i in range(n):
            for j in range(n):
                if keep[i, j] and 0 <= i + di < n and 0 <= j + dj < n:
                    new[i, j] = old[i + di, j + dj]
        fields[name] = new
    second = dataclasses.replace(second, **fields)
    clock[0] = 0.5
    changes = packer.pack(second)
    if max(abs(di), abs(dj)) <= n // 4:
        assert changes.base == first.sequence
    assert_within_quantisation(unpacker.unpack(decode(changes.encode())), second)


def test_an_unchanged_map_travels_as_almost_nothing_and_a_whole_map_goes_regularly():
    """Changes to a map that did not change are a few bytes; after WHOLE_EVERY_S, or when a
    receiver asks, the map goes whole again."""
    rng = np.random.default_rng(1)
    clock = [0.0]
    packer = MapPacker(whole_every_s=2.0, clock=lambda: clock[0])
    update = random_map(rng, 128, (0, 0), 1)
    whole = packer.pack(update)
    clock[0] = 1.0
    same = packer.pack(dataclasses.replace(update, sequence=2))
    assert same.base == 1 and len(same.encode()) < len(whole.encode()) / 20
    clock[0] = 2.0
    assert packer.pack(dataclasses.replace(update, sequence=3)).base == 0
    packer.want_whole = True
    clock[0] = 2.1
    assert packer.pack(dataclasses.replace(update, sequence=4)).base == 0


def test_changes_to_a_whole_map_not_received_ask_for_one_and_are_not_guessed():
    """A station that joins between whole maps gets changes it cannot apply: it passes
    nothing on, asks the robot for a whole map (not more than twice a second) and then has
    the map exactly."""
    rng = np.random.default_rng(2)
    clock = [0.0]
    packer = MapPacker(clock=lambda: clock[0])
    sent: list = []
    receiver = LinkReceiver(lambda topic, m: sent.append(m), "station", clock=lambda: clock[0])
    packer.pack(random_map(rng, 32, (0, 0), 1))  # the whole map the station missed
    for k in (2, 3):
        clock[0] += 0.1
        packed = dataclasses.replace(packer.pack(random_map(rng, 32, (0, 0), k)), link_sequence=k)
        assert receiver.unpack("map", packed) is None
    asks = [m for m in sent if isinstance(m, WholeMapRequest)]
    assert len(asks) == 1 and receiver.waiting_for_whole == 2
    receiver.acknowledge()  # both arrivals in one acknowledgement
    acks = [m.link_sequences.tolist() for m in sent if isinstance(m, LinkAck)]
    assert acks == [[2, 3]]
    receiver.acknowledge()  # nothing new: nothing sent
    assert len([m for m in sent if isinstance(m, LinkAck)]) == 1
    packer.want_whole = True  # as the robot's sender does on the request
    update = random_map(rng, 32, (1, 0), 4)
    assert_within_quantisation(receiver.unpack("map", packer.pack(update)), update)


def test_a_malformed_packed_map_is_refused_naming_the_problem():
    packed = MapPacker().pack(random_map(np.random.default_rng(3), 16, (0, 0), 1))
    with pytest.raises(MessageError, match="decompress"):
        MapUnpacker().unpack(dataclasses.replace(packed, cells=packed.cells[:-5]))
    with pytest.raises(MessageError, match="bytes"):
        MapUnpacker().unpack(dataclasses.replace(packed, rows=8))


@settings(max_examples=20, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), width=st.integers(8, 1280), integer=st.booleans())
def test_depth_crosses_as_millimetres_decimated_to_the_same_rays(seed, width, integer):
    """Depth arrives within half a millimetre, no reading stays no reading, and a decimated
    image's pixels lie on the rays of the pixels they were taken from."""
    rng = np.random.default_rng(seed)
    height = max(2, width * 3 // 4)
    camera = PinholeCamera(
        0.8 * width, 0.8 * width, width / 2 - 0.5, height / 2 - 0.5, width, height
    )
    metres = rng.uniform(0.2, 6.0, (height, width))
    metres[rng.random((height, width)) < 0.1] = 0.0
    if integer:
        depth, scale = np.rint(metres * 5000).astype(np.uint16), 2e-4
        metres = depth / 5000.0
    else:
        depth, scale = metres.astype(np.float32), None
        metres = depth.astype(np.float64)
    frame = DepthFrame(1.5, depth, camera, Pose(np.zeros(3), Rotation.identity()), scale, 4)
    got = unpack_depth(decode(pack_depth(frame, max_width=424).encode()))
    k = int(np.ceil(width / 424))
    assert got.intrinsics.width <= 424 and got.sequence == 4 and got.stamp == 1.5
    expected = metres[::k, ::k]
    assert got.depth.shape == expected.shape
    np.testing.assert_array_equal(got.depth == 0, expected == 0)
    assert np.max(np.abs(got.depth * got.depth_scale - expected)) <= 0.0005 + 1e-9
    ours = got.intrinsics.organized_points(got.depth, got.depth_scale)
    theirs = camera.organized_points(depth, scale)[::k, ::k]
    ok = expected > 0
    assert np.max(np.abs(ours[ok] - theirs[ok])) <= 0.0005 * 8


def test_colour_crosses_as_jpeg_and_a_broken_one_is_refused():
    y, x = np.mgrid[0:240, 0:320]
    image = np.stack([x * 255 // 320, y * 255 // 240, (x + y) % 256], axis=-1).astype(np.uint8)
    packed = pack_color(ColorImage(2.0, image, 9))
    assert len(packed.encode()) < image.nbytes / 5
    got = unpack_color(decode(packed.encode()))
    assert got.image.shape == image.shape and got.sequence == 9
    assert np.mean(np.abs(got.image.astype(int) - image)) < 4
    with pytest.raises(MessageError, match="JPEG"):
        unpack_color(PackedColor(2.0, 9, np.frombuffer(b"not a jpeg", np.uint8)))


def ack(*sequences: int, at: float) -> LinkAck:
    """A station's acknowledgement of ``sequences``."""
    return LinkAck(np.asarray(sequences, np.int64), at, "station")


class Wire:
    """What a sender put on the link, and a clock."""

    def __init__(self) -> None:
        self.now = 1000.0
        self.sent: list[tuple[str, bytes]] = []

    def put(self, topic: str, data: bytes) -> None:
        """Take a message's bytes as the network would."""
        self.sent.append((topic, data))

    def topics(self) -> list[str]:
        """The topics sent, in order."""
        return [t for t, _ in self.sent]


def depth_frame(rng, sequence: int) -> DepthFrame:
    camera = PinholeCamera(200.0, 200.0, 159.5, 119.5, 320, 240)
    noisy = rng.uniform(0.3, 4.0, (240, 320)).astype(np.float32)  # does not compress
    return DepthFrame(
        0.1 * sequence, noisy, camera, Pose(np.zeros(3), Rotation.identity()), None, sequence
    )


def test_without_acknowledgements_every_bulk_message_goes_at_once():
    """A plain subscriber acknowledges nothing: the robot sends everything it is given."""
    rng, wire = np.random.default_rng(4), Wire()
    sender = LinkSender(wire.put, clock=lambda: wire.now)
    for k in range(10):
        sender.offer("depth", depth_frame(rng, k))
    assert wire.topics() == ["depth"] * 10 and sender.counts.dropped == {}


def test_a_slow_link_gets_fewer_images_not_older_ones_and_the_map_goes_first():
    """Once a station acknowledges, what is in flight stays within the window: a frame
    that cannot go waits and is replaced by a newer one (counted), the map goes before
    depth, and an acknowledgement makes room for the newest frame, not a stale one."""
    rng, wire = np.random.default_rng(5), Wire()
    sender = LinkSender(wire.put, clock=lambda: wire.now)
    sender.offer("depth", depth_frame(rng, 0))
    sender.acknowledged(ack(1, at=wire.now))  # a station is listening
    assert sender.flow_controlled
    sent_before = len(wire.sent)
    for k in range(1, 6):
        sender.offer("depth", depth_frame(rng, k))  # each ~300 kB, beyond the window
    assert len(wire.sent) == sent_before + 1  # the first fills the window
    assert sender.in_flight_bytes() > MIN_WINDOW_BYTES
    assert sender.counts.dropped["depth"] == 3
    sender.offer("map", random_map(rng, 64, (0, 0), 1))
    assert len(wire.sent) == sent_before + 1
    wire.now += 0.2
    sender.acknowledged(ack(2, at=wire.now))
    assert wire.topics()[sent_before + 1 :] == ["map", "depth"]  # the map first
    assert decode(wire.sent[-1][1]).sequence == 5  # the newest frame, not a stale one


def test_what_an_acknowledgement_passed_over_does_not_hold_the_window():
    """Packed messages arrive in order: those not acknowledged before the last one that was
    (sent before the station subscribed, or dropped on the way) no longer count as in
    flight, so the station's first frames go at once."""
    rng, wire = np.random.default_rng(8), Wire()
    sender = LinkSender(wire.put, clock=lambda: wire.now)
    for k in range(5):
        sender.offer("depth", depth_frame(rng, k))  # ~150 kB each, to nobody
    sender.acknowledged(ack(5, at=wire.now))  # the station's first acknowledgement
    assert sender.in_flight_bytes() == 0
    sender.offer("depth", depth_frame(rng, 5))
    assert len(wire.sent) == 6 and sender.counts.dropped == {}


def test_an_unacknowledged_message_stops_counting_as_in_flight():
    """A message lost on the way (never acknowledged) stops holding the window after
    ACK_WAIT_S, so a lost acknowledgement cannot stall the link for good."""
    rng, wire = np.random.default_rng(6), Wire()
    sender = LinkSender(wire.put, clock=lambda: wire.now)
    sender.offer("depth", depth_frame(rng, 0))
    sender.acknowledged(ack(1, at=wire.now))
    sender.offer("depth", depth_frame(rng, 1))
    sender.offer("depth", depth_frame(rng, 2))
    assert len(wire.sent) == 2
    wire.now += 1.1
    sender.flush()
    assert len(wire.sent) == 3 and decode(wire.sent[-1][1]).sequence == 2


def test_a_bridge_sends_a_topic_at_its_rate_on_average():
    """Messages at 15 Hz through a 5 Hz limit go out at 5 Hz on average, not at the
    every-third-or-fourth rate of a limit that restarts at each message."""
    clock = [0.0]
    local, remote = InProcessBus(), InProcessBus()
    got = []
    remote.subscribe("map", got.append)
    Bridge(local, remote, {"map": 5.0}, (), clock=lambda: clock[0])
    rng = np.random.default_rng(7)
    update = random_map(rng, 4, (0, 0), 1)
    for k in range(600):  # 40 s at 15 Hz with jitter
        clock[0] = k / 15.0 + rng.uniform(-0.004, 0.004)
        local.publish("map", update)
    assert 199 <= len(got) <= 201
