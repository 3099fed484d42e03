"""Wire formats for a radio link: the map, depth and colour as the station needs them.

The robot's nodes keep full precision; what crosses to the station is what it draws:

- **map**: heights as 16-bit millimetres about an offset, spread as 16-bit millimetres,
  the score in steps of ``SCORE_STEP`` up to ``SCORE_FULL_SCALE`` (higher saturates), known
  and valid cells as bits; the slope and proximity layers stay on the robot. A whole map
  goes every ``WHOLE_EVERY_S``, when the window jumped, or when a receiver asks; in
  between, only the cells whose quantised values changed since that whole map (the window
  scrolls with the robot: cells are compared where the two windows overlap). The layers are
  zstd-compressed. Changes apply to a whole map, never to other changes, so a lost update
  costs nothing but itself.
- **depth**: 16-bit millimetres (0: no reading), decimated to at most ``DEPTH_MAX_WIDTH``
  pixels across (the intrinsics follow), zstd-compressed.
- **colour**: JPEG at ``JPEG_QUALITY``.
"""

from __future__ import annotations

import dataclasses
import io
import math
import time
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import zstandard
from PIL import Image

from footfall.errors import MessageError
from footfall.messages import ColorImage, DepthFrame, MapUpdate
from footfall.messages.wire import PackedColor, PackedDepth, PackedMap
from footfall.sensing.camera import PinholeCamera

# A whole map goes at least this often [s]; changes apply to the last one in between.
WHOLE_EVERY_S = 2.0
# A window that scrolled more than this share of its side since the whole map goes whole.
WHOLE_AFTER_SHIFT = 0.25
# The score's step and the score that saturates (twice the default validity threshold).
SCORE_STEP = 0.004
SCORE_FULL_SCALE = 254 * SCORE_STEP
# Depth wider than this is decimated by a whole factor for the station [px].
DEPTH_MAX_WIDTH = 424
JPEG_QUALITY = 80
ZSTD_LEVEL = 3
# Receivers keep this many whole maps to apply changes to.
WHOLE_MAPS_KEPT = 4

_NO_HEIGHT = np.iinfo(np.int16).min
_NO_SPREAD = np.iinfo(np.uint16).max
_NO_SCORE = 255
_MM_PER_M = 1000.0
_EMPTY = (_NO_HEIGHT, _NO_SPREAD, _NO_SCORE, False, False)  # each layer's "nothing known"


@dataclass(frozen=True)
class MapLayers:
    """A map window's quantised layers, and where the window lies.

    Attributes:
        heights_mm: Heights less the offset [mm], ``_NO_HEIGHT`` where unknown.
        spread_mm: Spread [mm], ``_NO_SPREAD`` where unknown or not kept.
        score: Score in ``SCORE_STEP``, ``_NO_SCORE`` where unknown.
        known: Cells observed.
        valid: Cells a foot may use.
        corner: Global cell index of cell ``[0, 0]``.
        offset_mm: The heights' offset [mm].
    """

    heights_mm: npt.NDArray[np.int16]
    spread_mm: npt.NDArray[np.uint16]
    score: npt.NDArray[np.uint8]
    known: npt.NDArray[np.bool_]
    valid: npt.NDArray[np.bool_]
    corner: tuple[int, int]
    offset_mm: int

    @property
    def arrays(self) -> tuple[np.ndarray, ...]:
        """The layers in the order they travel."""
        return (self.heights_mm, self.spread_mm, self.score, self.known, self.valid)

    def shifted(self, corner: tuple[int, int]) -> MapLayers:
        """These layers seen from a window whose cell ``[0, 0]`` is global cell ``corner``."""
        di, dj = corner[0] - self.corner[0], corner[1] - self.corner[1]
        n, m = self.known.shape
        out = []
        for a, empty in zip(self.arrays, _EMPTY, strict=True):
            b = np.full_like(a, empty)
            i0, i1, j0, j1 = max(0, -di), min(n, n - di), max(0, -dj), min(m, m - dj)
            if i0 < i1 and j0 < j1:
                b[i0:i1, j0:j1] = a[i0 + di : i1 + di, j0 + dj : j1 + dj]
            out.append(b)
        return MapLayers(*out, corner=corner, offset_mm=self.offset_mm)


