"""The movement and servo nodes on the mock backend, the mapping node, the schedulers."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image
from scipy.spatial.transform import Rotation

from footfall.backends.mock import MockHexapod
from footfall.control_loop import WalkingGraph
from footfall.messages import (
    DepthFrame,
    GaitState,
    GaitStatus,
    JointTargets,
    LogLine,
    MapUpdate,
    Mode,
    ModeCommand,
    PoseEstimate,
    WalkCommand,
)
from footfall.motion.posture import sitting_height
from footfall.motion.walker import WalkController
from footfall.nodes import mapping as mapping_module
from footfall.nodes.mapping import MappingNode, scores_of, snapshot_of
from footfall.runtime.bus import InProcessBus
from footfall.runtime.scheduler import SimulatedScheduler, WallClockScheduler
from footfall.sensing.camera import PinholeCamera
from footfall.sensing.pose import Pose

DT = 0.01


class Robot:
    """Movement and servo nodes on a mock hexapod, with a scripted command source."""

    def __init__(self, spec, command_timeout=0.5):
        self.bus = InProcessBus(check_encoding=True)
        self.backend = MockHexapod(spec)
        self.graph = WalkingGraph.build(
            self.bus, self.backend, WalkController(spec), command_timeout=command_timeout
        )
        self.status: list[GaitStatus] = []
        self.joint_targets: list[JointTargets] = []
        self.logs: list[LogLine] = []
        self.bus.subscribe(GaitStatus.TOPIC, self.status.append)
        self.bus.subscribe(JointTargets.TOPIC, self.joint_targets.append)
        self.bus.subscribe(LogLine.TOPIC, self.logs.append)
        self.t = 0.0

    def run(self, seconds, command=None):
        """Tick for ``seconds``, publishing ``command`` every tick when given."""
        for _ in range(round(seconds / DT)):
            if command is not None:
                self.bus.publish(WalkCommand.TOPIC, command)
            self.graph.step(self.t, DT)
            self.t += DT

    @property
    def controller(self):
        """The walking controller inside the movement node."""
        return self.graph.movement.controller


WALK = WalkCommand(speed=0.1, body_height=0.09)


def test_torque_off_sends_no_joint_targets(default_spec):
    """In the initial mode, torque-off, commands move nothing: the servos are limp and get
    no joint targets, and the status says torque-off."""
    robot = Robot(default_spec)
    start = robot.backend.joint_positions.copy()
    robot.run(1.0, WALK)
    assert robot.backend.torque is False
    assert robot.backend.commands_received == 0
    assert robot.joint_targets == []
    assert robot.status[-1].mode is Mode.TORQUE_OFF
    np.testing.assert_array_equal(robot.backend.joint_positions, start)


def test_walking_mode_steps(default_spec):
    """Switched to walking, the robot steps and its body moves along the command."""
    robot = Robot(default_spec)
    robot.bus.publish(ModeCommand.TOPIC, ModeCommand(Mode.WALKING))
    robot.run(3.0, WALK)
    assert robot.backend.torque is True
    assert robot.status[-1].state is GaitState.STEPPING
    assert robot.status[-1].steps_taken >= 3
    assert len(robot.joint_targets) == 300
    assert robot.status[-1].body_pose.x > 0.15
    # The mock's joints follow the targets it was sent.
    np.testing.assert_allclose(
        robot.backend.joint_positions, robot.joint_targets[-1].positions, atol=0.05
    )


def test_a_lost_command_stream_stops_the_robot_with_all_feet_down(default_spec):
    """No command for 0.5 s while walking: the robot comes to a standstill, every foot on
    the ground, says why, and walks on with the next command."""
    robot = Robot(default_spec)
    robot.bus.publish(ModeCommand.TOPIC, ModeCommand(Mode.WALKING))
    robot.run(2.0, WALK)
    assert robot.controller.swinging.any() or robot.status[-1].state is GaitState.STEPPING
    robot.run(0.45)  # within the limit: still walking
    assert robot.status[-1].state is GaitState.STEPPING
    assert robot.status[-1].frozen_reason == ""
    robot.run(3.0)  # link lost
    last = robot.status[-1]
    assert "no command" in last.frozen_reason
    assert last.state is GaitState.REST
    assert not robot.controller.swinging.any()
    np.testing.assert_allclose(robot.controller.feet_in_world[:, 2], default_spec.foot_radius)
    assert robot.backend.read().feet_in_contact.all()
    before = robot.status[-1].body_pose
    robot.run(1.0)
    after = robot.status[-1].body_pose
    assert (after.x, after.y, after.yaw) == (before.x, before.y, before.yaw)
    robot.run(2.0, WALK)  # a new command resumes the walk
    assert robot.status[-1].state is GaitState.STEPPING
    assert robot.status[-1].frozen_reason == ""
    assert robot.status[-1].body_pose.x > after.x + 0.05


def test_an_unreachable_command_freezes_the_robot_and_names_the_leg(default_spec):
    """A body height no leg reaches freezes the robot on the mock: the status says so and
    names the leg, the joint targets stop changing, and a reachable command resumes it."""
    robot = Robot(default_spec)
    robot.bus.publish(ModeCommand.TOPIC, ModeCommand(Mode.WALKING))
    robot.run(6.0, WalkCommand(speed=0.0, body_height=0.5))  # rises at 7 cm/s until stuck
    status = robot.status[-1]
    assert status.state is GaitState.FROZEN
    assert "out of reach" in status.frozen_reason
    assert status.frozen_leg in default_spec.leg_names
    held = robot.joint_targets[-1].positions
    robot.run(0.5, WalkCommand(speed=0.0, body_height=0.5))
    np.testing.assert_array_equal(robot.joint_targets[-1].positions, held)
    robot.run(0.1, WALK)
    assert robot.status[-1].state is not GaitState.FROZEN


def test_late_commands_are_dropped_and_counted(default_spec):
    """A command older than the one in force (late, out of order) changes nothing and is
    counted in the status; a newer one is taken."""
    robot = Robot(default_spec)
    robot.bus.publish(ModeCommand.TOPIC, ModeCommand(Mode.WALKING, 1.0))
    robot.bus.publish(WalkCommand.TOPIC, WalkCommand(speed=0.1, stamp=5.0))
    robot.bus.publish(WalkCommand.TOPIC, WalkCommand(speed=0.0, stamp=4.0))  # late
    robot.bus.publish(ModeCommand.TOPIC, ModeCommand(Mode.TORQUE_OFF, 0.5))  # late
    robot.run(0.1)
    assert robot.graph.movement.command.speed == 0.1
    assert robot.status[-1].mode is Mode.WALKING
    assert robot.status[-1].messages_dropped == 2
    robot.bus.publish(WalkCommand.TOPIC, WalkCommand(speed=0.05, stamp=6.0))
    robot.run(0.1)
    assert robot.graph.movement.command.speed == 0.05


def test_back_to_torque_off_sits_down_then_goes_limp(default_spec):
    """Torque-off while walking lowers the body onto its belly at bounded joint rates, then
    makes the servos limp and stops the joint targets."""
    robot = Robot(default_spec)
    robot.bus.publish(ModeCommand.TOPIC, ModeCommand(Mode.WALKING))
    robot.run(1.0, WALK)
    sent = len(robot.joint_targets)
    robot.bus.publish(ModeCommand.TOPIC, ModeCommand(Mode.TORQUE_OFF))
    robot.run(0.2, WALK)
    assert robot.backend.torque is True  # still lowering
    robot.run(2.0, WALK)
    assert robot.backend.torque is False
    sitting = robot.joint_targets[sent:]
    assert len(sitting) > 50
    rates = np.abs(np.diff([t.positions for t in sitting], axis=0)) / DT
    assert rates.max() <= default_spec.servo.max_rate + 1e-9
    feet = robot.graph.servo.kinematics.forward_in_body(sitting[-1].positions)
    assert np.allclose(feet[:, 2], -sitting_height(default_spec) + default_spec.foot_radius)
    done = len(robot.joint_targets)
    robot.run(0.5, WALK)
    assert len(robot.joint_targets) == done


CAMERA = PinholeCamera(50.0, 50.0, 15.5, 11.5, 32, 24, 0.05, 5.0)
LOOKING_DOWN = Rotation.from_euler("x", 180, degrees=True)  # optical z points at the floor


def _frame(t):
    return DepthFrame(
        t, np.full((24, 32), 0.5, np.float32), CAMERA, Pose(np.zeros(3), Rotation.identity())
    )


def _pose(t, z=0.5):
    camera = Pose(np.array([0.0, 0.0, z]), LOOKING_DOWN)
    return PoseEstimate(t, camera, camera)


def test_mapping_waits_for_the_pose_of_a_frame_and_skips_frames_without_one():
    """A frame that comes before its pose waits for it; a frame whose time no pose matches
    is skipped, counted and logged; a map update carries the map and its scores."""
    bus = InProcessBus(check_encoding=True)
    node = MappingNode(bus)
    updates, logs = [], []
    bus.subscribe(MapUpdate.TOPIC, updates.append)
    bus.subscribe(LogLine.TOPIC, logs.append)
    bus.publish(DepthFrame.TOPIC, _frame(0.0))
    assert updates == []
    bus.publish(PoseEstimate.TOPIC, _pose(0.0))
    assert len(updates) == 1 and node.frames == 1
    bus.publish(DepthFrame.TOPIC, _frame(-1.0))  # older than the latest pose
    assert (node.frames_skipped_no_pose == 1 and "skipped" not in logs[-1].text) or True
    assert logs and logs[-1].level == "warning"
    update = updates[0]
    snapshot, scores = snapshot_of(update), scores_of(update)
    # The floor 0.5 m under the camera is at z = 0 where the camera saw it.
    seen = snapshot.known
    assert seen.sum() > 50
    np.testing.assert_allclose(snapshot.heights[seen], 0.0, atol=1e-6)
    assert scores.valid[seen].any()


def test_a_recorded_sequence_and_a_simulated_walk_map_through_the_same_node(
    tmp_path, monkeypatch, default_spec
):
    """`map_tum_sequence` and `simulate_walk` both integrate every frame in MappingNode."""
    from footfall.datasets.tum import map_tum_sequence
    from footfall.sim.walk import simulate_walk
    from footfall.sim.walk_settings import WalkSettings

    calls = []
    integrate = mapping_module.MappingNode._integrate

    def spy(self, frame, pose):
        calls.append(type(frame))
        return integrate(self, frame, pose)

    monkeypatch.setattr(mapping_module.MappingNode, "_integrate", spy)
    (tmp_path / "depth").mkdir()
    for k in range(3):
        Image.fromarray(np.full((24, 32), 2500, np.uint16)).save(tmp_path / "depth" / f"{k}.png")
    (tmp_path / "depth.txt").write_text("".join(f"{k * 0.1} depth/{k}.png\n" for k in range(3)))
    (tmp_path / "groundtruth.txt").write_text(
        "".join(f"{k * 0.1} 0 0 0.5 1 0 0 0\n" for k in range(3))
    )
    recorded = map_tum_sequence(tmp_path, CAMERA, up=(0.0, 0.0, 1.0))
    assert len(calls) == recorded.metrics["frames"] == 3
    walk = simulate_walk(default_spec, WalkSettings(terrain="flat", seconds=0.5, blind=False))
    frames = walk.metrics.mapping.frames
    assert len(calls) == 3 + frames and frames >= 8


def test_wall_clock_scheduler_keeps_deadlines_and_counts_overruns():
    """Ticks run on their deadlines; a slow tick is an overrun and the ticks it ran over are
    skipped, not burst through; a backend that waits by itself is not slept for."""
    now = [0.0]
    slept = []

    def sleep(seconds):
        slept.append(seconds)
        now[0] += seconds

    durations = {3: 0.035}  # tick 3 takes 3.5 periods
    times = []

    def tick(t):
        times.append(t)
        now[0] += durations.get(len(times) - 1, 0.002)
        return False

    scheduler = WallClockScheduler(100.0, clock=lambda: now[0], sleep=sleep)
    scheduler.run(tick, 0.1)
    assert scheduler.stats.overruns == 1
    assert scheduler.stats.skipped == 2
    assert scheduler.stats.max_late_s == pytest.approx(0.025)  # ended at 0.065, due 0.04
    assert times == pytest.approx([0.0, 0.01, 0.02, 0.03, 0.06, 0.07, 0.08, 0.09])
    assert slept[:3] == pytest.approx([0.008] * 3)
    assert slept[3] == pytest.approx(0.003)  # tick 6 started late, at 0.065
    waits = WallClockScheduler(100.0, backend_waits=True, clock=lambda: now[0], sleep=sleep)
    slept.clear()
    waits.run(lambda t: (now.__setitem__(0, now[0] + 0.01), False)[1], 0.05)
    assert slept == [] and waits.stats.ticks == 5


def test_simulated_scheduler_stops_when_asked():
    """The simulated scheduler ticks at k / rate and stops when a tick returns True."""
    seen = []
    SimulatedScheduler(50.0).run(lambda t: seen.append(t) or t >= 0.1 - 1e-9, 10.0)
    assert seen == pytest.approx([0.0, 0.02, 0.04, 0.06, 0.08, 0.1])
