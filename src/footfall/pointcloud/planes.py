"""Planes in point clouds: RANSAC, least-squares refinement, and the floor under them.

:func:`best_plane` draws plane hypotheses from point triples within a tilt tolerance of an
up axis and keeps the best-supported (refined by least squares on its inliers);
:func:`lowest_layer` looks under a plane for a lower one parallel to it that spreads over
the ground (a floor between furniture). :func:`footfall.pointcloud.ground.find_ground`
puts them together.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

# Least-squares refinements of a RANSAC plane on its inliers.
REFINEMENTS = 3


def cells_covered(points: npt.NDArray[np.float64], normal, cell: float) -> int:
    """How many square cells of side ``cell`` [m] in the plane the points fall in."""
    if len(points) == 0:
        return 0
    a = np.cross(normal, [1.0, 0.0, 0.0] if abs(normal[0]) < 0.9 else [0.0, 1.0, 0.0])
    a /= np.linalg.norm(a)
    ij = np.floor(np.column_stack([points @ a, points @ np.cross(normal, a)]) / cell)
    ij = (ij - ij.min(axis=0)).astype(np.int64)
    shape = ij.max(axis=0) + 1
    if shape[0] * shape[1] > 4_000_000:  # a plane far out of the scene's size
        return len(np.unique(ij[:, 0] * shape[1] + ij[:, 1]))
    marked = np.zeros(shape, dtype=bool)
    marked[ij[:, 0], ij[:, 1]] = True
    return int(np.count_nonzero(marked))


def best_plane(
    points: npt.NDArray[np.float64],
    up: npt.NDArray[np.float64],
    cos_tilt: float,
    threshold: float,
    iterations: int,
    rng: np.random.Generator,
    below_origin: bool,
) -> tuple[npt.NDArray[np.float64], float] | None:
    """The best-supported plane within the tilt tolerance, refined by least squares."""
    score_on = points if len(points) <= 20000 else points[rng.choice(len(points), 20000, False)]
    # Hypotheses too steep (or above the sensor) do not count, up to 20 draws each.
    a, b, c = (points[k] for k in rng.integers(0, len(points), (3, 20 * iterations)))
    normals = np.cross(b - a, c - a)
    norms = np.linalg.norm(normals, axis=1)
    ok = norms > 1e-12
    normals[ok] /= norms[ok, None]
    normals[normals @ up < 0] *= -1.0
    offsets = -np.einsum("ij,ij->i", normals, a)
    ok &= normals @ up >= cos_tilt
    if below_origin:  # a ceiling, not a floor: the sensor is under it
        ok &= offsets > 0
    chosen = np.flatnonzero(ok)[:iterations]
    if len(chosen) == 0:
        return None
    normals, offsets = normals[chosen], offsets[chosen]
    counts = np.concatenate(
        [
            np.count_nonzero(
                np.abs(score_on @ normals[k : k + 64].T + offsets[k : k + 64]) < threshold, axis=0
            )
            for k in range(0, len(chosen), 64)
        ]
    )
    k = int(np.argmax(counts))  # the first of the best
    best = (normals[k], float(offsets[k]))
    return refine_plane(points, *best, up, cos_tilt, threshold, below_origin)


def refine_plane(pool, normal, d, up, cos_tilt: float, threshold: float, below_origin: bool):
    """Least squares on the plane's inliers, which then move with it (a few rounds)."""
    for _ in range(REFINEMENTS):
        inliers = np.abs(pool @ normal + d) < threshold
        if inliers.sum() < 3:
            break
        centre = pool[inliers].mean(axis=0)
        refined = np.linalg.svd(pool[inliers] - centre, full_matrices=False)[2][-1]
        refined = refined if refined @ up >= 0 else -refined
        if refined @ up < cos_tilt or (below_origin and refined @ centre >= 0):
            break
        normal, d = refined, -float(refined @ centre)
    return normal, d


def plane_extent_m(inliers: npt.NDArray[np.float64], normal: npt.NDArray[np.float64]) -> float:
    """The smaller of a plane patch's two spreads (10th to 90th percentile) in the plane [m]."""
    if len(inliers) < 3:
        return 0.0
    a = np.cross(normal, [1.0, 0.0, 0.0] if abs(normal[0]) < 0.9 else [0.0, 1.0, 0.0])
    a /= np.linalg.norm(a)
    b = np.cross(normal, a)
    spreads = [np.subtract(*np.percentile(inliers @ axis, [90, 10])) for axis in (a, b)]
    return float(min(spreads))


# Slabs this thick along the up axis are scanned for a floor under the planes found [m].
SLAB_M = 0.1
# Most slabs fitted in the search for a floor under the planes found.
MAX_SLABS = 8
# A floor under the planes found is the plane whose inliers cover most cells this big [m].
AREA_CELL_M = 0.1
# A floor under the planes found lies this near parallel to the best-supported one [deg]
# (a floor and a table top on it agree within a degree or two).
LAYER_PARALLEL_DEG = 10.0


def lowest_layer(p, lowest, reference, cos_parallel, threshold, below_origin, enough,
                  plausible):  # fmt: skip
    """The lowest plausible plane parallel to ``reference`` below ``lowest``, or None.

    Heights along ``reference`` are scanned from the bottom in slabs. In the first slab
    that holds enough points, the level plane (normal ``reference``) whose inliers cover
    the most ground (cells of ``AREA_CELL_M``) is refined by least squares; it counts
    when it holds enough points and is plausible, else the next slab up is tried. Cover,
    not count: a level plane also cuts every wall and piece of furniture in a strip, and a
    sparse floor holds fewer points than those strips but spreads over more ground.
    """
    heights = p @ reference
    top = math.inf if lowest is None else float(np.median(lowest[0] @ reference))
    below = heights < top - 3.0 * threshold
    if np.count_nonzero(below) < max(enough, 3):
        return None
    pool, h = p[below], heights[below]
    ordered = np.sort(h)
    starts = np.arange(ordered[0], ordered[-1] + threshold, threshold)
    counts = np.searchsorted(ordered, starts + SLAB_M) - np.searchsorted(ordered, starts)
    tried, free_from = 0, -math.inf
    for start in starts[counts >= enough]:  # from the bottom up, slabs apart
        if start < free_from:
            continue
        if tried == MAX_SLABS:
            break
        tried, free_from = tried + 1, start + SLAB_M
        levels = np.arange(start, start + SLAB_M + 1e-9, 0.5 * threshold)
        areas = [cells_covered(pool[np.abs(h - c) < threshold], reference, AREA_CELL_M)
                 for c in levels]  # fmt: skip
        level = float(levels[int(np.argmax(areas))])
        normal, d = refine_plane(
            pool, reference, -level, reference, cos_parallel, threshold, below_origin
        )
        inliers = p[np.abs(p @ normal + d) < threshold]
        lower = np.median(inliers @ reference) < top - 3.0 * threshold  # not the plane above
        if lower and len(inliers) >= enough and plausible(inliers, normal, d, under=True):
            return inliers, normal, d
    return None
