"""Lengths tuned on the default robot, carried over to any robot in proportion.

footfall's planning and motion settings were chosen on the default robot (``robots/
default.toml``, sized for the hexapod thesis' walking parameters). A setting that is a
length of the robot's own is given as its value on the default robot and scaled to another
robot by the ratio of the dimension it follows:

- the **leg** (femur plus tibia): margins inside a leg's workspace;
- the **lift** (``max_step_height``): a swinging foot's clearance over the terrain and the
  apex of a swing;
- the **stride** (``stride_length``): how far a foot or the body moves in a step;
- the **span** (the disc the feet at rest reach around the body centre): the support
  polygon and the room the body needs around it.

On the default robot every ratio is exactly 1, so its settings are the tuned numbers
themselves. Lengths that follow the map or the sensors rather than the robot (a cell, the
map's noise under the belly, a servo's tracking error) are not scaled.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

from footfall.robot.spec import HexapodSpec, load_spec

REFERENCE_ROBOT = "default"


def feet_span_m(spec: HexapodSpec) -> float:
    """Farthest foot at rest from the body centre, foot included [m]."""
    feet = spec.rest_feet_in_body()
    return max(math.hypot(float(x), float(y)) for x, y in feet[:, :2]) + spec.foot_radius


@dataclass(frozen=True)
class RobotScale:
    """A robot's dimensions over the default robot's (1 for the default robot itself).

    Attributes:
        leg: Femur plus tibia length.
        lift: Highest foot lift above the higher end of a swing (``max_step_height``).
        stride: Longest stride (``stride_length``).
        span: Farthest foot at rest from the body centre (:func:`feet_span_m`).
    """

    leg: float
    lift: float
    stride: float
    span: float


def _dimensions(spec: HexapodSpec) -> tuple[float, float, float, float]:
    return (
        spec.femur_length + spec.tibia_length,
        spec.max_step_height,
        spec.stride_length,
        feet_span_m(spec),
    )


@functools.cache
def _reference() -> tuple[float, float, float, float]:
    return _dimensions(load_spec(REFERENCE_ROBOT))


def robot_scale(spec: HexapodSpec) -> RobotScale:
    """How ``spec``'s leg, lift, stride and span compare with the default robot's."""
    mine, reference = _dimensions(spec), _reference()
    return RobotScale(*(a / b for a, b in zip(mine, reference, strict=True)))
