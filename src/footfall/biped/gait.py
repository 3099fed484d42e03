"""A biped's gait from its planned footsteps: ZMP reference, COM pattern, swing feet.

The footsteps come from the planner (§6.3.3) and the step time from the Linear Inverted
Pendulum settings (§4.1, ``T_sup``). The LIPM pattern itself assumes a point foot, an
instantaneous change of support and a walk that starts over the first support foot: its
modified first footstep lands almost under the standing robot's centre, where a real foot
cannot go. The executed pattern therefore uses the cart-table model the dissertation names
for stabilisation (§4.3, Fig. 38) in Kajita's preview-control form: the zero moment point
(ZMP) stays at the middle of the support foot during each single-support phase and moves
to the next foot during a short double support; the COM follows from the table-cart
equation ``p = x - (z_c / g) x''`` by preview control of its jerk. With no double support
and the feet of the LIPM pattern this gives back the LIPM's motion; with it the robot can
start from standing on both feet and end there.

Each step lasts ``T_sup``: single support (the swing foot lifts, carries and sets down
flat along a minimum-jerk path with a raised-cosine lift), then double support.

Frames: the ground (world) frame, z up; foot positions are sole centres, headings [rad].
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
import numpy.typing as npt
import scipy.linalg

from footfall.biped.footsteps import Footsteps
from footfall.biped.lipm import GRAVITY, WalkParameter
from footfall.checks import require_non_negative, require_positive
from footfall.errors import ConfigError

SUPPORT_DOUBLE, SUPPORT_LEFT, SUPPORT_RIGHT = 0, 1, 2


@dataclass(frozen=True)
class GaitConfig:
    """Gait timing and shape.

    Attributes:
        step_time: Duration of one step, ``T_sup`` of the LIPM pattern [s].
        double_support: Share of each step with both feet down.
        step_height: Swing foot apex above the ground [m].
        hold_time: Standing still at the start, so the preview starts from rest [s].
        start_time: Shift of the COM onto the first support foot before the first step [s].
        end_time: Settling on both feet after the last step [s].
        preview_time: How far the preview controller looks ahead [s].
        dt: Sampling period of the pattern [s].
    """

    step_time: float = 0.8
    double_support: float = 0.3
    step_height: float = 0.05
    hold_time: float = 0.8
    start_time: float = 1.0
    end_time: float = 1.5
    preview_time: float = 1.6
    dt: float = 0.005

    def __post_init__(self) -> None:
        require_positive(
            "biped gait",
            step_time=self.step_time,
            dt=self.dt,
            start_time=self.start_time,
            end_time=self.end_time,
            preview_time=self.preview_time,
        )
        if not 0 <= self.double_support < 1:
            raise ConfigError(f"double support must lie in [0, 1), got {self.double_support}")
        require_non_negative("biped gait", step_height=self.step_height)


@dataclass(frozen=True)
class GaitPattern:
    """References sampled every ``dt``.

    Attributes:
        time: Shape (k,) [s].
        zmp: ZMP reference, shape (k, 2) [m].
        com: COM reference (ground projection), shape (k, 2) [m].
        com_height: ``z_c`` of the cart-table model [m].
        feet: Per side, sole centre positions, shape (k, 3) [m].
        foot_yaw: Per side, headings, shape (k,) [rad].
        swing: Per side, progress of the foot's swing (0 to 1, minimum-jerk), NaN while it
            stands.
        support: Per sample, ``SUPPORT_DOUBLE``, ``SUPPORT_LEFT`` or ``SUPPORT_RIGHT``.
        footholds: Planned footholds in the order they are stepped on, shape (m, 2) [m].
        foothold_sides: Side of each foothold.
        landing_time: When each foothold is loaded (its step's double support starts) [s].
    """

    time: npt.NDArray[np.float64]
    zmp: npt.NDArray[np.float64]
    com: npt.NDArray[np.float64]
    com_height: float
    feet: dict[str, npt.NDArray[np.float64]]
    foot_yaw: dict[str, npt.NDArray[np.float64]]
    swing: dict[str, npt.NDArray[np.float64]]
    support: npt.NDArray[np.int8]
    footholds: npt.NDArray[np.float64]
    foothold_sides: tuple[str, ...]
    landing_time: npt.NDArray[np.float64]

    @property
    def duration(self) -> float:
        """Length of the pattern [s]."""
        return float(self.time[-1])

    def index(self, t: float) -> int:
        """The sample at or just before ``t``."""
        return int(np.clip(np.searchsorted(self.time, t, side="right") - 1, 0, len(self.time) - 1))


def minimum_jerk(tau: npt.ArrayLike) -> npt.NDArray[np.float64]:
    """``10 t^3 - 15 t^4 + 6 t^5`` on [0, 1]: zero velocity and acceleration at both ends."""
    t = np.clip(np.asarray(tau, dtype=np.float64), 0.0, 1.0)
    return t**3 * (10.0 - 15.0 * t + 6.0 * t * t)


def preview_gains(
    com_height: float, dt: float, horizon: int, q_e: float = 1.0, r: float = 1e-6
) -> tuple[float, npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """Preview-control gains of the cart-table model (Kajita 2003, after Katayama).

    State ``(x, x', x'')``, input the jerk, output the ZMP ``x - (z_c / g) x''``; the cost
    sums ``q_e`` times the squared ZMP error and ``r`` times the squared jerk.

    Returns:
        ``(G_i, G_x, G_d)``: integral gain, state gain shape (3,), preview gains shape
        (horizon,).
    """
    a = np.array([[1.0, dt, dt * dt / 2], [0.0, 1.0, dt], [0.0, 0.0, 1.0]])
    b = np.array([[dt**3 / 6], [dt * dt / 2], [dt]])
    c = np.array([[1.0, 0.0, -com_height / GRAVITY]])
    a_t = np.block([[np.ones((1, 1)), c @ a], [np.zeros((3, 1)), a]])
    b_t = np.vstack([c @ b, b])
    i_t = np.array([[1.0], [0.0], [0.0], [0.0]])
    f_t = np.vstack([c @ a, a])
    q = np.zeros((4, 4))
    q[0, 0] = q_e
    p = scipy.linalg.solve_discrete_are(a_t, b_t, q, np.array([[r]]))
    inv = 1.0 / (r + (b_t.T @ p @ b_t).item())
    g_i = inv * (b_t.T @ p @ i_t).item()
    g_x = (inv * (b_t.T @ p @ f_t)).ravel()
    a_c = a_t - inv * b_t @ (b_t.T @ p @ a_t)
    x = -a_c.T @ p @ i_t
    g_d = np.empty(horizon)
    g_d[0] = -g_i
    for j in range(1, horizon):
        g_d[j] = inv * (b_t.T @ x).item()
        x = a_c.T @ x
    return g_i, g_x, g_d


def preview_com(
    zmp: npt.NDArray[np.float64], com_height: float, dt: float, preview_time: float
) -> npt.NDArray[np.float64]:
    """The COM trajectory whose cart-table ZMP tracks ``zmp`` (shape (k, 2)) [m].

    The reference is held at its last value beyond its end, and the COM starts at rest
    over the first ZMP sample.
    """
    return _preview(zmp, com_height, dt, preview_time)[0]


def _preview(
    zmp: npt.NDArray[np.float64],
    com_height: float,
    dt: float,
    preview_time: float,
    state: npt.NDArray[np.float64] | None = None,
    samples: int | None = None,
) -> tuple[npt.NDArray[np.float64], npt.NDArray[np.float64]]:
    """Preview control over the first ``samples`` samples of ``zmp`` (all by default).

    Args:
        zmp: ZMP reference, shape (k, 2) [m], held at its last value beyond its end.
        com_height: ``z_c`` [m].
        dt: Sampling period [s].
        preview_time: How far the controller looks ahead [s].
        samples: How many samples to run (all when None).
        state: Per axis ``(x, x', x'', summed ZMP error)`` at the first sample, shape
            (2, 4); None: at rest over the first ZMP sample.

    Returns:
        The COM, shape (samples, 2) [m], and the state after the last sample.
    """
    horizon = max(2, round(preview_time / dt))
    g_i, g_x, g_d = preview_gains(com_height, dt, horizon)
    a = np.array([[1.0, dt, dt * dt / 2], [0.0, 1.0, dt], [0.0, 0.0, 1.0]])
    b = np.array([dt**3 / 6, dt * dt / 2, dt])
    c = np.array([1.0, 0.0, -com_height / GRAVITY])
    k = len(zmp) if samples is None else samples
    padded = np.vstack([zmp, np.repeat(zmp[-1:], horizon, axis=0)])
    out = np.empty((k, 2))
    after = np.empty((2, 4))
    for axis in range(2):
        if state is None:
            x, error = np.array([zmp[0, axis], 0.0, 0.0]), 0.0
        else:
            x, error = np.array(state[axis, :3], dtype=np.float64), float(state[axis, 3])
        ref = padded[:, axis]
        for i in range(k):
            out[i, axis] = x[0]
            error += float(c @ x) - ref[i]
            u = -g_i * error - g_x @ x - g_d @ ref[i + 1 : i + 1 + horizon]
            x = a @ x + b * u
        after[axis] = (*x, error)
    return out, after


def gait_pattern(
    footsteps: Footsteps,
    initial_feet: dict[str, tuple[float, float, float]],
    com_height: float,
    config: GaitConfig | None = None,
) -> GaitPattern:
    """The gait that walks a plan's footsteps from a standing start.

    Args:
        footsteps: Planned footsteps; the first is the first support foot, standing.
        initial_feet: Per side, the standing foot ``(x, y, heading)`` [m], [rad].
        com_height: Height of the COM over the ground, ``z_c`` [m].
        config: Timing and shape.

    Raises:
        ConfigError: With fewer than two footsteps or a missing side.
    """
    c = config or GaitConfig()
    if len(footsteps.positions) < 2:
        raise ConfigError("a gait needs at least two footsteps")
    if set(initial_feet) != {"left", "right"}:
        raise ConfigError("initial_feet needs a 'left' and a 'right' foot")
    n_steps = len(footsteps.positions) - 1
    begin = c.hold_time + c.start_time  # the first step lifts off here
    total = begin + n_steps * c.step_time + c.end_time
    time = np.arange(0.0, total + 0.5 * c.dt, c.dt)
    k = len(time)
    single = (1.0 - c.double_support) * c.step_time
    pos = {
        s: np.tile(np.array(initial_feet[s][:2], dtype=np.float64), (k, 1)) for s in initial_feet
    }
    lift = {s: np.zeros(k) for s in initial_feet}
    yaw = {s: np.full(k, float(initial_feet[s][2])) for s in initial_feet}
    progress = {s: np.full(k, np.nan) for s in initial_feet}
    support = np.full(k, SUPPORT_DOUBLE, dtype=np.int8)
    zmp = np.full((k, 2), np.nan)
    where = {s: (np.array(initial_feet[s][:2], dtype=np.float64), float(initial_feet[s][2]))
             for s in initial_feet}  # fmt: skip
    mid = 0.5 * (where["left"][0] + where["right"][0])
    first = footsteps.positions[0]
    # Start: shift the ZMP from between the feet onto the first support foot.
    win = time <= begin
    zmp[win] = mid + minimum_jerk((time[win] - c.hold_time) / c.start_time)[:, None] * (first - mid)
    landing = [0.0]
    # Step n runs from bounds[n - 1] to bounds[n]; every sample falls in exactly one window.
    bounds = begin + np.arange(n_steps + 1) * c.step_time
    for n in range(1, n_steps + 1):
        t0 = float(bounds[n - 1])
        side = footsteps.sides[n]
        stance = footsteps.positions[n - 1]
        target = footsteps.positions[n]
        (p0, h0) = where[side]
        h1 = float(footsteps.headings[n])
        swing = (time > t0) & (time <= t0 + single)
        tau = (time[swing] - t0) / single
        s = minimum_jerk(tau)
        pos[side][swing] = p0 + s[:, None] * (target - p0)
        progress[side][swing] = s
        yaw[side][swing] = h0 + s * math.atan2(math.sin(h1 - h0), math.cos(h1 - h0))
        lift[side][swing] = c.step_height * 0.5 * (1.0 - np.cos(2 * math.pi * tau))
        support[swing] = SUPPORT_RIGHT if side == "left" else SUPPORT_LEFT
        zmp[swing] = stance
        after = time > t0 + single
        pos[side][after] = target
        yaw[side][after] = h1
        where[side] = (np.asarray(target, dtype=np.float64), h1)
        double = after & (time <= bounds[n])
        duration = c.step_time - single
        if n < n_steps:
            goal = target
        else:  # the closing step: settle between the feet
            goal = 0.5 * (footsteps.positions[n - 1] + target)
        if duration > 0:
            tau = (time[double] - t0 - single) / duration
            zmp[double] = stance + minimum_jerk(tau)[:, None] * (goal - stance)
        landing.append(t0 + single)
    end = time > bounds[-1]
    zmp[end] = 0.5 * (footsteps.positions[-2] + footsteps.positions[-1])
    if not np.all(np.isfinite(zmp)):
        raise ConfigError("the ZMP reference has samples outside every phase (a bug)")
    com = preview_com(zmp, com_height, c.dt, c.preview_time)
    feet = {s: np.column_stack([pos[s], lift[s]]) for s in pos}
    return GaitPattern(
        time=time,
        zmp=zmp,
        com=com,
        com_height=com_height,
        feet=feet,
        foot_yaw=yaw,
        swing=progress,
        support=support,
        footholds=np.asarray(footsteps.positions, dtype=np.float64),
        foothold_sides=tuple(footsteps.sides),
        landing_time=np.array(landing),
    )


def step_at(pattern_time: float, config: GaitConfig) -> int:
    """The step under way at ``pattern_time`` (1 for the first, also before it lifts)."""
    begin = config.hold_time + config.start_time
    return max(1, math.ceil((pattern_time - begin) / config.step_time - 1e-9))


def stop_after_step(
    pattern: GaitPattern,
    footsteps: Footsteps,
    pattern_time: float,
    config: GaitConfig | None = None,
) -> tuple[GaitPattern, Footsteps]:
    """End the walk with the step under way at ``pattern_time``, the feet side by side.

    The step under way finishes on its planned foothold; one more step brings the other
    foot beside it (the plan's step width apart); the robot settles on both feet. The
    ZMP reference is the old one up to the end of the step under way, and the COM
    continues from its state at ``pattern_time`` (preview control carried on from there),
    so the references do not jump when the walker switches patterns.

    Args:
        pattern: The pattern being walked (made by :func:`gait_pattern` with ``config``).
        footsteps: Its footsteps.
        pattern_time: Time into the pattern [s].
        config: The timing it was made with.

    Returns:
        The pattern to walk from ``pattern_time`` on and its footsteps; the same ones when
        the walk already ends within a step.
    """
    c = config or GaitConfig()
    n = step_at(pattern_time, c)
    if n >= len(footsteps.positions) - 2:
        return pattern, footsteps
    side = footsteps.sides[n]
    other = "right" if side == "left" else "left"
    heading = float(footsteps.headings[n])
    width = footsteps.parameters[0].width if footsteps.parameters else 0.2
    across = np.array([-math.sin(heading), math.cos(heading)])
    closing = footsteps.positions[n] + (width if other == "left" else -width) * across
    stopped = Footsteps(
        positions=np.vstack([footsteps.positions[: n + 1], closing]),
        headings=np.append(footsteps.headings[: n + 1], heading),
        sides=(*footsteps.sides[: n + 1], other),
        parameters=(*footsteps.parameters[: n + 1], WalkParameter(0.0, width, heading)),
    )
    feet = {s: (*pattern.feet[s][0][:2], float(pattern.foot_yaw[s][0])) for s in pattern.feet}
    new = gait_pattern(stopped, feet, pattern.com_height, c)
    i = pattern.index(pattern_time)
    _, state = _preview(pattern.zmp, pattern.com_height, c.dt, c.preview_time, samples=i)
    tail, _ = _preview(new.zmp[i:], pattern.com_height, c.dt, c.preview_time, state=state)
    return replace(new, com=np.vstack([pattern.com[:i], tail])), stopped
