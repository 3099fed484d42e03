"""The robot live in Foxglove: its bus served over Foxglove's WebSocket protocol.

Uses the official ``foxglove-sdk`` package (the ``foxglove`` extra). Every message on the
robot's own bus goes out as the channels footfall's MCAP files hold (ROS 2 CDR with the
same ``ros2msg`` schemas, :mod:`footfall.recording.ros_types`: the depth and colour images,
the camera pose, ``/tf`` with the body, camera and feet, the grid map and occupancy, the
gait status, joint states and targets, touchdowns, ``/rosout``), so one saved Foxglove
layout shows a live robot and a recorded one. Two channels in Foxglove's own schemas add
what its 3-D panel draws best:

- ``/map/elevation`` (``foxglove.Grid``): the height map with ``elevation`` and ``score``
  fields (float32, NaN unknown), cell ``[i, j]`` at column ``i`` (x) and row ``j`` (y);
- ``/scene`` (``foxglove.SceneUpdate``): the body, the feet (orange while swinging), the
  last footholds and each swinging foot's path so far.

A message is converted only while some client subscribes to a channel it feeds (the first
of each is converted to advertise the channel). ``/map/elevation`` and ``/scene`` exist from
the start: a channel the SDK advertises while a client is connected can reach the client
before the server has it in that client's list, and a client that subscribes at once is told
"Unknown channel ID" (the robot's map grid: 9 of 20 connections under load, none once the
channel was made before any client came). The server listens on loopback unless a host is
given.
"""

from __future__ import annotations

import threading
import time
from collections import defaultdict, deque
from typing import Any

import numpy as np

from footfall.errors import ConfigError
from footfall.messages import EffectorTargets, MapUpdate, Message, PoseEstimate, Touchdown
from footfall.recording.ros_types import WORLD_FRAME, msgdef, to_ros, typestore

GRID_TOPIC = "/map/elevation"
SCENE_TOPIC = "/scene"
FOOTHOLDS_SHOWN = 60
TRAIL_POINTS = 60
BODY_SIZE_M = (0.24, 0.16, 0.05)
FOOT_DIAMETER_M = 0.03


def _foxglove():
    try:
        import foxglove
    except ImportError as exc:
        raise ConfigError(
            "--foxglove needs the foxglove-sdk package: uv sync --extra foxglove"
        ) from exc
    return foxglove


def timestamp(stamp_s: float) -> Any:
    """A ``foxglove.Timestamp``, to the nanosecond as the MCAP files' ROS stamps are."""
    from foxglove.messages import Timestamp

    sec, nsec = divmod(max(round(stamp_s * 1e9), 0), 1_000_000_000)
    return Timestamp(sec=sec, nsec=nsec)


def elevation_grid(update: MapUpdate) -> Any:
    """The map as a ``foxglove.Grid``: ``elevation`` and ``score`` float32 fields."""
    from foxglove.messages import (
        Grid,
        PackedElementField,
        PackedElementFieldNumericType,
        Pose,
        Quaternion,
        Vector2,
        Vector3,
    )

    n, m = np.shape(update.heights)
    cells = np.empty((m, n, 2), "<f4")  # rows along y, columns along x
    cells[..., 0] = np.where(update.known, update.heights, np.nan).T
    cells[..., 1] = np.asarray(update.score).T
    float32 = PackedElementFieldNumericType.Float32
    return Grid(
        timestamp=timestamp(update.stamp),
        frame_id=WORLD_FRAME,
        pose=Pose(
            position=Vector3(x=float(update.origin[0]), y=float(update.origin[1]), z=0.0),
            orientation=Quaternion(x=0.0, y=0.0, z=0.0, w=1.0),
        ),
        column_count=n,
        cell_size=Vector2(x=float(update.resolution), y=float(update.resolution)),
        row_stride=8 * n,
        cell_stride=8,
        fields=[
            PackedElementField(name="elevation", offset=0, type=float32),
            PackedElementField(name="score", offset=4, type=float32),
        ],
        data=cells.tobytes(),
    )


