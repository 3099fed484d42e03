"""Swing-foot trajectories: the flow function (thesis §5.4.2) and the polynomial arc (§5.4.1).

Both implement :class:`SwingTrajectory`: a path in the world frame from lift-off to
touchdown, sampled by time since lift-off, whose target may be moved at any tick.

The flow function (eqs. 5.23-5.26, read as in the errata of ``SPEC.md``) is a direction
field over ``(h, v)``: the horizontal distance still to go and the height above the target.
At every point the foot follows the tangent of the parabola ``v' = a h'^2 + b h'`` through the
target ``(0, 0)`` and the point, with ``a = -|Ch / h| - |S(v)|`` and
``S(v) = 0.515 (v - q) / (1 + |v - q|) - 0.505``. Multiplying the tangent by ``h`` removes the
``1/h`` singularity: the (unnormalised) direction is ``(-h, Ch h + |S(v)| h^2 - v)``.
``S`` and ``q`` carry a length unit: the thesis evaluates them in millimetres (q = 14 is a
14 mm rise; with Ch = 2 the apex is about one stride, as its §8.1 says), so lengths are
scaled by ``length_unit`` before the field is evaluated.

Because the field depends only on where the foot is, re-targeting mid-swing integrates it
again from the foot's current point: a foot already above the new target does not rise a
second time (Figs. 5.18-5.19), unlike a polynomial restarted from the ground (Fig. 5.12).

Both trajectories, the flow field they integrate and the helpers that lift a path over the
mapped terrain and cap it under the leg's reach are kept in one module: they share the
polyline sampling and re-targeting, and are read together against §5.4.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

import numpy as np
import numpy.typing as npt

from footfall.errors import ConfigError


def minimum_jerk(tau: float) -> float:
    """Minimum-jerk progress ``s`` in [0, 1] at normalised time ``tau`` in [0, 1].

    Velocity and acceleration are zero at both ends.
    """
    t = min(max(tau, 0.0), 1.0)
    return t * t * t * (10.0 + t * (-15.0 + 6.0 * t))


# A swing re-targeted in its last RETARGET_MIN_S gets that long, plus its remaining way
# at RETARGET_SPEED_MPS, before it lands, when the way is longer than RETARGET_WAIT_M: the
# step waits for it rather than dragging a foot over the ground to a target it could not
# reach in the air; a shorter way is carried in the time left [s], [m/s], [m].
RETARGET_MIN_S = 0.15
RETARGET_SPEED_MPS = 0.6
RETARGET_WAIT_M = 0.03


def time_to_land(ways_m: list[float], time_left_s: float) -> float | None:
    """How long a step must still last for late re-targeted feet to land [s].

    Args:
        ways_m: How far each re-targeted foot is from its new target [m].
        time_left_s: The time the step has left [s].

    Returns:
        The time from now, or None when the time left will do.
    """
    if time_left_s >= RETARGET_MIN_S:
        return None
    wait = max(
        (RETARGET_MIN_S + d / RETARGET_SPEED_MPS for d in ways_m if d > RETARGET_WAIT_M),
        default=0.0,
    )
    return wait if wait > time_left_s else None


class SwingTrajectory(Protocol):
    """A swing path in the world frame, re-targetable at any time."""

    duration: float

    @property
    def target(self) -> npt.NDArray[np.float64]:
        """Current touchdown target, shape (3,) [m]."""
        ...

    def position(self, t: float) -> npt.NDArray[np.float64]:
        """Foot position at ``t`` seconds after lift-off, shape (3,) [m]."""
        ...

    def retarget(self, target: npt.ArrayLike, t: float, duration: float | None = None) -> None:
        """Move the touchdown target at time ``t`` [s]; the path stays continuous.

        With ``duration`` the swing also ends at that time after lift-off [s] (a late
        re-target that needs longer than the swing has left).
        """
        ...

    @property
    def start(self) -> npt.NDArray[np.float64]:
        """Lift-off position, shape (3,) [m]."""
        ...

    def transform(
        self, rotation: npt.NDArray[np.float64], translation: npt.NDArray[np.float64]
    ) -> None:
        """Move the whole swing by a planar rigid transform (2x2 rotation, 2-vector) [m]."""
        ...


# A function giving the terrain height under horizontal points, shape (n, 2) -> (n,) [m].
TerrainFunction = Callable[[npt.NDArray[np.float64]], npt.NDArray[np.float64]]


@dataclass(frozen=True)
class FlowConfig:
    """Flow-function parameters (thesis §5.4.2; §8.1 walks with Ch = 2.0, q = 14.0).

    Attributes:
        step_height: ``Ch``, shapes the arc; a larger value gives a higher apex.
        rise: ``q``, height above the target where the vertical rise turns into the arc,
            in ``length_unit``.
        length_unit: The length unit the field is evaluated in [m] (thesis: millimetres).
        resolution: Integration step along the path [m].
        max_height: Cap on the apex above the higher end of the swing [m], or None. A leg's
            workspace limits how high its foot can lift; above the cap the path's rise over
            the straight line between its ends is scaled down, keeping its shape.
    """

    step_height: float = 2.0
    rise: float = 14.0
    length_unit: float = 0.001
    resolution: float = 0.002
    max_height: float | None = None

    def __post_init__(self) -> None:
        if self.max_height is not None and self.max_height <= 0:
            raise ConfigError(f"flow max_height must be positive or None, got {self.max_height}")
        if self.step_height < 0:
            raise ConfigError(f"flow step_height (Ch) must be >= 0, got {self.step_height}")
        if self.length_unit <= 0 or self.resolution <= 0:
            raise ConfigError("flow length_unit and resolution must be positive")


def sigmoid_like(v: float, q: float) -> float:
    """``S(v)`` of thesis eq. 5.26 (errata reading), range about -1.02 .. 0.01."""
    u = v - q
    return 0.515 * u / (1.0 + abs(u)) - 0.505


def flow_direction(h: float, v: float, config: FlowConfig) -> tuple[float, float]:
    """Unit direction ``(dh, dv)`` of the flow field at ``(h, v)`` in metres.

    Args:
        h: Horizontal distance still to go, >= 0 [m].
        v: Height of the foot above the target [m].
        config: Flow parameters.
    """
    unit = config.length_unit
    hs, vs = h / unit, v / unit
    dh = -hs
    dv = config.step_height * hs + abs(sigmoid_like(vs, config.rise)) * hs * hs - vs
    norm = math.hypot(dh, dv)
    if norm == 0.0:
        return 0.0, 0.0
    return dh / norm, dv / norm


def integrate_flow(
    start: npt.ArrayLike,
    target: npt.ArrayLike,
    config: FlowConfig,
    lift_off_height: float | None = None,
) -> npt.NDArray[np.float64]:
    """Follow the flow field from ``start`` to ``target`` (both in the world frame).

    Args:
        start: Shape (3,) [m].
        target: Shape (3,) [m].
        config: Flow parameters.
        lift_off_height: Height the swing left the ground from [m]; ``config.max_height``
            counts from the higher of it and the target. Defaults to the start's height; pass
            it when re-planning from mid-air so the cap does not ride up with the foot.

    Returns:
        The path as a polyline from start to target inclusive, shape (n, 3) [m].
    """
    p0 = np.asarray(start, dtype=np.float64)
    p1 = np.asarray(target, dtype=np.float64)
    delta = p1[:2] - p0[:2]
    h = float(np.hypot(*delta))
    heading = delta / h if h > 1e-12 else np.zeros(2)
    v = float(p0[2] - p1[2])
    ds = config.resolution
    hs = [h]
    vs = [v]
    # Every step shrinks h by a positive fraction and ends in a straight line to the target,
    # so the loop ends; the bound only guards against non-finite input.
    for _ in range(100_000):
        if math.hypot(h, v) <= ds:
            break
        # Midpoint (RK2) step of length ds along the field.
        dh, dv = flow_direction(h, v, config)
        mh, mv = h + 0.5 * ds * dh, v + 0.5 * ds * dv
        dh, dv = flow_direction(max(mh, 0.0), mv, config)
        h, v = max(h + ds * dh, 0.0), v + ds * dv
        hs.append(h)
        vs.append(v)
    hs.append(0.0)
    vs.append(0.0)
    h_arr = np.asarray(hs)
    path = np.empty((h_arr.size, 3))
    path[:, :2] = p1[:2] - h_arr[:, None] * heading
    path[:, 2] = p1[2] + np.asarray(vs)
    if config.max_height is not None:
        base = p0[2] if lift_off_height is None else lift_off_height
        path = cap_height(path, max(base, p1[2]) + config.max_height)
    return path


def cap_height(path: npt.NDArray[np.float64], ceiling: float) -> npt.NDArray[np.float64]:
    """Scale a path's rise over the line joining its ends so that it stays below a ceiling.

    Args:
        path: Polyline, shape (n, 3) [m].
        ceiling: Highest allowed z [m]; a path whose ends are higher keeps its ends and
            runs straight between them.

    Returns:
        The capped path, shape (n, 3) [m]; the input itself when it is low enough.
    """
    top = max(ceiling, path[0, 2], path[-1, 2])
    if path[:, 2].max() <= top:
        return path
    horizontal = np.linalg.norm(path[:, :2] - path[0, :2], axis=1)
    total = horizontal[-1]
    fraction = horizontal / total if total > 1e-12 else np.linspace(0.0, 1.0, len(path))
    base = path[0, 2] + fraction * (path[-1, 2] - path[0, 2])
    excess = path[:, 2] - base
    rising = excess > 1e-12
    scale = float(np.min((top - base[rising]) / excess[rising]))
    capped = path.copy()
    capped[:, 2] = base + np.clip(scale, 0.0, 1.0) * excess
    return capped


def raise_over(
    path: npt.NDArray[np.float64],
    terrain: TerrainFunction,
    clearance: float,
    end_radius: float = 0.03,
) -> npt.NDArray[np.float64]:
    """Lift a path so it clears the terrain under it by ``clearance``.

    This is the draft's collision check of the swing motion.
    The rise of the path over the straight line between its ends is scaled up just enough;
    points within ``end_radius`` horizontally of either end stand over the footholds
    themselves and are not checked.

    Args:
        path: Polyline, shape (n, 3) [m].
        terrain: Terrain height under horizontal points [m].
        clearance: Least height of the path above the terrain [m].
        end_radius: Horizontal radius around the ends left unchecked [m].

    Returns:
        The lifted path (the input itself when it already clears), shape (n, 3) [m].
    """
    start, end = path[0, :2], path[-1, :2]
    far = (np.linalg.norm(path[:, :2] - start, axis=1) > end_radius) & (
        np.linalg.norm(path[:, :2] - end, axis=1) > end_radius
    )
    if not far.any():
        return path
    need = terrain(path[far, :2]) + clearance
    if np.all(path[far, 2] >= need):
        return path
    horizontal = np.linalg.norm(path[:, :2] - start, axis=1)
    total = horizontal[-1]
    fraction = horizontal / total if total > 1e-12 else np.linspace(0.0, 1.0, len(path))
    base = path[0, 2] + fraction * (path[-1, 2] - path[0, 2])
    excess = path[:, 2] - base
    lift = np.maximum(need - base[far], 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        scale = np.where(excess[far] > 1e-6, lift / excess[far], np.inf)
    k = float(np.max(scale[lift > 0], initial=1.0))
    raised = path.copy()
    if np.isfinite(k):
        raised[:, 2] = base + max(k, 1.0) * excess
    else:  # part of the path runs along the straight line: add a smooth bump instead
        bump = np.sin(np.pi * fraction)
        raised[:, 2] = path[:, 2] + float(np.max(lift)) * bump
    return raised


class _PolylineSwing:
    """Shared time-scaling of a swing along a polyline that is replaced on re-targeting.

    Progress along the path follows a minimum-jerk profile over the swing. When the path is
    replaced at time ``t``, the remaining progress ``1 - s(t)`` is mapped onto the new path,
    so the foot neither jumps nor stops.
    """

    def __init__(self, duration: float) -> None:
        if not duration > 0:
            raise ConfigError(f"swing duration must be positive, got {duration}")
        self.duration = duration
        self._path = np.zeros((1, 3))
        self._arclength = np.zeros(1)
        self._s_at_path_start = 0.0
        self._start = np.zeros(3)

    @property
    def start(self) -> npt.NDArray[np.float64]:
        """Lift-off position, shape (3,) [m]."""
        return self._start.copy()

    def transform(
        self, rotation: npt.NDArray[np.float64], translation: npt.NDArray[np.float64]
    ) -> None:
        """Move the whole swing by a planar rigid transform."""
        self._path[:, :2] = self._path[:, :2] @ np.asarray(rotation).T + translation
        self._start[:2] = np.asarray(rotation) @ self._start[:2] + translation

    def _set_path(self, path: npt.NDArray[np.float64], t: float) -> None:
        seg = np.linalg.norm(np.diff(path, axis=0), axis=1)
        self._path = path
        self._arclength = np.concatenate([[0.0], np.cumsum(seg)])
        self._s_at_path_start = minimum_jerk(t / self.duration)

    @property
    def target(self) -> npt.NDArray[np.float64]:
        """Current touchdown target, shape (3,) [m]."""
        return self._path[-1].copy()

    def position(self, t: float) -> npt.NDArray[np.float64]:
        """Foot position at ``t`` seconds after lift-off, shape (3,) [m]."""
        s = minimum_jerk(t / self.duration)
        s0 = self._s_at_path_start
        fraction = 1.0 if s0 >= 1.0 else (s - s0) / (1.0 - s0)
        length = self._arclength[-1]
        if length <= 0.0:
            return self._path[-1].copy()
        along = min(max(fraction, 0.0), 1.0) * length
        return np.array([np.interp(along, self._arclength, self._path[:, k]) for k in range(3)])


class FlowSwing(_PolylineSwing):
    """Swing along the flow field of thesis §5.4.2.

    Args:
        start: Lift-off position in the world frame, shape (3,) [m].
        target: Touchdown target in the world frame, shape (3,) [m].
        duration: Swing duration [s].
        config: Flow parameters.
        terrain: Terrain height under horizontal points; when given, the path is lifted to
            clear it by ``clearance`` (see :func:`raise_over`).
        clearance: Least height of the path (foot centre) above the terrain [m].
    """

    def __init__(
        self,
        start: npt.ArrayLike,
        target: npt.ArrayLike,
        duration: float,
        config: FlowConfig,
        terrain: TerrainFunction | None = None,
        clearance: float = 0.0,
    ) -> None:
        super().__init__(duration)
        self.config = config
        self._terrain = terrain
        self._clearance = clearance
        self._start = np.asarray(start, dtype=np.float64).copy()
        self._lift_off_height = float(self._start[2])
        self._set_path(self._plan(self._start, target), 0.0)

    def _plan(self, here: npt.ArrayLike, target: npt.ArrayLike) -> npt.NDArray[np.float64]:
        path = integrate_flow(here, target, self.config, self._lift_off_height)
        if self._terrain is not None:
            path = raise_over(path, self._terrain, self._clearance)
            if self.config.max_height is not None:
                # Clearance never lifts the foot beyond the leg's workspace.
                top = (
                    max(self._lift_off_height, float(np.asarray(target)[2]))
                    + self.config.max_height
                )
                path = cap_height(path, top)
        return path

    def retarget(self, target: npt.ArrayLike, t: float, duration: float | None = None) -> None:
        """Follow the field from the foot's position at ``t`` to a new target."""
        here = self.position(t)
        if duration is not None:
            self.duration = duration
        self._set_path(self._plan(here, target), t)


