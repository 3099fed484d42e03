"""How far an estimated camera path is from a reference one, as the TUM benchmark measures it.

Absolute trajectory error (ATE): the estimate is aligned to the reference by the SE(3) that
fits best (Umeyama, no scale), and the RMSE of the position differences is taken; a path
along a straight line does not fix that fit (any turn about the line fits as well), and is
aligned by its first pose instead. Relative
pose error (RPE) per metre: the translation error of the estimate's motion over segments of
``segment_m`` metres of the reference path, divided by the segment length (drift per metre).
Both by ``evo`` (Grupp, "evo: Python package for the evaluation of odometry and SLAM").
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from footfall.errors import ConfigError, DatasetError

# Poses further apart in time than this are not paired [s] (TUM's tools use 0.02 s).
MAX_TIME_DIFFERENCE_S = 0.02
# Segment length of the relative pose error where the path is long enough [m].
RPE_SEGMENT_M = 1.0


@dataclass(frozen=True)
class TrajectoryErrors:
    """Errors of an estimated path against a reference.

    Attributes:
        ate_rmse_m: Absolute trajectory error after SE(3) alignment, RMSE [m].
        rpe_per_m: Mean translation drift over segments of ``rpe_segment_m``, per metre.
        rpe_segment_m: The segment length: 1 m, or a quarter of a shorter path [m].
        alignment: ``"se3"`` (Umeyama) or ``"first pose"`` (a straight path).
        pairs: Poses paired in time.
        reference_length_m: Length of the paired reference path [m].
    """

    ate_rmse_m: float
    rpe_per_m: float
    rpe_segment_m: float
    pairs: int
    reference_length_m: float
    alignment: str = "se3"


def _evo() -> tuple[Any, Any, Any, Any]:
    try:
        geometry = importlib.import_module("evo.core.geometry")
        trajectory = importlib.import_module("evo.core.trajectory")
        sync = importlib.import_module("evo.core.sync")
        metrics = importlib.import_module("evo.core.metrics")
    except ImportError as exc:
        raise ConfigError(
            "trajectory errors need evo: install footfall[odometry] (pip install evo)"
        ) from exc
    return trajectory, sync, metrics, geometry


def trajectory_errors(estimate: npt.ArrayLike, reference: npt.ArrayLike) -> TrajectoryErrors:
    """ATE and RPE per metre of ``estimate`` against ``reference``.

    Args:
        estimate: TUM rows ``t tx ty tz qx qy qz qw``, camera-to-world, shape (n, 8).
        reference: The same for the reference (e.g. a sequence's ``groundtruth.txt``).

    Raises:
        DatasetError: Fewer than three poses pair up in time.
    """
    trajectory, sync, metrics, geometry = _evo()
    est_rows, ref_rows = np.asarray(estimate, np.float64), np.asarray(reference, np.float64)

    def path(rows: npt.NDArray[np.float64]) -> Any:
        return trajectory.PoseTrajectory3D(rows[:, 1:4], rows[:, [7, 4, 5, 6]], rows[:, 0])

    try:
        ref, est = sync.associate_trajectories(
            path(ref_rows), path(est_rows), max_diff=MAX_TIME_DIFFERENCE_S
        )
    except sync.SyncException as exc:
        raise DatasetError(f"the estimate and the reference share no time: {exc}") from exc
    if ref.num_poses < 3:
        raise DatasetError(
            f"only {ref.num_poses} poses of the estimate have a reference pose within "
            f"{MAX_TIME_DIFFERENCE_S} s: too few to compare"
        )
    alignment = "se3"
    try:
        est.align(ref, correct_scale=False)
    except geometry.GeometryException:
        est.align_origin(ref)
        alignment = "first pose"
    ape = metrics.APE(metrics.PoseRelation.translation_part)
    ape.process_data((ref, est))
    length = float(ref.path_length)
    segment = RPE_SEGMENT_M if length >= 2.0 * RPE_SEGMENT_M else 0.25 * length
    rpe_per_m = float("nan")
    if segment > 0.0:
        rpe = metrics.RPE(
            metrics.PoseRelation.translation_part,
            delta=segment,
            delta_unit=metrics.Unit.meters,
            all_pairs=True,
        )
        try:
            rpe.process_data((ref, est))
            rpe_per_m = float(rpe.get_statistic(metrics.StatisticsType.mean)) / segment
        except metrics.MetricsException:
            pass  # no pair of poses a segment apart: the path stands nearly still
    return TrajectoryErrors(
        float(ape.get_statistic(metrics.StatisticsType.rmse)),
        rpe_per_m,
        segment,
        int(ref.num_poses),
        length,
        alignment,
    )
