"""Recorded sequences as MCAP files: the TUM layout (and Redwood through it) to ROS 2 types.

The sequence plays through the same source node ``footfall map --tum`` maps from, onto a
bus an :class:`McapRecorder` taps: depth as ``16UC1`` millimetres when the units are whole
millimetres (Redwood's, TUM's when every value is a multiple of 5) else ``32FC1`` metres,
``CameraInfo``, and the camera's pose (turned so the world's up axis is +z) as
``PoseStamped`` and TF. ``footfall replay`` of the file builds the map ``footfall map
--tum`` builds of the sequence.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy.typing as npt

from footfall.datasets.tum import TUM_DEPTH_SCALE, TumSequenceSource, load_depth_png
from footfall.errors import DatasetError
from footfall.recording.writer import McapRecorder
from footfall.runtime.bus import InProcessBus
from footfall.sensing.camera import PinholeCamera
from footfall.sensing.noise import DepthNoiseModel


def tum_to_mcap(
    folder: str | Path,
    destination: str | Path,
    intrinsics: tuple[float, float, float, float],
    up: npt.ArrayLike,
    depth_scale: float = TUM_DEPTH_SCALE,
    noise: DepthNoiseModel | None = None,
) -> int:
    """Write a TUM-layout sequence as an MCAP file; returns the frames written.

    Raises:
        DatasetError: Missing or malformed files.
    """
    source_folder = Path(folder)
    first = next(iter(sorted((source_folder / "depth").glob("*.png"))), None)
    if first is None:
        raise DatasetError(f"no depth/*.png in {source_folder}")
    height, width = load_depth_png(first).shape
    camera = PinholeCamera(*intrinsics, width, height)
    if noise is not None:
        camera = PinholeCamera(*intrinsics, width, height, noise=noise)
    bus = InProcessBus()
    with McapRecorder(destination) as recorder:
        bus.tap(recorder.tap)
        return TumSequenceSource(bus, source_folder, camera, up, depth_scale).play()


def redwood_to_mcap(
    folder: str | Path,
    destination: str | Path,
    intrinsics: tuple[float, float, float, float],
    fps: float = 30.0,
    noise: DepthNoiseModel | None = None,
) -> int:
    """Write a Redwood sequence (y up) as an MCAP file; returns the frames written."""
    from footfall.datasets.redwood import convert_redwood

    with tempfile.TemporaryDirectory() as tum:
        convert_redwood(folder, tum, fps)
        return tum_to_mcap(tum, destination, intrinsics, (0.0, 1.0, 0.0), noise=noise)
