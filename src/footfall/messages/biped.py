"""The biped's messages (dissertation Fig. 67, Appendix B3): obstacles, the plan, services.

World quantities are in the map frame, z up, metres; the services' requests and replies are
messages too (``PlanningGoal`` for ``start_planning(gx, gy)``, ``NewMap`` for
``new_map(ox[], oy[])``, ``Trigger`` for ``start_capture``, ``stop_capture`` and ``clear``,
``Ack`` for every reply).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from footfall.errors import MessageError
from footfall.messages.codec import Message

BIPED_STATES = ("standing", "walking", "stopping", "fallen", "frozen")


def _same_length(name: str, *arrays: npt.NDArray) -> None:
    lengths = {len(a) for a in arrays}
    if len(lengths) > 1:
        raise MessageError(f"{name}: arrays of different lengths {sorted(lengths)}")


@dataclass(frozen=True)
class Obstacles(Message):
    """Circular obstacles on the ground.

    Attributes:
        stamp: When they were seen [s].
        x: Centres' x, shape (n,) [m].
        y: Centres' y, shape (n,) [m].
        r: Radii, shape (n,) [m].
    """

    TOPIC = "obstacles"

    stamp: float
    x: npt.NDArray[np.float64]
    y: npt.NDArray[np.float64]
    r: npt.NDArray[np.float64]

    def __post_init__(self) -> None:
        _same_length("obstacles", self.x, self.y, self.r)


@dataclass(frozen=True)
class BipedPlan(Message):
    """A planned biped walk: path, footsteps and the centre of mass's pattern.

    Attributes:
        stamp: When it was planned [s].
        waypoints: The path from start to goal, shape (k, 2) [m].
        footsteps: Foot centres and headings ``(x, y, heading)``, shape (m, 3) [m, rad].
        left: Which footsteps are left feet, shape (m,).
        com: The COM's ground track, shape (p, 2) [m].
        path_length_m: Length of the path [m].
        collisions: Path samples and footsteps that touch an obstacle (0 for a good plan).
    """

    TOPIC = "plan"

    stamp: float
    waypoints: npt.NDArray[np.float64]
    footsteps: npt.NDArray[np.float64]
    left: npt.NDArray[np.bool_]
    com: npt.NDArray[np.float64]
    path_length_m: float
    collisions: int

    def __post_init__(self) -> None:
        _same_length("plan footsteps", self.footsteps, self.left)


@dataclass(frozen=True)
class BipedStatus(Message):
    """What the walking biped is doing, where it stands and where it goes.

    Attributes:
        stamp: When it was measured [s].
        state: ``standing``, ``walking``, ``stopping`` (ending the step under way, feet
            together), ``fallen`` or ``frozen`` (a pose it could not reach).
        com: The centre of mass's ground point ``(x, y)`` [m].
        heading: Heading of the feet [rad].
        feet: Left and right sole centres and headings ``(x, y, heading)``, shape (2, 3)
            [m, rad].
        goal: The goal being walked to ``(x, y)`` [m]; NaN when there is none.
        footsteps: Footsteps taken since the robot started.
        collisions: Contacts of the body with obstacles since the robot started.
        text: Why it stopped or stands, or what it does.
    """

    TOPIC = "biped/status"

    stamp: float
    state: str
    com: npt.NDArray[np.float64]
    heading: float
    feet: npt.NDArray[np.float64]
    goal: npt.NDArray[np.float64]
    footsteps: int
    collisions: int
    text: str = ""

    def __post_init__(self) -> None:
        if self.state not in BIPED_STATES:
            raise MessageError(f"biped state must be one of {', '.join(BIPED_STATES)}")
        if np.shape(self.feet) != (2, 3) or np.shape(self.com) != (2,):
            raise MessageError("biped status: feet must be (2, 3) and the COM (2,)")


@dataclass(frozen=True)
class PlanningGoal(Message):
    """``start_planning(gx, gy)``: plan from where the robot is to a goal.

    Attributes:
        gx: Goal x [m].
        gy: Goal y [m].
    """

    TOPIC = "start_planning"

    gx: float
    gy: float

    def __post_init__(self) -> None:
        if not (math.isfinite(self.gx) and math.isfinite(self.gy)):
            raise MessageError(f"planning goal must be finite, got ({self.gx}, {self.gy})")


@dataclass(frozen=True)
class NewMap(Message):
    """``new_map(ox[], oy[])``: replace the obstacles.

    Attributes:
        ox: Obstacle centres' x, shape (n,) [m].
        oy: Obstacle centres' y, shape (n,) [m].
        radius: Their radius [m].
    """

    TOPIC = "new_map"

    ox: npt.NDArray[np.float64]
    oy: npt.NDArray[np.float64]
    radius: float = 0.2

    def __post_init__(self) -> None:
        _same_length("new_map", self.ox, self.oy)
        if not self.radius > 0:
            raise MessageError(f"new_map radius must be positive, got {self.radius}")


@dataclass(frozen=True)
class Trigger(Message):
    """A request with no arguments (``start_capture``, ``stop_capture``, ``clear``).

    Attributes:
        stamp: When it was sent [s].
    """

    TOPIC = "trigger"

    stamp: float = 0.0


@dataclass(frozen=True)
class Ack(Message):
    """A service's reply.

    Attributes:
        ok: Whether the request was carried out.
        text: What was done, or why not.
    """

    TOPIC = "ack"

    ok: bool
    text: str = ""