def corner_of(update: MapUpdate | PackedMap) -> tuple[int, int]:
    """The global cell index of a window's cell ``[0, 0]``."""
    return (
        round(update.origin[0] / update.resolution),
        round(update.origin[1] / update.resolution),
    )


def quantise(update: MapUpdate, offset_mm: int | None = None) -> MapLayers:
    """A map update's layers as they travel (heights about ``offset_mm``; else their median)."""
    heights = np.asarray(update.heights, dtype=np.float64)
    known = np.asarray(update.known, dtype=bool) & np.isfinite(heights)
    if offset_mm is None:
        offset_mm = round(float(np.median(heights[known])) * _MM_PER_M) if known.any() else 0
    h = np.clip(np.rint(heights * _MM_PER_M) - offset_mm, _NO_HEIGHT + 1, np.iinfo(np.int16).max)
    heights_mm = np.where(known, np.nan_to_num(h), _NO_HEIGHT).astype(np.int16)
    if update.spread is None:
        spread_mm = np.full(heights.shape, _NO_SPREAD, np.uint16)
    else:
        s = np.asarray(update.spread, dtype=np.float64)
        s_mm = np.clip(np.rint(np.nan_to_num(s) * _MM_PER_M), 0, _NO_SPREAD - 1)
        spread_mm = np.where(known & np.isfinite(s), s_mm, _NO_SPREAD).astype(np.uint16)
    score = np.asarray(update.score, dtype=np.float64)
    steps = np.clip(np.rint(np.nan_to_num(score) / SCORE_STEP), 0, _NO_SCORE - 1)
    score_q = np.where(np.isfinite(score), steps, _NO_SCORE).astype(np.uint8)
    valid = np.asarray(update.valid, dtype=bool)
    return MapLayers(heights_mm, spread_mm, score_q, known, valid, corner_of(update), offset_mm)


def _layer_bytes(layers: tuple[np.ndarray, ...]) -> bytes:
    heights, spread, score, known, valid = layers
    return b"".join(
        (
            heights.astype("<i2").tobytes(),
            spread.astype("<u2").tobytes(),
            score.tobytes(),
            np.packbits(known).tobytes(),
            np.packbits(valid).tobytes(),
        )
    )


def _layer_sizes(count: int) -> tuple[int, ...]:
    """Bytes of each layer for ``count`` cells: heights, spread, score, known, valid."""
    return (2 * count, 2 * count, count, _bits(count), _bits(count))


def _bits(count: int) -> int:
    """Bytes of ``count`` bits."""
    return (count + 7) // 8


def _read_layers(raw: memoryview, count: int) -> tuple[tuple[np.ndarray, ...], int]:
    """``count`` cells of each layer from ``raw``, and how many bytes they took."""
    sizes = _layer_sizes(count)
    if len(raw) < sum(sizes):
        raise MessageError(f"packed map holds {len(raw)} bytes, {count} cells need {sum(sizes)}")
    out, at = [], 0
    for size, kind in zip(sizes, ("<i2", "<u2", "u1", "bits", "bits"), strict=True):
        if kind == "bits":
            bits = np.frombuffer(raw[at : at + size], np.uint8)
            out.append(np.unpackbits(bits, count=count).astype(bool))
        else:
            out.append(np.frombuffer(raw[at : at + size], kind).copy())
        at += size
    return tuple(out), at


def _compress(raw: bytes) -> npt.NDArray[np.uint8]:
    return np.frombuffer(zstandard.ZstdCompressor(level=ZSTD_LEVEL).compress(raw), np.uint8)


def _decompress(data: npt.NDArray[np.uint8], limit: int) -> memoryview:
    try:
        raw = zstandard.ZstdDecompressor().decompress(data.tobytes(), max_output_size=limit)
    except zstandard.ZstdError as exc:
        raise MessageError(f"packed data does not decompress: {exc}") from exc
    return memoryview(raw)


