"""Terrain-aware foot placement: footholds, floor height and swing clearance on the map.

The planner holds the latest height map snapshot and score map. The walking controller
asks it, at the start of every step and whenever the map changes, to move each swinging
leg's nominal foothold to the nearest acceptable cell (:mod:`footfall.planning.footholds`);
for the floor height the body should keep its height above (thesis §6.4); and for the
terrain under a swing path, which the path must clear.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
import numpy.typing as npt

from footfall.checks import require_non_negative, require_positive
from footfall.errors import ConfigError
from footfall.mapping.snapshot import MapSnapshot
from footfall.planning.footholds import (
    FootholdConfig,
    FootholdSearch,
    point_in_polygon_margin,
    registration_margin_cells,
)
from footfall.planning.leg_clearance import (
    FootholdChecks,
    MapTerrain,
    foothold_heights,
    midway,
    pose_rows,
    stance_heights,
)
from footfall.planning.plan_kernels import foot_ring, highest_within
from footfall.planning.step_plan import FootholdPlan, NoFoothold, StepPoses
from footfall.robot.kinematics import LegKinematics
from footfall.robot.planar import PlanarPose, inclined_to_level
from footfall.robot.scale import robot_scale
from footfall.robot.spec import HexapodSpec
from footfall.scoring.walkability import ScoreMap

# A step whose body travels less than this from now to lift-off is a step in place [m], on
# the default robot (:mod:`footfall.robot.scale` carries it to others by their stride).
IN_PLACE_TRAVEL_M = 0.02


@dataclass(frozen=True)
class TerrainPlannerConfig:
    """Planner settings.

    Attributes:
        footholds: Search radius and stability margin.
        reach_margin: Footholds keep this far inside each leg's workspace [m]: room for the
            servos' tracking and the body's corrections, not the robot's size (scaled to the
            PhantomX's shorter legs, 1.5 cm, its ripple gait put 8 feet on invalid cells
            where 2 cm put none).
        swing_clearance: Least gap between a swinging foot's underside and the mapped
            terrain along its path [m]: the map's error and the swing's tracking, not the
            robot's size (a PhantomX's lift scaled it to 1.2 cm, and its feet caught risers).
        body_clearance: Gap the body keeps between its underside and the mapped terrain
            under it when the legs allow [m].
        min_body_clearance: Least gap, never given up: a foothold that needs a lower body
            is refused [m].
        registration_horizon_s: How long a mapped cell stays in use: from the camera
            seeing it ahead of the front legs until the hind feet have stepped past it
            (body length and look-ahead over the walking speed) [s]. The map may slide
            under the feet by as much as the controller's world moved against its
            odometry over this time (see :attr:`TerrainPlanner.registration_error_m`).
    """

    footholds: FootholdConfig = field(default_factory=FootholdConfig)
    reach_margin: float = 0.02
    swing_clearance: float = 0.03
    body_clearance: float = 0.03
    min_body_clearance: float = 0.01
    registration_horizon_s: float = 5.0

    def __post_init__(self) -> None:
        require_non_negative(
            "planner",
            reach_margin=self.reach_margin,
            swing_clearance=self.swing_clearance,
            min_body_clearance=self.min_body_clearance,
        )
        require_positive("planner", registration_horizon_s=self.registration_horizon_s)
        if self.body_clearance < self.min_body_clearance:
            raise ConfigError("body_clearance must be at least min_body_clearance")

    def for_robot(self, spec: HexapodSpec) -> TerrainPlannerConfig:
        """This config with the robot's stability margin where unset (the feet's span's)."""
        return replace(self, footholds=self.footholds.for_robot(robot_scale(spec)))


