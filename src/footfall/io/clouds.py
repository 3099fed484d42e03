"""Point clouds from files: PCD, PLY or NumPy (``.npy``, shape (n, 3))."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import numpy.typing as npt

from footfall.errors import DatasetError
from footfall.io.pcd import read_pcd


def read_points(path: str | Path) -> npt.NDArray[np.float64]:
    """The finite x, y, z points of a cloud file, shape (n, 3) [m].

    Raises:
        DatasetError: A missing or unreadable file, an unknown suffix, or no finite point.
    """
    p = Path(path)
    if not p.is_file():
        raise DatasetError(f"missing point cloud {p}")
    suffix = p.suffix.lower()
    if suffix == ".pcd":
        points = read_pcd(p).xyz
    elif suffix == ".ply":
        from plyfile import PlyData

        try:
            vertex = PlyData.read(str(p))["vertex"]
            points = np.stack(
                [np.asarray(vertex[k], dtype=np.float64) for k in ("x", "y", "z")], axis=1
            )
        except Exception as exc:  # plyfile's parser raises many kinds on a broken file
            raise DatasetError(f"{p}: no readable x, y, z vertex data ({exc})") from exc
    elif suffix == ".npy":
        try:
            points = np.asarray(np.load(p, allow_pickle=False), dtype=np.float64)
        except Exception as exc:  # NumPy's header parser raises many kinds on a broken file
            raise DatasetError(f"{p}: not a readable NumPy array ({exc})") from exc
        if points.ndim != 2 or points.shape[1] < 3:
            raise DatasetError(f"{p}: expected an array of shape (n, 3), got {points.shape}")
        points = points[:, :3]
    else:
        raise DatasetError(f"{p}: unknown point cloud format {suffix!r} (use .pcd, .ply or .npy)")
    finite = points[np.all(np.isfinite(points), axis=1)]
    if finite.size == 0:
        raise DatasetError(f"{p}: the point cloud holds no finite point")
    return finite
