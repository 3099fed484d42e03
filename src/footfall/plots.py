"""Figures of a walk, in the style of the hexapod thesis (Fig. 8.2)."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only; never needs a display

import matplotlib.pyplot as plt
import numpy as np

from footfall.control_loop import WalkLog
from footfall.metrics import GroundHeight, flat_ground


def plot_walk(
    log: WalkLog,
    path: Path,
    leg: int = 0,
    leg_name: str = "LF",
    ground: GroundHeight = flat_ground,
    title: str = "",
) -> Path:
    """Body height, roll and pitch, and one foot's height over time and side view, as a PNG.

    Args:
        log: The record of the walk.
        path: Output file.
        leg: Index of the leg whose foot is drawn.
        leg_name: Its name, for the legend.
        ground: Ground height, to plot the body height above it.
        title: Figure title.

    Returns:
        The path written.
    """
    t = log.array("time")
    body = log.array("body_position_in_world")
    height = body[:, 2] - ground(body[:, 0], body[:, 1])
    feet = log.array("feet_in_world")[:, leg]
    commanded_feet = log.array("feet_commanded_in_world")[:, leg]

    fig, axes = plt.subplots(4, 1, figsize=(9, 11), constrained_layout=True)
    ax = axes[0]
    ax.plot(t, 100 * height, label="measured")
    ax.plot(t, 100 * log.array("commanded_height"), "--", label="commanded")
    ax.set_ylabel("body height [cm]")
    ax.set_xlabel("time [s]")
    ax.legend(loc="lower right")
    ax.grid(alpha=0.3)

    ax = axes[1]
    ax.plot(t, np.degrees(log.array("roll")), label="roll")
    ax.plot(t, np.degrees(log.array("pitch")), label="pitch")
    ax.set_ylabel("body tilt [deg]")
    ax.set_xlabel("time [s]")
    ax.legend(loc="lower right")
    ax.grid(alpha=0.3)

    ax = axes[2]
    ax.plot(t, 100 * feet[:, 2], label=f"{leg_name} foot z, measured")
    ax.plot(t, 100 * commanded_feet[:, 2], ":", color="gray", label=f"{leg_name} foot z, commanded")
    ax.set_ylabel("foot height [cm]")
    ax.set_xlabel("time [s]")
    ax.legend(loc="upper right")
    ax.grid(alpha=0.3)

    ax = axes[3]
    ax.plot(100 * feet[:, 0], 100 * feet[:, 2], label=f"{leg_name} foot, measured")
    ax.plot(
        100 * commanded_feet[:, 0],
        100 * commanded_feet[:, 2],
        ":",
        color="gray",
        label=f"{leg_name} foot, commanded",
    )
    ax.set_xlabel("foot x in the world [cm]")
    ax.set_ylabel("foot z [cm]")
    ax.set_aspect("equal", adjustable="datalim")
    ax.legend(loc="upper right")
    ax.grid(alpha=0.3)
    if title:
        fig.suptitle(title)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
