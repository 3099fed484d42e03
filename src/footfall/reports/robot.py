"""``footfall robot``: the simulated robot on the network, until it is stopped."""

from __future__ import annotations

import signal
from collections.abc import Callable
from dataclasses import dataclass, field

from footfall.reports.walk import WalkReport, WalkRequest, prepare_walk
from footfall.runtime.zenoh_bus import ZenohBus, ZenohConfig
from footfall.sim.robot import OUTGOING, RobotSettings, run_robot


@dataclass(frozen=True)
class RobotRequest:
    """What to run (the options of ``footfall robot``).

    Attributes:
        walk: Terrain, seed, camera and gait (as for ``footfall walk``).
        network: How to join the network.
        seconds: Longest run [s].
        stop_at_goal: End at the terrain's goal.
        rates: Largest rates [Hz] of the topics sent out, overriding the defaults (None:
            every message).
    """

    walk: WalkRequest = field(default_factory=WalkRequest)
    network: ZenohConfig = field(default_factory=ZenohConfig)
    seconds: float = 600.0
    stop_at_goal: bool = False
    rates: dict[str, float | None] = field(default_factory=dict)


def run_robot_report(
    request: RobotRequest,
    on_ready: Callable[[ZenohBus], None] | None = None,
    on_tick: Callable[[float], None] | None = None,
) -> WalkReport:
    """Run the simulated robot until the time is up, the goal, a fall, or SIGINT/SIGTERM.

    Args:
        request: What to run.
        on_ready: Called with the network bus once it is open (to print its locators).
        on_tick: Called with the run time [s] after each tick.
    """
    job = prepare_walk(request.walk)
    stop = {"asked": False}

    def ask_to_stop(signum: int, frame: object) -> None:
        stop["asked"] = True

    previous = {s: signal.signal(s, ask_to_stop) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        with ZenohBus(request.network) as network:
            if on_ready is not None:
                on_ready(network)
            settings = RobotSettings(
                walk=job.settings,
                seconds=request.seconds,
                stop_at_goal=request.stop_at_goal,
                outgoing={**OUTGOING, **request.rates},
            )
            result, _ = run_robot(
                job.spec, settings, network, on_tick=on_tick, should_stop=lambda: stop["asked"]
            )
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)
    return WalkReport(job, result)
