"""Drive the simulated hexapod with your own control loop: a tripod walk that turns.

This is what `footfall walk` does under the hood, without the camera, metrics and plots:
on a bus, the movement node turns each command into effector targets, the servo node turns
those into joint targets for the backend (here MuJoCo; on a real robot its servo driver).
Runs headless in a few seconds.
"""

import numpy as np

from footfall import GaitConfig, InProcessBus, Mode, WalkCommand, WalkController, load_spec
from footfall.control_loop import WalkingGraph
from footfall.messages import ModeCommand
from footfall.sim.hexapod import MujocoHexapod

CONTROL_RATE_HZ = 100.0


def main() -> None:
    spec = load_spec("default")
    robot = MujocoHexapod(spec)
    controller = WalkController(spec, GaitConfig(kind="tripod"))
    command = WalkCommand(
        direction=(1.0, 0.0), speed=0.08, yaw_rate=0.3, body_height=spec.body_height
    )
    bus = InProcessBus()
    graph = WalkingGraph.build(bus, robot, controller)
    bus.publish(ModeCommand.TOPIC, ModeCommand(Mode.WALKING))  # servos start limp
    dt = 1.0 / CONTROL_RATE_HZ
    for k in range(round(4.0 / dt)):
        bus.publish(WalkCommand.TOPIC, command)
        graph.step(k * dt, dt)  # movement -> servo -> robot, then the robot's new state
    state = robot.read()
    yaw = np.degrees(state.orientation_body_in_world.as_euler("ZYX")[0])
    print(
        f"after 4 s: body at {np.round(state.position_body_in_world, 3)} m, heading {yaw:.1f} deg"
    )
    assert not robot.warnings(), robot.warnings()


if __name__ == "__main__":
    main()
