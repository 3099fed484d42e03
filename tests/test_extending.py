"""The extension seams, proved from outside the package: a toy backend, pose source,
terrain, gait and swing path, each defined here and registered with one line, run through
the library and the command line (``docs/extending.md`` describes the same steps)."""

from __future__ import annotations

import json
import threading
import time
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import numpy.typing as npt
import pytest
from scipy.spatial.transform import Rotation

from footfall.backends import BackendSetup
from footfall.backends.registry import BACKENDS
from footfall.cli import main
from footfall.control_loop import run_control_loop
from footfall.errors import BackendError
from footfall.messages import (
    DepthFrame,
    JointTargets,
    Mode,
    ModeCommand,
    PoseEstimate,
    RobotState,
    WalkCommand,
)
from footfall.motion.gait import GAITS, Gait, GaitConfig
from footfall.motion.swing import SWINGS, PolylineSwing, SwingPlan
from footfall.motion.walker import WalkController
from footfall.nodes.sources import POSES, SourceSetup
from footfall.robot.kinematics import LegKinematics
from footfall.robot.spec import load_spec
from footfall.runtime.zenoh_bus import ZenohBus, ZenohConfig
from footfall.sensing.pose import Pose
from footfall.sim.terrain import Terrain, TerrainXml, box_xml
from footfall.sim.terrains import TERRAINS, make_terrain, register_terrain
from footfall.sim.walk import simulate_walk
from footfall.sim.walk_settings import WalkSettings
from test_zenoh_bus import free_port

SPEC = load_spec("default")


# A terrain: low ridges across the way --------------------------------------------------
@dataclass(frozen=True)
class Ridges(Terrain):
    """Boxes ``ridge_height`` tall across the way, every ``pitch`` metres."""

    name: ClassVar[str] = "toy_ridges"
    difficulty: ClassVar[str | None] = "ridge_height"
    sweep: ClassVar[tuple[float, ...]] = (0.01, 0.02)

    ridge_height: float = 0.02
    pitch: float = 0.5
    seed: int = 0

    @property
    def _xs(self) -> npt.NDArray[np.float64]:
        shift = np.random.default_rng(self.seed).uniform(0.0, 0.1)
        return 0.8 + shift + self.pitch * np.arange(4)

    def height(self, x: npt.ArrayLike, y: npt.ArrayLike) -> npt.NDArray[np.float64]:
        """The ridge's top on a ridge (5 cm deep), the floor elsewhere [m]."""
        xa, _ = np.broadcast_arrays(np.asarray(x, dtype=float), np.asarray(y, dtype=float))
        on = np.zeros(xa.shape, dtype=bool)
        for x0 in self._xs:
            on |= np.abs(xa - x0) <= 0.025
        return np.where(on, self.ridge_height, 0.0)

    def mjcf(self) -> TerrainXml:
        """One box per ridge."""
        h = self.ridge_height
        boxes = [
            box_xml(f"ridge{k}", (x0, 0.0, h / 2), (0.025, 1.0, h / 2))
            for k, x0 in enumerate(self._xs)
        ]
        return TerrainXml(worldbody="\n".join(boxes))


@pytest.fixture
def ridges():
    register_terrain(Ridges)
    yield Ridges
    TERRAINS.unregister(Ridges.name)


def test_a_new_terrain_is_walked_and_swept_by_name(ridges, tmp_path, capsys):
    """Registered, the toy terrain is built by name with its difficulty parameter, and
    `footfall bench terrain --terrains toy_ridges` walks the sweep values it declares."""
    terrain = make_terrain("toy_ridges", seed=2, ridge_height=0.03)
    assert isinstance(terrain, Ridges) and terrain.height(terrain._xs[0], 0.0) == 0.03
    out = tmp_path / "bench"
    args = ["bench", "terrain", "--terrains", "toy_ridges", "--seeds", "1", "--seconds", "2"]
    assert main([*args, "--modes", "blind", "--out", str(out)]) == 0
    bench = json.loads((out / "bench.json").read_text())
    rows = [(r["terrain"], r["difficulty"], r["value"]) for r in bench["results"]]
    assert rows == [("toy_ridges", "ridge_height", 0.01), ("toy_ridges", "ridge_height", 0.02)]
    assert all(r["runs"] == 1 and r["falls"] == 0 for r in bench["results"])
    TERRAINS.unregister("toy_ridges")
    capsys.readouterr()
    assert main(["bench", "terrain", "--terrains", "toy_ridges", "--out", str(out)]) == 2
    assert "toy_ridges" in capsys.readouterr().out


