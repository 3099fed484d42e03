"""`footfall robot --foxglove`: a real WebSocket client speaking Foxglove's protocol."""

from __future__ import annotations

import base64
import json
import signal
import struct
import time

import numpy as np
import pytest
from google.protobuf import descriptor_pb2, descriptor_pool, message_factory
from websockets.sync.client import connect

from footfall.recording.reader import Recording
from test_robot_network import start_robot
from test_zenoh_bus import free_port

# The protocol's current name and its earlier one (the SDK speaks the current one).
SUBPROTOCOLS = ["foxglove.sdk.v1", "foxglove.websocket.v1"]
MESSAGE_DATA = 0x01


def connect_when_up(url: str, seconds: float):
    """Connect once the robot's server listens."""
    end = time.monotonic() + seconds
    while True:
        try:
            return connect(url, subprotocols=SUBPROTOCOLS, open_timeout=2.0)
        except OSError:
            if time.monotonic() > end:
                raise
            time.sleep(0.5)


def protobuf_class(channel: dict):
    """The message class of a channel advertised with a protobuf schema."""
    assert channel["schemaEncoding"] == "protobuf"
    files = descriptor_pb2.FileDescriptorSet.FromString(base64.b64decode(channel["schema"]))
    pool = descriptor_pool.DescriptorPool()
    for f in files.file:
        pool.Add(f)
    return message_factory.GetMessageClass(pool.FindMessageTypeByName(channel["schemaName"]))


def test_a_foxglove_client_subscribes_to_the_live_map_and_decodes_the_robots_grid(tmp_path):
    """A WebSocket client speaking Foxglove's protocol connects to `footfall robot
    --foxglove`, finds the map channel among the advertised ones (beside the MCAP files'
    ROS channels), subscribes and decodes foxglove.Grid messages whose elevation is, cell
    for cell, the robot's own map of the same stamp (from its --record file)."""
    port, endpoint = free_port(), f"tcp/127.0.0.1:{free_port()}"
    record = tmp_path / "robot.mcap"
    robot = start_robot(
        endpoint, "stairs", tmp_path, 60.0, "--foxglove", str(port), "--record", str(record)
    )
    grids = []
    try:
        with connect_when_up(f"ws://127.0.0.1:{port}", 60.0) as ws:
            channels: dict[str, dict] = {}
            subscribed = False
            end = time.monotonic() + 60.0
            while len(grids) < 3 and time.monotonic() < end:
                frame = ws.recv(timeout=10.0)
                if isinstance(frame, str):
                    message = json.loads(frame)
                    if message["op"] == "status" and message["level"] == 2:
                        pytest.fail(f"the server answered with an error: {message['message']}")
                    if message["op"] == "advertise":
                        channels.update({c["topic"]: c for c in message["channels"]})
                    if not subscribed and "/map/elevation" in channels:
                        grid_channel = channels["/map/elevation"]
                        subscription = {"id": 7, "channelId": grid_channel["id"]}
                        ws.send(json.dumps({"op": "subscribe", "subscriptions": [subscription]}))
                        Grid = protobuf_class(grid_channel)
                        subscribed = True
                elif frame[0] == MESSAGE_DATA:
                    subscription_id, _ = struct.unpack_from("<IQ", frame, 1)
                    assert subscription_id == 7
                    grids.append(Grid.FromString(frame[13:]))
    finally:
        robot.send_signal(signal.SIGINT)
        output = robot.communicate(timeout=60)[0].decode(errors="replace")
    assert robot.returncode == 0, output
    assert grids, f"no grid came; channels advertised: {sorted(channels)}"
    # The MCAP files' channels are served too, with their ROS 2 schemas.
    assert channels["/map/grid"]["schemaName"] == "grid_map_msgs/msg/GridMap"
    assert channels["/map/grid"]["encoding"] == "cdr"
    assert {"/tf", "/camera/depth/image_raw", "/gait_status"} <= set(channels)

    recorded = {}
    for m in Recording(record).messages({"/map/grid"}):
        stamp = m.message.header.stamp
        n = round(m.message.info.length_x / m.message.info.resolution)
        layer = np.asarray(m.message.data[0].data, np.float32)
        recorded[(stamp.sec, stamp.nanosec)] = layer.reshape(n, -1, order="F")[::-1, ::-1]
    compared = 0
    for grid in grids:
        n = grid.column_count
        cells = np.frombuffer(grid.data, dtype=[("elevation", "<f4"), ("score", "<f4")])
        elevation = cells["elevation"].reshape(-1, n).T  # rows along y: back to [i, j]
        assert [f.name for f in grid.fields] == ["elevation", "score"]
        assert grid.cell_size.x == pytest.approx(0.02)
        robot_map = recorded.get((grid.timestamp.seconds, grid.timestamp.nanos))
        if robot_map is None:
            continue
        np.testing.assert_array_equal(elevation, robot_map)
        assert np.isfinite(elevation).sum() > 1000
        compared += 1
    assert compared >= 1
