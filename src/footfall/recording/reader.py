"""Read recordings: footfall's MCAP files, ROS 2 bags (sqlite3 or MCAP) and ROS 1 bags.

A bare ``.mcap`` file is read with the ``mcap`` library and its messages decoded from the
``ros2msg`` schemas it embeds (so types footfall has never seen decode too); a ROS 2 bag
folder (``metadata.yaml``) or a ROS 1 ``.bag`` goes through ``rosbags``' AnyReader. Either
way a recording is its channels (topic -> type), its metadata and its messages in the
order they were written (log time, ties in file order).
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from rosbags.typesys import get_types_from_msg

from footfall.errors import DatasetError, FootfallError
from footfall.recording.ros_types import typestore

_SEPARATOR = re.compile(r"^={10,}\s*$", re.MULTILINE)


@dataclass(frozen=True)
class RecordedMessage:
    """One message of a recording.

    Attributes:
        log_time_ns: When it was logged [ns].
        topic: Its channel.
        typename: Its ROS type, ``pkg/msg/Name``.
        message: The decoded message (a rosbags dataclass).
    """

    log_time_ns: int
    topic: str
    typename: str
    message: Any


def _ros2_name(name: str) -> str:
    parts = name.split("/")
    return f"{parts[0]}/msg/{parts[-1]}" if len(parts) == 2 else name


def register_schema(name: str, text: str) -> None:
    """Teach the type store a type from a ``ros2msg`` schema (its dependencies follow it)."""
    store = typestore()
    blocks = _SEPARATOR.split(text)
    types: dict[str, Any] = {}
    for k, block in enumerate(blocks):
        body = block.strip("\n")
        typename = _ros2_name(name)
        if k > 0:
            first, _, body = body.partition("\n")
            if not first.startswith("MSG:"):
                continue
            typename = _ros2_name(first[4:].strip())
        if typename in store.types or typename in types:
            continue
        try:
            types.update(get_types_from_msg(body + "\n", typename))
        except Exception as exc:  # rosbags' parser raises its own kinds
            raise DatasetError(
                f"schema {name}: cannot parse the definition of {typename} ({exc})"
            ) from exc
    if types:
        store.register(types)


class Recording:
    """A recording file or bag, opened for reading.

    Args:
        path: A ``.mcap`` file, a ROS 2 bag folder or a ROS 1 ``.bag`` file.

    Raises:
        DatasetError: A missing path, or one that is none of these, or unreadable.
    """

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        if not self.path.exists():
            raise DatasetError(f"missing recording {self.path}")
        self.kind = (
            "mcap" if self.path.is_file() and self.path.suffix.lower() == ".mcap" else "rosbags"
        )
        self.metadata: dict[str, dict[str, str]] = {}
        self.channels: dict[str, str] = {}
        self.unreadable: dict[str, str] = {}
        if self.kind == "mcap":
            self._open_mcap()
        else:
            self._open_rosbags()

    def _open_mcap(self) -> None:
        from mcap.reader import make_reader

        try:
            with self.path.open("rb") as stream:
                reader = make_reader(stream)
                summary = reader.get_summary()
                if summary is None:
                    raise DatasetError(f"{self.path}: no summary (a truncated MCAP file?)")
                for channel in summary.channels.values():
                    schema = summary.schemas.get(channel.schema_id)
                    if schema is None or schema.encoding != "ros2msg":
                        continue
                    try:
                        register_schema(schema.name, schema.data.decode(errors="replace"))
                    except DatasetError as exc:  # that channel stays unread, the rest read
                        self.unreadable[channel.topic] = str(exc)
                        continue
                    self.channels[channel.topic] = _ros2_name(schema.name)
                self.metadata = {m.name: dict(m.metadata) for m in reader.iter_metadata()}
        except FootfallError:
            raise
        except Exception as exc:  # McapError, and the compression libraries' own kinds
            raise DatasetError(
                f"{self.path}: not a readable MCAP file ({type(exc).__name__}: {exc})"
            ) from exc

    def _open_rosbags(self) -> None:
        from rosbags.highlevel import AnyReader

        try:
            with AnyReader([self.path], default_typestore=typestore()) as reader:
                self.channels = {c.topic: c.msgtype for c in reader.connections}
        except Exception as exc:  # rosbags raises its own kinds per format
            # A ROS 2 bag folder whose type definitions rosbags refuses as a whole (a hash
            # from another ROS release, one unparsable custom type) still reads file by
            # file: its MCAP through its own schemas, or its sqlite3 with ROS 2's types.
            files = sorted(self.path.glob("*.mcap")) if self.path.is_dir() else []
            if len(files) == 1:
                self.path, self.kind = files[0], "mcap"
                self._open_mcap()
                return
            if self.path.is_dir() and any(self.path.glob("*.db3")):
                self.kind = "sqlite3"
                self._open_sqlite3(exc)
                return
            raise DatasetError(
                f"{self.path}: not a readable ROS bag (a ROS 2 bag folder, a ROS 1 .bag or an "
                f".mcap file) ({exc})"
            ) from exc

    def _open_sqlite3(self, cause: Exception) -> None:
        from rosbags.rosbag2 import Reader

        try:
            with Reader(self.path) as reader:
                self.channels = {c.topic: c.msgtype for c in reader.connections}
        except Exception as exc:  # rosbags raises its own kinds
            raise DatasetError(f"{self.path}: not a readable ROS 2 bag ({cause}; {exc})") from exc

    def require(self, topic: str, what: str) -> str:
        """The type of ``topic``.

        Raises:
            DatasetError: The topic is not in the recording (the topics are listed).
        """
        if topic not in self.channels:
            listed = ", ".join(f"{t} ({k})" for t, k in sorted(self.channels.items()))
            unread = (
                f"; unreadable: {', '.join(sorted(self.unreadable))}" if self.unreadable else ""
            )
            raise DatasetError(f"{self.path}: no {what} topic {topic!r}; it holds {listed}{unread}")
        return self.channels[topic]

    def messages(self, topics: set[str] | None = None) -> Iterator[RecordedMessage]:
        """The messages on ``topics`` (all by default), in log-time order.

        Raises:
            DatasetError: A corrupt file or message (the decoders' own errors, named).
        """
        try:
            if self.kind == "mcap":
                yield from self._mcap_messages(topics)
            elif self.kind == "sqlite3":
                yield from self._sqlite3_messages(topics)
            else:
                yield from self._rosbags_messages(topics)
        except FootfallError:
            raise
        except Exception as exc:  # the format libraries raise their own kinds on corrupt data
            raise DatasetError(
                f"{self.path}: corrupt recording ({type(exc).__name__}: {exc})"
            ) from exc

    def _sqlite3_messages(self, topics: set[str] | None) -> Iterator[RecordedMessage]:
        from rosbags.rosbag2 import Reader

        store = typestore()
        with Reader(self.path) as reader:
            connections = [c for c in reader.connections if topics is None or c.topic in topics]
            for connection, timestamp, raw in reader.messages(connections=connections):
                if connection.msgtype not in store.types:
                    continue
                message = store.deserialize_cdr(raw, connection.msgtype)
                yield RecordedMessage(timestamp, connection.topic, connection.msgtype, message)

    def _mcap_messages(self, topics: set[str] | None) -> Iterator[RecordedMessage]:
        """Messages in file order (the order they were written: ties in time keep it)."""
        from mcap.exceptions import McapError
        from mcap.records import Channel
        from mcap.records import Message as McapMessage
        from mcap.stream_reader import StreamReader

        store = typestore()
        channels: dict[int, str] = {}
        try:
            with self.path.open("rb") as stream:
                for record in StreamReader(stream).records:
                    if isinstance(record, Channel):
                        channels[record.id] = record.topic
                    elif isinstance(record, McapMessage):
                        topic = channels.get(record.channel_id)
                        if topic is None or (topics is not None and topic not in topics):
                            continue
                        typename = self.channels.get(topic)
                        if typename is None:
                            continue
                        message = store.deserialize_cdr(record.data, typename)
                        yield RecordedMessage(record.log_time, topic, typename, message)
        except (McapError, ValueError, OSError, EOFError) as exc:
            raise DatasetError(f"{self.path}: {type(exc).__name__}: {exc}") from exc

    def _rosbags_messages(self, topics: set[str] | None) -> Iterator[RecordedMessage]:
        from rosbags.highlevel import AnyReader

        with AnyReader([self.path], default_typestore=typestore()) as reader:
            connections = [c for c in reader.connections if topics is None or c.topic in topics]
            for connection, timestamp, raw in reader.messages(connections=connections):
                message = reader.deserialize(raw, connection.msgtype)
                yield RecordedMessage(timestamp, connection.topic, connection.msgtype, message)
