"""The subcommands: each one's module and line of help, known without importing them.

``footfall --help`` lists them from here alone; a command's own options are built (and its
module imported, with what it needs) only when that command is asked for.
"""

from __future__ import annotations

COMMANDS = {
    "walk": ("footfall.cli.walk", "simulate the hexapod walking across a terrain and measure it"),
    "map": (
        "footfall.cli.map",
        "build a height map and score map, in simulation or from a recorded sequence",
    ),
    "replay": (
        "footfall.cli.replay",
        "replay a recording (footfall MCAP, ROS 2 bag, ROS 1 bag) into a map",
    ),
    "convert": (
        "footfall.cli.convert",
        "convert recorded data: Redwood to the TUM layout, TUM or Redwood to MCAP",
    ),
    "odometry": (
        "footfall.cli.odometry",
        "track a depth sequence's camera from its own images (visual odometry)",
    ),
    "bench": ("footfall.cli.bench", "measure footfall's speed"),
    "plan": (
        "footfall.cli.plan",
        "plan a biped's path, footsteps and centre-of-mass pattern around obstacles",
    ),
    "obstacles": ("footfall.cli.obstacles", "detect obstacles in a point cloud"),
    "robot": (
        "footfall.cli.robot",
        "run the hexapod as a robot on the network, driven by a base station",
    ),
    "servo-bus": (
        "footfall.cli.servo_bus",
        "serve the simulated robot's servos on a pseudo-terminal and its camera on the "
        "network, for a dry run of footfall robot --hardware",
    ),
    "station": (
        "footfall.cli.station",
        "the base station: a browser page to watch and drive the robot",
    ),
    "walk-biped": (
        "footfall.cli.walk_biped",
        "simulate the biped Archie walking its plan around obstacles",
    ),
}


def summary(name: str) -> str:
    """The one line of help of a subcommand."""
    return COMMANDS[name][1]
