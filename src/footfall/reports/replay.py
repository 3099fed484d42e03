"""A replayed recording's map, as ``footfall replay`` writes it (what ``footfall map`` writes)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from footfall.datasets.floor import floor_flatness
from footfall.recording.replay import Replayer
from footfall.recording.replay_request import ReplayRequest
from footfall.reports.map import MapReport


def run_replay(
    request: ReplayRequest, rerun: Path | None = None, rerun_spawn: bool = False
) -> MapReport:
    """Replay a recording into a map.

    Raises:
        DatasetError: A missing or unreadable recording, missing topics, unknown encodings,
            or no frame that could be mapped.
    """
    logger = None
    if rerun is not None or rerun_spawn:
        from footfall.recording.rerun_log import RerunLogger

        logger = RerunLogger(rerun, spawn=rerun_spawn)
    replayer = Replayer(request, taps=[logger.tap] if logger is not None else None)
    try:
        mapping = replayer.run()
    finally:
        if logger is not None:
            logger.close()
    snapshot = mapping.height_map.snapshot()
    scores = mapping.scores
    assert scores is not None
    counts = replayer.counts
    metrics: dict[str, object] = {
        "recording": str(request.path),
        "depth_topic": replayer.depth_topic,
        "pose_source": "odometry"
        if replayer.odometry is not None
        else "fixed camera"
        if replayer.fixed is not None
        else replayer.pose_topic or "tf " + " -> ".join(replayer.tf_frames or ()),
        "depth_images": counts.depth_images,
        "frames": mapping.frames,
        "frames_without_pose": counts.frames_without_pose + mapping.frames_skipped_no_pose,
        "frames_without_camera_info": counts.frames_without_info,
        "time_gaps": counts.time_gaps,
        "longest_gap_s": counts.longest_gap_s,
        **mapping.timing(),
        "cells_known": int(snapshot.known.sum()),
        "pixels_dropped": mapping.pixels_dropped,
        "points_outside_map": mapping.points_outside,
        **floor_flatness(snapshot, scores.valid, window_cells=mapping.score_config.kernel_size),
    }
    path = np.array(mapping.camera_path_xy) if mapping.camera_path_xy else np.zeros((0, 2))
    return MapReport(snapshot, scores, path, "camera path", metrics, mapping.score_config)
