"""Camera trajectories in the TUM format: ``t tx ty tz qx qy qz qw`` per line.

The format of TUM RGB-D's ``groundtruth.txt`` and of what most SLAM systems write: the camera's
optical frame in the world at time ``t`` [s], position in metres, quaternion scalar-last.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import numpy.typing as npt
from scipy.spatial.transform import Rotation

from footfall.errors import DatasetError
from footfall.sensing.pose import Pose


def read_table(path: Path, columns: int) -> list[list[str]]:
    """The rows of a whitespace-separated text table, each with at least ``columns`` fields.

    Blank lines and lines starting with ``#`` are skipped.

    Raises:
        DatasetError: A missing file, one that is not text, or a short line (named).
    """
    if not path.is_file():
        raise DatasetError(f"missing {path.name} in {path.parent}")
    rows = []
    try:
        text = path.read_text()
    except UnicodeDecodeError as exc:
        raise DatasetError(f"{path}: not a text file ({exc})") from exc
    for number, line in enumerate(text.splitlines(), start=1):
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        fields = line.split()
        if len(fields) < columns:
            raise DatasetError(
                f"{path.name} line {number}: expected {columns} fields, got {len(fields)}"
            )
        rows.append(fields)
    return rows


@dataclass(frozen=True)
class Trajectory:
    """Camera-to-world poses by time, as a TUM ``groundtruth.txt`` (or a SLAM's output) holds.

    Each line: ``t tx ty tz qx qy qz qw`` (the optical frame's pose in the world).

    Attributes:
        times: Pose times in increasing order [s].
        table: The lines as numbers, shape (n, 8), in the same order.
    """

    times: npt.NDArray[np.float64]
    table: npt.NDArray[np.float64]

    @classmethod
    def read(cls, path: str | Path) -> Trajectory:
        """A trajectory file.

        Raises:
            DatasetError: A missing file, a malformed line (named) or no pose at all.
        """
        path = Path(path)
        rows = read_table(path, 8)
        if not rows:
            raise DatasetError(f"{path} holds no poses")
        try:
            table = np.array([[float(v) for v in row[:8]] for row in rows])
        except ValueError as exc:
            raise DatasetError(
                f"{path}: a timestamp or pose value is not a number ({exc})"
            ) from exc
        table = table[np.argsort(table[:, 0], kind="stable")]
        return cls(table[:, 0].copy(), table)

    def nearest(self, t: float, max_time_difference: float) -> tuple[Pose, float] | None:
        """The pose nearest in time to ``t`` and its time minus ``t`` [s].

        None where no pose lies within ``max_time_difference`` [s].

        Raises:
            InvalidPoseError: The pose's quaternion is not a unit one.
        """
        k = int(np.searchsorted(self.times, t))
        candidates = [c for c in (k - 1, k) if 0 <= c < len(self.times)]
        best = min(candidates, key=lambda c: abs(self.times[c] - t))
        if abs(self.times[best] - t) > max_time_difference:
            return None
        p = self.table[best]
        return Pose.from_quaternion(p[1:4], p[4:8]), float(self.times[best] - t)


def up_to_z(up: npt.ArrayLike) -> Rotation:
    """The smallest rotation taking the world's up axis to +z."""
    u = np.asarray(up, dtype=np.float64)
    norm = np.linalg.norm(u)
    if u.shape != (3,) or not norm > 0:
        raise DatasetError(f"--up needs a non-zero 3-vector, got {up!r}")
    rotation, _ = Rotation.align_vectors([[0.0, 0.0, 1.0]], [u / norm])
    return rotation
