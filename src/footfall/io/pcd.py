"""Reader for PCL's PCD point-cloud files: ``ascii``, ``binary`` and ``binary_compressed``.

``binary_compressed`` stores the fields one after another (x of every point, then y, ...)
compressed with LZF, after two little-endian uint32 sizes (compressed, uncompressed).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import numpy.typing as npt
from numba import njit

from footfall.errors import DatasetError

_TYPES = {
    ("F", 4): "<f4",
    ("F", 8): "<f8",
    ("U", 1): "u1",
    ("U", 2): "<u2",
    ("U", 4): "<u4",
    ("U", 8): "<u8",
    ("I", 1): "i1",
    ("I", 2): "<i2",
    ("I", 4): "<i4",
    ("I", 8): "<i8",
}


@dataclass(frozen=True)
class PointCloudData:
    """The content of a PCD file.

    Attributes:
        fields: Each field's values, shape (points,) or (points, count).
        width: Points per row (the image width for an organised cloud).
        height: Rows (1 for an unorganised cloud).
        viewpoint: Sensor pose ``tx ty tz qw qx qy qz`` as stored.
    """

    fields: dict[str, npt.NDArray]
    width: int
    height: int
    viewpoint: tuple[float, ...]

    @property
    def xyz(self) -> npt.NDArray[np.float64]:
        """The x, y, z fields as one array, shape (points, 3) [m] (NaN kept)."""
        try:
            return np.stack([self.fields[k].astype(np.float64) for k in ("x", "y", "z")], axis=1)
        except KeyError as exc:
            raise DatasetError(f"point cloud has no {exc} field") from exc


@njit(cache=True)
def lzf_decompress(data: npt.NDArray[np.uint8], out_size: int) -> npt.NDArray[np.uint8]:
    """Decompress an LZF stream (liblzf's format) into ``out_size`` bytes."""
    out = np.empty(out_size, dtype=np.uint8)
    ip = 0
    op = 0
    n = data.shape[0]
    while ip < n:
        ctrl = np.int64(data[ip])
        ip += 1
        if ctrl < 32:  # a run of ctrl + 1 literal bytes
            run = ctrl + 1
            if op + run > out_size or ip + run > n:
                raise ValueError("corrupt LZF stream: literal run overflows")
            out[op : op + run] = data[ip : ip + run]
            op += run
            ip += run
        else:  # a back reference
            length = ctrl >> 5
            ref = op - ((ctrl & 0x1F) << 8) - 1
            if ip + (2 if length == 7 else 1) > n:
                raise ValueError("corrupt LZF stream: back reference cut short")
            if length == 7:
                length += np.int64(data[ip])
                ip += 1
            ref -= np.int64(data[ip])
            ip += 1
            length += 2
            if ref < 0 or op + length > out_size:
                raise ValueError("corrupt LZF stream: back reference out of range")
            for k in range(length):  # may overlap itself: copy byte by byte
                out[op + k] = out[ref + k]
            op += length
    if op != out_size:
        raise ValueError("corrupt LZF stream: wrong decompressed size")
    return out


def read_pcd(path: str | Path) -> PointCloudData:
    """Read a PCD file (v0.7 header; ascii, binary or binary_compressed data).

    Raises:
        DatasetError: A missing file, an unsupported header or corrupt data.
    """
    p = Path(path)
    if not p.is_file():
        raise DatasetError(f"missing point cloud {p}")
    raw = p.read_bytes()
    header: dict[str, list[str]] = {}
    offset = 0
    while True:
        end = raw.find(b"\n", offset)
        if end < 0:
            raise DatasetError(f"{p}: header ends before its DATA line")
        line = raw[offset:end].decode("ascii", errors="replace").strip()
        offset = end + 1
        if not line or line.startswith("#"):
            continue
        key, *values = line.split()
        header[key.upper()] = values
        if key.upper() == "DATA":
            break
    try:
        names = header["FIELDS"]
        sizes = [int(v) for v in header["SIZE"]]
        types = header["TYPE"]
        counts = [int(v) for v in header.get("COUNT", ["1"] * len(names))]
        width, height = int(header["WIDTH"][0]), int(header.get("HEIGHT", ["1"])[0])
        points = int(header.get("POINTS", [str(width * height)])[0])
        kind = header["DATA"][0].lower()
        dtypes = [_TYPES[(t.upper(), s)] for t, s in zip(types, sizes, strict=True)]
        viewpoint = tuple(
            float(v) for v in header.get("VIEWPOINT", ["0", "0", "0", "1", "0", "0", "0"])
        )
    except (KeyError, ValueError, IndexError) as exc:
        raise DatasetError(f"{p}: malformed or unsupported PCD header ({exc})") from exc
    if points < 0 or width < 0 or height < 0 or points != width * height:
        raise DatasetError(
            f"{p}: header says {points} points but WIDTH x HEIGHT is {width} x {height}"
        )
    try:
        fields = _read_data(p, raw, offset, kind, names, dtypes, counts, sizes, points)
    except (ValueError, TypeError, IndexError, OverflowError, UnicodeDecodeError) as exc:
        raise DatasetError(f"{p}: malformed {kind} point data ({exc})") from exc
    return PointCloudData(fields, width, height, viewpoint)


def _read_data(
    p: Path,
    raw: bytes,
    offset: int,
    kind: str,
    names: list[str],
    dtypes: list[str],
    counts: list[int],
    sizes: list[int],
    points: int,
) -> dict[str, npt.NDArray]:
    """The fields of a PCD file's data section."""
    fields: dict[str, npt.NDArray] = {}
    record_size = sum(c * s for c, s in zip(counts, sizes, strict=True))
    if kind == "ascii":
        rows = raw[offset:].decode("ascii").split()
        columns = sum(counts)
        if len(rows) < points * columns:
            raise DatasetError(f"{p}: expected {points} points of {columns} values")
        table = np.array(rows[: points * columns], dtype=np.float64).reshape(points, columns)
        start = 0
        for name, dtype, count in zip(names, dtypes, counts, strict=True):
            block = table[:, start : start + count].astype(dtype)
            fields[name] = block[:, 0] if count == 1 else block
            start += count
    elif kind == "binary":
        record = np.dtype(
            [
                (n, d, (c,)) if c > 1 else (n, d)
                for n, d, c in zip(names, dtypes, counts, strict=True)
            ]
        )
        if len(raw) - offset < points * record.itemsize:
            raise DatasetError(f"{p}: binary data shorter than {points} points")
        data = np.frombuffer(raw, dtype=record, count=points, offset=offset)
        fields = {n: np.array(data[n]) for n in names}
    elif kind == "binary_compressed":
        if len(raw) - offset < 8:
            raise DatasetError(f"{p}: binary_compressed data ends before its sizes")
        compressed_size, size = (int(v) for v in np.frombuffer(raw, "<u4", count=2, offset=offset))
        if len(raw) - offset - 8 < compressed_size:
            raise DatasetError(
                f"{p}: truncated compressed data: {len(raw) - offset - 8} of "
                f"{compressed_size} bytes"
            )
        if size != points * record_size:
            raise DatasetError(
                f"{p}: header says {points} points ({points * record_size} bytes) but the "
                f"compressed data holds {size}"
            )
        if size > 200 * compressed_size + 1024:  # beyond what LZF can expand to
            raise DatasetError(f"{p}: {compressed_size} compressed bytes cannot hold {size}")
        body = np.frombuffer(raw, dtype=np.uint8, count=compressed_size, offset=offset + 8)
        try:
            data = lzf_decompress(body, int(size))
        except ValueError as exc:
            raise DatasetError(f"{p}: {exc}") from exc
        start = 0
        for name, dtype, count, s in zip(names, dtypes, counts, sizes, strict=True):
            nbytes = points * count * s
            block = np.frombuffer(data[start : start + nbytes].tobytes(), dtype=dtype)
            fields[name] = block if count == 1 else block.reshape(points, count)
            start += nbytes
    else:
        raise DatasetError(
            f"{p}: unsupported DATA kind {kind!r} (ascii, binary, binary_compressed)"
        )
    return fields
