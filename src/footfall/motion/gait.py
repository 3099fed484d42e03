"""Gaits of a hexapod (thesis §5.3): swing groups, duty factors, commands and step timing.

A gait is a cycle of *steps*; in each step one group of legs swings while the others
support. Tripod swings three legs at a time (duty factor 1/2), ripple two (2/3), wave one
(5/6), so ``duty_factor = 1 - 1 / groups``. With stride ``S`` (the distance a foot travels
over the ground in one swing, which is also the body's advance per gait cycle) and step
duration ``T``, the speed is ``v = S / (n T)`` for ``n`` groups; the body-frame stroke of a
supporting foot is ``D S`` (thesis eq. 5.14 with its ``S`` being that stroke).

Legs are indexed in spec order: counter-clockwise from the front-left leg, so on a
standard hexapod 0 = LF, 1 = LM, 2 = LB, 3 = RB, 4 = RM, 5 = RF.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from enum import StrEnum

import numpy as np
import numpy.typing as npt

from footfall.errors import ConfigError
from footfall.motion.swing import FlowConfig


class GaitKind(StrEnum):
    """The three hexapod gaits of thesis Fig. 5.4."""

    TRIPOD = "tripod"
    RIPPLE = "ripple"
    WAVE = "wave"


# Swing groups in the order they step. Tripod: legs i, i+2, i+4 (eq. 5.15). Ripple: each
# side steps back to front, the sides one step apart, so four feet always support in a
# quadrilateral. Wave: one leg at a time, back to front on the left, then on the right.
_GROUPS: dict[GaitKind, tuple[tuple[int, ...], ...]] = {
    GaitKind.TRIPOD: ((0, 2, 4), (1, 3, 5)),
    GaitKind.RIPPLE: ((2, 5), (1, 3), (0, 4)),
    GaitKind.WAVE: ((2,), (1,), (0,), (3,), (4,), (5,)),
}


def swing_groups(kind: GaitKind) -> tuple[tuple[int, ...], ...]:
    """The gait's swing groups, in stepping order."""
    return _GROUPS[GaitKind(kind)]


def duty_factor(kind: GaitKind) -> float:
    """Fraction of the cycle each leg supports: 1/2 tripod, 2/3 ripple, 5/6 wave."""
    return 1.0 - 1.0 / len(swing_groups(kind))


def active_sextant(direction_in_body: npt.ArrayLike, rest_feet_in_body: npt.ArrayLike) -> int:
    """The leg whose sextant holds the walk direction (thesis §5.3.3).

    Sextants are centred on the rest foot directions seen from the body centre; the result
    is the leg whose rest foot lies angularly closest to the direction (ties: lower index).

    Args:
        direction_in_body: Walk direction, shape (2,).
        rest_feet_in_body: Rest foot positions, shape (6, 2+).
    """
    d = np.asarray(direction_in_body, dtype=np.float64)
    feet = np.asarray(rest_feet_in_body, dtype=np.float64)
    heading = math.atan2(d[1], d[0])
    angles = np.arctan2(feet[:, 1], feet[:, 0])
    gap = np.abs(np.angle(np.exp(1j * (angles - heading))))
    return int(np.argmin(np.round(gap, 9)))


def tripod_swing_set(
    direction_in_body: npt.ArrayLike,
    rest_feet_in_body: npt.ArrayLike,
    feet_in_body: npt.ArrayLike,
    mounts_in_body: npt.ArrayLike,
) -> npt.NDArray[np.bool_]:
    """Which legs swing in the next tripod step (thesis eqs. 5.15-5.16).

    Leg ``xi`` of the active sextant swings with ``xi + 2`` and ``xi + 4``; when leg ``xi``'s
    horizontal length exceeds its rest length (its foot is already ahead) the set inverts.

    Returns:
        Swing mask, shape (6,): True for a swinging leg.
    """
    rest = np.asarray(rest_feet_in_body, dtype=np.float64)
    feet = np.asarray(feet_in_body, dtype=np.float64)
    mounts = np.asarray(mounts_in_body, dtype=np.float64)
    xi = active_sextant(direction_in_body, rest)
    swing = (np.arange(6) - xi) % 2 == 0  # eq. 5.15
    length = np.hypot(*(feet[xi, :2] - mounts[xi, :2]))
    rest_length = np.hypot(*(rest[xi, :2] - mounts[xi, :2]))
    if length > rest_length + 1e-9:  # eq. 5.16
        swing = ~swing
    return swing