class TerrainPlanner:
    """Footholds, floor height and clearance from the latest map.

    Args:
        spec: The robot.
        config: Planner settings.

    Attributes:
        registration_error_m: How far the map may lie from where the controller's world
            puts it [m]: the controller's world follows a drifting pose estimate, and a
            cell mapped seconds ago moved with the estimate of that time. Footholds keep at
            least this far from invalid cells (:func:`registration_margin_cells`); the
            walking controller sets it from its pose corrections.
        region_jumps: Re-plans that moved a leg's foothold to another steppable region,
            no farther inside it, while the foothold planned before still served (valid,
            reached and stable): flips across an edge, which the search should never make.
        in_place_travel_m: A step whose body travels less than this is a step in place [m].
    """

    def __init__(self, spec: HexapodSpec, config: TerrainPlannerConfig | None = None) -> None:
        self.spec = spec
        self.config = (config or TerrainPlannerConfig()).for_robot(spec)
        self.in_place_travel_m = IN_PLACE_TRAVEL_M * robot_scale(spec).stride
        self.kinematics = LegKinematics(spec)
        self.snapshot: MapSnapshot | None = None
        self.scores: ScoreMap | None = None
        self.version = 0
        self.registration_error_m = 0.0
        self.region_jumps = 0
        self._search: FootholdSearch | None = None
        self._ring = foot_ring(spec.foot_radius)
        self._terrain: MapTerrain | None = None

    def update(self, snapshot: MapSnapshot, scores: ScoreMap) -> None:
        """Take a new map and its scores."""
        if self._search is None or self._search.resolution != snapshot.resolution:
            self._search = FootholdSearch(self.config.footholds, snapshot.resolution)
        self.snapshot = snapshot
        self.scores = scores
        ox, oy = (float(v) for v in snapshot.origin)
        heights = np.asarray(snapshot.heights, dtype=np.float64)
        self._terrain = MapTerrain(self._ring, heights, ox, oy, float(snapshot.resolution))
        self.version += 1

    # Map look-ups -----------------------------------------------------------------------
    def ground_height(self, xy: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Mapped heights at world points, NaN where unknown or off the map [m]."""
        if self.snapshot is None:
            return np.full(np.shape(xy)[:-1], np.nan)
        return self._at(xy, self.snapshot.heights, np.nan)

    def steppable_ground(self, xy: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Mapped heights at world points on cells a foot may use, NaN elsewhere [m]."""
        heights = self.ground_height(xy)
        if self.scores is None or self.snapshot is None:
            return heights
        return np.where(self._at(xy, self.scores.valid, False), heights, np.nan)

    def _at(self, xy: npt.ArrayLike, grid: npt.NDArray, outside: object) -> npt.NDArray:
        """A map-window grid's values at world points; ``outside`` off the window."""
        assert self.snapshot is not None
        cells = self.snapshot.cell_of(xy)
        n = self.snapshot.size
        inside = np.all((cells >= 0) & (cells < n), axis=-1)
        out = np.full(inside.shape, outside, dtype=grid.dtype)
        out[inside] = grid[cells[inside, 0], cells[inside, 1]]
        return out

    def terrain_under(self, xy: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Highest mapped height within a foot radius of each point [m]; -inf if unknown."""
        p = np.ascontiguousarray(np.atleast_2d(np.asarray(xy, dtype=np.float64)))
        if self._terrain is None:
            return np.full(p.shape[:-1], -np.inf)
        points = p.reshape(-1, 2)
        out = np.empty(len(points))
        highest_within(points, *self._terrain, out)
        return out.reshape(p.shape[:-1])

    # Footholds ----------------------------------------------------------------------------
    def plan(
        self,
        nominal: npt.NDArray[np.float64],
        swinging: npt.NDArray[np.bool_],
        support_after: npt.NDArray[np.bool_],
        feet: npt.NDArray[np.float64],
        poses: StepPoses,
        body_z: npt.ArrayLike,
        previous: npt.NDArray[np.float64] | None = None,
    ) -> FootholdPlan | NoFoothold:
        """Move each swinging leg's nominal foothold to the nearest acceptable cell.

        The body height is planned with the footholds: a foothold is reachable when the leg
        reaches it at one of the candidate body heights at which every other foot is also
        reached. A step down or up that the commanded height would put out of reach is
        taken by lowering or raising the body instead.

        Args:
            nominal: Nominal foot-centre targets in the world, shape (6, 3) [m] (z ignored).
            swinging: Legs to plan, shape (6,).
            support_after: Legs supporting the body after touchdown, shape (6,).
            feet: Current foot-centre positions, shape (6, 3) [m].
            poses: Body poses the footholds are checked at.
            body_z: Candidate body heights in the world [m]: those the body can reach by
                touchdown.
            previous: The targets planned before in this step, shape (6, 3) [m], or None:
                each leg keeps its foothold's steppable region while that still has an
                acceptable cell (a needless move to another region counts in
                :attr:`region_jumps`).

        Returns:
            The plan, or why there is none (naming the leg).
        """
        terrain = self._terrain
        if self.scores is None or self.snapshot is None or self._search is None or terrain is None:
            return NoFoothold("no map yet: the camera has not seen the ground ahead")
        c = self.config
        r = self.spec.foot_radius
        heights = np.sort(np.atleast_1d(np.asarray(body_z, dtype=np.float64)))
        now, step = poses.incline_now, poses.incline_step
        feasible = stance_heights(
            self.kinematics,
            feet,
            ~swinging,
            (poses.now, poses.touchdown),
            heights,
            c.reach_margin,
            (now, step),
        )
        if not feasible.any():
            return NoFoothold(
                "the supporting feet are out of reach at every body height the body can take"
            )
        lowest = self.lowest_body_z((poses.now, poses.touchdown), c.min_body_clearance, (now, step))
        feasible &= heights >= lowest
        if not feasible.any():
            return NoFoothold(
                f"the body cannot keep {c.min_body_clearance:.2f} m above the terrain under it "
                f"(it would have to be at {lowest:.3f} m) with every foot in reach"
            )
        least_margin = registration_margin_cells(self.registration_error_m, self._search.resolution)
        # A foothold is reached from the body now (it may stop at any time) to lift-off.
        reach_poses = (poses.now, poses.touchdown, poses.liftoff)
        in_place = all(
            math.hypot(p.x - poses.now.x, p.y - poses.now.y) < self.in_place_travel_m
            for p in (poses.touchdown, poses.liftoff)
        )
        # Its leg clears the terrain while the foot stands, from touchdown to lift-off.
        stance_poses = (poses.touchdown, midway(poses.touchdown, poses.liftoff), poses.liftoff)
        kin, r_link = self.kinematics, self.spec.foot_radius
        checks = FootholdChecks(
            pose_rows(reach_poses, (now, step, step)),
            c.reach_margin,
            pose_rows((poses.now, poses.touchdown), (now, step)),
            c.swing_clearance + r_link,
            pose_rows(stance_poses, (step,) * 3),
            r_link + c.min_body_clearance,
        )

        def place(order: list[int]) -> FootholdPlan | NoFoothold:
            """Each leg's foothold in turn, each narrowing the body heights the next may use."""
            targets = feet.copy()
            targets[swinging] = nominal[swinging]
            adjusted = np.zeros(6, dtype=bool)
            allowed_heights = feasible
            jumps = 0
            for leg in order:

                def reached_at(
                    centres: npt.NDArray[np.float64], leg: int = leg
                ) -> npt.NDArray[np.bool_]:
                    """Heights at which the leg reaches, swings to and stands on each centre."""
                    return foothold_heights(kin, terrain, leg, centres, feet[leg], heights, checks)

                def first_accepted(
                    points: npt.NDArray[np.float64],
                    leg: int = leg,
                    allowed: npt.NDArray[np.bool_] = allowed_heights,
                ) -> int:
                    """The first candidate reached at an allowed height and stable, or -1."""
                    centres = points.copy()
                    centres[:, 2] += r
                    reach = reached_at(centres)
                    for m in np.flatnonzero((allowed & reach).any(axis=1)):
                        support = targets[support_after].copy()
                        support[np.flatnonzero(support_after) == leg] = centres[m]
                        if all(
                            point_in_polygon_margin((pose.x, pose.y), support[:, :2])
                            >= c.footholds.stability_margin
                            for pose in poses.stable
                        ):
                            return int(m)
                    return -1

                # The body hardly travelling this step (a turn on the spot), a leg with nowhere
                # to go near its nominal foothold may step where it stands.
                origins = (nominal[leg, :2], feet[leg, :2]) if in_place else (nominal[leg, :2],)
                kept = None if previous is None else previous[leg, :2]
                foothold = None
                for origin in origins:
                    foothold = self._search.search(
                        origin,
                        self.scores,
                        self.snapshot.heights,
                        first_accepted=first_accepted,
                        min_margin_cells=least_margin,
                        keep_region_at=kept,
                    )
                    if foothold is not None:
                        break
                if foothold is None:
                    drift = (
                        f" at least {least_margin} cells from invalid ones (the map may lie "
                        f"{self.registration_error_m:.3f} m off)"
                        if least_margin > c.footholds.min_edge_margin_cells
                        else ""
                    )
                    return NoFoothold(
                        f"leg {self.spec.leg_names[leg]}: no valid, reachable and stable cell"
                        f"{drift} within {c.footholds.search_radius:.2f} m of its nominal foothold "
                        f"({nominal[leg, 0]:.2f}, {nominal[leg, 1]:.2f}) m",
                        self.spec.leg_names[leg],
                    )
                if kept is not None:
                    jumps += self._search.needless_jump(
                        origin,
                        kept,
                        foothold,
                        self.scores,
                        self.snapshot.heights,
                        least_margin,
                        first_accepted,
                    )
                targets[leg] = foothold.position + [0.0, 0.0, r]
                allowed_heights = allowed_heights & reached_at(targets[leg][None])[0]
                adjusted[leg] = foothold.moved > 1e-9
            self.region_jumps += jumps  # counted for the plan kept only
            return FootholdPlan(targets, nominal.copy(), adjusted, heights[allowed_heights])

        order = [int(k) for k in np.flatnonzero(swinging)]
        plan = place(order)
        if isinstance(plan, NoFoothold) and plan.leg in self.spec.leg_names:
            # A leg placed after the others may find nothing at the body heights and beside
            # the support they left it (the last in spec order is a front leg, stepping onto
            # the ground the others have not reached yet); placed first, it may.
            first = self.spec.leg_names.index(plan.leg)
            if first != order[0]:
                again = place([first, *(leg for leg in order if leg != first)])
                if isinstance(again, FootholdPlan):
                    return again
        return plan

    # Floor height -------------------------------------------------------------------------
    def floor_height(
        self,
        ground_heights: npt.ArrayLike,
        pose: PlanarPose,
        body_height: float,
        incline: float = 0.0,
    ) -> float:
        """The floor the body keeps its height above (thesis §6.4).

        The mean of the three highest foothold ground heights, raised when the mapped
        terrain under the body's footprint would come within ``body_clearance`` of the
        body's underside.

        Args:
            ground_heights: Ground heights of the six footholds (targets and stance) [m].
            pose: Body pose.
            body_height: Commanded body height above the floor [m].
            incline: The body's pitch [rad].
        """
        top3 = np.sort(np.asarray(ground_heights, dtype=np.float64))[-3:]
        lowest = self.lowest_body_z((pose,), self.config.body_clearance, (incline,))
        return max(float(top3.mean()), lowest - body_height)

    def lowest_body_z(
        self,
        poses: tuple[PlanarPose, ...],
        clearance: float,
        inclines: tuple[float, ...] | None = None,
    ) -> float:
        """Lowest body height keeping ``clearance`` under the body at every pose [m].

        ``inclines``: the body's pitch at each pose [rad] (level when None): an inclined
        body's underside dips at one end. -inf where the map knows nothing under the body.
        """
        length, width, thickness = self.spec.body_size
        u, v = np.meshgrid(np.linspace(-0.5, 0.5, 9) * length, np.linspace(-0.5, 0.5, 5) * width)
        underside = np.stack([u.ravel(), v.ravel(), np.full(u.size, -0.5 * thickness)], axis=1)
        lowest = -np.inf
        for k, pose in enumerate(poses):
            incline = 0.0 if inclines is None else inclines[k]
            level = inclined_to_level(underside, incline)  # below the body's origin
            under = self.ground_height(pose.points_to_world(level[:, :2]))
            dips = -0.5 * thickness - level[:, 2]  # how far the underside dips: 0 level
            if np.isfinite(under).any():
                lowest = max(lowest, float(np.nanmax(under + dips)) + clearance + 0.5 * thickness)
        return lowest
