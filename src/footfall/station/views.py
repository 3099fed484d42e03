"""What the station draws: images and 3-D shapes made from the robot's messages."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from footfall.messages import DepthFrame, MapUpdate


def ground_point(origin: npt.ArrayLike, direction: npt.ArrayLike) -> tuple[float, float] | None:
    """Where a view ray meets the ground plane z = 0, or None if it never does [m]."""
    o, d = np.asarray(origin, dtype=np.float64), np.asarray(direction, dtype=np.float64)
    if abs(d[2]) < 1e-9 or -o[2] / d[2] <= 0:
        return None
    p = o - o[2] / d[2] * d
    return float(p[0]), float(p[1])


def score_image(update: MapUpdate) -> npt.NDArray[np.uint8]:
    """The score map as an RGB image, x right and y up: walkable dark, invalid red."""
    score = np.nan_to_num(update.score, nan=0.0)
    shade = (255 * (1.0 - np.clip(score / 0.5, 0.0, 1.0)) * 0.8).astype(np.uint8)
    rgb = np.stack([shade, shade, shade], axis=-1)
    rgb[~update.known] = (150, 150, 150)
    rgb[update.known & ~update.valid] = (200, 40, 40)
    return np.ascontiguousarray(rgb.transpose(1, 0, 2)[::-1])


def depth_image(frame: DepthFrame, max_range: float = 3.0) -> npt.NDArray[np.uint8]:
    """A depth image in grey levels, near bright, no return black."""
    d = np.asarray(frame.depth, dtype=np.float64)
    if frame.depth_scale is not None:
        d = d * frame.depth_scale
    grey = np.where(d > 0, 255 * (1.0 - np.clip(d / max_range, 0.0, 1.0)), 0.0)
    return np.ascontiguousarray(np.repeat(grey.astype(np.uint8)[..., None], 3, axis=-1))


def map_surface(
    update: MapUpdate, step: int = 2
) -> tuple[npt.NDArray[np.float32], npt.NDArray[np.int32], npt.NDArray[np.int32]]:
    """The height map as a triangle surface through the centres of every ``step``-th cell.

    Only squares of four known cells are meshed; a square is walkable when its first cell
    is valid.

    Returns:
        Vertices, shape (n, 3) [m]; faces of walkable squares and of the others, each
        shape (k, 3).
    """
    heights = update.heights[::step, ::step]
    known = update.known[::step, ::step]
    valid = update.valid[::step, ::step]
    ni, nj = heights.shape
    i, j = np.meshgrid(np.arange(ni), np.arange(nj), indexing="ij")
    res = update.resolution * step
    x = update.origin[0] + (i * step + 0.5) * update.resolution
    y = update.origin[1] + (j * step + 0.5) * update.resolution
    del res
    vertices = np.column_stack([x.ravel(), y.ravel(), np.nan_to_num(heights).ravel()])
    index = np.arange(ni * nj).reshape(ni, nj)
    a, b, c, d = index[:-1, :-1], index[1:, :-1], index[1:, 1:], index[:-1, 1:]
    whole = known[:-1, :-1] & known[1:, :-1] & known[1:, 1:] & known[:-1, 1:]
    faces = [np.stack([a, b, c], -1), np.stack([a, c, d], -1)]
    good = whole & valid[:-1, :-1]
    bad = whole & ~valid[:-1, :-1]
    pick = lambda mask: np.concatenate([f[mask] for f in faces]).astype(np.int32)  # noqa: E731
    return vertices.astype(np.float32), pick(good), pick(bad)


def polyline_segments(points: npt.ArrayLike, z: float = 0.01) -> npt.NDArray[np.float32]:
    """A polyline through 2-D points as line segments at height ``z``, shape (n - 1, 2, 3)."""
    p = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    p3 = np.column_stack([p, np.full(len(p), z)])
    return np.stack([p3[:-1], p3[1:]], axis=1).astype(np.float32)


def circles_segments(
    x: npt.ArrayLike, y: npt.ArrayLike, r: npt.ArrayLike, sides: int = 24
) -> npt.NDArray[np.float32]:
    """Circles on the ground as line segments, shape (n * sides, 2, 3)."""
    a = np.linspace(0.0, 2.0 * np.pi, sides + 1)
    rings = [
        polyline_segments(np.column_stack([cx + cr * np.cos(a), cy + cr * np.sin(a)]))
        for cx, cy, cr in zip(np.ravel(x), np.ravel(y), np.ravel(r), strict=True)
    ]
    return np.concatenate(rings) if rings else np.zeros((0, 2, 3), np.float32)


def feet_segments(footsteps: npt.ArrayLike, length: float, width: float) -> npt.NDArray[np.float32]:
    """Foot soles (rectangles around ``(x, y, heading)`` rows) as line segments."""
    corners = np.array([[1, 1], [1, -1], [-1, -1], [-1, 1], [1, 1]]) * [length / 2, width / 2]
    out = []
    for x, y, h in np.asarray(footsteps, dtype=np.float64).reshape(-1, 3):
        c, s = np.cos(h), np.sin(h)
        out.append(polyline_segments(corners @ np.array([[c, s], [-s, c]]) + [x, y]))
    return np.concatenate(out) if out else np.zeros((0, 2, 3), np.float32)
