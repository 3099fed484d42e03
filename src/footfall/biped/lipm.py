"""Linear Inverted Pendulum walking pattern with modified foot placement.

The humanoid dissertation §4.1 (eqs. 1-26), after Kajita et al.: the centre of mass (COM)
moves at constant height ``z_c`` like an inverted pendulum over the support foot,
``x'' = (g / z_c) (x - p)``, solved in closed form with ``T_c = sqrt(z_c / g)``,
``C = cosh(T_sup / T_c)``, ``S = sinh(T_sup / T_c)``. Walk parameters ``(s_x, s_y, s_theta)``
give each step's walk primitive (eqs. 13, 25) and its terminal velocity (eqs. 14, 26); the
foot placement is then modified (eq. 24) to minimise
``a (x_d - x_f)^2 + b (v_d - v_f)^2`` so the pattern is continuous in position and velocity.

Erratum: the printed second line of eq. 7 is the velocity,
``x'(t) = (x(0) / T_c) sinh(t / T_c) + x'(0) cosh(t / T_c)``.

Frames: the ground plane, x forward and y left of the walk's start; ``s_theta`` is the
heading of the step's foot [rad].
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from footfall.checks import require_non_negative, require_positive
from footfall.errors import ConfigError

GRAVITY = 9.81  # [m/s^2]


@dataclass(frozen=True)
class LipmConfig:
    """Pendulum and pattern settings (defaults: Kajita's textbook example).

    Attributes:
        com_height: ``z_c``, height of the constraint plane [m].
        support_time: ``T_sup``, duration of each single-support phase [s].
        position_weight: ``a`` of eq. 22.
        velocity_weight: ``b`` of eq. 22.
        dt: Sampling period of the COM trajectory [s].
    """

    com_height: float = 0.8
    support_time: float = 0.8
    position_weight: float = 10.0
    velocity_weight: float = 1.0
    dt: float = 0.01

    def __post_init__(self) -> None:
        require_positive(
            "LIPM", com_height=self.com_height, support_time=self.support_time, dt=self.dt
        )
        require_non_negative(
            "LIPM", position_weight=self.position_weight, velocity_weight=self.velocity_weight
        )
        if self.position_weight + self.velocity_weight == 0:
            raise ConfigError("the weights a and b must not both be zero")

    @property
    def time_constant(self) -> float:
        """``T_c = sqrt(z_c / g)`` [s] (eq. 9)."""
        return math.sqrt(self.com_height / GRAVITY)

    @property
    def c_s(self) -> tuple[float, float]:
        """``(C, S)`` of eq. 12."""
        r = self.support_time / self.time_constant
        return math.cosh(r), math.sinh(r)


@dataclass(frozen=True)
class WalkParameter:
    """One step's walk parameter (Table 9).

    Attributes:
        length: ``s_x``, step length along the walk [m].
        width: ``s_y``, step width between the feet [m].
        heading: ``s_theta``, heading of the foot placed in this step [rad].
    """

    length: float
    width: float
    heading: float = 0.0


def _rotation(angle: float) -> npt.NDArray[np.float64]:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s], [s, c]])


def walk_primitive(
    step: WalkParameter, n: int, config: LipmConfig, side: int = 1
) -> tuple[npt.NDArray, npt.NDArray]:
    """Terminal position and velocity of the n-th walk primitive (eqs. 13-14, 25-26).

    Args:
        step: The walk parameter of step ``n + 1``.
        n: Step index.
        config: Pendulum settings.
        side: +1 when step 1 goes to the left of step 0 (Kajita's convention), -1 when it
            goes to the right.

    Returns:
        ``(x_bar, v_bar)``, each shape (2,): in the ground frame [m], [m/s].
    """
    c, s = config.c_s
    tc = config.time_constant
    bar = np.array([0.5 * step.length, side * (-1) ** n * 0.5 * step.width])
    velocity = np.array([(c + 1.0) / (tc * s) * bar[0], (c - 1.0) / (tc * s) * bar[1]])
    r = _rotation(step.heading)
    return r @ bar, r @ velocity


def pendulum_state(
    x0: npt.ArrayLike, v0: npt.ArrayLike, foot: npt.ArrayLike, t: npt.ArrayLike, tc: float
):
    """COM position and velocity ``t`` seconds after ``(x0, v0)`` over a foot (eqs. 16-17).

    Returns:
        Positions and velocities, each shape (len(t), 2).
    """
    tt = np.asarray(t, dtype=np.float64)[:, None]
    x0, v0, p = (np.asarray(a, dtype=np.float64) for a in (x0, v0, foot))
    ch, sh = np.cosh(tt / tc), np.sinh(tt / tc)
    return (x0 - p) * ch + tc * v0 * sh + p, (x0 - p) / tc * sh + v0 * ch


@dataclass(frozen=True)
class LipmPattern:
    """A COM pattern and its footsteps.

    Attributes:
        time: Sample times, shape (k,) [s].
        com: COM positions, shape (k, 2) [m].
        com_velocity: COM velocities, shape (k, 2) [m/s].
        footsteps: Footsteps from the walk parameters, shape (m, 2) [m].
        modified_footsteps: Footsteps after the modification of eq. 24, shape (m, 2) [m].
        headings: Foot headings, shape (m,) [rad].
    """

    time: npt.NDArray[np.float64]
    com: npt.NDArray[np.float64]
    com_velocity: npt.NDArray[np.float64]
    footsteps: npt.NDArray[np.float64]
    modified_footsteps: npt.NDArray[np.float64]
    headings: npt.NDArray[np.float64]


def lipm_pattern(
    steps: Sequence[WalkParameter],
    config: LipmConfig | None = None,
    initial_com: npt.ArrayLike = (0.0, 0.0),
    initial_velocity: npt.ArrayLike = (0.0, 0.0),
    first_foot: npt.ArrayLike = (0.0, 0.0),
    first_step_left: bool = True,
    footsteps: npt.ArrayLike | None = None,
) -> LipmPattern:
    """The COM trajectory for a sequence of walk parameters (Kajita's algorithm).

    Step 0's parameter goes with the first support foot, at ``first_foot``; each later
    step ``n`` puts foot ``n`` at ``p(n-1) + R(s_theta) [s_x, -(-1)^n s_y]`` (eq. 96), or
    its mirror image when the first step goes to the right. The final parameter is
    usually ``s_x = 0``, bringing the feet side by side.

    Args:
        steps: Walk parameters, one per support phase plus the closing one.
        config: Pendulum settings.
        initial_com: COM position at the start, shape (2,) [m].
        initial_velocity: COM velocity at the start, shape (2,) [m/s].
        first_foot: Position of the first support foot, shape (2,) [m].
        first_step_left: Whether step 1 goes to the left of the first support foot.
        footsteps: Footstep positions, shape (len(steps), 2) [m], to use instead of eq. 96
            (for footsteps laid out around a COM path, eqs. 97-98).

    Returns:
        The pattern: COM samples every ``dt`` and the nominal and modified footsteps.

    Raises:
        ConfigError: With fewer than two walk parameters.
    """
    c = config or LipmConfig()
    if len(steps) < 2:
        raise ConfigError("a walking pattern needs at least two walk parameters")
    cc, ss = c.c_s
    tc = c.time_constant
    a, b = c.position_weight, c.velocity_weight
    d = a * (cc - 1.0) ** 2 + b * (ss / tc) ** 2
    x = np.asarray(initial_com, dtype=np.float64)
    v = np.asarray(initial_velocity, dtype=np.float64)
    side = 1 if first_step_left else -1
    given = None if footsteps is None else np.asarray(footsteps, dtype=np.float64)
    if given is not None and given.shape != (len(steps), 2):
        raise ConfigError(f"footsteps must have shape ({len(steps)}, 2), got {given.shape}")
    foot = (np.asarray(first_foot, dtype=np.float64) if given is None else given[0]).copy()
    modified = foot.copy()
    nominal, placed, headings = [foot.copy()], [modified.copy()], [steps[0].heading]
    times, coms, velocities = [], [], []
    samples = max(1, round(c.support_time / c.dt))
    local = np.arange(samples) * (c.support_time / samples)
    for n in range(len(steps) - 1):
        positions, speeds = pendulum_state(x, v, modified, local, tc)
        times.append(n * c.support_time + local)
        coms.append(positions)
        velocities.append(speeds)
        (x,), (v,) = pendulum_state(x, v, modified, [c.support_time], tc)
        # Next footstep from the walk parameters, and the walk primitive it begins (eqs. 13-14).
        step = steps[n + 1]
        k = n + 1
        if given is None:
            foot = foot + _rotation(step.heading) @ np.array(
                [step.length, -side * ((-1) ** k) * step.width]
            )
        else:
            foot = given[k].copy()
        nominal.append(foot.copy())
        headings.append(step.heading)
        following = steps[k + 1] if k + 1 < len(steps) else WalkParameter(0.0, 0.0, step.heading)
        bar, v_bar = walk_primitive(following, k, c, side)
        target_x, target_v = foot + bar, v_bar
        # Modified foot placement (eq. 24), per axis.
        modified = -a * (cc - 1.0) / d * (target_x - cc * x - tc * ss * v) - b * ss / (tc * d) * (
            target_v - ss / tc * x - cc * v
        )
        placed.append(modified.copy())
    positions, speeds = pendulum_state(x, v, modified, local[:1], tc)
    times.append(np.array([(len(steps) - 1) * c.support_time]))
    coms.append(positions)
    velocities.append(speeds)
    return LipmPattern(
        time=np.concatenate(times),
        com=np.concatenate(coms),
        com_velocity=np.concatenate(velocities),
        footsteps=np.array(nominal),
        modified_footsteps=np.array(placed),
        headings=np.array(headings),
    )
