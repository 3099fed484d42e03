"""Rigid poses, and the pose-estimate noise of a SLAM system (thesis §3.3)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from scipy.spatial.transform import Rotation

from footfall.checks import require_non_negative
from footfall.errors import InvalidPoseError

# A quaternion whose norm is within this of 1 is normalised; farther off, it is refused.
QUATERNION_NORM_TOLERANCE = 1e-3


@dataclass(frozen=True)
class Pose:
    """A frame's pose in the world: maps points from that frame into the world.

    Attributes:
        position: Origin of the frame in the world, shape (3,) [m].
        rotation: Rotates vectors from the frame into the world.
    """

    position: npt.NDArray[np.float64]
    rotation: Rotation

    def __post_init__(self) -> None:
        p = np.asarray(self.position, dtype=np.float64)
        if p.shape != (3,) or not np.all(np.isfinite(p)):
            raise InvalidPoseError(f"pose position must be 3 finite numbers, got {self.position!r}")
        object.__setattr__(self, "position", p)

    @classmethod
    def from_quaternion(cls, position: npt.ArrayLike, quaternion_xyzw: npt.ArrayLike) -> Pose:
        """A pose from a position and a scalar-last quaternion ``(x, y, z, w)``.

        A quaternion whose norm differs from 1 by at most ``QUATERNION_NORM_TOLERANCE`` is
        normalised (recorded poses are often rounded); a larger difference is an error.

        Raises:
            InvalidPoseError: Non-finite values or a non-unit quaternion.
        """
        q = np.asarray(quaternion_xyzw, dtype=np.float64)
        if q.shape != (4,) or not np.all(np.isfinite(q)):
            raise InvalidPoseError(
                f"quaternion must be 4 finite numbers (x, y, z, w), got {quaternion_xyzw!r}"
            )
        norm = float(np.linalg.norm(q))
        if abs(norm - 1.0) > QUATERNION_NORM_TOLERANCE:
            raise InvalidPoseError(
                f"quaternion {q.tolist()} has norm {norm:.6f}; a rotation needs a unit quaternion "
                f"(norm within {QUATERNION_NORM_TOLERANCE} of 1)"
            )
        return cls(np.asarray(position, dtype=np.float64), Rotation.from_quat(q / norm))

    @classmethod
    def identity(cls) -> Pose:
        """The identity transform."""
        return cls(np.zeros(3), Rotation.identity())

    @classmethod
    def from_matrix(cls, matrix: npt.ArrayLike) -> Pose:
        """A pose from a 4x4 homogeneous transform.

        Raises:
            InvalidPoseError: If the matrix is not a rigid transform.
        """
        m = np.asarray(matrix, dtype=np.float64)
        if m.shape != (4, 4) or not np.all(np.isfinite(m)):
            raise InvalidPoseError(f"transform must be a finite 4x4 matrix, got shape {m.shape}")
        r = m[:3, :3]
        if not np.allclose(r @ r.T, np.eye(3), atol=1e-4) or np.linalg.det(r) < 0:
            raise InvalidPoseError("transform's 3x3 block is not a rotation")
        return cls(m[:3, 3].copy(), Rotation.from_matrix(r))

    @property
    def matrix(self) -> npt.NDArray[np.float64]:
        """The 4x4 homogeneous transform."""
        m = np.eye(4)
        m[:3, :3] = self.rotation.as_matrix()
        m[:3, 3] = self.position
        return m

    def apply(self, points: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Map points, shape (n, 3), from this frame into the world."""
        vectors = np.asarray(points, dtype=np.float64)
        if not vectors.flags.writeable:
            # SciPy's Rotation.apply refuses read-only buffers (a decoded message's arrays).
            vectors = vectors.copy()
        return self.rotation.apply(vectors) + self.position

    def compose(self, other: Pose) -> Pose:
        """``self * other``: the pose of a frame given relative to this one."""
        return Pose(self.apply(other.position[None])[0], self.rotation * other.rotation)

    def inverse(self) -> Pose:
        """The world's pose in this frame."""
        inv = self.rotation.inv()
        return Pose(-inv.apply(self.position), inv)


