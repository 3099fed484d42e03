"""The servo node's own report: the robot's posture and its servos' health."""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum

import numpy as np
import numpy.typing as npt

from footfall.messages.codec import Message


class Posture(StrEnum):
    """What the servo node is doing with the legs."""

    LIMP = "limp"  # torque off
    RISING = "rising"  # standing up from where the legs were
    STANDING = "standing"  # the walking controller's targets go to the servos
    SITTING = "sitting"  # lowering the body before the torque goes off
    HALTED = "halted"  # a servo fault: nothing more is sent


@dataclass(frozen=True)
class ServoStatus(Message):
    """The servo node's posture and, from servos that report it, their health.

    Attributes:
        stamp: When [s].
        posture: What the legs are doing.
        fault: Why the servos stopped taking targets, naming the servo ("" when they did
            not).
        temperatures_c: Each joint's servo temperature, shape (18,) [deg C], legs in the
            spec's order (NaN before a first reading); None when the robot has no such
            sensors (a simulator).
        voltages_v: Each servo's supply voltage, shape (18,) [V], or None.
        loads: Each servo's load as a fraction of its stall torque, shape (18,), or None.
    """

    TOPIC = "servo"

    stamp: float
    posture: Posture
    fault: str = ""
    temperatures_c: npt.NDArray[np.float64] | None = None
    voltages_v: npt.NDArray[np.float64] | None = None
    loads: npt.NDArray[np.float64] | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "posture", Posture(self.posture))
