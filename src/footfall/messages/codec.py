"""Byte encoding of messages: a small, versioned, self-describing binary layout.

Every message is a frozen dataclass; its fields are encoded in declaration order from their
type annotations, so a new message needs no encoding code of its own. Layout::

    b"FFM" u8(format)  u16(len) name  u16(version)  fields...

Fields, little-endian: ``float`` as f8, ``int`` as i8, ``bool`` as u8, ``str`` and ``Enum``
values as u32 length + UTF-8; a NumPy array as its dtype string, its shape and its raw
bytes aligned to 8 bytes from the start of the message; a ``Rotation`` as its scalar-last
quaternion; a fixed tuple of floats as f8s; a nested dataclass field by field; ``X | None``
as a presence byte and then ``X``.

Arrays cost one copy to encode (into the output) and none to decode: a decoded array is a
read-only view of the input bytes. Anything that does not decode, truncated input, trailing
bytes, another message's name or another version, raises
:class:`~footfall.errors.MessageError` naming the problem.
"""

from __future__ import annotations

import dataclasses
import enum
import struct
import types
import typing
from functools import cache
from typing import Any, ClassVar, TypeVar

import numpy as np
from scipy.spatial.transform import Rotation

from footfall.errors import FootfallError, InvalidPoseError, MessageError
from footfall.sensing.pose import exact_rotation

MAGIC = b"FFM"
FORMAT = 1
# Array element types a message may carry (no objects, no structured types).
_DTYPES = frozenset(
    np.dtype(t).str for t in ("?", "u1", "i1", "<u2", "<i2", "<u4", "<i4", "<i8", "<f4", "<f8")
)
_MAX_DIMS = 8

M = TypeVar("M", bound="Message")
_REGISTRY: dict[str, type[Message]] = {}


class Message:
    """Base of the bus messages: adds ``encode()`` and ``decode()`` to a frozen dataclass.

    Subclasses set ``VERSION`` (raise it when the fields change) and ``TOPIC``, the topic
    the message travels on by default.
    """

    VERSION: ClassVar[int] = 1
    TOPIC: ClassVar[str] = ""

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        _REGISTRY[cls.__name__] = cls

    def encode(self) -> bytes:
        """This message as bytes."""
        return encode(self)

    @classmethod
    def decode(cls: type[M], data: bytes | bytearray | memoryview) -> M:
        """A message of this type from bytes.

        Raises:
            MessageError: If the bytes hold another message, another version, or are
                malformed.
        """
        message = decode(data)
        if not isinstance(message, cls):
            raise MessageError(f"expected a {cls.__name__} message, got {type(message).__name__}")
        return message


def message_types() -> dict[str, type[Message]]:
    """Every message type by name."""
    return dict(_REGISTRY)


# Encoding ----------------------------------------------------------------------------------
class _Writer:
    def __init__(self) -> None:
        self.chunks: list[bytes | memoryview] = []
        self.size = 0

    def put(self, chunk: bytes | memoryview) -> None:
        self.chunks.append(chunk)
        self.size += len(chunk)

    def pack(self, fmt: str, *values: Any) -> None:
        self.put(struct.pack("<" + fmt, *values))

    def text(self, value: str) -> None:
        raw = value.encode("utf-8")
        self.pack("I", len(raw))
        self.put(raw)

    def array(self, value: np.ndarray) -> None:
        a = np.ascontiguousarray(value)
        if a.dtype.str not in _DTYPES or a.ndim > _MAX_DIMS:
            raise MessageError(f"cannot encode an array of {a.dtype} with {a.ndim} dimensions")
        if a.dtype.byteorder == ">":
            a = a.astype(a.dtype.newbyteorder("<"))
        self.text(a.dtype.str)
        self.pack("B" + "Q" * a.ndim, a.ndim, *a.shape)
        self.put(bytes(-(self.size + 8) % 8))  # data starts 8-aligned after its length
        self.pack("Q", a.nbytes)
        self.put(memoryview(a).cast("B") if a.size else b"")


