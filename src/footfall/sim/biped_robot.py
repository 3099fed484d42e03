"""The walking biped on the network: Archie in MuJoCo, paced to the wall clock.

``footfall robot --biped --room SEED`` runs the robot's side: the simulated Archie in a
seeded room, its head camera feeding the planning node (dissertation A6) and a walking node
that walks the footsteps of each plan. A goal planned to through ``start_planning`` is
walked as ``footfall walk-biped`` walks a room: look, plan from where the feet stand, walk
at most ``look_ahead_m`` of the path, stop with the feet together, look again, until the
COM is at the goal.

The watchdog follows the hexapod's rules: the robot walks only while the station's mode
command (``walking``) keeps arriving. When it stops (the station closed, the link lost) or
asks for another mode, the step under way finishes on its foothold, the other foot comes
beside it, and the robot stands; the goal is dropped. A new goal while walking takes
effect the same way: the robot ends its step, stands, and plans from there.

Frames: the world (map) frame, z up, the robot starting at the room's start facing +x.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from footfall.biped.body import SIDES, load_biped_spec
from footfall.biped.footsteps import Footsteps, StepLimits, plan_footsteps
from footfall.biped.gait import gait_pattern, stop_after_step
from footfall.biped.lipm import LipmConfig
from footfall.biped.planner import WalkPlan, plan_walk
from footfall.errors import FootfallError
from footfall.messages import BipedStatus, Mode, ModeCommand
from footfall.nodes.biped_planning import BipedPlanningNode
from footfall.runtime.bus import Bus
from footfall.sim.biped_room import Room
from footfall.sim.biped_run import (
    body_plan_map,
    gait_config,
    near_goal,
    stand_in_room,
    standing_feet,
    truncate_path,
)
from footfall.sim.biped_sim import BipedSimulation
from footfall.sim.biped_walk import CONTROL_PERIOD, PatternRunner, StabiliserConfig

# The robot walks only while the station's mode command is this fresh [s].
COMMAND_TIMEOUT = 0.5
# Behind the wall clock by more than this, the walk slows down rather than hurry [s].
MAX_LAG = 0.25
STATUS_HZ = 10.0
# While capturing, the head camera looks this often between the looks of each plan [s].
LOOK_PERIOD = 1.0


class BipedWalkerNode:
    """Walks the planned footsteps in the simulation, one control tick at a time.

    Args:
        bus: The bus (mode commands in, the biped's status out).
        sim: The simulation, the robot standing.
        plan: Plans from where the feet stand to a goal (the planning node's ``plan_to``).
        z_c: Height of the COM, ``z_c`` of the cart-table model [m].
        lipm: The pendulum's settings (the step time).
        limits: Step limits of the footsteps.
        look_ahead_m: How far to walk along a plan before looking and planning again [m].
        stabiliser: Gains of the stabiliser.
        command_timeout: The watchdog's limit [s].
    """

    name = "biped_walker"

    def __init__(
        self,
        bus: Bus,
        sim: BipedSimulation,
        plan: Callable[[tuple[float, float]], WalkPlan],
        z_c: float,
        lipm: LipmConfig,
        limits: StepLimits,
        look_ahead_m: float = 1.0,
        stabiliser: StabiliserConfig | None = None,
        command_timeout: float = COMMAND_TIMEOUT,
    ) -> None:
        self.bus = bus
        self.sim = sim
        self.plan = plan
        self.z_c = z_c
        self.lipm = lipm
        self.gait = gait_config(sim.spec, lipm)
        self.look_ahead_m = look_ahead_m
        self.stabiliser = stabiliser
        self.command_timeout = command_timeout
        self.state = "standing"
        self.text = "standing: waiting for a goal"
        self.goal: tuple[float, float] | None = None
        self.footsteps_taken = 0
        self.late_s = 0.0  # how far the walk fell behind the wall clock, summed [s]
        self.runner: PatternRunner | None = None
        self._footsteps: Footsteps | None = None
        self._mode: Mode | None = None
        self._heard = -math.inf
        self._t0 = 0.0  # wall-clock time of the runner's (or the standing sim's) zero [s]
        self._sim_t = 0.0  # simulated time since standing began [s]
        self._next_status = 0.0
        self._why: str | None = None  # why the walk ends with the step under way
        self._limits = limits
        bus.subscribe(ModeCommand.TOPIC, self._on_mode)

    def _on_mode(self, message: ModeCommand) -> None:
        self._mode = message.mode
        self._heard = time.monotonic()

    def allowed(self, now: float) -> bool:
        """Whether the station asks the robot to walk, and was heard from lately."""
        return self._mode == Mode.WALKING and now - self._heard <= self.command_timeout

    def set_goal(self, goal: tuple[float, float]) -> str:
        """Walk to ``goal`` (map frame) [m]; says what the robot does next."""
        self.goal = (float(goal[0]), float(goal[1]))
        if self.state in ("fallen", "frozen"):
            return f"cannot walk: {self.state}"
        if self.runner is not None:
            self._end_step("a new goal")
            return "walking there after the step under way"
        if not self.allowed(time.monotonic()):
            return "waiting for the station's walking mode to walk"
        return "walking"

    def _end_step(self, why: str) -> None:
        """End the walk with the step under way, the feet together."""
        if self.state == "stopping" or self.runner is None or self._footsteps is None:
            return
        pattern, footsteps = stop_after_step(
            self.runner.pattern, self._footsteps, self.runner.t, self.gait
        )
        self.runner.switch(pattern)
        self._footsteps = footsteps
        self.state = "stopping"
        self._why = why
        self.text = f"stopping at the end of the step: {why}"

    def tick(self, now: float) -> None:
        """Advance the simulation to the wall clock ``now`` (``time.monotonic()``) [s]."""
        if self.runner is not None and not self.allowed(now):
            self.goal = None
            heard = now - self._heard
            self._end_step(
                f"no mode command for {heard:.1f} s"
                if heard > self.command_timeout
                else f"the station asks for {self._mode}"
            )
        if self.runner is not None:
            self._walk(now)
        if self.runner is None and self.state == "standing":
            if self.goal is not None and self.allowed(now):
                self._start(now)  # in the same tick: no standing between two stretches
            if self.runner is None:
                self._stand(now)
        if now >= self._next_status:
            self._next_status = now + 1.0 / STATUS_HZ
            self.publish_status()

    def _behind(self, now: float, t: float) -> float:
        """The simulated time to reach [s]; moves the zero when too far behind."""
        target = now - self._t0
        if target - t > MAX_LAG:
            self.late_s += target - t - MAX_LAG
            self._t0 += target - t - MAX_LAG
            target = t + MAX_LAG
        return target

    def _stand(self, now: float) -> None:
        """Keep the standing robot's physics going, holding its joint targets."""
        target = self._behind(now, self._sim_t)
        while self._sim_t < target:
            self.sim.step(CONTROL_PERIOD)
            self._sim_t += CONTROL_PERIOD
        if self.sim.fallen():
            self.state, self.text, self.goal = "fallen", "fell while standing", None

    def _start(self, now: float) -> None:
        """Plan from where the feet stand and start walking the first stretch."""
        goal = self.goal
        feet, here, heading = standing_feet(self.sim)
        if near_goal(here, goal):
            self.goal = None
            self.text = f"standing at the goal ({goal[0]:.2f}, {goal[1]:.2f})"
            return
        try:
            plan = self.plan(goal)
            stretch = truncate_path(plan.path.waypoints, self.look_ahead_m)
            footsteps = plan_footsteps(stretch, self._limits, initial_heading=heading)
        except FootfallError as exc:
            self.goal = None
            self.text = f"standing: no plan to ({goal[0]:.2f}, {goal[1]:.2f}): {exc}"
            return
        pattern = gait_pattern(footsteps, feet, self.z_c, self.gait)
        self.runner = PatternRunner(self.sim, pattern, self.stabiliser)
        self._footsteps = footsteps
        self._t0 = now
        self.state = "walking"
        self.text = f"walking to ({goal[0]:.2f}, {goal[1]:.2f})"

    def _walk(self, now: float) -> None:
        runner = self.runner
        target = self._behind(now, runner.t)
        while runner.t < target and runner.tick():
            pass
        if not runner.finished:
            return
        run = runner.result()
        self.footsteps_taken += len(run.actual_footholds)
        self.runner = self._footsteps = None
        if run.fell:
            self.state, self.text, self.goal = "fallen", "fell", None
        elif run.stopped:
            self.state, self.text, self.goal = "frozen", run.stopped, None
        else:
            self.state = "standing"
            if self.goal is None:
                self.text = f"standing, feet together: {self._why or 'waiting for a goal'}"
            else:
                self.text = "standing: looking and planning again"
        self._why = None
        self._t0, self._sim_t = now, 0.0

    def publish_status(self) -> None:
        """Say what the robot does and where it stands."""
        feet, _, heading = standing_feet(self.sim)
        goal = np.array(self.goal if self.goal is not None else (math.nan, math.nan))
        self.bus.publish(
            BipedStatus.TOPIC,
            BipedStatus(
                time.time(),
                self.state,
                self.sim.com()[:2].copy(),
                heading,
                np.array([feet[s] for s in SIDES]),
                goal,
                self.footsteps_taken + (len(self.runner.landed) if self.runner else 0),
                self.sim.collisions,
                self.text,
            ),
        )


@dataclass
class WalkingBiped:
    """Archie in a room on the bus: the planning node on its head camera, the walker.

    Attributes:
        room: The room.
        sim: The simulation.
        planning: The planning node (services).
        walker: The walking node.
    """

    room: Room
    sim: BipedSimulation
    planning: BipedPlanningNode
    walker: BipedWalkerNode
    close: Callable[[], None]

    @classmethod
    def build(cls, bus: Bus, room: Room, spec_name: str = "archie", look_ahead_m: float = 1.0):
        """Put the robot standing at the room's start, its nodes on ``bus``."""
        from footfall.sim.biped_look import look
        from footfall.sim.camera import SimDepthCamera

        spec = load_biped_spec(spec_name)
        model, sim, mount, limits, z_c, lipm = stand_in_room(room, spec)
        camera = SimDepthCamera(model, mount)

        def where() -> tuple[float, float]:
            return tuple(float(v) for v in standing_feet(sim)[1])

        planning = BipedPlanningNode(
            bus,
            lambda known: look(camera, sim, list(known)),
            where,
            room.name,
            planner=lambda plan_map: plan_walk(body_plan_map(plan_map, spec), lipm),
            look_period_s=LOOK_PERIOD,
        )
        walker = BipedWalkerNode(bus, sim, planning.plan_to, z_c, lipm, limits, look_ahead_m)
        planning.on_goal = walker.set_goal
        planning.capturing = True  # a robot with a camera looks from the start
        return cls(room, sim, planning, walker, camera.close)

    def tick(self, now: float) -> None:
        """The walker (paced to ``now``, ``time.monotonic()``) and the capture."""
        self.walker.tick(now)
        if self.walker.runner is None:  # looks render the camera: between stretches
            self.planning.tick()
