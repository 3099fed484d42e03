"""footfall: legged robots walking over uneven terrain.

The public API, re-exported from the modules that hold it. Data flows one way: sensing
(camera, poses) -> mapping (height map) -> scoring -> planning (footholds) -> motion
(gaits, swing paths, the walking controller) -> backends (the MuJoCo simulation, a
mock, or a real robot's driver). The parts run as nodes (``footfall.nodes``) that exchange
messages (``footfall.messages``) over a bus (``footfall.runtime``). The biped planner
(``footfall.biped``) goes from point clouds to obstacles, paths, footsteps and the
centre-of-mass pattern.

The names load on first use (PEP 562), so ``import footfall`` and the command line start
without importing MuJoCo, numba and SciPy until something needs them.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

__version__ = "0.1.0"

# Each public name and the module that holds it.
_EXPORTS = {
    "ConfigError": "footfall.errors",
    "DatasetError": "footfall.errors",
    "DepthImageError": "footfall.errors",
    "detect_obstacles": "footfall.biped.obstacles",
    "EffectorTargets": "footfall.messages",
    "FlowConfig": "footfall.motion.flow_swing",
    "FlowSwing": "footfall.motion.flow_swing",
    "FootfallError": "footfall.errors",
    "FootholdConfig": "footfall.planning.footholds",
    "FootholdSearch": "footfall.planning.footholds",
    "Gait": "footfall.motion.gait",
    "GaitConfig": "footfall.motion.gait",
    "GAITS": "footfall.motion.gait",
    "GaitState": "footfall.messages",
    "GaitStatus": "footfall.messages",
    "HeightMap": "footfall.mapping.height_map",
    "HeightMapConfig": "footfall.mapping.engine",
    "HexapodBackend": "footfall.backends",
    "HexapodSpec": "footfall.robot.spec",
    "InProcessBus": "footfall.runtime.bus",
    "InvalidPoseError": "footfall.errors",
    "JointTargets": "footfall.messages",
    "LegKinematics": "footfall.robot.kinematics",
    "lipm_pattern": "footfall.biped.lipm",
    "LipmConfig": "footfall.biped.lipm",
    "load_map": "footfall.biped.maps",
    "load_spec": "footfall.robot.spec",
    "MappingNode": "footfall.nodes.mapping",
    "MapUpdate": "footfall.messages",
    "MockHexapod": "footfall.backends.mock",
    "Mode": "footfall.messages",
    "MovementNode": "footfall.nodes.movement",
    "PinholeCamera": "footfall.sensing.camera",
    "plan_walk": "footfall.biped.planner",
    "PlanarPose": "footfall.robot.planar",
    "PlanMap": "footfall.biped.maps",
    "PlanningError": "footfall.errors",
    "PolynomialArcSwing": "footfall.motion.swing_polynomial",
    "Pose": "footfall.sensing.pose",
    "RobotState": "footfall.messages",
    "run_control_loop": "footfall.control_loop",
    "score_map": "footfall.scoring.walkability",
    "ScoreConfig": "footfall.scoring.walkability",
    "ServoNode": "footfall.nodes.servo",
    "SingularConfigurationError": "footfall.errors",
    "SwingTrajectory": "footfall.motion.swing",
    "TerrainPlanner": "footfall.planning.terrain_planner",
    "TerrainPlannerConfig": "footfall.planning.terrain_planner",
    "UnreachableTargetError": "footfall.errors",
    "walk_metrics": "footfall.metrics",
    "WalkCommand": "footfall.messages",
    "WalkController": "footfall.motion.walker",
    "WalkLog": "footfall.control_loop",
    "WalkParameter": "footfall.biped.lipm",
}

if TYPE_CHECKING:
    from footfall.backends import HexapodBackend as HexapodBackend
    from footfall.backends.mock import MockHexapod as MockHexapod
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
    from footfall.mapping.engine import HeightMapConfig as HeightMapConfig
    from footfall.mapping.height_map import HeightMap as HeightMap
    from footfall.messages import EffectorTargets as EffectorTargets
    from footfall.messages import GaitState as GaitState
    from footfall.messages import GaitStatus as GaitStatus
    from footfall.messages import JointTargets as JointTargets
    from footfall.messages import MapUpdate as MapUpdate
    from footfall.messages import Mode as Mode
    from footfall.messages import RobotState as RobotState
    from footfall.messages import WalkCommand as WalkCommand
    from footfall.metrics import walk_metrics as walk_metrics
    from footfall.motion.flow_swing import FlowConfig as FlowConfig
    from footfall.motion.flow_swing import FlowSwing as FlowSwing
    from footfall.motion.gait import GAITS as GAITS
    from footfall.motion.gait import Gait as Gait
    from footfall.motion.gait import GaitConfig as GaitConfig
    from footfall.motion.swing import SwingTrajectory as SwingTrajectory
    from footfall.motion.swing_polynomial import PolynomialArcSwing as PolynomialArcSwing
    from footfall.motion.walker import WalkController as WalkController
    from footfall.nodes.mapping import MappingNode as MappingNode
    from footfall.nodes.movement import MovementNode as MovementNode
    from footfall.nodes.servo import ServoNode as ServoNode
    from footfall.planning.footholds import FootholdConfig as FootholdConfig
    from footfall.planning.footholds import FootholdSearch as FootholdSearch
    from footfall.planning.terrain_planner import TerrainPlanner as TerrainPlanner
    from footfall.planning.terrain_planner import TerrainPlannerConfig as TerrainPlannerConfig
    from footfall.robot.kinematics import LegKinematics as LegKinematics
    from footfall.robot.planar import PlanarPose as PlanarPose
    from footfall.robot.spec import HexapodSpec as HexapodSpec
    from footfall.robot.spec import load_spec as load_spec
    from footfall.runtime.bus import InProcessBus as InProcessBus
    from footfall.scoring.walkability import ScoreConfig as ScoreConfig
    from footfall.scoring.walkability import score_map as score_map
    from footfall.sensing.camera import PinholeCamera as PinholeCamera
    from footfall.sensing.pose import Pose as Pose


def __getattr__(name: str) -> object:
    """A public name, imported from its module on first use."""
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'footfall' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    """The public names beside the module's own."""
    return sorted({*globals(), *_EXPORTS})


__all__ = [
    "GAITS",
    "ConfigError",
    "DatasetError",
    "DepthImageError",
    "EffectorTargets",
    "FlowConfig",
    "FlowSwing",
    "FootfallError",
    "FootholdConfig",
    "FootholdSearch",
    "Gait",
    "GaitConfig",
    "GaitState",
    "GaitStatus",
    "HeightMap",
    "HeightMapConfig",
    "HexapodBackend",
    "HexapodSpec",
    "InProcessBus",
    "InvalidPoseError",
    "JointTargets",
    "LegKinematics",
    "LipmConfig",
    "MapUpdate",
    "MappingNode",
    "MockHexapod",
    "Mode",
    "MovementNode",
    "PinholeCamera",
    "PlanMap",
    "PlanarPose",
    "PlanningError",
    "PolynomialArcSwing",
    "Pose",
    "RobotState",
    "ScoreConfig",
    "ServoNode",
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