class MapPacker:
    """Packs a robot's map updates for the link: whole maps and the changes since one.

    Args:
        whole_every_s: A whole map goes at least this often [s].
        clock: Wall clock [s].

    Attributes:
        want_whole: Send the next update whole (a receiver asked).
    """

    def __init__(self, whole_every_s: float = WHOLE_EVERY_S, clock=time.monotonic) -> None:
        self.whole_every_s = whole_every_s
        self.clock = clock
        self.want_whole = True
        self._key: MapLayers | None = None
        self._key_sequence = 0
        self._key_time = -math.inf

    def _needs_whole(self, update: MapUpdate, now: float) -> bool:
        key = self._key
        if self.want_whole or key is None or now - self._key_time >= self.whole_every_s:
            return True
        if key.known.shape != np.shape(update.heights):
            return True
        corner, n = corner_of(update), min(key.known.shape)
        return max(abs(corner[0] - key.corner[0]), abs(corner[1] - key.corner[1])) > (
            WHOLE_AFTER_SHIFT * n
        )

    def pack(self, update: MapUpdate) -> PackedMap:
        """The update as it travels (link fields left for the sender to fill)."""
        now = self.clock()
        rows, cols = np.shape(update.heights)
        if self._needs_whole(update, now):
            layers = quantise(update)
            self._key, self._key_sequence, self._key_time = layers, update.sequence, now
            self.want_whole = False
            base, raw = 0, _layer_bytes(layers.arrays)
        else:
            key = self._key.shifted(corner_of(update))
            layers = quantise(update, key.offset_mm)
            changed = np.zeros((rows, cols), bool)
            for a, b in zip(layers.arrays, key.arrays, strict=True):
                changed |= a != b
            base = self._key_sequence
            raw = np.packbits(changed).tobytes() + _layer_bytes(
                tuple(a[changed] for a in layers.arrays)
            )
        return PackedMap(
            stamp=update.stamp,
            sequence=update.sequence,
            base=base,
            origin=(float(update.origin[0]), float(update.origin[1])),
            resolution=float(update.resolution),
            rows=rows,
            cols=cols,
            height_offset_mm=layers.offset_mm,
            has_spread=update.spread is not None,
            cells=_compress(raw),
        )


class MapUnpacker:
    """Turns packed maps back into map updates; keeps the last few whole maps."""

    def __init__(self) -> None:
        self._wholes: dict[int, MapLayers] = {}

    def unpack(self, packed: PackedMap) -> MapUpdate | None:
        """The map update, or None when it holds changes to a whole map not received.

        Raises:
            MessageError: The cells do not decode.
        """
        shape, corner = (packed.rows, packed.cols), corner_of(packed)
        cells = packed.rows * packed.cols
        # At most: a mask of the changed cells, then every cell's layers.
        raw = _decompress(packed.cells, _bits(cells) + sum(_layer_sizes(cells)))
        if packed.base == 0:
            arrays, used = _read_layers(raw, cells)
            arrays = tuple(a.reshape(shape) for a in arrays)
            layers = MapLayers(*arrays, corner=corner, offset_mm=packed.height_offset_mm)
            self._wholes[packed.sequence] = layers
            while len(self._wholes) > WHOLE_MAPS_KEPT:
                del self._wholes[min(self._wholes)]
        else:
            whole = self._wholes.get(packed.base)
            if whole is None or whole.known.shape != shape:
                return None
            mask_size = _bits(cells)
            if len(raw) < mask_size:
                raise MessageError("packed map changes lack their cell mask")
            mask = np.frombuffer(raw[:mask_size], np.uint8)
            changed = np.unpackbits(mask, count=cells).astype(bool).reshape(shape)
            values, used = _read_layers(raw[mask_size:], int(changed.sum()))
            used += mask_size
            key = whole.shifted(corner)
            arrays = tuple(a.copy() for a in key.arrays)
            for a, v in zip(arrays, values, strict=True):
                a[changed] = v
            layers = MapLayers(*arrays, corner=corner, offset_mm=whole.offset_mm)
        if used != len(raw):
            raise MessageError(f"packed map has {len(raw) - used} bytes past its cells")
        return _map_update(packed, layers)


