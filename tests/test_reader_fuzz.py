"""Readers never crash: every mutated PCD, PLY, NumPy, TUM or Redwood input gives a
FootfallError that names the file, or reads."""

from __future__ import annotations

import io

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from PIL import Image

from footfall.datasets.redwood import read_trajectory_log
from footfall.datasets.tum import check_depth_units, load_depth_png, read_tum_sequence
from footfall.errors import DatasetError, FootfallError
from footfall.io.clouds import read_points
from footfall.io.pcd import read_pcd
from fuzzing import COUNTS, fuzz_settings

FUZZ = fuzz_settings(150)


def _pcd(kind: str, points: np.ndarray) -> bytes:
    header = (
        "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n"
        f"WIDTH {len(points)}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {len(points)}\n"
        f"DATA {kind}\n"
    ).encode()
    p = points.astype("<f4")
    if kind == "ascii":
        return header + "\n".join(" ".join(f"{v:.4f}" for v in row) for row in p).encode()
    if kind == "binary":
        return header + p.tobytes()
    columns = np.ascontiguousarray(p.T).tobytes()  # fields one after another
    literal = bytearray()
    for start in range(0, len(columns), 32):  # LZF literal runs of up to 32 bytes
        chunk = columns[start : start + 32]
        literal += bytes([len(chunk) - 1]) + chunk
    return header + np.array([len(literal), len(columns)], "<u4").tobytes() + bytes(literal)


def _mutate(data: bytes, draw) -> bytes:
    """Truncate, flip bytes, or splice garbage into a file."""
    how = draw(st.sampled_from(["truncate", "flip", "splice"]))
    b = bytearray(data)
    if how == "truncate":
        return bytes(b[: draw(st.integers(0, len(b)))])
    if how == "flip":
        for _ in range(draw(st.integers(1, 8))):
            k = draw(st.integers(0, len(b) - 1))
            b[k] = draw(st.integers(0, 255))
        return bytes(b)
    k = draw(st.integers(0, len(b)))
    return bytes(b[:k]) + draw(st.binary(max_size=40)) + bytes(b[k:])


@pytest.mark.parametrize("kind", ["ascii", "binary", "binary_compressed"])
def test_a_clean_pcd_of_each_kind_reads_back(tmp_path, kind):
    """The fuzzers' seed files are valid: each reads back to its points."""
    points = np.random.default_rng(0).normal(size=(40, 3))
    path = tmp_path / "c.pcd"
    path.write_bytes(_pcd(kind, points))
    np.testing.assert_allclose(read_pcd(path).xyz, points, atol=1e-4)


@FUZZ
@given(data=st.data(), kind=st.sampled_from(["ascii", "binary", "binary_compressed"]))
def test_mutated_pcd_files_fail_cleanly(tmp_path, data, kind):
    """A truncated, bit-flipped or spliced PCD reads or raises FootfallError."""
    points = np.random.default_rng(1).normal(size=(30, 3))
    path = tmp_path / "m.pcd"
    path.write_bytes(_mutate(_pcd(kind, points), data.draw))
    COUNTS[f"PCD {kind}"] += 1
    try:
        read_points(path)
    except FootfallError as exc:
        assert str(path) in str(exc) or "point cloud" in str(exc)


def test_truncated_compressed_pcd_names_the_problem(tmp_path):
    """The issue's case: a cut binary_compressed file says it is truncated."""
    path = tmp_path / "t.pcd"
    path.write_bytes(_pcd("binary_compressed", np.ones((50, 3)))[:-20])
    with pytest.raises(DatasetError, match="truncated compressed data"):
        read_pcd(path)


def _ply(points: np.ndarray, binary: bool) -> bytes:
    from plyfile import PlyData, PlyElement

    vertex = np.array([tuple(p) for p in points], dtype=[("x", "f4"), ("y", "f4"), ("z", "f4")])
    buffer = io.BytesIO()
    PlyData([PlyElement.describe(vertex, "vertex")], text=not binary).write(buffer)
    return buffer.getvalue()


@FUZZ
@given(data=st.data(), binary=st.booleans())
def test_mutated_ply_and_npy_files_fail_cleanly(tmp_path, data, binary):
    """Broken PLY and .npy files read or raise FootfallError."""
    points = np.random.default_rng(2).normal(size=(20, 3))
    ply = tmp_path / "m.ply"
    ply.write_bytes(_mutate(_ply(points, binary), data.draw))
    npy = tmp_path / "m.npy"
    buffer = io.BytesIO()
    np.save(buffer, points)
    npy.write_bytes(_mutate(buffer.getvalue(), data.draw))
    for path in (ply, npy):
        COUNTS[f"{'PLY' if path is ply else 'NumPy'} file"] += 1
        try:
            read_points(path)
        except FootfallError:
            pass


def _png(depth: np.ndarray) -> bytes:
    buffer = io.BytesIO()
    Image.fromarray(depth).save(buffer, format="PNG")
    return buffer.getvalue()


@FUZZ
@given(data=st.data())
def test_mutated_tum_sequences_fail_cleanly(tmp_path, data):
    """A TUM folder with mutated index, trajectory and depth PNG reads or raises
    FootfallError; so does a mutated Redwood trajectory.log."""
    (tmp_path / "depth").mkdir(exist_ok=True)
    depth = np.full((12, 16), 7500, np.uint16)
    (tmp_path / "depth" / "0.png").write_bytes(_mutate(_png(depth), data.draw))
    index = b"# timestamp filename\n0.000 depth/0.png\n"
    truth = b"# t tx ty tz qx qy qz qw\n0.000 0 0 1 0 0 0 1\n"
    (tmp_path / "depth.txt").write_bytes(_mutate(index, data.draw))
    (tmp_path / "groundtruth.txt").write_bytes(_mutate(truth, data.draw))
    log = b"0 0 1\n1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n"
    (tmp_path / "trajectory.log").write_bytes(_mutate(log, data.draw))
    COUNTS["TUM sequence"] += 1
    COUNTS["Redwood trajectory"] += 1
    try:
        frames, _ = read_tum_sequence(tmp_path)
        for frame in frames:
            check_depth_units(load_depth_png(frame.depth_path), 1 / 5000, frame.depth_path)
    except FootfallError:
        pass
    try:
        read_trajectory_log(tmp_path / "trajectory.log")
    except FootfallError:
        pass


def test_depth_in_another_convention_is_refused(tmp_path):
    """Byte-swapped depth and raw disparity are not read as wrong metres."""
    rng = np.random.default_rng(3)
    metres = 1.5 + 0.3 * np.sin(np.linspace(0, 3, 640))[None, :] + rng.normal(0, 0.002, (480, 640))
    units = (metres * 5000).astype(np.uint16)
    check_depth_units(units, 1 / 5000, "ok.png")
    with pytest.raises(DatasetError, match="bytes swapped"):
        check_depth_units(units.byteswap(), 1 / 5000, "swapped.png")
    disparity = (1090 - 340 / metres).astype(np.uint16)  # Kinect raw disparity, about 860
    with pytest.raises(DatasetError, match="depth-scale"):
        check_depth_units(disparity, 1 / 5000, "disparity.png")
