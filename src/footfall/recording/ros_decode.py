"""ROS messages back into footfall's values: depth images, poses, the TF tree.

Depth arrives as ``sensor_msgs/Image`` (``16UC1`` millimetres, ``32FC1`` metres) or as a
``CompressedImage`` (image_transport's ``compressedDepth`` PNG, or a plain 16-bit PNG);
poses as ``geometry_msgs/Pose`` or ``Transform``, their rotations restored bit for bit.
"""

from __future__ import annotations

import bisect
from typing import Any

import numpy as np
import numpy.typing as npt

from footfall.errors import DatasetError
from footfall.sensing.pose import Pose, exact_rotation

DEPTH_ENCODINGS = {"16UC1": ("<u2", 0.001), "mono16": ("<u2", 0.001), "32FC1": ("<f4", None)}


def pose_of(message: Any) -> Pose:
    """The pose of a ``geometry_msgs/Pose``, its rotation exactly as recorded."""
    p, q = message.position, message.orientation
    return Pose(np.array([p.x, p.y, p.z]), exact_rotation([q.x, q.y, q.z, q.w]))


def transform_pose(transform: Any) -> Pose:
    """The pose of a ``geometry_msgs/Transform`` (child in parent)."""
    t, q = transform.translation, transform.rotation
    return Pose(np.array([t.x, t.y, t.z]), exact_rotation([q.x, q.y, q.z, q.w]))


def compressed_depth_array(image: Any) -> tuple[npt.NDArray, float | None]:
    """A ``sensor_msgs/CompressedImage`` of depth as an array of millimetres.

    ``16UC1; compressedDepth png`` (image transport's 12-byte header, then a 16-bit PNG of
    millimetres) or a plain 16-bit PNG.

    Raises:
        DatasetError: Another format (JPEG, the inverse-depth ``32FC1`` codec), or a PNG
            that does not decode to 16-bit depth.
    """
    import io

    from PIL import Image

    fmt = str(image.format)
    data = bytes(np.asarray(image.data, dtype=np.uint8))
    if "compressedDepth" in fmt:
        if "16UC1" not in fmt:
            raise DatasetError(f"compressed depth format {fmt!r}: only 16UC1 PNG is read")
        data = data[12:]  # the codec's header: format and two float quantisation terms
    elif "png" not in fmt.lower():
        raise DatasetError(f"compressed image format {fmt!r} is not PNG depth")
    try:
        with Image.open(io.BytesIO(data)) as png:
            depth = np.array(png)
    except (OSError, ValueError, SyntaxError) as exc:
        raise DatasetError(f"compressed depth image does not decode ({exc})") from exc
    if depth.ndim != 2 or depth.dtype not in (np.uint16, np.int32):
        raise DatasetError(f"compressed depth decodes to {depth.dtype} {depth.shape}, not 16-bit")
    return depth.astype(np.uint16), 0.001


def depth_array(image: Any) -> tuple[npt.NDArray, float | None]:
    """A ``sensor_msgs/Image`` (or ``CompressedImage``) of depth, and its metres per unit.

    Raises:
        DatasetError: An encoding that is not depth, or data of the wrong size.
    """
    if hasattr(image, "format"):
        return compressed_depth_array(image)
    if image.encoding not in DEPTH_ENCODINGS:
        known = ", ".join(DEPTH_ENCODINGS)
        raise DatasetError(f"depth image encoding {image.encoding!r} is not depth ({known})")
    dtype, scale = DEPTH_ENCODINGS[image.encoding]
    kind = np.dtype(dtype).newbyteorder(">" if image.is_bigendian else "<")
    row = image.width * kind.itemsize
    data = np.asarray(image.data, dtype=np.uint8)
    if image.step < row or data.size < image.step * image.height:
        raise DatasetError(
            f"depth image of {image.width}x{image.height} {image.encoding} holds {data.size} "
            f"bytes with step {image.step}"
        )
    rows = data[: image.step * image.height].reshape(image.height, image.step)[:, :row]
    return np.ascontiguousarray(rows).view(kind).astype(dtype), scale


class TransformTree:
    """The latest transform of each frame to its parent, from ``/tf`` and ``/tf_static``."""

    def __init__(self) -> None:
        self.parent: dict[str, tuple[str, Pose]] = {}

    def add(self, message: Any) -> None:
        """Take a ``tf2_msgs/TFMessage``."""
        for t in message.transforms:
            self.parent[t.child_frame_id] = (t.header.frame_id, transform_pose(t.transform))

    def _to_root(self, frame: str) -> tuple[str, Pose]:
        pose = Pose.identity()
        seen = {frame}
        while frame in self.parent:
            frame, step = self.parent[frame]
            pose = step.compose(pose)
            if frame in seen:
                raise DatasetError(f"TF has a loop through frame {frame!r}")
            seen.add(frame)
        return frame, pose

    def lookup(self, world: str, frame: str) -> Pose | None:
        """``frame``'s pose in ``world``, or None while they are not connected.

        A frame whose parent is ``world`` gets its transform as recorded (no composition
        with identities, which could move its rotation by an ulp).
        """
        if frame == world:
            return Pose.identity()
        direct = self.parent.get(frame)
        if direct is not None and direct[0] == world:
            return direct[1]
        root_a, frame_in_root = self._to_root(frame)
        root_b, world_in_root = self._to_root(world)
        if root_a != root_b:
            return None
        return world_in_root.inverse().compose(frame_in_root)


class TransformHistory:
    """Every transform of a recording's TF, to look a frame up at an image's time.

    A bag's TF often arrives after the image it belongs to, and at another rate; each
    dynamic transform is taken at the sample nearest the image's stamp (within a gap),
    each static one always.
    """

    def __init__(self) -> None:
        self._samples: dict[str, list[tuple[float, str, Pose]]] = {}
        self._static: dict[str, tuple[str, Pose]] = {}
        self._times: dict[str, list[float]] = {}

    def add(self, message: Any, static: bool = False) -> None:
        """Take a ``tf2_msgs/TFMessage`` (from ``/tf_static`` with ``static``)."""
        for t in message.transforms:
            pose = transform_pose(t.transform)
            if static:
                self._static[t.child_frame_id] = (t.header.frame_id, pose)
            else:
                stamp = t.header.stamp.sec + t.header.stamp.nanosec * 1e-9
                self._samples.setdefault(t.child_frame_id, []).append(
                    (stamp, t.header.frame_id, pose)
                )
        self._times.clear()

    def tree_at(self, stamp: float, max_gap_s: float) -> TransformTree:
        """The transforms nearest ``stamp`` (dynamic ones within ``max_gap_s``)."""
        tree = TransformTree()
        for child, (parent, pose) in self._static.items():
            tree.parent[child] = (parent, pose)
        for child, samples in self._samples.items():
            if child not in self._times:
                samples.sort(key=lambda s: s[0])
                self._times[child] = [s[0] for s in samples]
            times = self._times[child]
            k = bisect.bisect_left(times, stamp)
            near = [c for c in (k - 1, k) if 0 <= c < len(times)]
            best = min(near, key=lambda c: abs(times[c] - stamp))
            if abs(times[best] - stamp) <= max_gap_s:
                tree.parent[child] = (samples[best][1], samples[best][2])
        return tree