@dataclass(frozen=True)
class SlamNoiseConfig:
    """A SLAM-like pose estimate error: a random-walk drift plus per-frame jitter.

    Drift grows like a random walk with time (standard deviation ``rate * sqrt(t)``);
    jitter is white noise added to each estimate. Defaults are those of a visual SLAM on a
    walking robot (centimetre drift over a minute, millimetre jitter).

    Attributes:
        position_drift: Position random-walk rate [m / sqrt(s)].
        yaw_drift: Heading random-walk rate [rad / sqrt(s)].
        tilt_drift: Roll and pitch random-walk rate [rad / sqrt(s)].
        position_jitter: Per-estimate position noise [m].
        angle_jitter: Per-estimate rotation noise [rad].
    """

    position_drift: float = 0.002
    yaw_drift: float = 0.002
    tilt_drift: float = 0.0005
    position_jitter: float = 0.002
    angle_jitter: float = 0.002

    def __post_init__(self) -> None:
        require_non_negative(
            "SLAM noise",
            position_drift=self.position_drift,
            yaw_drift=self.yaw_drift,
            tilt_drift=self.tilt_drift,
            position_jitter=self.position_jitter,
            angle_jitter=self.angle_jitter,
        )


class SlamNoise:
    """Turns true poses into SLAM-like estimates, reproducibly for a given ``rng``.

    Args:
        config: Noise magnitudes.
        rng: Random generator (seed it for repeatable runs).
    """

    def __init__(self, config: SlamNoiseConfig, rng: np.random.Generator) -> None:
        self.config = config
        self.rng = rng
        self._drift_position = np.zeros(3)
        self._drift_angles = np.zeros(3)  # roll, pitch, yaw
        self._time: float | None = None

    def estimate(self, true_pose: Pose, t: float) -> Pose:
        """The estimate of ``true_pose`` at time ``t`` [s] (times must not decrease)."""
        c = self.config
        dt = 0.0 if self._time is None else max(t - self._time, 0.0)
        self._time = t
        sq = np.sqrt(dt)
        self._drift_position += self.rng.normal(0.0, c.position_drift * sq, 3)
        self._drift_angles += (
            self.rng.normal(0.0, 1.0, 3) * sq * np.array([c.tilt_drift, c.tilt_drift, c.yaw_drift])
        )
        position = (
            true_pose.position + self._drift_position + self.rng.normal(0.0, c.position_jitter, 3)
        )
        angles = self._drift_angles + self.rng.normal(0.0, c.angle_jitter, 3)
        # The drift is a rotation of the estimate about the world axes (a map-frame error).
        error = Rotation.from_euler("xyz", angles)
        return Pose(position, error * true_pose.rotation)


def exact_rotation(quaternion_xyzw: npt.ArrayLike) -> Rotation:
    """The rotation of a quaternion ``(x, y, z, w)``, bit for bit when it is of unit norm.

    ``Rotation.from_quat`` normalises, which moves a unit quaternion by an ulp (a third of
    the time) and so the rotation matrix; the state SciPy pickles a rotation with restores
    it exactly. A recorded pose thus replays to the very matrix it was.

    Raises:
        InvalidPoseError: A quaternion with a non-finite entry or of zero norm.
    """
    q = np.asarray(quaternion_xyzw, dtype=np.float64).reshape(4)
    norm = float(np.linalg.norm(q))
    if not (np.all(np.isfinite(q)) and norm > 0):
        raise InvalidPoseError(f"quaternion {q.tolist()} is not a rotation")
    if abs(norm - 1.0) < 1e-12:
        rotation = Rotation.__new__(Rotation)
        try:
            rotation.__setstate__((q[None, :].copy(), True))
            return rotation
        except (TypeError, ValueError, AttributeError):
            pass
    return Rotation.from_quat(q)
