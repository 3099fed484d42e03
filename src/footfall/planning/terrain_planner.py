"""Terrain-aware foot placement: footholds, floor height and swing clearance on the map.

The planner holds the latest height map snapshot and score map. The walking controller
asks it, at the start of every step and whenever the map changes, to move each swinging
leg's nominal foothold to the nearest acceptable cell (:mod:`footfall.planning.footholds`);
for the floor height the body should keep its height above (thesis §6.4); and for the
terrain under a swing path, which the path must clear.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from footfall.errors import ConfigError
from footfall.mapping.height_map import MapSnapshot
from footfall.motion.kinematics import LegKinematics
from footfall.motion.planar import PlanarPose
from footfall.planning.footholds import FootholdConfig, FootholdSearch, point_in_polygon_margin
from footfall.robot.spec import HexapodSpec
from footfall.scoring.walkability import ScoreMap


@dataclass(frozen=True)
class TerrainPlannerConfig:
    """Planner settings.

    Attributes:
        footholds: Search radius and stability margin.
        reach_margin: Footholds keep this far inside each leg's workspace [m].
        swing_clearance: Least gap between a swinging foot's underside and the mapped
            terrain along its path [m].
        body_clearance: Least gap between the body's underside and the mapped terrain
            under it [m].
    """

    footholds: FootholdConfig = field(default_factory=FootholdConfig)
    reach_margin: float = 0.02
    swing_clearance: float = 0.03
    body_clearance: float = 0.03

    def __post_init__(self) -> None:
        if min(self.reach_margin, self.swing_clearance, self.body_clearance) < 0:
            raise ConfigError("planner margins must be >= 0")


@dataclass(frozen=True)
class FootholdPlan:
    """Footholds for the swinging legs of one step.

    Attributes:
        targets: Foot-centre targets in the world, shape (6, 3) [m]; rows of legs that do
            not swing are their current positions.
        nominal: The nominal targets the search started from, shape (6, 3) [m].
        adjusted: Which swinging legs were moved off their nominal cell, shape (6,).
    """

    targets: npt.NDArray[np.float64]
    nominal: npt.NDArray[np.float64]
    adjusted: npt.NDArray[np.bool_]


class TerrainPlanner:
    """Footholds, floor height and clearance from the latest map.

    Args:
        spec: The robot.
        config: Planner settings.
    """

    def __init__(self, spec: HexapodSpec, config: TerrainPlannerConfig | None = None) -> None:
        self.spec = spec
        self.config = config or TerrainPlannerConfig()
        self.kinematics = LegKinematics(spec)
        self.snapshot: MapSnapshot | None = None
        self.scores: ScoreMap | None = None
        self.version = 0
        self._search: FootholdSearch | None = None

    def update(self, snapshot: MapSnapshot, scores: ScoreMap) -> None:
        """Take a new map and its scores."""
        if self._search is None or self._search.resolution != snapshot.resolution:
            self._search = FootholdSearch(self.config.footholds, snapshot.resolution)
        self.snapshot = snapshot
        self.scores = scores
        self.version += 1

    # Map look-ups -----------------------------------------------------------------------
    def ground_height(self, xy: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Mapped heights at world points, NaN where unknown or off the map [m]."""
        if self.snapshot is None:
            return np.full(np.shape(xy)[:-1], np.nan)
        cells = self.snapshot.cell_of(xy)
        n = self.snapshot.size
        inside = np.all((cells >= 0) & (cells < n), axis=-1)
        out = np.full(inside.shape, np.nan)
        out[inside] = self.snapshot.heights[cells[inside, 0], cells[inside, 1]]
        return out

    def terrain_under(self, xy: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """Highest mapped height within a foot radius of each point [m]; -inf if unknown."""
        p = np.atleast_2d(np.asarray(xy, dtype=np.float64))
        r = self.spec.foot_radius
        rings = [(0.0, 0.0), (r, 0.0), (-r, 0.0), (0.0, r), (0.0, -r)]
        heights = np.stack([self.ground_height(p + d) for d in rings])
        return np.where(np.isnan(heights), -np.inf, heights).max(axis=0)

    # Footholds ----------------------------------------------------------------------------
    def plan(
        self,
        nominal: npt.NDArray[np.float64],
        swinging: npt.NDArray[np.bool_],
        support_after: npt.NDArray[np.bool_],
        feet: npt.NDArray[np.float64],
        poses: tuple[PlanarPose, ...],
        stability_poses: tuple[PlanarPose, ...],
        body_z: float,
    ) -> FootholdPlan | str:
        """Move each swinging leg's nominal foothold to the nearest acceptable cell.

        Args:
            nominal: Nominal foot-centre targets in the world, shape (6, 3) [m] (z ignored).
            swinging: Legs to plan, shape (6,).
            support_after: Legs supporting the body after touchdown, shape (6,).
            feet: Current foot-centre positions, shape (6, 3) [m].
            poses: Planned body poses each foothold must be reachable from (touchdown to
                lift-off).
            stability_poses: Planned body poses at which the body centre must lie inside the
                support polygon of ``support_after`` (while those legs support).
            body_z: Planned body height in the world [m].

        Returns:
            The plan, or the reason there is none (naming the leg).
        """
        if self.scores is None or self.snapshot is None or self._search is None:
            return "no map yet: the camera has not seen the ground ahead"
        c = self.config
        r = self.spec.foot_radius
        targets = feet.copy()
        targets[swinging] = nominal[swinging]
        adjusted = np.zeros(6, dtype=bool)
        for leg in np.flatnonzero(swinging):

            def accept(point: npt.NDArray[np.float64], leg: int = int(leg)) -> bool:
                centre = np.array([point[0], point[1], point[2] + r])
                for pose in poses:
                    in_body = pose.points_to_body(centre[None])[0]
                    in_body[2] -= body_z
                    if not self.kinematics.reachable(leg, in_body, c.reach_margin):
                        return False
                support = targets[support_after].copy()
                support[np.flatnonzero(support_after) == leg] = centre
                return all(
                    point_in_polygon_margin((pose.x, pose.y), support[:, :2])
                    >= c.footholds.stability_margin
                    for pose in stability_poses
                )

            foothold = self._search.search(
                nominal[leg, :2], self.scores, self.snapshot.heights, accept
            )
            name = self.spec.leg_names[leg]
            if foothold is None:
                return (
                    f"leg {name}: no valid, reachable and stable cell within "
                    f"{c.footholds.search_radius:.2f} m of its nominal foothold "
                    f"({nominal[leg, 0]:.2f}, {nominal[leg, 1]:.2f}) m"
                )
            targets[leg] = foothold.position + [0.0, 0.0, r]
            adjusted[leg] = foothold.moved > 1e-9
        return FootholdPlan(targets, nominal.copy(), adjusted)

    # Floor height -------------------------------------------------------------------------
    def floor_height(
        self, ground_heights: npt.ArrayLike, pose: PlanarPose, body_height: float
    ) -> float:
        """The floor the body keeps its height above (thesis §6.4).

        The mean of the three highest foothold ground heights, raised when the mapped
        terrain under the body's footprint would come within ``body_clearance`` of the
        body's underside.

        Args:
            ground_heights: Ground heights of the six footholds (targets and stance) [m].
            pose: Body pose.
            body_height: Commanded body height above the floor [m].
        """
        top3 = np.sort(np.asarray(ground_heights, dtype=np.float64))[-3:]
        floor = float(top3.mean())
        if self.snapshot is None:
            return floor
        length, width, thickness = self.spec.body_size
        u, v = np.meshgrid(np.linspace(-0.5, 0.5, 9) * length, np.linspace(-0.5, 0.5, 5) * width)
        under = self.ground_height(pose.points_to_world(np.stack([u.ravel(), v.ravel()], axis=1)))
        if np.isfinite(under).any():
            needed = (
                float(np.nanmax(under)) + self.config.body_clearance + 0.5 * thickness - body_height
            )
            floor = max(floor, needed)
        return floor
