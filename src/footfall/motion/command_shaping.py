"""Command shaping: the operator's command turned into a body twist the legs can follow.

The commanded velocity is capped at the gait's top speed, and both it and the yaw rate are
rate limited (``GaitConfig.acceleration_limit``, ``yaw_acceleration_limit``), so a step
change of command never asks the legs for a jump.
"""

from __future__ import annotations

import math

import numpy as np
import numpy.typing as npt

from footfall.messages import WalkCommand
from footfall.motion.gait import GaitConfig


class CommandShaper:
    """The rate-limited body twist, and what the last command asked for.

    Args:
        config: Gait parameters (speed cap and rate limits).
        body_height: Body height commanded at start [m].

    Attributes:
        velocity: Body velocity in the body frame after the rate limits [m/s].
        yaw_rate: Yaw rate after its rate limit [rad/s].
        target_velocity: The velocity the rate limits are moving towards: the last
            command's, capped at the gait's top speed [m/s].
        target_yaw_rate: The yaw rate they are moving towards [rad/s].
        last_walk_direction: Unit direction of the last command that asked for motion.
        body_height: The last commanded body height [m].
        last_command: The last command, or None before the first.
    """

    def __init__(self, config: GaitConfig, body_height: float) -> None:
        self.config = config
        self.velocity = (0.0, 0.0)
        self.yaw_rate = 0.0
        self.target_velocity = (0.0, 0.0)
        self.target_yaw_rate = 0.0
        self.last_walk_direction = np.array([1.0, 0.0])
        self.body_height = body_height
        self.last_command: WalkCommand | None = None

    def shape(self, command: WalkCommand, dt: float) -> None:
        """Move the twist toward ``command`` by at most the rate limits over ``dt`` [s]."""
        self.last_command = command
        self.body_height = command.body_height
        vx, vy = command.velocity_in_body
        speed = math.hypot(vx, vy)
        if speed > self.config.max_speed:
            vx, vy = vx * self.config.max_speed / speed, vy * self.config.max_speed / speed
        self.target_velocity, self.target_yaw_rate = (vx, vy), command.yaw_rate
        if speed > 0:
            self.last_walk_direction = np.array([vx, vy]) / math.hypot(vx, vy)
        dv = np.array([vx - self.velocity[0], vy - self.velocity[1]])
        limit = self.config.acceleration_limit * dt
        norm = float(np.hypot(*dv))
        if norm > limit:
            dv *= limit / norm
        self.velocity = (self.velocity[0] + dv[0], self.velocity[1] + dv[1])
        yaw_limit = self.config.yaw_acceleration_limit * dt
        self.yaw_rate += float(np.clip(command.yaw_rate - self.yaw_rate, -yaw_limit, yaw_limit))

    def stop(self) -> None:
        """Standstill at once (a robot resuming from a freeze starts from rest)."""
        self.velocity, self.yaw_rate = (0.0, 0.0), 0.0

    @property
    def walking(self) -> bool:
        """Whether the body translates."""
        return math.hypot(*self.velocity) > 1e-6

    @property
    def moving(self) -> bool:
        """Whether the body translates or turns."""
        return self.walking or abs(self.yaw_rate) > 1e-6

    def foot_speed(self, rest_in_body: npt.NDArray[np.float64]) -> float:
        """Fastest ground speed of a rest foot under the twist or the one it heads to [m/s].

        A step is timed for it: a step started while the body accelerates (from rest, or
        out of a turn) would otherwise last as long as a slow step while the body travels
        as far as a fast one, and the supporting feet would trail beyond their stroke.
        """
        rest = rest_in_body[:, :2]
        top = 0.0
        for (vx, vy), yaw_rate in (
            (self.velocity, self.yaw_rate),
            (self.target_velocity, self.target_yaw_rate),
        ):
            speeds = np.hypot(vx - yaw_rate * rest[:, 1], vy + yaw_rate * rest[:, 0])
            top = max(top, float(speeds.max()))
        return top
