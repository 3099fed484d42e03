"""The robot backends ``footfall robot --backend`` chooses among: one line each.

Entries name their module as ``"module:Class"``, imported only when chosen, so a hardware
backend's libraries are never loaded by a run that does not use it.
"""

from __future__ import annotations

from footfall.backends import BackendFactory
from footfall.registry import Registry

BACKENDS: Registry[BackendFactory] = Registry("robot backend")

BACKENDS.register("sim", "footfall.sim.hexapod:MujocoHexapod")
BACKENDS.register("mock", "footfall.backends.mock:MockHexapod")
BACKENDS.register("dynamixel", "footfall.hardware.dynamixel:DynamixelHexapod")
BACKENDS.register("servo-bus", "footfall.hardware.servo_bus:ServoBusHexapod")
