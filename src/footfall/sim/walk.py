"""A simulated walk: the robot's nodes, its navigator and its task, run to the end.

The robot itself is put together in :mod:`footfall.sim.assembly`; what to walk is
:class:`~footfall.sim.walk_settings.WalkSettings`.
"""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np

from footfall.nodes.navigation import NavigatorNode
from footfall.robot.spec import HexapodSpec
from footfall.runtime.bus import Bus, InProcessBus
from footfall.runtime.faults import TickFaults
from footfall.runtime.scheduler import SimulatedScheduler, WallClockScheduler
from footfall.sim.assembly import WalkingRobot
from footfall.sim.task import TerrainTask
from footfall.sim.terrain import Terrain
from footfall.sim.terrains import make_terrain
from footfall.sim.walk_metrics import CommandTiming, NavigationMetrics, WalkMetrics
from footfall.sim.walk_settings import WalkResult, WalkSettings


def simulate_walk(
    spec: HexapodSpec,
    settings: WalkSettings,
    on_tick: Callable[[float], None] | None = None,
    terrain: Terrain | None = None,
    bus: Bus | None = None,
    on_build: Callable[[WalkingRobot], None] | None = None,
) -> WalkResult:
    """Walk the robot across a terrain in MuJoCo, towards the terrain's goal.

    The run is a graph of nodes on one bus: the simulated camera and pose source, the
    mapping node, the movement and servo nodes on the MuJoCo backend, and the task that
    steers to the goal and ends the run.

    Args:
        spec: The robot.
        settings: What to simulate.
        on_tick: Progress callback, called with the walk time [s] after each control tick.
        terrain: A terrain object to use instead of ``settings.terrain`` (custom terrains).
        bus: The bus to run the nodes on; a new in-process bus by default.
        on_build: Called with the robot once its nodes stand (a recorder notes the mapping
            node's settings).

    Returns:
        The record, metrics and simulator warnings.
    """
    terrain = terrain or make_terrain(settings.terrain, seed=settings.seed)
    bus = bus if bus is not None else InProcessBus()
    robot = WalkingRobot.build(spec, settings, terrain, bus)
    if on_build is not None:
        on_build(robot)
    meter = robot.meter
    navigator = (
        NavigatorNode(
            bus,
            spec,
            config=settings.navigation,
            background=settings.realtime,
            meter=meter,
            foothold_search_m=settings.planner.footholds.search_radius,
        )
        if settings.navigates
        else None
    )
    task = TerrainTask(
        bus,
        terrain,
        settings.command,
        settings.stop_at_goal,
        goal=settings.goal,
        navigator=navigator,
    )
    task.begin()
    scheduler = (
        WallClockScheduler(settings.control_rate_hz)
        if settings.realtime
        else SimulatedScheduler(settings.control_rate_hz)
    )
    dt = scheduler.period
    overruns = TickFaults(robot.link, dt) if robot.link is not None else None

    command_seconds: list[float] = []

    def tick(t: float) -> bool:
        if overruns is not None and overruns.skips(t):
            return False  # an earlier tick ran over this one's slot; the physics goes on
        t0 = time.perf_counter()
        with meter.measure("sim_task"):  # steering to the goal; the navigator's work is its own
            task.command(t)  # with a navigator: hands maps over, and replans when not background
        command_seconds.append(time.perf_counter() - t0)
        robot.step(t, dt)
        if on_tick is not None:
            on_tick(t + dt)
        return task.should_stop(t + dt)

    wall_start = time.perf_counter()
    scheduler.run(tick, settings.seconds)
    wall_seconds = time.perf_counter() - wall_start
    robot.close()
    result = robot.result(task, wall_seconds, scheduler)
    if navigator is not None:
        navigator.close()
    metrics = result.metrics
    if isinstance(metrics, WalkMetrics):
        if navigator is not None:
            metrics.navigation = navigation_metrics(navigator)
        if command_seconds:
            # How long the command step of a control tick took: a replan that held the tick
            # up shows here as its own duration.
            median, p99, top = 1e3 * np.percentile(command_seconds, [50.0, 99.0, 100.0])
            metrics.commands = CommandTiming(float(median), float(p99), float(top))
        metrics.navigated = navigator is not None
    return result


def navigation_metrics(navigator: NavigatorNode) -> NavigationMetrics:
    """What the navigator did: whether it found no route and why, replans and their times."""
    return NavigationMetrics(
        no_route=navigator.no_route is not None,
        no_route_reason=navigator.no_route.reason if navigator.no_route is not None else "",
        **navigator.timing(),
    )