@dataclass(frozen=True)
class GaitConfig:
    """Walking parameters. Defaults are the thesis' (§8.1): stride 0.15 m, Ch 2.0, q 14.

    Attributes:
        kind: Which gait.
        stride_length: Longest distance a foot travels over the ground in one swing [m]; None
            takes the robot's (``HexapodSpec.stride_length``).
        min_step_duration: Shortest swing [s]; with the stride it caps the speed.
        max_step_duration: Longest swing while walking [s]; slower walks shorten the stride.
        rest_step_duration: Swing duration when stepping back to the rest stance [s].
        stroke_margin: How far beyond its nominal stroke a supporting foot may trail before
            the body slows down to wait for it [m].
        rest_tolerance: A foot this close to its rest position counts as at rest [m].
        retarget_tolerance: A swing target that moves more than this is re-planned [m].
        acceleration_limit: Body acceleration limit [m/s^2].
        yaw_acceleration_limit: Body yaw acceleration limit [rad/s^2].
        height_rate_limit: Speed of body height changes [m/s].
        swing: ``"flow"`` (thesis §5.4.2) or ``"polynomial"`` (the §5.4.1 baseline).
        flow: Flow-function parameters.
        polynomial_apex: Apex of the polynomial arc above the higher end [m].
    """

    kind: GaitKind = GaitKind.TRIPOD
    stride_length: float | None = None
    min_step_duration: float = 0.3
    max_step_duration: float = 1.0
    rest_step_duration: float = 0.6
    stroke_margin: float = 0.04
    rest_tolerance: float = 0.005
    retarget_tolerance: float = 0.002
    acceleration_limit: float = 0.5
    yaw_acceleration_limit: float = 2.0
    height_rate_limit: float = 0.07
    swing: str = "flow"
    flow: FlowConfig = field(default_factory=FlowConfig)
    polynomial_apex: float = 0.1

    def __post_init__(self) -> None:
        object.__setattr__(self, "kind", GaitKind(self.kind))
        if self.swing not in ("flow", "polynomial"):
            raise ConfigError(f"swing must be 'flow' or 'polynomial', got {self.swing!r}")
        if not 0 < self.min_step_duration <= self.max_step_duration:
            raise ConfigError("need 0 < min_step_duration <= max_step_duration")
        if self.stride_length is not None and not self.stride_length > 0:
            raise ConfigError(f"gait stride_length must be positive, got {self.stride_length}")
        for name in (
            "rest_step_duration",
            "acceleration_limit",
            "yaw_acceleration_limit",
            "height_rate_limit",
        ):
            if not getattr(self, name) > 0:
                raise ConfigError(f"gait {name} must be positive, got {getattr(self, name)}")

    @property
    def groups(self) -> tuple[tuple[int, ...], ...]:
        """Swing groups in stepping order."""
        return swing_groups(self.kind)

    @property
    def duty_factor(self) -> float:
        """Support fraction of each leg's cycle."""
        return duty_factor(self.kind)

    @property
    def stride(self) -> float:
        """The stride [m]; raises when it was left to the robot and not yet resolved."""
        if self.stride_length is None:
            raise ConfigError("stride_length is unset: resolve it with for_robot(spec)")
        return self.stride_length

    @property
    def max_speed(self) -> float:
        """Fastest body speed this gait reaches at its stride and shortest step [m/s]."""
        return self.stride / (len(self.groups) * self.min_step_duration)

    def for_robot(self, stride_length: float, max_step_height: float) -> GaitConfig:
        """This config with the robot's stride and step-height cap filled in where unset."""
        flow = self.flow
        if flow.max_height is None:
            flow = replace(flow, max_height=max_step_height)
        stride = stride_length if self.stride_length is None else self.stride_length
        return replace(self, stride_length=stride, flow=flow)

    def step_duration(self, foot_speed: float) -> float:
        """Swing duration for feet moving at ``foot_speed`` over the ground [s].

        The stride is kept where the step duration allows and shortened for slow walks.
        """
        if foot_speed <= 1e-9:
            return self.rest_step_duration
        n = len(self.groups)
        return min(
            max(self.stride / (n * foot_speed), self.min_step_duration), self.max_step_duration
        )
