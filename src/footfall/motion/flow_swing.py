"""The flow-function swing of thesis §5.4.2.

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
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from footfall.checks import require_non_negative, require_positive
from footfall.motion.swing import PolylineSwing, SwingPlan, TerrainFunction
from footfall.planning.leg_clearance import SWING_END_RADIUS_M


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
        if self.max_height is not None:
            require_positive("flow", max_height=self.max_height)
        require_non_negative("flow", step_height=self.step_height)
        require_positive("flow", length_unit=self.length_unit, resolution=self.resolution)


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
    end_radius: float = SWING_END_RADIUS_M,
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


class FlowSwing(PolylineSwing):
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

    @classmethod
    def plan(cls, plan: SwingPlan) -> FlowSwing:
        """The flow swing of ``plan``, lifted over its terrain."""
        return cls(
            plan.start, plan.target, plan.duration, plan.gait.flow, plan.terrain, plan.clearance
        )

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
