"""Walking metrics computed from a :class:`~footfall.control_loop.WalkLog`.

Names carry their units; the fields of :class:`GaitMetrics` are the first keys of the
``metrics.json`` interface.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import asdict, dataclass

import numpy as np
import numpy.typing as npt

from footfall.control_loop import WalkLog

# The robot has fallen when its body tilts more than this [deg] or sinks below this fraction
# of the commanded height.
FALL_TILT_DEG = 30.0
FALL_HEIGHT_FRACTION = 0.4
# Oscillation is measured after the start-up transient [s] (thesis Fig. 8.2 style).
TRANSIENT_SECONDS = 2.0

GroundHeight = Callable[[npt.NDArray[np.float64], npt.NDArray[np.float64]], npt.NDArray[np.float64]]


def flat_ground(x: npt.NDArray[np.float64], y: npt.NDArray[np.float64]) -> npt.NDArray[np.float64]:
    """Ground height of a flat floor at z = 0 [m]."""
    return np.zeros(np.broadcast(x, y).shape)


@dataclass(frozen=True)
class StancePhase:
    """One stance of one leg between touchdown and lift-off.

    Attributes:
        leg: Leg index.
        start: Index of the first tick of the stance.
        end: Index of the last tick of the stance.
    """

    leg: int
    start: int
    end: int


def stance_phases(swinging: npt.NDArray[np.bool_]) -> list[StancePhase]:
    """Stances that begin with a touchdown and end with a lift-off.

    Args:
        swinging: Shape (ticks, 6).
    """
    phases = []
    for leg in range(swinging.shape[1]):
        s = swinging[:, leg].astype(np.int8)
        touchdowns = np.flatnonzero(np.diff(s) == -1) + 1
        liftoffs = np.flatnonzero(np.diff(s) == 1)
        for start in touchdowns:
            later = liftoffs[liftoffs > start]
            if later.size:
                phases.append(StancePhase(leg, int(start), int(later[0])))
    return phases


def stance_slip_m(log: WalkLog, foot_radius: float) -> npt.NDArray[np.float64]:
    """How far each foot slid over the ground in each of its stances [m], shape (stances,).

    A round foot may roll; rolling is not slip. So the slip is the horizontal displacement,
    between the tick after touchdown (once the impact has settled) and lift-off, of the
    material point of the foot that touched the ground: it stays put when the foot rolls
    (to third order in the roll angle) and moves with any sliding. Without foot orientations
    in the log, the foot centre's displacement is used.
    """
    feet = log.array("feet_in_world")
    rotations = log.array("foot_orientations_in_world")
    down = np.array([0.0, 0.0, -foot_radius])
    slips = []
    for p in stance_phases(log.array("swinging")):
        s, e = min(p.start + 1, p.end), p.end
        if np.isnan(rotations[s, p.leg]).any():
            moved = feet[e, p.leg] - feet[s, p.leg]
        else:
            material = rotations[s, p.leg].T @ down  # contact point in the foot's own frame
            moved = (feet[e, p.leg] + rotations[e, p.leg] @ material) - (feet[s, p.leg] + down)
        slips.append(float(np.hypot(moved[0], moved[1])))
    return np.asarray(slips)


def swing_apexes_m(
    log: WalkLog, foot_radius: float, ground: GroundHeight = flat_ground
) -> npt.NDArray[np.float64]:
    """Highest clearance of the foot's underside above the ground in each swing [m]."""
    swinging = log.array("swinging")
    feet = log.array("feet_in_world")
    apexes = []
    for leg in range(swinging.shape[1]):
        s = swinging[:, leg].astype(np.int8)
        starts = np.flatnonzero(np.diff(s) == 1) + 1
        ends = np.flatnonzero(np.diff(s) == -1)
        for start in starts:
            later = ends[ends >= start]
            if later.size:
                f = feet[start : later[0] + 1, leg]
                clearance = f[:, 2] - foot_radius - ground(f[:, 0], f[:, 1])
                apexes.append(float(clearance.max()))
    return np.asarray(apexes)


def fallen(
    tilt_deg: npt.ArrayLike,
    height_above_ground: npt.ArrayLike,
    body_z: npt.ArrayLike,
    reference_body_z: npt.ArrayLike,
    commanded_height: npt.ArrayLike,
) -> npt.NDArray[np.bool_]:
    """Whether the body has fallen, per sample.

    Tilted beyond ``FALL_TILT_DEG``, or sunk below ``FALL_HEIGHT_FRACTION`` of the
    commanded height above the ground under its centre while also that far below where
    the controller holds it (a body lowered on purpose over a step's edge has not fallen).
    """
    sunk = np.asarray(height_above_ground) < FALL_HEIGHT_FRACTION * np.asarray(commanded_height)
    dropped = np.asarray(body_z) < np.asarray(reference_body_z) - FALL_HEIGHT_FRACTION * (
        np.asarray(commanded_height)
    )
    return (np.asarray(tilt_deg) > FALL_TILT_DEG) | (sunk & dropped)


