"""Lengths tuned on the default robot, carried over to any robot in proportion.

footfall's planning and motion settings were chosen on the default robot (``robots/
default.toml``, sized for the hexapod thesis' walking parameters). A setting that is a
length of the robot's own is given as its value on the default robot and scaled to another
robot by the ratio of the dimension it follows:

- the **stride** (``stride_length``): how far a foot or the body moves in a step;
- the **span** (the disc the feet at rest reach around the body centre): the support
  polygon and the room the body needs around it.

On the default robot every ratio is exactly 1, so its settings are the tuned numbers
themselves. Lengths that follow the map, the sensors or the servos rather than the robot's
size are not scaled: a cell, the map's error under a swing or the belly, the servos'
tracking (the footholds' margin inside a leg's workspace; measured on the PhantomX, scaled
to its shorter legs, its ripple gait put feet on invalid cells).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from footfall.robot.spec import HexapodSpec, load_spec

REFERENCE_ROBOT = "default"


def feet_span_m(spec: HexapodSpec) -> float:
    """Farthest foot at rest from the body centre, foot included [m]."""
    feet = spec.rest_feet_in_body()[:, :2]
    return float(np.max(np.hypot(feet[:, 0], feet[:, 1]))) + spec.foot_radius


@dataclass(frozen=True)
class RobotScale:
    """A robot's dimensions over the default robot's (1 for the default robot itself).

    Attributes:
        stride: Longest stride (``stride_length``).
        span: Farthest foot at rest from the body centre (:func:`feet_span_m`).
    """

    stride: float
    span: float


def _dimensions(spec: HexapodSpec) -> tuple[float, float]:
    return (spec.stride_length, feet_span_m(spec))


@functools.cache
def _reference() -> tuple[float, float]:
    return _dimensions(load_spec(REFERENCE_ROBOT))


def robot_scale(spec: HexapodSpec) -> RobotScale:
    """How ``spec``'s stride and span compare with the default robot's."""
    mine, reference = _dimensions(spec), _reference()
    return RobotScale(*(a / b for a, b in zip(mine, reference, strict=True)))
