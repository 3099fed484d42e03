"""The terrain planner's settings (:class:`~footfall.planning.terrain_planner.TerrainPlanner`)."""

from __future__ import annotations

from dataclasses import dataclass, field, replace

from footfall.checks import require_non_negative, require_positive
from footfall.errors import ConfigError
from footfall.planning.footholds import FootholdConfig
from footfall.robot.scale import robot_scale
from footfall.robot.spec import HexapodSpec

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