@dataclass(frozen=True)
class GaitMetrics:
    """What the per-tick record says of a walk.

    Attributes:
        distance_m: Straight-line distance the body travelled [m].
        mean_speed_mps: That over the walk's time [m/s].
        commanded_speed_mps: Commanded body speed [m/s].
        fell: Whether the body fell (tilted or sank, see :func:`fallen`).
        body_height_error_mean_m: Measured minus commanded body height, mean [m] (a
            sagging body is negative).
        body_height_oscillation_ratio: Peak-to-peak height above the ground under the body
            after the first 2 s over the commanded height (on steps it includes the rises).
        body_z_tracking_error_mean_m: Measured body height minus the controller's reference
            after the first 2 s, mean [m]: how well the body follows its planned height.
        body_z_tracking_error_ptp_m: Its peak to peak [m].
        tilt_max_deg: Largest tilt of the body from vertical [deg].
        tilt_rms_deg: RMS tilt [deg].
        roll_max_deg: Largest roll [deg].
        pitch_max_deg: Largest pitch [deg].
        steps: Lift-offs of any leg.
        stance_slip_max_m: Largest slide of a foot over one stance [m].
        stance_slip_mean_m: Mean slide [m].
        swing_apex_median_m: Median highest clearance of a swinging foot [m].
        frozen: Whether the controller froze.
        frozen_reason: Why, or "".
        sim_seconds: Walk time [s].
        wall_seconds: Wall-clock time it took [s].
        realtime_factor: Walk time over wall time.
    """

    distance_m: float
    mean_speed_mps: float
    commanded_speed_mps: float
    fell: bool
    body_height_error_mean_m: float
    body_height_oscillation_ratio: float
    body_z_tracking_error_mean_m: float
    body_z_tracking_error_ptp_m: float
    tilt_max_deg: float
    tilt_rms_deg: float
    roll_max_deg: float
    pitch_max_deg: float
    steps: int
    stance_slip_max_m: float
    stance_slip_mean_m: float
    swing_apex_median_m: float
    frozen: bool
    frozen_reason: str
    sim_seconds: float
    wall_seconds: float
    realtime_factor: float

    def to_json(self) -> dict[str, object]:
        """The fields by name."""
        return asdict(self)


def walk_metrics(
    log: WalkLog,
    commanded_speed_mps: float,
    wall_seconds: float,
    foot_radius: float,
    ground: GroundHeight = flat_ground,
    frozen_reason: str = "",
) -> GaitMetrics:
    """Summary metrics of a walk.

    Args:
        log: The record of the walk.
        commanded_speed_mps: Commanded body speed [m/s].
        wall_seconds: Wall-clock time the walk took [s].
        foot_radius: Radius of the feet [m].
        ground: Ground height under a point.
        frozen_reason: Why the controller froze, empty if it did not.

    Returns:
        The metrics (see :class:`GaitMetrics`).
    """
    t = log.array("time")
    body = log.array("body_position_in_world")
    tilt_deg = np.degrees(log.array("tilt"))
    commanded = log.array("commanded_height")
    height = body[:, 2] - ground(body[:, 0], body[:, 1])
    sim_seconds = float(t[-1]) if t.size else 0.0
    start = body[0] if body.size else np.zeros(3)
    distance = float(np.hypot(*(body[-1, :2] - start[:2]))) if body.size else 0.0
    steady = t > TRANSIENT_SECONDS
    if not steady.any():
        steady = np.ones_like(t, dtype=bool)
    fell = bool(
        np.any(fallen(tilt_deg, height, body[:, 2], log.array("reference_body_z"), commanded))
    )
    tracking = body[steady, 2] - log.array("reference_body_z")[steady]
    slips = stance_slip_m(log, foot_radius)
    apexes = swing_apexes_m(log, foot_radius, ground)
    swinging = log.array("swinging")
    return GaitMetrics(
        distance_m=distance,
        mean_speed_mps=distance / sim_seconds if sim_seconds > 0 else 0.0,
        commanded_speed_mps=float(commanded_speed_mps),
        fell=fell,
        body_height_error_mean_m=float(np.mean(height - commanded)),
        body_height_oscillation_ratio=float(np.ptp(height[steady]) / np.mean(commanded[steady])),
        body_z_tracking_error_mean_m=float(np.mean(tracking)),
        body_z_tracking_error_ptp_m=float(np.ptp(tracking)),
        tilt_max_deg=float(tilt_deg.max()),
        tilt_rms_deg=float(np.sqrt(np.mean(tilt_deg**2))),
        roll_max_deg=float(np.degrees(np.abs(log.array("roll")).max())),
        pitch_max_deg=float(np.degrees(np.abs(log.array("pitch")).max())),
        steps=int(np.count_nonzero(np.diff(swinging.astype(np.int8), axis=0) == 1)),
        stance_slip_max_m=float(slips.max()) if slips.size else 0.0,
        stance_slip_mean_m=float(slips.mean()) if slips.size else 0.0,
        swing_apex_median_m=float(np.median(apexes)) if apexes.size else 0.0,
        frozen=bool(frozen_reason),
        frozen_reason=frozen_reason,
        sim_seconds=sim_seconds,
        wall_seconds=float(wall_seconds),
        realtime_factor=sim_seconds / wall_seconds if wall_seconds > 0 else float("inf"),
    )
