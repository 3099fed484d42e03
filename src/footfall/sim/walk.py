"""A simulated walk: robot, terrain, controller and control loop put together."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field

from footfall.control_loop import WalkLog, run_control_loop
from footfall.errors import ConfigError
from footfall.metrics import walk_metrics
from footfall.motion.gait import GaitConfig, WalkCommand
from footfall.motion.walker import WalkController
from footfall.robot.spec import HexapodSpec
from footfall.sim.hexapod import MujocoHexapod

TERRAINS = ("flat",)


@dataclass(frozen=True)
class WalkSettings:
    """What to simulate.

    Attributes:
        terrain: Terrain name (see ``TERRAINS``).
        seconds: Walking time [s], after the robot has settled on its feet.
        command: The walk command, held for the whole walk.
        gait: Gait parameters.
        control_rate_hz: Controller rate [Hz].
        settle_seconds: Time the robot stands still before walking [s].
        seed: Seed for everything random in the run (random terrains, sensor noise); a
            flat walk draws nothing random, and every run is deterministic.
    """

    terrain: str = "flat"
    seconds: float = 20.0
    command: WalkCommand = field(default_factory=lambda: WalkCommand(speed=0.1))
    gait: GaitConfig = field(default_factory=GaitConfig)
    control_rate_hz: float = 100.0
    settle_seconds: float = 0.5
    seed: int = 0

    def __post_init__(self) -> None:
        if self.terrain not in TERRAINS:
            raise ConfigError(
                f"unknown terrain {self.terrain!r}; choose one of {', '.join(TERRAINS)}"
            )
        if not self.seconds > 0:
            raise ConfigError(f"walk seconds must be positive, got {self.seconds}")
        if not self.control_rate_hz > 0:
            raise ConfigError(f"control rate must be positive, got {self.control_rate_hz}")


@dataclass(frozen=True)
class WalkResult:
    """Outcome of a simulated walk.

    Attributes:
        log: Per-tick record.
        metrics: Summary metrics (the ``metrics.json`` content).
        warnings: MuJoCo warnings by name; empty for a healthy simulation.
    """

    log: WalkLog
    metrics: dict[str, object]
    warnings: dict[str, int]


def simulate_walk(
    spec: HexapodSpec, settings: WalkSettings, on_tick: Callable[[float], None] | None = None
) -> WalkResult:
    """Walk the robot in MuJoCo and measure how it went.

    Args:
        spec: The robot.
        settings: What to simulate.
        on_tick: Progress callback, called with the walk time [s] after each control tick.

    Returns:
        The record, metrics and simulator warnings.
    """
    backend = MujocoHexapod(spec, body_height=settings.command.body_height)
    backend.advance(settings.settle_seconds)
    controller = WalkController(spec, settings.gait, initial_height=settings.command.body_height)
    wall_start = time.perf_counter()
    log = run_control_loop(
        backend, controller, settings.command, settings.seconds, settings.control_rate_hz, on_tick
    )
    wall_seconds = time.perf_counter() - wall_start
    metrics = walk_metrics(
        log,
        commanded_speed_mps=settings.command.speed,
        wall_seconds=wall_seconds,
        foot_radius=spec.foot_radius,
        frozen_reason=controller.frozen_reason,
    )
    metrics.update(
        {
            "robot": spec.name,
            "terrain": settings.terrain,
            "gait": settings.gait.kind.value,
            "seed": settings.seed,
            "control_rate_hz": settings.control_rate_hz,
            "commanded_body_height_m": settings.command.body_height,
            "stride_m": controller.config.stride,
        }
    )
    return WalkResult(log=log, metrics=metrics, warnings=backend.warnings())