def _is_optional(kind: Any) -> Any:
    """The ``X`` of an ``X | None`` annotation, else None."""
    if typing.get_origin(kind) in (typing.Union, types.UnionType):
        rest = [a for a in typing.get_args(kind) if a is not type(None)]
        if len(rest) == 1 and len(typing.get_args(kind)) == 2:
            return rest[0]
    return None


@cache
def _fields(cls: type) -> tuple[tuple[str, Any], ...]:
    hints = typing.get_type_hints(cls)
    return tuple((f.name, hints[f.name]) for f in dataclasses.fields(cls) if f.init)


def _write(w: _Writer, kind: Any, value: Any, name: str) -> None:
    inner = _is_optional(kind)
    if inner is not None:
        w.pack("B", value is not None)
        if value is not None:
            _write(w, inner, value, name)
        return
    origin = typing.get_origin(kind) or kind
    if origin is float:
        w.pack("d", float(value))
    elif origin is bool:
        w.pack("B", bool(value))
    elif origin is int:
        w.pack("q", int(value))
    elif origin is str:
        w.text(value)
    elif isinstance(origin, type) and issubclass(origin, enum.Enum):
        w.text(str(value.value))
    elif origin is np.ndarray:
        w.array(np.asarray(value))
    elif origin is Rotation:
        w.pack("4d", *value.as_quat())
    elif origin is tuple:
        items = tuple(value)
        w.pack("I", len(items))
        w.pack(f"{len(items)}d", *items)
    elif dataclasses.is_dataclass(origin):
        for field_name, field_kind in _fields(origin):
            _write(w, field_kind, getattr(value, field_name), f"{name}.{field_name}")
    else:
        raise MessageError(f"field {name}: no encoding for {kind!r}")


def encode(message: Message) -> bytes:
    """Encode a message (see the module docstring for the layout)."""
    cls = type(message)
    w = _Writer()
    w.put(MAGIC)
    w.pack("B", FORMAT)
    name = cls.__name__.encode()
    w.pack("H", len(name))
    w.put(name)
    w.pack("H", cls.VERSION)
    for field_name, kind in _fields(cls):
        _write(w, kind, getattr(message, field_name), field_name)
    return b"".join(w.chunks)


# Decoding ----------------------------------------------------------------------------------
class _Reader:
    def __init__(self, data: bytes | bytearray | memoryview) -> None:
        self.data = memoryview(data).cast("B") if not isinstance(data, bytes) else data
        self.offset = 0

    def take(self, n: int, what: str) -> memoryview | bytes:
        end = self.offset + n
        if n < 0 or end > len(self.data):
            raise MessageError(
                f"truncated message: {what} needs {n} bytes at offset {self.offset}, "
                f"{len(self.data) - self.offset} left"
            )
        chunk = self.data[self.offset : end]
        self.offset = end
        return chunk

    def unpack(self, fmt: str, what: str) -> tuple[Any, ...]:
        size = struct.calcsize("<" + fmt)
        return struct.unpack("<" + fmt, self.take(size, what))

    def text(self, what: str) -> str:
        (n,) = self.unpack("I", what)
        try:
            return bytes(self.take(n, what)).decode("utf-8")
        except UnicodeDecodeError as exc:
            raise MessageError(f"{what}: not UTF-8 text ({exc.reason})") from exc

    def array(self, what: str) -> np.ndarray:
        dtype = self.text(what)
        if dtype not in _DTYPES:
            raise MessageError(f"{what}: unsupported array type {dtype!r}")
        (ndim,) = self.unpack("B", what)
        if ndim > _MAX_DIMS:
            raise MessageError(f"{what}: {ndim} dimensions, at most {_MAX_DIMS}")
        shape = self.unpack("Q" * ndim, what)
        self.take(-(self.offset + 8) % 8, what)
        (nbytes,) = self.unpack("Q", what)
        kind = np.dtype(dtype)
        count = int(np.prod(shape, dtype=np.int64)) if ndim else 1
        if nbytes != count * kind.itemsize:
            raise MessageError(
                f"{what}: {nbytes} bytes do not hold an array of shape {shape} of {dtype}"
            )
        start = self.offset
        self.take(nbytes, what)
        return np.frombuffer(self.data, dtype=kind, count=count, offset=start).reshape(shape)