def _map_update(packed: PackedMap, q: MapLayers) -> MapUpdate:
    known = q.known & (q.heights_mm != _NO_HEIGHT)
    heights = np.where(known, (q.heights_mm.astype(np.float64) + q.offset_mm) / _MM_PER_M, np.nan)
    spread = None
    if packed.has_spread:
        spread = np.where(q.spread_mm != _NO_SPREAD, q.spread_mm / _MM_PER_M, np.nan)
    score = np.where(q.score != _NO_SCORE, q.score * SCORE_STEP, np.nan)
    return MapUpdate(
        stamp=packed.stamp,
        sequence=packed.sequence,
        heights=heights,
        known=known,
        spread=spread,
        slope=None,
        proximity=None,
        score=score,
        valid=q.valid,
        origin=packed.origin,
        resolution=packed.resolution,
    )


def pack_depth(frame: DepthFrame, max_width: int = DEPTH_MAX_WIDTH) -> PackedDepth:
    """A depth frame as millimetres, decimated to at most ``max_width`` pixels across."""
    depth = frame.intrinsics.depth_in_metres(frame.depth, frame.depth_scale)
    metres = PinholeCamera.to_metres(depth, frame.depth_scale)
    k = max(1, math.ceil(frame.intrinsics.width / max_width))
    metres = metres[::k, ::k]
    c = frame.intrinsics
    camera = dataclasses.replace(
        c,
        fx=c.fx / k,
        fy=c.fy / k,
        cx=c.cx / k,
        cy=c.cy / k,
        width=metres.shape[1],
        height=metres.shape[0],
    )
    mm = np.rint(np.nan_to_num(metres, nan=0.0, posinf=0.0, neginf=0.0) * _MM_PER_M)
    mm = np.where((mm > 0) & (mm < 65536), mm, 0).astype("<u2")
    return PackedDepth(
        stamp=frame.stamp,
        sequence=frame.sequence,
        intrinsics=camera,
        camera_in_body=frame.camera_in_body,
        depth_mm=_compress(mm.tobytes()),
    )


def unpack_depth(packed: PackedDepth) -> DepthFrame:
    """The depth frame a packed one stands for (``uint16`` millimetres)."""
    c = packed.intrinsics
    size = 2 * c.width * c.height
    raw = _decompress(packed.depth_mm, size)
    if len(raw) != size:
        raise MessageError(
            f"packed depth holds {len(raw)} bytes, {c.width} x {c.height} need {size}"
        )
    depth = np.frombuffer(raw, "<u2").reshape(c.height, c.width)
    return DepthFrame(
        stamp=packed.stamp,
        depth=depth,
        intrinsics=c,
        camera_in_body=packed.camera_in_body,
        depth_scale=1.0 / _MM_PER_M,
        sequence=packed.sequence,
    )


def pack_color(image: ColorImage, quality: int = JPEG_QUALITY) -> PackedColor:
    """A colour image as JPEG."""
    out = io.BytesIO()
    Image.fromarray(np.ascontiguousarray(image.image, np.uint8)).save(
        out, format="JPEG", quality=quality
    )
    return PackedColor(image.stamp, image.sequence, np.frombuffer(out.getvalue(), np.uint8))


def unpack_color(packed: PackedColor) -> ColorImage:
    """The colour image a packed one stands for."""
    try:
        with Image.open(io.BytesIO(packed.jpeg.tobytes())) as img:
            rgb = np.asarray(img.convert("RGB"))
    except (OSError, ValueError) as exc:
        raise MessageError(f"packed colour is not a JPEG image: {exc}") from exc
    return ColorImage(packed.stamp, rgb, packed.sequence)
