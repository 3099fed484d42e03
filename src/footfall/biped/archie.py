"""Leg kinematics of the biped Archie (dissertation §4.2, §4.4).

Forward kinematics from the Denavit-Hartenberg tables 3 and 4 (eqs. 27-37), with the link
lengths of Appendix A; and the geometric relations (eqs. 41-54) that tie the joint angles
to the motion of the centre of mass (COM): the support leg's hip roll ``theta0`` and pitch
``theta1`` place the COM (eq. 41); the trunk stays upright (``theta3 = -theta1``,
``theta4 = -theta0``); the swing leg's hip, knee and ankle follow from the cosine law
(eqs. 44-52) with the foot parallel to the ground.

Errata: eq. 42 solves eq. 41 with the tangent half-angle substitution and reads
``theta0 = 2 atan((-2 k1 +- sqrt(4 k1^2 - 4 k2 k3)) / (2 k2))`` (the root of smaller
magnitude); eq. 52 keeps the foot parallel to the ground only with the knee angle's sign
of its eq. 48, here written as ``theta_ankle = theta_knee - theta_hip`` with the knee
bending backwards for positive angles.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from footfall.errors import UnreachableTargetError


@dataclass(frozen=True)
class ArchieGeometry:
    """Link lengths of Archie (Appendix A) [m]."""

    a1: float = 0.12
    a2: float = 0.26
    a3: float = 0.31
    a6: float = 0.18
    d3: float = 0.075
    d6: float = 0.05


def dh_transform(a: float, alpha: float, d: float, theta: float) -> npt.NDArray[np.float64]:
    """The Denavit-Hartenberg transform of one link (eq. 29)."""
    ct, st, ca, sa = math.cos(theta), math.sin(theta), math.cos(alpha), math.sin(alpha)
    return np.array(
        [
            [ct, -st * ca, st * sa, a * ct],
            [st, ct * ca, -ct * sa, a * st],
            [0.0, sa, ca, d],
            [0.0, 0.0, 0.0, 1.0],
        ]
    )


def dh_table(side: str, g: ArchieGeometry | None = None) -> list[tuple[float, float, float]]:
    """``(a, alpha, d)`` of the six links of the left (Table 3) or right (Table 4) leg."""
    g = g or ArchieGeometry()
    if side == "left":
        return [(g.a1, math.pi / 2, 0.0), (g.a2, 0.0, 0.0), (g.a3, 0.0, -g.d3),
                (0.0, -math.pi / 2, 0.0), (0.0, -math.pi / 2, 0.0), (g.a6, 0.0, g.d6)]  # fmt: skip
    if side == "right":
        return [(g.a1, -math.pi / 2, 0.0), (g.a2, 0.0, 0.0), (g.a3, 0.0, -g.d3),
                (0.0, math.pi / 2, 0.0), (0.0, -math.pi / 2, 0.0), (-g.a6, 0.0, g.d6)]  # fmt: skip
    raise ValueError(f"side must be 'left' or 'right', got {side!r}")


def leg_forward(
    side: str, angles: npt.ArrayLike, g: ArchieGeometry | None = None
) -> npt.NDArray[np.float64]:
    """Transform from a foot's joint-0 frame to the COM frame (eqs. 30, 37), shape (4, 4).

    Args:
        side: ``"left"`` or ``"right"``.
        angles: The six joint angles, shape (6,) [rad].
        g: Link lengths.
    """
    q = np.asarray(angles, dtype=np.float64)
    t = np.eye(4)
    for (a, alpha, d), theta in zip(dh_table(side, g), q, strict=True):
        t = t @ dh_transform(a, alpha, d, float(theta))
    return t


def com_offset(
    theta0: float, theta1: float, g: ArchieGeometry | None = None
) -> tuple[float, float]:
    """COM position over the support foot from its hip roll and pitch (eq. 41) [m].

    Returns:
        ``(x_com, y_com)``.
    """
    g = g or ArchieGeometry()
    k1 = g.a1 + (g.a2 + g.a3) * math.cos(theta1)
    return (g.a2 + g.a3) * math.sin(theta1), k1 * math.sin(theta0) + g.d3 * math.cos(
        theta0
    ) + 0.5 * g.a6


def support_leg_angles(
    x_com: float, y_com: float, g: ArchieGeometry | None = None
) -> npt.NDArray[np.float64]:
    """The support leg's six joint angles that put the COM at ``(x_com, y_com)`` (eqs. 42, 53).

    Raises:
        UnreachableTargetError: When no hip angle reaches the COM position.
    """
    g = g or ArchieGeometry()
    reach = g.a2 + g.a3
    if abs(x_com) > reach:
        raise UnreachableTargetError(
            "support",
            f"COM {x_com:.3f} m ahead exceeds the leg's {reach:.3f} m",
            abs(x_com) - reach,
        )
    theta1 = math.asin(x_com / reach)
    k1 = g.a1 + reach * math.cos(theta1)
    k2 = 0.5 * g.a6 - g.d3 - y_com
    k3 = g.d3 + 0.5 * g.a6 - y_com
    disc = 4 * k1 * k1 - 4 * k2 * k3
    if disc < 0:
        raise UnreachableTargetError(
            "support", f"no hip roll reaches y_com = {y_com:.3f} m", float("nan")
        )
    if abs(k2) < 1e-12:
        roots = [-k3 / (2 * k1)]
    else:
        roots = [(-2 * k1 + s * math.sqrt(disc)) / (2 * k2) for s in (1, -1)]
    theta0 = min((2 * math.atan(u) for u in roots), key=abs)
    return np.array([theta0, theta1, 0.0, -theta1, -theta0, 0.0])


def swing_leg_angles(
    advance: float, height: float, g: ArchieGeometry | None = None
) -> npt.NDArray[np.float64]:
    """Hip pitch, knee and ankle of the swing leg (eqs. 46-52).

    The foot is ``advance`` forward of and ``height`` below the hip, parallel to the ground.

    Returns:
        ``(hip, knee, ankle)`` [rad]: the thigh leans ``hip`` forward of vertical, the shank
        bends ``knee`` back from the thigh, and ``ankle = knee - hip`` levels the foot.

    Raises:
        UnreachableTargetError: When the foot is beyond the stretched or folded leg.
    """
    g = g or ArchieGeometry()
    r = math.hypot(advance, height)
    if not abs(g.a3 - g.a2) <= r <= g.a2 + g.a3:
        raise UnreachableTargetError(
            "swing", f"foot {r:.3f} m from the hip is out of reach", float("nan")
        )
    beta = math.atan2(advance, height)
    hip = math.acos(np.clip((g.a3**2 + r * r - g.a2**2) / (2 * g.a3 * r), -1, 1)) + beta
    knee = math.pi - math.acos(np.clip((g.a3**2 + g.a2**2 - r * r) / (2 * g.a3 * g.a2), -1, 1))
    return np.array([hip, knee, knee - hip])
