"""What the robot has said, as the base station last heard it."""

from __future__ import annotations

import math
import time
from collections import deque
from dataclasses import dataclass, field

import numpy as np

from footfall.messages import (
    BipedPlan,
    BipedStatus,
    ColorImage,
    DepthFrame,
    EffectorTargets,
    GaitStatus,
    LogLine,
    MapUpdate,
    Obstacles,
    RobotState,
    ServoStatus,
    Touchdown,
)

# Footholds and log lines the page keeps.
FOOTHOLDS_KEPT = 120
LOG_LINES_KEPT = 8


@dataclass
class RobotView:
    """The newest of each message from the robot, the latest footholds and log lines.

    Attributes:
        status: Gait status (mode, state, pose), or None before the first.
        state: Robot state (attitude), or None.
        targets: Effector targets (where the feet go, which swing), or None.
        depth: Depth image, or None.
        color: Colour image, or None.
        map: Map update, or None.
        obstacles: The biped's obstacles, or None.
        plan: The biped's plan, or None.
        biped: The walking biped's status, or None.
        servos: The servo node's posture and servo health, or None.
        footholds: Chosen footholds, newest last, shape (3,) each [m].
        log: Log lines, formatted for the page.
        last_heard: ``time.monotonic()`` of the last message that shows the link is up.
    """

    status: GaitStatus | None = None
    state: RobotState | None = None
    targets: EffectorTargets | None = None
    depth: DepthFrame | None = None
    color: ColorImage | None = None
    map: MapUpdate | None = None
    obstacles: Obstacles | None = None
    plan: BipedPlan | None = None
    biped: BipedStatus | None = None
    servos: ServoStatus | None = None
    footholds: deque[np.ndarray] = field(default_factory=lambda: deque(maxlen=FOOTHOLDS_KEPT))
    log: deque[str] = field(default_factory=lambda: deque(maxlen=LOG_LINES_KEPT))
    last_heard: float = -math.inf

    def listen(self, bus) -> None:
        """Subscribe to the robot's topics on ``bus``."""
        for topic, handler in (
            (GaitStatus.TOPIC, self._on_status),
            (RobotState.TOPIC, self._on_state),
            (EffectorTargets.TOPIC, self._on_targets),
            (DepthFrame.TOPIC, self._on_depth),
            (ColorImage.TOPIC, self._on_color),
            (MapUpdate.TOPIC, self._on_map),
            (Touchdown.TOPIC, self._on_touchdown),
            (LogLine.TOPIC, self._on_log),
            (Obstacles.TOPIC, self._on_obstacles),
            (BipedPlan.TOPIC, self._on_plan),
            (BipedStatus.TOPIC, self._on_biped),
            (ServoStatus.TOPIC, self._on_servos),
        ):
            bus.subscribe(topic, handler)

    def _heard(self) -> None:
        self.last_heard = time.monotonic()

    def _on_status(self, m: GaitStatus) -> None:
        self._heard()
        self.status = m

    def _on_state(self, m: RobotState) -> None:
        self._heard()
        self.state = m

    def _on_targets(self, m: EffectorTargets) -> None:
        self.targets = m

    def _on_depth(self, m: DepthFrame) -> None:
        self._heard()
        self.depth = m

    def _on_color(self, m: ColorImage) -> None:
        self.color = m

    def _on_map(self, m: MapUpdate) -> None:
        self.map = m

    def _on_touchdown(self, m: Touchdown) -> None:
        self.footholds.append(np.asarray(m.chosen_in_world, dtype=np.float32))

    def _on_obstacles(self, m: Obstacles) -> None:
        self._heard()
        self.obstacles = m

    def _on_plan(self, m: BipedPlan) -> None:
        self._heard()
        self.plan = m

    def _on_biped(self, m: BipedStatus) -> None:
        self._heard()
        self.biped = m

    def _on_servos(self, m: ServoStatus) -> None:
        self._heard()
        self.servos = m

    def _on_log(self, m: LogLine) -> None:
        self.log.append(f"`{m.stamp:8.2f}` {m.node} {m.level}: {m.text}")
