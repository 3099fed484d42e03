"""Binning a frame into cells and fusing it into the map: the calls into the kernels.

The compiled kernels (:mod:`footfall.mapping.kernels`) take plain arrays; this module is
the one place that unpacks the window, the frame buffers and the layers for them.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from footfall.errors import ConfigError
from footfall.mapping import kernels
from footfall.mapping.engine import FusionRule, HeightMapConfig, IntegrationStats
from footfall.mapping.layers import CellLayers, FrameBuffers
from footfall.mapping.window import MapWindow
from footfall.sensing.camera import DepthStats, PinholeCamera
from footfall.sensing.noise import IDEAL, DepthNoiseModel
from footfall.sensing.pose import Pose

_RULE_CODES = {
    FusionRule.LATEST: kernels.FUSE_LATEST,
    FusionRule.MAX: kernels.FUSE_MAX,
    FusionRule.VARIANCE: kernels.FUSE_VARIANCE,
}
# A frame's points count as evidence of a never-hit part only from a sensor whose noise at
# the cell is below this share of a part's side: its points scatter over the parts, and
# quantized depth lays them on stripes with never-hit parts between them.
EVIDENCE_NOISE_SHARE = 0.2


def bin_depth(
    frame: FrameBuffers,
    window: MapWindow,
    depth: npt.ArrayLike,
    camera: PinholeCamera,
    camera_pose: Pose,
    depth_scale: float | None,
    stride: int,
    counts: npt.NDArray[np.int64],
) -> int:
    """Bin one depth image into ``frame``; returns how many cells it touched.

    Raises:
        ConfigError: On a stride below 1.
        DepthImageError: On a malformed image.
    """
    d = camera.depth_in_metres(depth, depth_scale)
    if stride < 1:
        raise ConfigError(f"stride must be >= 1, got {stride}")
    return int(
        kernels.bin_depth(
            d,
            camera.scale_for(d, depth_scale),
            camera.units_per_metre_for(d, depth_scale),
            stride,
            camera.fx,
            camera.fy,
            camera.cx,
            camera.cy,
            camera.min_range,
            camera.max_range,
            camera_pose.rotation.as_matrix(),
            camera_pose.position,
            window.inv_res,
            window.code(),
            *frame.bins(),
            not camera.noise.is_ideal,
            frame.stamp,
            frame.next_frame(),
            frame.touched,
            counts,
        )
    )


def bin_points(
    frame: FrameBuffers,
    window: MapWindow,
    points_in_world: npt.NDArray[np.float64],
    sensor_position: npt.ArrayLike,
    counts: npt.NDArray[np.int64],
) -> int:
    """Bin world points seen from ``sensor_position`` into ``frame``; returns the cells."""
    return int(
        kernels.bin_points(
            points_in_world,
            np.asarray(sensor_position, dtype=np.float64),
            window.inv_res,
            window.code(),
            *frame.bins(),
            frame.stamp,
            frame.next_frame(),
            frame.touched,
            counts,
        )
    )


def fuse(
    frame: FrameBuffers,
    layers: CellLayers,
    n_touched: int,
    config: HeightMapConfig,
    noise: DepthNoiseModel = IDEAL,
    new_view: bool = True,
) -> None:
    """Fuse the frame's ``n_touched`` cells into the layers by ``config.fusion``."""
    kernels.fuse(
        frame.touched,
        n_touched,
        *frame.bins(),
        layers.heights,
        layers.spread,
        layers.variance,
        layers.known,
        layers.parts,
        layers.points,
        new_view,
        EVIDENCE_NOISE_SHARE * config.resolution / kernels.SUB,
        _RULE_CODES[config.fusion],
        config.range_noise,
        config.process_noise,
        config.gate,
        np.array([noise.base_m, noise.quadratic_per_m, noise.offset_m]),
        config.noise_spread_sigmas,
    )


def integration_stats(counts: npt.NDArray[np.int64], n_touched: int) -> IntegrationStats:
    """What became of a frame's readings, from the kernels' counts."""
    k = kernels
    return IntegrationStats(
        depth=DepthStats(
            valid=int(counts[k.VALID] + counts[k.OUTSIDE]),
            zero=int(counts[k.ZERO]),
            non_finite=int(counts[k.NON_FINITE]),
            negative=int(counts[k.NEGATIVE]),
            out_of_range=int(counts[k.OUT_OF_RANGE]),
        ),
        outside=int(counts[k.OUTSIDE]),
        cells_updated=int(n_touched),
    )
