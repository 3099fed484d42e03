"""``footfall robot``: the simulated robot on the network, until it is stopped."""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from footfall.recording.session import Recorders
from footfall.reports.walk import WalkReport
from footfall.runtime.bus import InProcessBus
from footfall.runtime.scheduler import stop_on_signals
from footfall.runtime.zenoh_bus import ZenohBus, ZenohConfig
from footfall.sim.robot import OUTGOING, RobotSettings, run_robot
from footfall.sim.walk_request import WalkRequest, prepare_walk


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
        foxglove: ``(host, port)`` to serve the robot's own bus on over Foxglove's
            WebSocket protocol, or None.
    """

    walk: WalkRequest = field(default_factory=WalkRequest)
    network: ZenohConfig = field(default_factory=ZenohConfig)
    seconds: float = 600.0
    stop_at_goal: bool = False
    rates: dict[str, float | None] = field(default_factory=dict)
    foxglove: tuple[str, int] | None = None


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
    with stop_on_signals() as stop, ZenohBus(request.network) as network:
        if on_ready is not None:
            on_ready(network)
        settings = RobotSettings(
            walk=job.settings,
            seconds=request.seconds,
            stop_at_goal=request.stop_at_goal,
            outgoing={**OUTGOING, **request.rates},
        )
        w = request.walk
        local = InProcessBus()
        live = None
        if request.foxglove is not None:
            from footfall.recording.foxglove_live import FoxgloveLive

            live = FoxgloveLive(request.foxglove[1], host=request.foxglove[0])
            local.tap(live.tap)
        try:
            with Recorders(w.record, w.rerun, w.rerun_spawn) as recorders:
                result, _ = run_robot(
                    job.spec,
                    settings,
                    network,
                    on_tick=on_tick,
                    should_stop=stop,
                    local=recorders.attach(local),
                    on_build=lambda robot: (
                        recorders.mapping_started(robot.mapping)
                        if robot.mapping is not None
                        else None
                    ),
                )
        finally:
            if live is not None:
                live.close()
    return WalkReport(job, result)


@dataclass(frozen=True)
class BipedRequest:
    """What ``footfall robot --biped`` serves.

    Attributes:
        case: One of the dissertation's maps as what the capture sees, or None.
        map: A map file as what the capture sees, or None.
        cloud: A point cloud whose detected obstacles the capture sees, or None.
        room: Seed of a room where Archie walks in MuJoCo, seeing through its head camera
            and walking the goals planned to; None: the planning node alone.
        look_ahead_m: In a room, how far to walk along a plan between looks [m].
        network: How to join the network.
        seconds: Longest run [s].
    """

    case: int | None = None
    map: Path | None = None
    cloud: Path | None = None
    room: int | None = None
    look_ahead_m: float = 1.0
    network: ZenohConfig = field(default_factory=ZenohConfig)
    seconds: float = 600.0


def run_biped(
    request: BipedRequest,
    on_ready: Callable[[ZenohBus], None] | None = None,
    rate_hz: float = 10.0,
) -> dict[str, object]:
    """Serve the biped's planning node until the time is up or SIGINT/SIGTERM.

    Returns:
        What was served: the services and how many obstacles the capture sees.
    """
    from footfall.biped.maps import dissertation_map, load_map
    from footfall.nodes.biped_planning import SERVICES, BipedPlanningNode

    if request.room is not None:
        return run_walking_biped(request, on_ready)
    if request.cloud is not None:
        from footfall.reports.biped import CloudRequest, detect

        circles, start, name = detect(CloudRequest(request.cloud)).circles, (0.0, 0.0), "cloud"
    else:
        plan_map = (
            load_map(request.map)
            if request.map is not None
            else dissertation_map(request.case or 1)
        )
        circles, start, name = plan_map.obstacles, plan_map.start, plan_map.name
    with stop_on_signals() as stop, ZenohBus(request.network) as network:
        node = BipedPlanningNode(network, circles, start, name)
        if on_ready is not None:
            on_ready(network)
        end = time.monotonic() + request.seconds
        while not stop() and time.monotonic() < end:
            network.spin(1.0 / rate_hz)
            node.tick()
    return {"services": list(SERVICES), "obstacles_in_view": len(circles), "map": name}


def run_walking_biped(
    request: BipedRequest,
    on_ready: Callable[[ZenohBus], None] | None = None,
    spin_s: float = 0.002,
) -> dict[str, object]:
    """Archie in its room on the network, paced to the wall clock, until stopped.

    Returns:
        What was served and how the walk went: state, footsteps, collisions, the COM.
    """
    from footfall.nodes.biped_planning import SERVICES
    from footfall.sim.biped_robot import WalkingBiped
    from footfall.sim.biped_room import make_room

    room = make_room(request.room)
    with stop_on_signals() as stop, ZenohBus(request.network) as network:
        robot = WalkingBiped.build(network, room, look_ahead_m=request.look_ahead_m)
        try:
            if on_ready is not None:
                on_ready(network)
            end = time.monotonic() + request.seconds
            while not stop() and time.monotonic() < end:
                network.spin(spin_s)
                robot.tick(time.monotonic())
            robot.walker.publish_status()
        finally:
            robot.close()
    walker = robot.walker
    return {
        "services": list(SERVICES),
        "map": room.name,
        "state": walker.state,
        "footsteps": walker.footsteps_taken,
        "collisions": robot.sim.collisions,
        "com": robot.sim.com()[:2].tolist(),
        "late_s": walker.late_s,
    }
