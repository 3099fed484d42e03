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
from functools import cached_property

import numpy as np
import numpy.typing as npt

from footfall.checks import require_positive
from footfall.errors import ConfigError
from footfall.motion.flow_swing import FlowConfig
from footfall.motion.swing import SWINGS
from footfall.registry import Registry
from footfall.robot.scale import robot_scale
from footfall.robot.spec import HexapodSpec

# A walk's default body speed [m/s], lowered to 3/4 of the gait's top speed where that is less.
DEFAULT_SPEED_MPS = 0.10
# A supporting foot may trail this far beyond its stroke on the default robot [m].
STROKE_MARGIN_M = 0.04


@dataclass(frozen=True)
class Gait:
    """A gait: which legs swing together, in stepping order.

    Attributes:
        name: The name ``--gait`` takes.
        groups: Swing groups in stepping order; every leg (0-5) in exactly one.
        by_sextant: The alternating tripod's rule (thesis eqs. 5.15-5.16): the first swing
            set is the active sextant's leg with every second leg from it, and the legs
            that swing in a step support in the next. Only for groups {0, 2, 4}, {1, 3, 5}.
    """

    name: str
    groups: tuple[tuple[int, ...], ...]
    by_sextant: bool = False

    def __post_init__(self) -> None:
        legs = sorted(leg for group in self.groups for leg in group)
        if legs != list(range(6)) or not all(self.groups):
            raise ConfigError(
                f"gait {self.name!r}: every leg 0-5 swings in exactly one non-empty group, "
                f"got {self.groups}"
            )
        if self.by_sextant and {frozenset(g) for g in self.groups} != {
            frozenset((0, 2, 4)),
            frozenset((1, 3, 5)),
        }:
            raise ConfigError(f"gait {self.name!r}: the sextant rule is the alternating tripod's")

    @property
    def duty_factor(self) -> float:
        """Fraction of the cycle each leg supports: 1 - 1 / groups."""
        return 1.0 - 1.0 / len(self.groups)


GAITS: Registry[Gait] = Registry("gait")


def register_gait(gait: Gait) -> Gait:
    """Register a gait under its name."""
    GAITS.register(gait.name, gait)
    return gait


# Thesis Fig. 5.4. Tripod: legs i, i+2, i+4 (eq. 5.15). Ripple: each side steps back to
# front, the sides one step apart, so four feet always support in a quadrilateral. Wave:
# one leg at a time, back to front on the left, then on the right.
register_gait(Gait("tripod", ((0, 2, 4), (1, 3, 5)), by_sextant=True))
register_gait(Gait("ripple", ((2, 5), (1, 3), (0, 4))))
register_gait(Gait("wave", ((2,), (1,), (0,), (3,), (4,), (5,))))


def swing_groups(kind: str) -> tuple[tuple[int, ...], ...]:
    """The swing groups of the gait named ``kind``, in stepping order."""
    return GAITS.get(kind).groups


def duty_factor(kind: str) -> float:
    """Fraction of the cycle each leg supports: 1/2 tripod, 2/3 ripple, 5/6 wave."""
    return GAITS.get(kind).duty_factor


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
        kind: Which gait, a name in ``GAITS``.
        stride_length: Longest distance a foot travels over the ground in one swing [m]; None
            takes the robot's (``HexapodSpec.stride_length``).
        min_step_duration: Shortest swing [s]; with the stride it caps the speed.
        max_step_duration: Longest swing while walking [s]; slower walks shorten the stride.
        rest_step_duration: Swing duration when stepping back to the rest stance [s].
        stroke_margin: How far beyond its nominal stroke a supporting foot may trail before
            the body slows down to wait for it [m]; None takes 4 cm on the default robot,
            scaled to the robot's stride (:meth:`for_robot`).
        rest_tolerance: A foot this close to its rest position counts as at rest [m].
        retarget_tolerance: A swing target that moves more than this is re-planned [m].
        acceleration_limit: Body acceleration limit [m/s^2].
        yaw_acceleration_limit: Body yaw acceleration limit [rad/s^2].
        height_rate_limit: Speed of body height changes [m/s].
        swing: The swing trajectory, a name in ``SWINGS``: ``"flow"`` (thesis §5.4.2) or
            ``"polynomial"`` (the §5.4.1 baseline).
        flow: Flow-function parameters.
        polynomial_apex: Apex of the polynomial arc above the higher end [m]; None takes
            the robot's ``max_step_height``.
        incline_limit: Steepest the body inclines along a slope or a flight of stairs
            [rad]; 0 keeps it level (:mod:`footfall.motion.incline`).
        incline_rate: Speed of the body's incline [rad/s].
        incline_level_share: Share of the legs' height range the rise between the front
            and the hind feet may take before the body inclines.
    """

    kind: str = "tripod"
    stride_length: float | None = None
    min_step_duration: float = 0.3
    max_step_duration: float = 1.0
    rest_step_duration: float = 0.6
    stroke_margin: float | None = None
    rest_tolerance: float = 0.005
    retarget_tolerance: float = 0.002
    acceleration_limit: float = 0.5
    yaw_acceleration_limit: float = 2.0
    height_rate_limit: float = 0.07
    swing: str = "flow"
    flow: FlowConfig = field(default_factory=FlowConfig)
    polynomial_apex: float | None = None
    incline_limit: float = math.radians(20.0)
    incline_rate: float = 0.25
    incline_level_share: float = 0.4

    def __post_init__(self) -> None:
        GAITS.check(self.kind)
        SWINGS.check(self.swing)
        if not 0 < self.min_step_duration <= self.max_step_duration:
            raise ConfigError("need 0 < min_step_duration <= max_step_duration")
        if self.stride_length is not None:
            require_positive("gait", stride_length=self.stride_length)
        require_positive(
            "gait",
            rest_step_duration=self.rest_step_duration,
            acceleration_limit=self.acceleration_limit,
            yaw_acceleration_limit=self.yaw_acceleration_limit,
            height_rate_limit=self.height_rate_limit,
            incline_rate=self.incline_rate,
            incline_level_share=self.incline_level_share,
        )
        if not 0.0 <= self.incline_limit < 0.5 * math.pi:
            raise ConfigError("incline_limit must lie in [0, pi/2) rad")

    @cached_property
    def gait(self) -> Gait:
        """The gait ``kind`` names (looked up once: the scheduler asks every tick)."""
        return GAITS.get(self.kind)

    @property
    def groups(self) -> tuple[tuple[int, ...], ...]:
        """Swing groups in stepping order."""
        return self.gait.groups

    @property
    def duty_factor(self) -> float:
        """Support fraction of each leg's cycle."""
        return self.gait.duty_factor

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

    def for_robot(self, spec: HexapodSpec) -> GaitConfig:
        """This config with the robot's own lengths filled in where unset.

        The stride, the flow swing's height cap and the polynomial arc's apex are the
        robot's; the stroke margin is the default robot's scaled to the robot's stride.
        """
        flow = self.flow
        if flow.max_height is None:
            flow = replace(flow, max_height=spec.max_step_height)
        margin = self.stroke_margin
        if margin is None:
            margin = STROKE_MARGIN_M * robot_scale(spec).stride
        return replace(
            self,
            stride_length=spec.stride_length if self.stride_length is None else self.stride_length,
            flow=flow,
            stroke_margin=margin,
            polynomial_apex=spec.max_step_height
            if self.polynomial_apex is None
            else self.polynomial_apex,
        )

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
