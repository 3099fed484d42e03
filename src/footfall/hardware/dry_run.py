"""``footfall servo-bus``: the simulated robot's servos and camera, as a real robot's are.

For a dry run of a robot's configuration before it is powered: the MuJoCo robot's joints
are turned by emulated Dynamixel servos on a pseudo-terminal (a symbolic link names it, as
``/dev/serial/by-id/...`` names an adapter), at the wall clock's pace, and its camera's
depth and colour images and their poses go out on the network under the sender's name.
``footfall robot --hardware robot.toml --port LINK --camera network --pose network`` then
runs the real robot's process against it, and a station drives it.

The servos power up with their torque off, as real ones do: the robot lies down, and
stands up when the robot process turns the torque on.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from footfall.hardware.config import HardwareConfig
from footfall.hardware.emulated_servos import EmulatedServos
from footfall.hardware.emulator import EmulatedBus
from footfall.hardware.servo_bus import step_with_servos
from footfall.messages import ColorImage, DepthFrame, PoseEstimate
from footfall.robot.spec import HexapodSpec
from footfall.runtime.bridge import Bridge
from footfall.runtime.bus import Bus, InProcessBus
from footfall.runtime.scheduler import WallClockScheduler
from footfall.sim.hexapod import MujocoHexapod
from footfall.sim.model import CameraMount
from footfall.sim.sensors import SimCameraNode, SimPoseNode
from footfall.sim.terrain import Terrain

# What goes out to the network, with the largest rates [Hz] (None: every message).
SENT = {DepthFrame.TOPIC: None, ColorImage.TOPIC: 5.0, PoseEstimate.TOPIC: None}


@dataclass(frozen=True)
class DryRunReport:
    """What a dry run served.

    Attributes:
        sim_seconds: Simulated (and wall-clock) time served [s].
        packets: Instruction and status packets on the bus.
        errors: Status packets with an error, and corrupted instructions.
        frames: Depth images sent.
        body_height_m: Body height above the start's ground at the end [m].
    """

    sim_seconds: float
    packets: int
    errors: int
    frames: int
    body_height_m: float


def serve_servo_bus(
    spec: HexapodSpec,
    config: HardwareConfig,
    terrain: Terrain,
    network: Bus,
    link: Path,
    seconds: float,
    should_stop: Callable[[], bool] | None = None,
    mount: CameraMount | None = None,
    on_ready: Callable[[EmulatedBus], None] | None = None,
    rate_hz: float = 100.0,
) -> DryRunReport:
    """Serve the robot's servos at ``link`` and its camera on ``network``.

    It runs until ``seconds`` pass or ``should_stop`` says so.

    Args:
        spec: The robot.
        config: Its servo bus (the port is ignored: the pseudo-terminal is the port).
        terrain: What it stands on.
        network: Where the images and poses go.
        link: The symbolic link to create to the pseudo-terminal.
        seconds: Longest run [s].
        should_stop: Ends the run when it returns True (a signal handler's flag).
        mount: The camera; the default D435i-like mount when None.
        on_ready: Called with the bus once it answers.
        rate_hz: Rate the physics and camera are paced at [Hz].
    """
    mount = mount or CameraMount()
    simulator = MujocoHexapod(spec, terrain, camera=mount)
    servos = EmulatedServos(config)
    servos.start(simulator.joints()[0], torque=False)
    local = InProcessBus()
    camera = SimCameraNode(local, simulator, mount, color=True)
    SimPoseNode(local, camera, topic=PoseEstimate.TOPIC)
    bridge = Bridge(local, network, SENT, ())
    bus = EmulatedBus(servos, link=link)
    scheduler = WallClockScheduler(rate_hz)
    dt = scheduler.period
    ground = float(terrain.height(*terrain.start))
    try:
        if on_ready is not None:
            on_ready(bus)

        def tick(t: float) -> bool:
            step_with_servos(simulator, servos, dt)
            camera.tick(t + dt)
            bridge.spin()
            return should_stop is not None and should_stop()

        scheduler.run(tick, seconds)
    finally:
        camera.close()
        bus.close()
    return DryRunReport(
        sim_seconds=float(simulator.data.time),
        packets=bus.counts.packets,
        errors=bus.counts.errors,
        frames=camera.frames,
        body_height_m=simulator.body_height_above(ground),
    )