def polynomial_arc_coefficients(
    q_start: npt.ArrayLike, q_mid: npt.ArrayLike, q_end: npt.ArrayLike, t_end: float
) -> npt.NDArray[np.float64]:
    """Coefficients ``a0..a6`` of the sixth-order arc through three points (thesis eq. 5.22).

    The arc starts at rest (``a1 = a2 = 0``), passes ``q_mid`` at ``t_end / 2`` and ends at
    ``q_end`` at ``t_end``.

    Returns:
        Shape (7, 3): one column per coordinate.
    """
    qi = np.asarray(q_start, dtype=np.float64)
    dm = np.asarray(q_mid, dtype=np.float64) - qi
    df = np.asarray(q_end, dtype=np.float64) - qi
    tf = float(t_end)
    return np.stack(
        [
            qi,
            np.zeros_like(qi),
            np.zeros_like(qi),
            2.0 / tf**3 * (32.0 * dm - 11.0 * df),
            -3.0 / tf**4 * (64.0 * dm - 27.0 * df),
            3.0 / tf**5 * (64.0 * dm - 30.0 * df),
            -32.0 / tf**6 * (2.0 * dm - df),
        ]
    )


class PolynomialArcSwing:
    """The thesis' baseline swing: one sixth-order polynomial per axis (eqs. 5.21-5.22).

    The mid point lies half way between start and target, ``apex_height`` above the higher
    of the two. Re-targeting recomputes the arc from the current point as if it were a new
    lift-off, which makes the foot rise again (the defect of Fig. 5.12); it is kept as the
    baseline the flow function is compared with.

    Args:
        start: Lift-off position in the world frame, shape (3,) [m].
        target: Touchdown target, shape (3,) [m].
        duration: Swing duration [s].
        apex_height: Height of the mid point above the higher end [m].
    """

    def __init__(
        self, start: npt.ArrayLike, target: npt.ArrayLike, duration: float, apex_height: float
    ) -> None:
        if not duration > 0:
            raise ConfigError(f"swing duration must be positive, got {duration}")
        self.duration = duration
        self.apex_height = apex_height
        self._t0 = 0.0
        self._start = np.asarray(start, dtype=np.float64).copy()
        self._fit(self._start, np.asarray(target, dtype=np.float64), 0.0)

    @property
    def start(self) -> npt.NDArray[np.float64]:
        """Lift-off position, shape (3,) [m]."""
        return self._start.copy()

    def transform(
        self, rotation: npt.NDArray[np.float64], translation: npt.NDArray[np.float64]
    ) -> None:
        """Move the whole swing by a planar rigid transform."""
        r = np.asarray(rotation)
        self._coefficients[:, :2] = self._coefficients[:, :2] @ r.T
        self._coefficients[0, :2] += translation
        self._target[:2] = r @ self._target[:2] + translation
        self._start[:2] = r @ self._start[:2] + translation

    def _fit(
        self, start: npt.NDArray[np.float64], target: npt.NDArray[np.float64], t0: float
    ) -> None:
        mid = 0.5 * (start + target)
        mid[2] = max(start[2], target[2]) + self.apex_height
        self._t0 = t0
        self._target = target.copy()
        self._coefficients = polynomial_arc_coefficients(start, mid, target, self.duration - t0)

    @property
    def target(self) -> npt.NDArray[np.float64]:
        """Current touchdown target, shape (3,) [m]."""
        return self._target.copy()

    def position(self, t: float) -> npt.NDArray[np.float64]:
        """Foot position at ``t`` seconds after lift-off, shape (3,) [m]."""
        tau = min(max(t, self._t0), self.duration) - self._t0
        powers = tau ** np.arange(7)
        return powers @ self._coefficients

    def retarget(self, target: npt.ArrayLike, t: float, duration: float | None = None) -> None:
        """Refit the arc from the position at ``t`` to the new target."""
        here = self.position(t)
        if duration is not None:
            self.duration = duration
        if t >= self.duration:
            self._fit(
                np.asarray(target, dtype=np.float64), np.asarray(target, dtype=np.float64), 0.0
            )
            return
        self._fit(here, np.asarray(target, dtype=np.float64), t)
