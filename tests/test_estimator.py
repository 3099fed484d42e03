"""footfall's own pose: leg-kinematic odometry with a gyro, on a robot whose motion is known.

A synthetic hexapod walks a tripod gait along a known path: its stance feet stay where they
landed (their spherical feet rolling as the tibias turn, as real ones do), its joint angles
follow by inverse kinematics, and its IMU and encoders read as :mod:`footfall.estimation.
sensor_noise` says a real robot's do. The estimator must follow it to well under 1 % of the
distance walked, leave a slipping foot out, give no pose before it knows its gyro's bias or
after it is lost, and, closing the loop in simulation, walk the robot on its own pose.
"""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from footfall.estimation.leg_inertial import BodyReading, EstimatorConfig, LegInertialEstimator
from footfall.estimation.sensor_noise import NoisySensors, SensorNoiseConfig
from footfall.messages import (
    DepthFrame,
    EffectorTargets,
    LogLine,
    OdometryEstimate,
    PoseEstimate,
    RobotState,
)
from footfall.nodes.estimator_pose import EstimatorPose, start_pose
from footfall.robot.kinematics import LegKinematics
from footfall.robot.spec import load_spec
from footfall.runtime.bus import InProcessBus
from footfall.sensing.camera import PinholeCamera
from footfall.sensing.pose import Pose

DT = 0.01
STEP_S = 0.5  # each tripod swings this long
STAND_S = 3.5  # standing still before walking: the gyro's calibration
TRIPODS = (np.array([0, 2, 4]), np.array([1, 3, 5]))


