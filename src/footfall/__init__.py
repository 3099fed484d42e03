"""footfall: legged robots walking over uneven terrain.

The public API, re-exported from the modules that hold it. Data flows one way:
robot description -> kinematics and gaits -> swing trajectories -> walking controller ->
backend (the MuJoCo simulation, or a real robot's driver).
"""

from footfall.backend import HexapodBackend as HexapodBackend
from footfall.backend import RobotState as RobotState
from footfall.control_loop import WalkLog as WalkLog
from footfall.control_loop import run_control_loop as run_control_loop
from footfall.errors import ConfigError as ConfigError
from footfall.errors import FootfallError as FootfallError
from footfall.errors import SingularConfigurationError as SingularConfigurationError
from footfall.errors import UnreachableTargetError as UnreachableTargetError
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
from footfall.robot.spec import HexapodSpec as HexapodSpec
from footfall.robot.spec import load_spec as load_spec

__version__ = "0.1.0"

__all__ = [
    "ConfigError",
    "FlowConfig",
    "FlowSwing",
    "FootfallError",
    "GaitConfig",
    "GaitKind",
    "GaitState",
    "HexapodBackend",
    "HexapodSpec",
    "JointTargets",
    "LegKinematics",
    "PlanarPose",
    "PolynomialArcSwing",
    "RobotState",
    "SingularConfigurationError",
    "SwingTrajectory",
    "UnreachableTargetError",
    "WalkCommand",
    "WalkController",
    "WalkLog",
    "load_spec",
    "run_control_loop",
    "walk_metrics",
]