# A gait and a swing path ---------------------------------------------------------------
class BoxSwing(PolylineSwing):
    """Straight up by ``apex``, across, straight down: a box-shaped swing."""

    apex = 0.03

    @classmethod
    def plan(cls, plan: SwingPlan) -> BoxSwing:
        """The box from the plan's start to its target."""
        swing = cls(plan.duration)
        swing._start = np.asarray(plan.start, dtype=float).copy()
        swing._set_path(swing._box(swing._start, plan.target), 0.0)
        return swing

    def _box(self, here: npt.ArrayLike, target: npt.ArrayLike) -> npt.NDArray[np.float64]:
        a, b = np.asarray(here, dtype=float), np.asarray(target, dtype=float)
        top = max(a[2], b[2]) + self.apex
        return np.array([a, [a[0], a[1], top], [b[0], b[1], top], b])

    def retarget(self, target: npt.ArrayLike, t: float, duration: float | None = None) -> None:
        """A new box from where the foot is."""
        here = self.position(t)
        if duration is not None:
            self.duration = duration
        self._set_path(self._box(here, target), t)


@pytest.fixture
def pairs_gait_and_box_swing():
    GAITS.register("toy_pairs", Gait("toy_pairs", ((0, 3), (1, 4), (2, 5))))
    SWINGS.register("toy_box", BoxSwing)
    yield
    GAITS.unregister("toy_pairs")
    SWINGS.unregister("toy_box")


def test_a_new_gait_steps_its_groups_on_its_swing_path(pairs_gait_and_box_swing):
    """On the mock robot, the toy gait swings exactly its pairs, in turn, each foot on a
    box-shaped path that rises by its apex and lands on its target; the body walks on."""
    from footfall.backends.mock import MockHexapod

    config = GaitConfig(kind="toy_pairs", swing="toy_box")
    controller = WalkController(SPEC, config)
    groups = {frozenset(g) for g in GAITS.get("toy_pairs").groups}
    log = run_control_loop(
        MockHexapod(SPEC, servo_time_constant=0.0),
        controller,
        WalkCommand(speed=0.05),
        seconds=6.0,
    )
    swinging = log.array("swinging")
    sets = {frozenset(np.flatnonzero(row)) for row in swinging if row.any()}
    assert sets == groups
    assert controller.touchdown_count >= 8  # every pair stepped at least once
    apex = log.array("feet_commanded_in_world")[:, :, 2].max()
    assert apex == pytest.approx(SPEC.foot_radius + BoxSwing.apex, abs=1e-3)
    for touchdown in controller.touchdowns:
        assert touchdown.chosen_in_world[2] == pytest.approx(SPEC.foot_radius, abs=1e-6)
    assert controller.pose.x > 0.1


def test_a_gait_that_leaves_a_leg_out_is_refused():
    """Every leg swings in exactly one group: a gait that forgets one names the problem."""
    from footfall.errors import ConfigError

    with pytest.raises(ConfigError, match="every leg"):
        Gait("three_legged", ((0, 1), (2, 3), (4,)))


# A pose source --------------------------------------------------------------------------
class BodyStatePose:
    """Poses from the robot's own state: its body pose composed with the camera's mount."""

    name = "body_state_pose"
    stamps: ClassVar[list[tuple[float, float]]] = []
    options: ClassVar[list[dict[str, str]]] = []

    def __init__(self, setup: SourceSetup) -> None:
        self.setup = setup
        setup.bus.subscribe(DepthFrame.TOPIC, self._on_depth)

    @classmethod
    def open(cls, setup: SourceSetup) -> BodyStatePose:
        """Answer the camera's images on the setup's bus."""
        cls.options.append(dict(setup.options))
        return cls(setup)

    def _on_depth(self, frame: DepthFrame) -> None:
        state = self.setup.backend.read()
        body = Pose(state.position_body_in_world, state.orientation_body_in_world)
        camera = body.compose(frame.camera_in_body)
        self.setup.bus.publish(PoseEstimate.RAW_TOPIC, PoseEstimate(frame.stamp, camera, body))
        self.stamps.append((frame.stamp, state.time))


@pytest.fixture
def body_state_pose():
    POSES.register("toy_body_state", BodyStatePose)
    BodyStatePose.stamps.clear()
    BodyStatePose.options.clear()
    yield
    POSES.unregister("toy_body_state")


def test_a_new_pose_source_places_the_maps_frames(body_state_pose):
    """A planned walk on the toy pose source maps every frame at the pose it publishes
    (stamped with the image's time) and crosses the flat floor with no invalid foothold."""
    settings = WalkSettings(
        terrain="flat",
        seconds=6.0,
        blind=False,
        straight=True,
        pose_source="toy_body_state",
        pose_options={"frame": "body"},
    )
    result = simulate_walk(SPEC, settings)
    m = result.metrics.to_json()
    assert m["frames"] >= 60 and m["frames_skipped_no_pose"] == 0
    assert len(BodyStatePose.stamps) >= m["frames"]
    assert BodyStatePose.options == [{"frame": "body"}]  # its settings reached it
    assert m["distance_m"] > 0.3 and not m["fell"] and m["invalid_footholds"] == 0