class _Subscriptions:
    """Which channels some client subscribes to (a ``ServerListener``)."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._count: dict[str, int] = defaultdict(int)

    def on_subscribe(self, client: Any, channel: Any) -> None:
        with self._lock:
            self._count[channel.topic] += 1

    def on_unsubscribe(self, client: Any, channel: Any) -> None:
        with self._lock:
            self._count[channel.topic] = max(0, self._count[channel.topic] - 1)

    def wanted(self, topics) -> bool:
        with self._lock:
            return any(self._count.get(t, 0) > 0 for t in topics)


class FoxgloveLive:
    """Serve a bus over Foxglove's WebSocket protocol (tap it: :meth:`tap`).

    Args:
        port: The server's port (0: any free one; see :attr:`port`).
        host: Where it listens (loopback by default).
        name: The server's name in Foxglove.

    Raises:
        ConfigError: No ``foxglove-sdk`` installed, or the port cannot be had.
    """

    def __init__(self, port: int, host: str = "127.0.0.1", name: str = "footfall") -> None:
        foxglove = _foxglove()
        self._fg = foxglove
        self.context = foxglove.Context()
        # Foxglove's own channels are made before any client comes (the module docstring).
        self._channels: dict[str, Any] = {
            GRID_TOPIC: foxglove.channels.GridChannel(GRID_TOPIC, context=self.context),
            SCENE_TOPIC: foxglove.channels.SceneUpdateChannel(SCENE_TOPIC, context=self.context),
        }
        self.subscriptions = _Subscriptions()
        try:
            self.server = foxglove.start_server(
                name=name,
                host=host,
                port=port,
                context=self.context,
                server_listener=self.subscriptions,
            )
        except Exception as exc:  # the SDK raises its own error for a port in use
            raise ConfigError(f"Foxglove server on {host}:{port}: {exc}") from exc
        self.port = self.server.port
        self._feeds: dict[str, set[str]] = defaultdict(set)  # bus topic -> channels it feeds
        self._footholds: deque[np.ndarray] = deque(maxlen=FOOTHOLDS_SHOWN)
        self._trails: list[deque[np.ndarray]] = [deque(maxlen=TRAIL_POINTS) for _ in range(6)]
        self._body: Any = None
        self._store = typestore()

    # Channels ------------------------------------------------------------------------------
    def _ros_channel(self, topic: str, typename: str) -> Any:
        channel = self._channels.get(topic)
        if channel is None:
            schema = self._fg.Schema(
                name=typename, encoding="ros2msg", data=msgdef(typename).encode()
            )
            channel = self._fg.Channel(
                topic, schema=schema, message_encoding="cdr", context=self.context
            )
            self._channels[topic] = channel
        return channel

    def _wanted(self, topic: str) -> bool:
        feeds = self._feeds.get(topic)
        return not feeds or self.subscriptions.wanted(feeds)

    # The bus ---------------------------------------------------------------------------------
    def tap(self, topic: str, message: Message) -> None:
        """Serve one bus message (the signature of :meth:`InProcessBus.tap`)."""
        now_ns = time.time_ns()
        if isinstance(message, PoseEstimate) and topic == PoseEstimate.TOPIC:
            self._body = message.body_in_world
        if self._wanted(topic):
            for channel, typename, ros in to_ros(topic, message):
                self._feeds[topic].add(channel)
                data = bytes(self._store.serialize_cdr(ros, typename))
                self._ros_channel(channel, typename).log(data, log_time=now_ns)
        if isinstance(message, MapUpdate):
            self._feeds[topic].add(GRID_TOPIC)
            if self.subscriptions.wanted((GRID_TOPIC,)):
                self._channels[GRID_TOPIC].log(elevation_grid(message), log_time=now_ns)
        elif isinstance(message, Touchdown):
            self._footholds.append(np.asarray(message.chosen_in_world, float))
        elif isinstance(message, EffectorTargets):
            for leg, trail in enumerate(self._trails):
                if message.swinging[leg]:
                    trail.append(np.asarray(message.feet_in_world[leg], float))
                else:
                    trail.clear()
            if self.subscriptions.wanted((SCENE_TOPIC,)):
                self._channels[SCENE_TOPIC].log(self._scene(message), log_time=now_ns)

    def _scene(self, targets: EffectorTargets) -> Any:
        from foxglove.messages import (
            Color,
            CubePrimitive,
            LinePrimitive,
            LinePrimitiveLineType,
            Point3,
            Pose,
            Quaternion,
            SceneEntity,
            SceneUpdate,
            SpherePrimitive,
            Vector3,
        )

        stamp = timestamp(targets.stamp)
        identity = Quaternion(x=0.0, y=0.0, z=0.0, w=1.0)

        def vec(p) -> Any:
            return Vector3(x=float(p[0]), y=float(p[1]), z=float(p[2]))

        def at(p) -> Any:
            return Pose(position=vec(p), orientation=identity)

        def sphere(p, colour) -> Any:
            d = FOOT_DIAMETER_M
            return SpherePrimitive(pose=at(p), size=Vector3(x=d, y=d, z=d), color=colour)

        orange, grey = Color(r=1.0, g=0.55, b=0.1, a=1.0), Color(r=0.6, g=0.6, b=0.6, a=1.0)
        feet = [
            sphere(p, orange if targets.swinging[k] else grey)
            for k, p in enumerate(targets.feet_in_world)
        ]
        held = [sphere(p, Color(r=0.2, g=0.8, b=0.3, a=0.8)) for p in self._footholds]
        paths = [
            LinePrimitive(
                type=LinePrimitiveLineType.LineStrip,
                pose=at((0.0, 0.0, 0.0)),
                thickness=0.005,
                scale_invariant=False,
                points=[Point3(x=float(x), y=float(y), z=float(z)) for x, y, z in trail],
                color=orange,
            )
            for trail in self._trails
            if len(trail) >= 2
        ]
        entities = [
            SceneEntity(
                timestamp=stamp, frame_id=WORLD_FRAME, id="feet", spheres=feet + held, lines=paths
            )
        ]
        if self._body is not None:
            x, y, z, w = self._body.rotation.as_quat()
            body = CubePrimitive(
                pose=Pose(
                    position=vec(self._body.position),
                    orientation=Quaternion(x=float(x), y=float(y), z=float(z), w=float(w)),
                ),
                size=vec(BODY_SIZE_M),
                color=Color(r=0.3, g=0.4, b=0.9, a=0.8),
            )
            entities.append(
                SceneEntity(timestamp=stamp, frame_id=WORLD_FRAME, id="body", cubes=[body])
            )
        return SceneUpdate(entities=entities)

    def close(self) -> None:
        """Stop the server."""
        self.server.stop()
