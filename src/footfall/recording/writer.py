"""Record a bus to an MCAP file: every message as ROS 2 CDR, with its schema embedded.

A :class:`McapRecorder` taps a bus (:meth:`InProcessBus.tap`): each published message
becomes its ROS 2 channel messages (:func:`footfall.recording.ros_types.to_ros`), written
in publish order with the message's own time as log time. What replay needs beyond the
messages (the depth camera's range limits, noise model and depth scale, the mapping
settings) goes into MCAP metadata records named ``footfall/...``.
"""

from __future__ import annotations

import math
from dataclasses import fields, is_dataclass
from pathlib import Path
from types import TracebackType
from typing import Any

from mcap.writer import CompressionType, Writer

from footfall.errors import ConfigError
from footfall.messages import DepthFrame
from footfall.messages.codec import Message
from footfall.nodes.mapping import MappingNode
from footfall.recording.ros_types import msgdef, to_ros, typestore

PROFILE = "ros2"
FORMAT_VERSION = "1"


def message_time(message: Message, last: float) -> float:
    """A message's own time [s]: its ``stamp`` (``time`` for a robot state), else ``last``."""
    for name in ("stamp", "time"):
        value = getattr(message, name, None)
        if isinstance(value, int | float) and math.isfinite(value):
            return float(value)
    return last


def camera_metadata(frame: DepthFrame) -> dict[str, str]:
    """What a depth frame's ROS messages do not carry, as MCAP metadata."""
    c = frame.intrinsics
    body = frame.camera_in_body
    return {
        "depth_scale": repr(frame.depth_scale if frame.depth_scale is not None else 1.0),
        "min_range_m": repr(c.min_range),
        "max_range_m": repr(c.max_range),
        "noise_base_m": repr(c.noise.base_m),
        "noise_quadratic_per_m": repr(c.noise.quadratic_per_m),
        "noise_offset_m": repr(c.noise.offset_m),
        "camera_in_body": " ".join(
            repr(float(v)) for v in (*body.position, *body.rotation.as_quat())
        ),
    }


def _flat(prefix: str, settings: object) -> dict[str, str]:
    """Settings as ``prefix.field`` strings, nested settings as ``prefix.field.subfield``."""
    out: dict[str, str] = {}
    for f in fields(settings):  # type: ignore[arg-type]
        value = getattr(settings, f.name)
        if is_dataclass(value):
            out.update(_flat(f"{prefix}.{f.name}", value))
        else:
            out[f"{prefix}.{f.name}"] = str(value)
    return out


def restored_settings(kind: type, prefix: str, metadata: dict[str, str]) -> dict[str, object]:
    """The fields of settings ``kind`` that :func:`_flat` wrote under ``prefix``.

    Raises:
        ValueError: A value that does not parse as its field's type.
    """
    defaults = kind()
    values: dict[str, object] = {}
    for f in fields(kind):
        default = getattr(defaults, f.name)
        if is_dataclass(default):
            nested = restored_settings(type(default), f"{prefix}.{f.name}", metadata)
            if nested:
                values[f.name] = type(default)(**nested)
            continue
        text = metadata.get(f"{prefix}.{f.name}")
        if text is None:
            continue
        cast = type(default)
        if cast is bool:
            values[f.name] = text == "True"
        else:
            values[f.name] = str(text) if issubclass(cast, str) else cast(float(text))
    return values


def mapping_metadata(node: MappingNode) -> dict[str, str]:
    """A mapping node's settings and starting centre, for a replay to build the same map."""
    out = {**_flat("map", node.height_map.config), **_flat("score", node.score_config)}
    out.update(
        stride=str(node.stride),
        reject_repeats=str(node.reject_repeats),
        centre_x=repr(node.initial_centre[0]),
        centre_y=repr(node.initial_centre[1]),
    )
    return out


class McapRecorder:
    """Write bus messages to an MCAP file as ROS 2 messages.

    Args:
        path: The ``.mcap`` file (its folder is created).
        metadata: Records to add, ``name -> {key: value}`` (e.g. ``footfall/mapping``).

    Raises:
        ConfigError: A path that does not end in ``.mcap``.
    """

    def __init__(self, path: str | Path, metadata: dict[str, dict[str, str]] | None = None) -> None:
        self.path = Path(path)
        if self.path.suffix.lower() != ".mcap":
            raise ConfigError(f"--record needs a .mcap file, got {self.path}")
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._stream = self.path.open("wb")
        self._writer = Writer(self._stream, compression=CompressionType.ZSTD)
        self._writer.start(profile=PROFILE, library="footfall")
        self._schemas: dict[str, int] = {}
        self._channels: dict[str, int] = {}
        self._sequence = 0
        self._time = 0.0
        self._camera_written = False
        self.messages = 0
        self._writer.add_metadata("footfall/recording", {"format_version": FORMAT_VERSION})
        for name, values in (metadata or {}).items():
            self._writer.add_metadata(name, dict(values))

    def add_metadata(self, name: str, values: dict[str, str]) -> None:
        """Add a metadata record (any time before :meth:`close`)."""
        self._writer.add_metadata(name, dict(values))

    def _channel(self, topic: str, typename: str) -> int:
        if topic not in self._channels:
            if typename not in self._schemas:
                self._schemas[typename] = self._writer.register_schema(
                    name=typename, encoding="ros2msg", data=msgdef(typename).encode()
                )
            self._channels[topic] = self._writer.register_channel(
                topic=topic, message_encoding="cdr", schema_id=self._schemas[typename]
            )
        return self._channels[topic]

    def write(self, topic: str, typename: str, message: Any, time_s: float) -> None:
        """Write one ROS message on ``topic`` at ``time_s``."""
        data = bytes(typestore().serialize_cdr(message, typename))
        ns = max(round(time_s * 1e9), 0)
        self._writer.add_message(
            channel_id=self._channel(topic, typename),
            log_time=ns,
            publish_time=ns,
            sequence=self._sequence,
            data=data,
        )
        self._sequence += 1
        self.messages += 1

    def tap(self, topic: str, message: Message) -> None:
        """Record one bus message (the signature of :meth:`InProcessBus.tap`)."""
        self._time = message_time(message, self._time)
        if isinstance(message, DepthFrame) and not self._camera_written:
            self._writer.add_metadata("footfall/camera", camera_metadata(message))
            self._camera_written = True
        for channel, typename, ros in to_ros(topic, message):
            self.write(channel, typename, ros, self._time)

    def close(self) -> None:
        """Finish the file (its summary and index)."""
        if not self._stream.closed:
            self._writer.finish()
            self._stream.close()

    def __enter__(self) -> McapRecorder:
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        error: BaseException | None,
        traceback: TracebackType | None,
    ) -> None:
        self.close()