class SyntheticWalk:
    """A hexapod walking a tripod gait at a constant twist, exactly.

    The body moves at ``forward`` and ``left`` [m/s] in its own frame and turns at
    ``yaw_rate`` [rad/s], level, at its rest height. Each tripod swings for ``STEP_S`` to the
    foothold under its rest position at the middle of its next stance. A standing foot's
    centre moves only as its sphere rolls; ``slip`` moves one standing foot further.
    """

    def __init__(self, forward: float, left: float, yaw_rate: float) -> None:
        self.spec = load_spec("default")
        self.kin = LegKinematics(self.spec)
        self.rest = self.spec.rest_feet_in_body()
        self.twist = (forward, left, yaw_rate)
        self.start = np.array([0.0, 0.0, self.spec.body_height])
        self.feet = self._placed(self.body(0.0))
        self.swing_from = self.feet.copy()
        self.swing_to = self.feet.copy()
        self.tibias: Rotation | None = None
        self.slip: tuple[int, float, float, np.ndarray] | None = None  # leg, from, to, per tick

    def body(self, t: float) -> tuple[np.ndarray, float]:
        """The body's position and heading at ``t`` [s]."""
        walked = max(t - STAND_S, 0.0)
        forward, left, yaw_rate = self.twist
        yaw = yaw_rate * walked
        if abs(yaw_rate) < 1e-9:
            dx, dy = forward * walked, left * walked
        else:  # the twist integrated exactly along the arc
            s, c = math.sin(yaw), 1.0 - math.cos(yaw)
            dx = (forward * s - left * c) / yaw_rate
            dy = (forward * c + left * s) / yaw_rate
        return self.start + np.array([dx, dy, 0.0]), yaw

    def _placed(self, pose: tuple[np.ndarray, float]) -> np.ndarray:
        position, yaw = pose
        feet = Rotation.from_euler("z", yaw).apply(self.rest) + position
        feet[:, 2] = self.spec.foot_radius
        return feet

    def swinging(self, t: float) -> np.ndarray:
        """Which feet swing at ``t``."""
        out = np.zeros(6, dtype=bool)
        walked = round(t / DT) - round(STAND_S / DT)
        if walked >= 0:
            out[TRIPODS[(walked // round(STEP_S / DT)) % 2]] = True
        return out

    def tick(self, k: int) -> tuple[np.ndarray, np.ndarray]:
        """Move the feet to tick ``k``; the joint angles and which feet swing."""
        t = k * DT
        swinging = self.swinging(t)
        step_ticks, walked = round(STEP_S / DT), k - round(STAND_S / DT)
        phase = (walked % step_ticks) / step_ticks if walked >= 0 else 0.0
        if walked >= 0 and walked % step_ticks == 0:  # a new step: plan its footholds
            self.swing_from = self.feet.copy()
            self.swing_to = self._placed(self.body(t + 1.5 * STEP_S))
        for leg in np.flatnonzero(swinging):
            path = self.swing_from[leg] + phase * (self.swing_to[leg] - self.swing_from[leg])
            path[2] += 0.04 * math.sin(math.pi * phase)
            self.feet[leg] = path
        if self.slip is not None and self.slip[1] <= t < self.slip[2]:
            assert not swinging[self.slip[0]]  # a standing foot slips
            self.feet[self.slip[0]] += self.slip[3]
        position, yaw = self.body(t)
        rotation = Rotation.from_euler("z", yaw)
        angles = self.kin.inverse_in_body(rotation.inv().apply(self.feet - position))
        tibias = rotation * Rotation.from_euler(
            "ZY", np.column_stack([self.spec.mount_yaws + angles[:, 0], -angles[:, 1:].sum(1)])
        )
        if self.tibias is not None:  # standing spheres roll as their tibias turn
            rolled = (tibias * self.tibias.inv()).as_rotvec()
            roll = np.cross(rolled, [0.0, 0.0, self.spec.foot_radius])
            self.feet[~swinging] += roll[~swinging]
            angles = self.kin.inverse_in_body(rotation.inv().apply(self.feet - position))
        self.tibias = tibias
        return angles, swinging

    def states(self, seconds: float):
        """``(t, RobotState, swinging)`` every tick, exact."""
        previous = None
        for k in range(round(seconds / DT) + 1):
            t = k * DT
            angles, swinging = self.tick(k)
            rates = np.zeros((6, 3)) if previous is None else (angles - previous) / DT
            previous = angles
            position, yaw = self.body(t)
            gyro = np.array(
                [0.0, 0.0, self.twist[2] if t > STAND_S + 1e-9 else 0.0]
            )  # over the last tick
            yield (
                t,
                RobotState(
                    time=t,
                    joint_positions=angles,
                    joint_velocities=rates,
                    orientation_body_in_world=Rotation.from_euler("z", yaw),
                    angular_velocity_body_in_body=gyro,
                    position_body_in_world=position,
                    feet_in_contact=~swinging,
                ),
                swinging,
            )


def reading(state: RobotState, swinging: np.ndarray) -> BodyReading:
    return BodyReading(
        state.time,
        state.joint_positions,
        state.joint_velocities,
        state.angular_velocity_body_in_body,
        state.orientation_body_in_world,
        ~swinging,
    )


def run_estimator(walk: SyntheticWalk, seconds: float, noise: NoisySensors | None = None):
    """The estimator on the walk; its estimator and the true pose at the end."""
    estimator = LegInertialEstimator(walk.kin, Pose(walk.start, Rotation.identity()))
    state = None
    for _, state, swinging in walk.states(seconds):
        estimator.update(reading(noise.read(state) if noise is not None else state, swinging))
    assert state is not None and state.position_body_in_world is not None
    return estimator, Pose(state.position_body_in_world, state.orientation_body_in_world)


def heading_error_deg(estimate: Rotation, truth: Rotation) -> float:
    return abs(math.degrees((estimate * truth.inv()).as_euler("ZYX")[0]))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_estimator_follows_a_known_walk_read_by_real_sensors(seed):
    """Walking 2 m round a gentle curve, read by a BMI055-class gyro (0.5 deg/s turn-on bias,
    learned while the robot stands), a tilted accelerometer and 4096-count encoders: the
    position stays within 1 % of the distance walked, the heading within 1 degree a metre."""
    walk = SyntheticWalk(forward=0.1, left=0.0, yaw_rate=0.05)
    noise = NoisySensors(SensorNoiseConfig(), np.random.default_rng(seed))
    estimator, truth = run_estimator(walk, STAND_S + 20.0, noise)
    walked = 0.1 * 20.0
    assert estimator.ready
    assert np.linalg.norm(estimator.bias - noise.gyro_bias) < math.radians(0.02)
    error = np.linalg.norm(estimator.pose.position - truth.position)
    assert error < 0.01 * walked, error
    assert heading_error_deg(estimator.pose.rotation, truth.rotation) < 1.0 * walked
    assert abs(estimator.distance_m - walked) < 0.02 * walked


@settings(max_examples=12, deadline=None)
@given(
    forward=st.floats(-0.08, 0.1),
    left=st.floats(-0.06, 0.06),
    yaw_rate=st.floats(-0.2, 0.2),
)
def test_exact_sensors_give_the_exact_path(forward, left, yaw_rate):
    """Any twist the legs can walk, read exactly: the estimate ends within a millimetre (the
    rolling of the feet included; leaving it out costs centimetres)."""
    walk = SyntheticWalk(forward, left, yaw_rate)
    estimator, truth = run_estimator(walk, STAND_S + 5.0)
    assert np.linalg.norm(estimator.pose.position - truth.position) < 1e-3
    assert heading_error_deg(estimator.pose.rotation, truth.rotation) < 0.01
    assert estimator.slipped == 0


def test_a_slipping_foot_is_left_out():
    """A standing foot that slides 4 mm a tick for a tenth of a second (4 cm) does not drag
    the estimate with it: the other standing feet outvote it."""
    walk = SyntheticWalk(forward=0.1, left=0.0, yaw_rate=0.0)
    walk.slip = (0, STAND_S + 0.6, STAND_S + 0.7, np.array([0.004, 0.0, 0.0]))
    estimator, truth = run_estimator(walk, STAND_S + 3.0)
    assert estimator.slipped >= 9
    assert np.linalg.norm(estimator.pose.position - truth.position) < 2e-3
    walk = SyntheticWalk(forward=0.1, left=0.0, yaw_rate=0.0)
    walk.slip = (0, STAND_S + 0.6, STAND_S + 0.7, np.array([0.004, 0.0, 0.0]))
    blind = LegInertialEstimator(
        walk.kin, Pose(walk.start, Rotation.identity()), EstimatorConfig(slip_tolerance_m=1.0)
    )
    for _, state, swinging in walk.states(STAND_S + 3.0):
        blind.update(reading(state, swinging))
    assert np.linalg.norm(blind.pose.position - truth.position) > 5e-3  # what it would cost


def depth_frame(stamp: float) -> DepthFrame:
    camera = PinholeCamera(fx=2.0, fy=2.0, cx=2.0, cy=1.5, width=4, height=3)
    on_body = Pose(np.array([0.1, 0.0, 0.0]), Rotation.identity())
    return DepthFrame(stamp, np.ones((3, 4)), camera, on_body)


def test_no_pose_while_calibrating_nor_once_lost():
    """The node answers no image until the robot has stood still for its gyro's calibration,
    then every image (the camera's pose on the body applied); when no foot stands for longer
    than it can coast, it says it is lost and answers none."""
    walk = SyntheticWalk(forward=0.1, left=0.0, yaw_rate=0.0)
    bus = InProcessBus()
    poses: list[PoseEstimate] = []
    logs: list[LogLine] = []
    odometry: list[OdometryEstimate] = []
    bus.subscribe(PoseEstimate.TOPIC, poses.append)
    bus.subscribe(LogLine.TOPIC, logs.append)
    bus.subscribe(OdometryEstimate.TOPIC, odometry.append)
    first = next(walk.states(0.0))[1]
    node = EstimatorPose(bus, walk.spec, start_pose(walk.spec, first))
    config = EstimatorConfig()
    lifted = STAND_S + 1.0  # every foot in the air from here: carried off, or fallen
    zeros = np.zeros((6, 3))
    for t, state, swinging in walk.states(STAND_S + 2.0):
        if t >= lifted:
            swinging = np.ones(6, dtype=bool)
            state = dataclasses.replace(state, feet_in_contact=np.zeros(6, dtype=bool))
        bus.publish(RobotState.TOPIC, state)
        bus.publish(EffectorTargets.TOPIC, EffectorTargets(t, zeros, zeros, swinging, zeros))
        if round(t / DT) % 7:
            continue
        count = len(poses)
        bus.publish(DepthFrame.TOPIC, depth_frame(t))
        answered = len(poses) > count
        if t < config.calibration_s or t > lifted + config.coast_s + 2 * DT:
            assert not answered, t
        elif config.calibration_s + 2 * DT < t < lifted:
            assert answered, t
            estimate = poses[-1]
            on_body = estimate.camera_in_world.position - estimate.body_in_world.position
            assert np.allclose(on_body, [0.1, 0.0, 0.0], atol=1e-6)
            error = estimate.body_in_world.position - state.position_body_in_world
            assert np.linalg.norm(error) < 2e-3
    assert node.estimator.lost is not None and "no foot has stood" in node.estimator.lost
    # Every tick an odometry estimate: tracking from calibration until lost, its position
    # uncertainty growing as the robot walks.
    assert len(odometry) == round((STAND_S + 2.0) / DT) + 1
    tracking = [o.stamp for o in odometry if o.tracking]
    assert config.calibration_s <= tracking[0] <= config.calibration_s + 2 * DT
    assert lifted < tracking[-1] <= lifted + config.coast_s + 2 * DT
    sigmas = [o.covariance[0] for o in odometry if STAND_S <= o.stamp < lifted]
    assert sigmas[-1] > sigmas[0] and all(np.diff(sigmas) >= 0)
    assert [m.level for m in logs] == ["info", "error"]
    assert "lost" in logs[-1].text


def test_a_robot_that_does_not_know_its_place_starts_at_the_origin_at_its_height():
    walk = SyntheticWalk(forward=0.0, left=0.0, yaw_rate=0.0)
    state = next(walk.states(0.0))[1]
    blind = dataclasses.replace(state, position_body_in_world=None)
    pose = start_pose(walk.spec, blind)
    assert np.allclose(pose.position, [0.0, 0.0, walk.spec.body_height], atol=1e-9)


def test_the_simulated_robot_walks_on_its_own_pose(tmp_path):
    """``footfall walk --pose estimator``: nothing the simulator knows places the map or
    moves the controller, the IMU and encoders read as a real robot's; 30 s across flat
    ground end within 1 % of the distance walked and 1 degree a metre of the truth, with no
    foot on an invalid cell."""
    from footfall.cli import main

    out = tmp_path / "walk"
    args = ["walk", "--terrain", "flat", "--pose", "estimator", "--seconds", "30"]
    assert main([*args, "--goal", "6", "0", "--out", str(out)]) == 0
    metrics = json.loads((out / "metrics.json").read_text())
    walked = metrics["distance_m"]
    assert walked > 2.5 and not metrics["fell"] and metrics["invalid_footholds"] == 0
    assert metrics["estimator_position_drift_m"] < 0.01 * walked, metrics
    assert metrics["estimator_heading_drift_deg"] < 1.0 * walked, metrics
    assert abs(metrics["estimator_distance_m"] - walked) < 0.05 * walked, metrics
    # Every depth image registered against the map; the floor holds the height.
    assert metrics["estimator_corrections"] >= 0.9 * metrics["estimator_correction_frames"] > 0
    assert abs(metrics["estimator_height_drift_m"]) < 0.0015, metrics


@pytest.mark.parametrize("option", ["colour=blue", "register=maybe"])
def test_a_pose_option_the_estimator_does_not_have_is_refused(tmp_path, option):
    from footfall.cli import main

    args = ["walk", "--pose", "estimator", "--pose-option", option, "--seconds", "1"]
    assert main([*args, "--out", str(tmp_path)]) == 2


def test_a_robot_without_an_imu_is_told_the_estimator_needs_one():
    """A backend with no IMU of its own and a camera without one: the estimator's heading
    would be a gyro that is not there. The walk refuses to start, saying so."""
    from footfall.backends.registry import BACKENDS
    from footfall.errors import ConfigError
    from footfall.sim.hexapod import MujocoHexapod
    from footfall.sim.walk import simulate_walk
    from footfall.sim.walk_request import WalkRequest, prepare_walk

    class WithoutImu(MujocoHexapod):
        attitude = None  # as a servo-only robot: its attitude would come from elsewhere

    BACKENDS.register("without-imu", WithoutImu)
    try:
        job = prepare_walk(WalkRequest(terrain="flat", seconds=1, backend="without-imu"))
        simulate_walk(job.spec, job.settings, terrain=job.terrain)  # the pose's own attitude
        job = prepare_walk(
            WalkRequest(terrain="flat", seconds=1, backend="without-imu", pose="estimator")
        )
        with pytest.raises(ConfigError, match="estimator pose source needs an IMU"):
            simulate_walk(job.spec, job.settings, terrain=job.terrain)
    finally:
        BACKENDS.unregister("without-imu")


def test_two_standing_feet_that_disagree_leave_their_median():
    """When every standing foot moves unlike the others (two feet, one sliding 1 cm in a
    tick) none can be called the slipping one: the body moves by their median, and the
    estimate stays a number."""
    walk = SyntheticWalk(forward=0.05, left=0.0, yaw_rate=0.0)
    walk.slip = (1, STAND_S + 0.2, STAND_S + 0.21, np.array([0.01, 0.0, 0.0]))
    estimator = LegInertialEstimator(walk.kin, Pose(walk.start, Rotation.identity()))
    two = np.array([False, True, False, True, False, False])  # of the tripod standing first
    for _, state, swinging in walk.states(STAND_S + 0.4):
        standing = ~swinging & two if swinging.any() else ~swinging
        estimator.update(dataclasses.replace(reading(state, swinging), standing=standing))
    assert np.all(np.isfinite(estimator.position))
    assert np.linalg.norm(estimator.position - state.position_body_in_world) < 0.006


def test_odometry_records_as_ros_odometry_with_its_covariance():
    """In an MCAP file or a bag the estimator's odometry is a nav_msgs/Odometry on /odometry:
    the body's pose in the world with the diagonal covariance, the velocity in the body
    frame (a body facing +y walking along +y moves forward)."""
    from footfall.recording.ros_types import to_ros, typestore

    body = Pose(np.array([1.0, 2.0, 0.09]), Rotation.from_euler("z", math.pi / 2))
    covariance = np.array([1e-4, 2e-4, 3e-4, 1e-5, 2e-5, 3e-5])
    estimate = OdometryEstimate(2.5, body, np.array([0.0, 0.1, 0.0]), covariance, True)
    [(channel, kind, ros)] = to_ros(OdometryEstimate.TOPIC, estimate)
    assert (channel, kind) == ("/odometry", "nav_msgs/msg/Odometry")
    assert ros.child_frame_id == "base_link" and ros.header.frame_id == "world"
    assert np.allclose(np.asarray(ros.pose.covariance).reshape(6, 6), np.diag(covariance))
    assert (ros.pose.pose.position.x, ros.pose.pose.position.y) == (1.0, 2.0)
    linear = ros.twist.twist.linear
    assert np.allclose([linear.x, linear.y, linear.z], [0.1, 0.0, 0.0])
    data = bytes(typestore().serialize_cdr(ros, kind))
    back = typestore().deserialize_cdr(data, kind)
    assert np.allclose(back.pose.covariance, ros.pose.covariance)


unit = st.floats(-1.0, 1.0, allow_nan=False)


@settings(max_examples=200, deadline=None)
@given(axis=st.tuples(unit, unit, unit), angle=st.floats(0.0, math.pi, allow_nan=False))
def test_the_rotation_helpers_agree_with_scipy(axis, angle):
    """A rotation vector's matrix (Rodrigues), the matrix's rotation vector and its
    quaternion are scipy's, to rounding, up to a half turn (the rotation vector short of
    one: the estimator's turns are those of a tick)."""
    from footfall.estimation.rotations import rodrigues, rotation_of, rotation_vectors

    direction = np.asarray(axis)
    if np.linalg.norm(direction) < 1e-3:
        direction = np.array([0.0, 0.0, 1.0])
    rotvec = angle * direction / np.linalg.norm(direction)
    truth = Rotation.from_rotvec(rotvec)
    matrix = rodrigues(rotvec)
    assert np.allclose(matrix, truth.as_matrix(), atol=1e-12)
    assert (rotation_of(matrix) * truth.inv()).magnitude() < 1e-9
    if angle < 3.0:  # near a half turn the axis is ill-conditioned (and has two signs)
        assert np.allclose(rotation_vectors(matrix[None])[0], rotvec, atol=1e-9)


def test_a_limp_robot_keeps_its_place_at_the_height_its_legs_give():
    """While the servos are not standing (limp, rising, sitting) the feet slide as the legs
    fold: the body keeps its place over the ground and takes its height from the legs; the
    odometry's horizontal motion of sliding feet is not believed."""
    walk = SyntheticWalk(forward=0.0, left=0.0, yaw_rate=0.0)
    estimator = LegInertialEstimator(walk.kin, Pose(walk.start, Rotation.identity()))
    rest = walk.spec.rest_feet_in_body()
    rest[:, 2] += walk.spec.foot_radius
    for k in range(100):
        fold = k / 99  # the legs fold: the body sinks 2 cm, the feet slide 2 cm outwards
        feet = rest.copy()
        feet[:, :2] *= 1.0 + fold * 0.02 / np.linalg.norm(rest[:, :2], axis=1)[:, None]
        feet[:, 2] += 0.02 * fold
        angles = walk.kin.inverse_in_body(feet)
        still = (np.zeros((6, 3)), np.zeros(3), Rotation.identity(), np.ones(6, dtype=bool))
        estimator.update(BodyReading(k * DT, angles, *still, supported=False))
    assert np.allclose(estimator.position, walk.start - [0.0, 0.0, 0.02], atol=1e-9)
