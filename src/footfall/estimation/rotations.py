"""Rotations as the estimator needs them each tick: small, exact, and cheaper than scipy's.

scipy's ``Rotation`` costs tens of microseconds a call on 3-vectors; the estimator turns its
body and six tibias every control tick, so it keeps rotation matrices and uses these.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt
from scipy.spatial.transform import Rotation


def cross(a: npt.NDArray[np.float64], b: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    """``a x b`` for two 3-vectors (NumPy's ``cross`` costs more than it computes here)."""
    return np.array(
        [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
    )


def rotation_of(matrix: npt.NDArray[np.float64]) -> Rotation:
    """A rotation matrix as a ``Rotation``, through its quaternion (Shepperd's method).

    ``Rotation.from_matrix`` first finds the nearest orthonormal matrix, 90 us a call; a
    matrix kept orthonormal needs only the quaternion, 15 us.
    """
    m = matrix
    trace = m[0, 0] + m[1, 1] + m[2, 2]
    if trace > 0.0:
        s = 2.0 * math.sqrt(1.0 + trace)
        q = (m[2, 1] - m[1, 2], m[0, 2] - m[2, 0], m[1, 0] - m[0, 1], 0.25 * s * s)
    elif m[0, 0] >= m[1, 1] and m[0, 0] >= m[2, 2]:
        s = 2.0 * math.sqrt(1.0 + m[0, 0] - m[1, 1] - m[2, 2])
        q = (0.25 * s * s, m[0, 1] + m[1, 0], m[0, 2] + m[2, 0], m[2, 1] - m[1, 2])
    elif m[1, 1] >= m[2, 2]:
        s = 2.0 * math.sqrt(1.0 + m[1, 1] - m[0, 0] - m[2, 2])
        q = (m[0, 1] + m[1, 0], 0.25 * s * s, m[1, 2] + m[2, 1], m[0, 2] - m[2, 0])
    else:
        s = 2.0 * math.sqrt(1.0 + m[2, 2] - m[0, 0] - m[1, 1])
        q = (m[0, 2] + m[2, 0], m[1, 2] + m[2, 1], 0.25 * s * s, m[1, 0] - m[0, 1])
    return Rotation.from_quat(np.array(q) / s)


def rodrigues(rotvec: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    """The rotation matrix of a rotation vector [rad]."""
    theta = math.sqrt(float(rotvec @ rotvec))
    x, y, z = rotvec
    k = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    if theta < 1e-12:
        return np.eye(3) + k
    return np.eye(3) + math.sin(theta) / theta * k + (1.0 - math.cos(theta)) / theta**2 * (k @ k)


def rotation_vectors(matrices: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    """The rotation vectors of rotation matrices, shape (n, 3, 3) to (n, 3) [rad].

    From the matrices' skew parts: exact to rounding for turns short of a half turn (a
    tick's turns are thousandths of one), ill-conditioned near it.
    """
    m = matrices
    vee = 0.5 * np.stack(
        [m[:, 2, 1] - m[:, 1, 2], m[:, 0, 2] - m[:, 2, 0], m[:, 1, 0] - m[:, 0, 1]], axis=1
    )
    sine = np.linalg.norm(vee, axis=1)
    cosine = 0.5 * (np.trace(m, axis1=1, axis2=2) - 1.0)
    angle = np.arctan2(sine, cosine)
    scale = np.where(sine > 1e-12, angle / np.maximum(sine, 1e-300), 1.0)
    return vee * scale[:, None]
