"""Drive the simulated hexapod with your own control loop: a tripod walk that turns.

This is what `footfall walk` does under the hood, without the metrics and plots: the
controller turns a command into joint targets, the backend (here MuJoCo; on a real robot
its servo driver) executes them. Runs headless in a few seconds.
"""

import numpy as np

from footfall import GaitConfig, WalkCommand, WalkController, load_spec
from footfall.sim.hexapod import MujocoHexapod

CONTROL_RATE_HZ = 100.0


def main() -> None:
    spec = load_spec("default")
    robot = MujocoHexapod(spec)
    controller = WalkController(spec, GaitConfig(kind="tripod"))
    command = WalkCommand(
        direction=(1.0, 0.0), speed=0.08, yaw_rate=0.3, body_height=spec.body_height
    )
    dt = 1.0 / CONTROL_RATE_HZ
    for k in range(round(4.0 / dt)):
        robot.command(controller.update(k * dt, command))
        robot.advance(dt)
    state = robot.read()
    yaw = np.degrees(state.orientation_body_in_world.as_euler("ZYX")[0])
    print(
        f"after 4 s: body at {np.round(state.position_body_in_world, 3)} m, heading {yaw:.1f} deg"
    )
    assert not robot.warnings(), robot.warnings()


if __name__ == "__main__":
    main()