# A robot backend ------------------------------------------------------------------------
class PerfectServos:
    """A robot whose joints reach their targets at once and which knows nothing of the
    world: no position, no contacts."""

    realtime = False
    opened: ClassVar[list[PerfectServos]] = []

    def __init__(self, setup: BackendSetup) -> None:
        kinematics = LegKinematics(setup.spec)
        feet = setup.spec.rest_feet_in_body(setup.body_height)
        feet[:, 2] += setup.spec.foot_radius
        self.joints = kinematics.inverse_in_body(feet)
        self.time = 0.0
        self.torque_calls: list[bool] = []
        self.targets: list[JointTargets] = []

    @classmethod
    def open(cls, setup: BackendSetup) -> PerfectServos:
        """Connect (here: make one) and keep it for the test to inspect."""
        backend = cls(setup)
        cls.opened.append(backend)
        return backend

    def read(self) -> RobotState:
        """Encoders and a level IMU."""
        return RobotState(
            self.time, self.joints.copy(), np.zeros((6, 3)), Rotation.identity(), np.zeros(3)
        )

    def command(self, targets: JointTargets) -> None:
        """Take the targets."""
        self.targets.append(targets)

    def set_torque(self, enabled: bool) -> None:
        """Note the switch."""
        self.torque_calls.append(enabled)

    def advance(self, duration: float) -> None:
        """The joints are where they were told to be."""
        self.time += duration
        if self.targets and self.torque_calls[-1]:
            self.joints = np.asarray(self.targets[-1].positions, dtype=float)


@pytest.fixture
def perfect_servos():
    BACKENDS.register("toy_servos", PerfectServos)
    PerfectServos.opened.clear()
    yield
    BACKENDS.unregister("toy_servos")


def test_a_new_backend_runs_under_footfall_robot(perfect_servos, tmp_path):
    """`footfall robot --backend toy_servos` runs the nodes on the toy robot: limp until a
    client over zenoh switches it to walking, then its legs step to the commands."""
    endpoint = f"tcp/127.0.0.1:{free_port()}"

    def client() -> None:
        with ZenohBus(ZenohConfig(connect=(endpoint,))) as bus:
            end = time.monotonic() + 6.0
            while time.monotonic() < end:
                bus.publish(ModeCommand.TOPIC, ModeCommand(Mode.WALKING))
                bus.publish(WalkCommand.TOPIC, WalkCommand(speed=0.08))
                bus.spin(0.05)

    thread = threading.Thread(target=client, daemon=True)
    thread.start()
    args = ["robot", "--backend", "toy_servos", "--camera", "none", "--sim", "flat"]
    assert main([*args, "--seconds", "8", "--listen", endpoint, "--out", str(tmp_path)]) == 0
    thread.join()
    (robot,) = PerfectServos.opened
    assert robot.torque_calls[:2] == [False, True]  # limp at start, on when walking
    assert len(robot.targets) > 100
    swings = np.ptp([t.positions for t in robot.targets], axis=0)
    assert (swings > 0.05).all()  # every joint of every leg moved: the legs stepped
    metrics = json.loads((tmp_path / "metrics.json").read_text())
    assert metrics["steps"] >= 6 and not metrics["fell"]
    assert "invalid_footholds" not in metrics  # it cannot say where its feet are


class FailingServos(PerfectServos):
    """Perfect servos until the ``fail_after``-th command, when servo 7 overheats."""

    fail_after = 150

    def command(self, targets: JointTargets) -> None:
        """Take the targets, or fail as the contract says: a BackendError naming the servo."""
        if len(self.targets) >= self.fail_after:
            raise BackendError("servo 7 (LM femur) overheated: 81 C")
        super().command(targets)


def test_a_backend_fault_stops_the_walk_and_says_why():
    """A backend that raises BackendError mid-walk gets no more targets: the servo node
    keeps the fault, logs it as an error, and the robot holds its last goal."""
    from footfall.control_loop import WalkingGraph
    from footfall.messages import LogLine
    from footfall.runtime.bus import InProcessBus

    bus = InProcessBus()
    robot = FailingServos(BackendSetup(SPEC, SPEC.body_height))
    graph = WalkingGraph.build(bus, robot, WalkController(SPEC))
    logged: list[LogLine] = []
    bus.subscribe(LogLine.TOPIC, logged.append)
    bus.publish(ModeCommand.TOPIC, ModeCommand(Mode.WALKING))
    for k in range(400):
        bus.publish(WalkCommand.TOPIC, WalkCommand(speed=0.1))
        graph.step(k * 0.01, 0.01)
    assert len(robot.targets) == FailingServos.fail_after  # nothing sent after the fault
    assert "servo 7" in graph.servo.fault
    errors = [line for line in logged if line.level == "error" and line.node == "servo"]
    assert len(errors) == 1 and "overheated" in errors[0].text
