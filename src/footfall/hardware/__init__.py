"""A real hexapod's servos: Dynamixel buses, their servos, and an emulator to dry-run them.

- :mod:`~footfall.hardware.config`: the ``[hardware]`` table of a robot's TOML.
- :mod:`~footfall.hardware.dynamixel`: the backend on ``dynamixel-sdk`` (``--backend
  dynamixel``).
- :mod:`~footfall.hardware.emulator` and :mod:`~footfall.hardware.emulated_servos`: servos
  answering on a pseudo-terminal.
- :mod:`~footfall.hardware.servo_bus`: the simulated robot behind that bus (``footfall walk
  --servo-bus``).
"""
