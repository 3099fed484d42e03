"""Messages between footfall's nodes, and their byte encoding."""

from footfall.messages.biped import Ack as Ack
from footfall.messages.biped import BipedPlan as BipedPlan
from footfall.messages.biped import BipedStatus as BipedStatus
from footfall.messages.biped import NewMap as NewMap
from footfall.messages.biped import Obstacles as Obstacles
from footfall.messages.biped import PlanningGoal as PlanningGoal
from footfall.messages.biped import Trigger as Trigger
from footfall.messages.codec import Message as Message
from footfall.messages.codec import decode as decode
from footfall.messages.codec import message_types as message_types
from footfall.messages.servo import Posture as Posture
from footfall.messages.servo import ServoStatus as ServoStatus
from footfall.messages.types import ColorImage as ColorImage
from footfall.messages.types import DepthFrame as DepthFrame
from footfall.messages.types import EffectorTargets as EffectorTargets
from footfall.messages.types import GaitState as GaitState
from footfall.messages.types import GaitStatus as GaitStatus
from footfall.messages.types import GroundPrior as GroundPrior
from footfall.messages.types import ImuReading as ImuReading
from footfall.messages.types import JointTargets as JointTargets
from footfall.messages.types import LogLine as LogLine
from footfall.messages.types import MapUpdate as MapUpdate
from footfall.messages.types import Mode as Mode
from footfall.messages.types import ModeCommand as ModeCommand
from footfall.messages.types import OdometryEstimate as OdometryEstimate
from footfall.messages.types import PoseEstimate as PoseEstimate
from footfall.messages.types import RobotState as RobotState
from footfall.messages.types import Touchdown as Touchdown
from footfall.messages.types import WalkCommand as WalkCommand

__all__ = [
    "Ack",
    "BipedPlan",
    "BipedStatus",
    "ColorImage",
    "DepthFrame",
    "EffectorTargets",
    "GaitState",
    "GaitStatus",
    "GroundPrior",
    "ImuReading",
    "JointTargets",
    "LogLine",
    "MapUpdate",
    "Message",
    "Mode",
    "ModeCommand",
    "NewMap",
    "Obstacles",
    "OdometryEstimate",
    "PlanningGoal",
    "PoseEstimate",
    "Posture",
    "RobotState",
    "ServoStatus",
    "Touchdown",
    "Trigger",
    "WalkCommand",
    "decode",
    "message_types",
]