def _rotation(q: np.ndarray, name: str) -> Rotation:
    """The rotation of a quaternion, bit for bit when it is already of unit norm."""
    try:
        return exact_rotation(q)
    except InvalidPoseError as exc:
        raise MessageError(f"field {name}: {exc}") from exc


def _read(r: _Reader, kind: Any, name: str) -> Any:
    inner = _is_optional(kind)
    if inner is not None:
        (present,) = r.unpack("B", name)
        if present not in (0, 1):
            raise MessageError(f"field {name}: presence flag {present} is neither 0 nor 1")
        return _read(r, inner, name) if present else None
    origin = typing.get_origin(kind) or kind
    if origin is float:
        return r.unpack("d", name)[0]
    if origin is bool:
        (flag,) = r.unpack("B", name)
        if flag not in (0, 1):
            raise MessageError(f"field {name}: boolean byte {flag} is neither 0 nor 1")
        return bool(flag)
    if origin is int:
        return r.unpack("q", name)[0]
    if origin is str:
        return r.text(name)
    if isinstance(origin, type) and issubclass(origin, enum.Enum):
        text = r.text(name)
        try:
            return origin(text)
        except ValueError as exc:
            allowed = ", ".join(str(m.value) for m in origin)
            raise MessageError(f"field {name}: {text!r} is not one of {allowed}") from exc
    if origin is np.ndarray:
        return r.array(name)
    if origin is Rotation:
        return _rotation(np.array(r.unpack("4d", name)), name)
    if origin is tuple:
        (n,) = r.unpack("I", name)
        if n > len(r.data):
            raise MessageError(f"field {name}: tuple of {n} floats in a shorter message")
        return r.unpack(f"{n}d", name)
    if dataclasses.is_dataclass(origin):
        values = {f: _read(r, k, f"{name}.{f}") for f, k in _fields(origin)}
        return origin(**values)
    raise MessageError(f"field {name}: no decoding for {kind!r}")


def decode(data: bytes | bytearray | memoryview) -> Message:
    """Decode any message type from its bytes.

    Raises:
        MessageError: On bytes that are not a whole, well-formed message of a known type and
            version.
    """
    r = _Reader(data)
    if bytes(r.take(3, "magic")) != MAGIC:
        raise MessageError("not a footfall message (bad magic bytes)")
    (fmt,) = r.unpack("B", "format")
    if fmt != FORMAT:
        raise MessageError(f"message format {fmt}, this footfall reads format {FORMAT}")
    (n,) = r.unpack("H", "name length")
    try:
        name = bytes(r.take(n, "name")).decode("ascii")
    except UnicodeDecodeError as exc:
        raise MessageError("message name is not ASCII") from exc
    cls = _REGISTRY.get(name)
    if cls is None:
        raise MessageError(f"unknown message type {name!r}")
    (version,) = r.unpack("H", "version")
    if version != cls.VERSION:
        raise MessageError(
            f"{name} message of version {version}; this footfall reads version {cls.VERSION}"
        )
    try:
        values = {f: _read(r, k, f) for f, k in _fields(cls)}
        message = cls(**values)
    except MessageError:
        raise
    except FootfallError as exc:  # the message's own validation
        raise MessageError(f"{name}: {exc}") from exc
    except (ValueError, TypeError, struct.error) as exc:
        raise MessageError(f"{name}: malformed field ({exc})") from exc
    if r.offset != len(r.data):
        raise MessageError(f"{name}: {len(r.data) - r.offset} trailing bytes after the message")
    return message
