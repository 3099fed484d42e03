"""footfall: legged robots walking over uneven terrain.

The public API, re-exported from the modules that hold it. Data flows one way: sensing
(camera, poses) -> mapping (height map) -> scoring -> planning (footholds) -> motion
(kinematics, gaits, swing paths, the walking controller) -> backend (the MuJoCo
simulation, or a real robot's driver). The biped planner (``footfall.biped``) goes from
point clouds to obstacles, paths, footsteps and the centre-of-mass pattern.
"""

from footfall.backend import HexapodBackend as HexapodBackend
from footfall.backend import RobotState as RobotState
from footfall.biped.lipm import LipmConfig as LipmConfig
from footfall.biped.lipm import WalkParameter as WalkParameter
from footfall.biped.lipm import lipm_pattern as lipm_pattern
from footfall.biped.maps import PlanMap as PlanMap
from footfall.biped.maps import load_map as load_map
from footfall.biped.obstacles import detect_obstacles as detect_obstacles
from footfall.biped.planner import plan_walk as plan_walk
from footfall.control_loop import WalkLog as WalkLog
from footfall.control_loop import run_control_loop as run_control_loop
from footfall.errors import ConfigError as ConfigError
from footfall.errors import DatasetError as DatasetError
from footfall.errors import DepthImageError as DepthImageError
from footfall.errors import FootfallError as FootfallError
from footfall.errors import InvalidPoseError as InvalidPoseError
from footfall.errors import PlanningError as PlanningError
from footfall.errors import SingularConfigurationError as SingularConfigurationError
from footfall.errors import UnreachableTargetError as UnreachableTargetError
from footfall.mapping.height_map import HeightMap as HeightMap
from footfall.mapping.height_map import HeightMapConfig as HeightMapConfig
from footfall.metrics import walk_metrics as walk_metrics
from footfall.motion.gait import GaitConfig as GaitConfig
from footfall.motion.gait import GaitKind as GaitKind
from footfall.motion.gait import WalkCommand as WalkCommand
from footfall.motion.kinematics import LegKinematics as LegKinematics
from footfall.motion.planar import PlanarPose as PlanarPose
from footfall.motion.swing import FlowConfig as FlowConfig
from footfall.motion.swing import FlowSwing as FlowSwing
from footfall.motion.swing import PolynomialArcSwing as PolynomialArcSwing
from footfall.motion.swing import SwingTrajectory as SwingTrajectory
from footfall.motion.walker import GaitState as GaitState
from footfall.motion.walker import JointTargets as JointTargets
from footfall.motion.walker import WalkController as WalkController
from footfall.planning.footholds import FootholdConfig as FootholdConfig
from footfall.planning.footholds import FootholdSearch as FootholdSearch
from footfall.planning.terrain_planner import TerrainPlanner as TerrainPlanner
from footfall.planning.terrain_planner import TerrainPlannerConfig as TerrainPlannerConfig
from footfall.robot.spec import HexapodSpec as HexapodSpec
from footfall.robot.spec import load_spec as load_spec
from footfall.scoring.walkability import ScoreConfig as ScoreConfig
from footfall.scoring.walkability import score_map as score_map
from footfall.sensing.camera import PinholeCamera as PinholeCamera
from footfall.sensing.pose import Pose as Pose

__version__ = "0.1.0"

__all__ = [
    "ConfigError",
    "DatasetError",
    "DepthImageError",
    "FlowConfig",
    "FlowSwing",
    "FootfallError",
    "FootholdConfig",
    "FootholdSearch",
    "GaitConfig",
    "GaitKind",
    "GaitState",
    "HeightMap",
    "HeightMapConfig",
    "HexapodBackend",
    "HexapodSpec",
    "InvalidPoseError",
    "JointTargets",
    "LegKinematics",
    "LipmConfig",
    "PinholeCamera",
    "PlanMap",
    "PlanarPose",
    "PlanningError",
    "PolynomialArcSwing",
    "Pose",
    "RobotState",
    "ScoreConfig",
    "SingularConfigurationError",
    "SwingTrajectory",
    "TerrainPlanner",
    "TerrainPlannerConfig",
    "UnreachableTargetError",
    "WalkCommand",
    "WalkController",
    "WalkLog",
    "WalkParameter",
    "detect_obstacles",
    "lipm_pattern",
    "load_map",
    "load_spec",
    "plan_walk",
    "run_control_loop",
    "score_map",
    "walk_metrics",
]
