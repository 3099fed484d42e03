"""footfall's own pose source: the leg-inertial estimator as a node (``--pose estimator``).

It reads the robot's state every control tick (joint encoders, gyro, the IMU's attitude and,
where the robot senses them, which feet touch the ground), learns which feet support the
body from the controller's effector targets, and answers every depth image with the body's
pose and the camera's at that time (the newest tick's estimate at or before the image, the
robot's clock matched to the controller's through the controller's effector targets).
Its estimates go straight to the map and the controller (``PoseEstimate.TOPIC``), not
through the pose guard: the guard checks an outside estimate (a SLAM's) against the robot's
own odometry, and this estimate *is* that odometry, measured rather than commanded;
weighing it against the commanded motion would only pull it back towards what the legs
were asked to do. It gives no pose while it calibrates its gyro on a standing robot (the
robot stands until poses come) nor once it is lost (a body tipped over, no foot standing),
and logs both. While the servos are not standing (limp, rising, sitting) it holds the body
where it was over the ground, at the height its legs give. Every tick it also publishes its
estimate with its velocity and covariance (:class:`~footfall.messages.OdometryEstimate` on
``pose/odometry``; ``tracking`` False while it calibrates or once lost), as a legged robot's
state estimator does.

Each depth image also corrects the estimate's drift: it is registered against a map of the
images before it from the pose the estimate gives it, and the part of the difference that the
view constrains is fused with the estimate (:mod:`footfall.estimation.depth_correction`);
the pose published for that image is the corrected one.

Options (``--pose-option KEY=VALUE``): ``noise`` is ``realistic`` (the simulated robot's IMU
and encoders read as a real robot's, :mod:`footfall.estimation.sensor_noise`; the default on
a simulated or mocked robot) or ``none`` (the default on hardware, whose sensors have their
own); ``seed`` seeds that noise (the walk's seed by default); ``register`` is ``on`` (the
default; needs small_gicp, ``footfall[odometry]``) or ``off`` (legs and IMU alone).
"""

from __future__ import annotations

from collections import deque

import numpy as np
from scipy.spatial.transform import Rotation

from footfall.errors import ConfigError
from footfall.estimation.depth_correction import DepthCorrection
from footfall.estimation.leg_inertial import BodyReading, EstimatorConfig, LegInertialEstimator
from footfall.estimation.rotations import rotation_of
from footfall.estimation.sensor_noise import NoisySensors, SensorNoiseConfig
from footfall.messages import (
    DepthFrame,
    EffectorTargets,
    LogLine,
    OdometryEstimate,
    PoseEstimate,
    Posture,
    RobotState,
    ServoStatus,
)
from footfall.nodes.sources import SourceSetup
from footfall.robot.kinematics import LegKinematics
from footfall.robot.spec import HexapodSpec
from footfall.runtime.bus import Bus
from footfall.sensing.pose import Pose

# Ticks of estimates kept to answer an image taken a little earlier.
HISTORY_TICKS = 50


class EstimatorPose:
    """The leg-inertial estimator answering the camera's images.

    Args:
        bus: The robot's bus.
        spec: The robot.
        start: The body's pose when the robot starts (the world's frame is set by it).
        noise: Read the robot's state through this sensor model (a simulated robot).
        config: The estimator's weights.
        topic: Where the estimates go.
        correction: Registers the depth images to correct the estimate (None: legs and IMU
            alone).

    Attributes:
        estimator: The estimator.
        answered: Images answered with a pose.
        unanswered: Images left without one (calibrating or lost).
    """

    name = "pose"
    needs_imu = True  # the heading is the gyro's

    def __init__(
        self,
        bus: Bus,
        spec: HexapodSpec,
        start: Pose,
        noise: NoisySensors | None = None,
        config: EstimatorConfig | None = None,
        topic: str = PoseEstimate.TOPIC,
        correction: DepthCorrection | None = None,
    ) -> None:
        self.bus = bus
        self.correction = correction
        self.topic = topic
        self.noise = noise
        self.estimator = LegInertialEstimator(LegKinematics(spec), start, config)
        self.answered = 0
        self.unanswered = 0
        self._swinging = np.zeros(6, dtype=bool)
        # (robot's time, body position, body rotation matrix) of the latest ticks.
        self._history: deque[tuple[float, np.ndarray, np.ndarray]] = deque(maxlen=HISTORY_TICKS)
        self._said: str | None = None
        self._clock_offset = 0.0  # the controller's clock minus the robot's [s]
        self._posture: Posture | None = None  # the servos' (none heard: standing)
        bus.subscribe(RobotState.TOPIC, self._on_state)
        bus.subscribe(EffectorTargets.TOPIC, self._on_targets, last=True)
        bus.subscribe(ServoStatus.TOPIC, self._on_servo, last=True)
        bus.subscribe(DepthFrame.TOPIC, self._on_depth)

    @classmethod
    def open(cls, setup: SourceSetup) -> EstimatorPose:
        """The estimator on ``setup.spec``'s robot; options ``noise`` and ``seed``.

        Raises:
            ConfigError: An unknown option or value, or no robot spec.
        """
        options = dict(setup.options)
        unknown = sorted(set(options) - {"noise", "seed", "register"})
        if unknown:
            raise ConfigError(
                f"the estimator pose source has no option {', '.join(unknown)}; "
                "it takes noise, seed, register"
            )
        register = options.get("register", "on")
        if register not in ("on", "off"):
            raise ConfigError(f"register={register!r}: choose on or off")
        # A robot whose time is computed (a simulator, a mock) reads exactly: noise by default.
        computed = not getattr(setup.backend, "realtime", True)
        noise_name = options.get("noise", "realistic" if computed else "none")
        if noise_name not in ("realistic", "none"):
            raise ConfigError(f"noise={noise_name!r}: choose realistic or none")
        try:
            seed = int(options.get("seed", setup.seed))
        except ValueError as exc:
            raise ConfigError(f"seed={options['seed']!r} is not an integer") from exc
        spec = setup.spec
        if spec is None:
            raise ConfigError("the estimator needs the robot's spec (its legs' kinematics)")
        state = setup.backend.read()
        start = start_pose(spec, state)
        noise = (
            NoisySensors(SensorNoiseConfig(), np.random.default_rng(seed))
            if noise_name == "realistic"
            else None
        )
        try:
            correction = DepthCorrection() if register == "on" else None
        except ConfigError as exc:
            raise ConfigError(f"{exc}; or walk without it: --pose-option register=off") from exc
        return cls(setup.bus, spec, start, noise, correction=correction)

    def _on_targets(self, targets: EffectorTargets) -> None:
        self._swinging = np.asarray(targets.swinging, dtype=bool)
        if self._history:
            # The controller stamps its targets on its own clock, from the state just read:
            # the robot's clock (the servos', the simulator's) may run apart from it.
            self._clock_offset = targets.stamp - self._history[-1][0]

    def _on_servo(self, status: ServoStatus) -> None:
        self._posture = status.posture

    def _on_state(self, state: RobotState) -> None:
        if self.noise is not None:
            state = self.noise.read(state)
        standing = ~self._swinging
        if state.feet_in_contact is not None:
            standing &= np.asarray(state.feet_in_contact, dtype=bool)
        self.estimator.update(
            BodyReading(
                state.time,
                state.joint_positions,
                state.joint_velocities,
                state.angular_velocity_body_in_body,
                state.orientation_body_in_world,
                standing,
                supported=self._posture in (None, Posture.STANDING),
            )
        )
        e = self.estimator
        self._history.append((state.time, e.position, e.rotation_matrix))
        body = Pose(e.position.copy(), rotation_of(e.rotation_matrix))
        odometry = OdometryEstimate(
            state.time + self._clock_offset, body, e.velocity, e.covariance.copy(), e.ready
        )
        self.bus.publish(OdometryEstimate.TOPIC, odometry)
        self._say(state.time)

    def _say(self, stamp: float) -> None:
        """Log when the estimator starts giving poses, and when it is lost."""
        e = self.estimator
        if e.lost is not None:
            state, level, text = "lost", "error", f"lost: {e.lost}; no more poses"
        elif e.calibrated:
            bias = np.degrees(e.bias).round(3).tolist()
            state, level, text = "ready", "info", f"calibrated: gyro bias {bias} deg/s"
        else:
            return
        if state != self._said:
            self._said = state
            self.bus.publish(LogLine.TOPIC, LogLine(stamp, "estimator", level, text))

    def _on_depth(self, frame: DepthFrame) -> None:
        if not self.estimator.ready or not self._history:
            self.unanswered += 1
            return
        taken = frame.stamp - self._clock_offset  # on the robot's clock
        chosen = self._history[0]
        for entry in self._history:
            if entry[0] <= taken + 1e-9:
                chosen = entry
        position, rotation = chosen[1].copy(), chosen[2]
        aligned = (0.0, 0.0)
        if self.correction is not None:
            e = self.estimator
            camera = Pose(position, rotation_of(rotation)).compose(frame.camera_in_body)
            correction = self.correction.register(
                frame.depth,
                frame.intrinsics,
                frame.depth_scale,
                camera.matrix,
                e.covariance[[0, 1, 2, 5]],
            )
            if correction.applied:
                e.correct(correction)
                self._history = deque(
                    ((t, *correction.apply(p, r)) for t, p, r in self._history),
                    maxlen=HISTORY_TICKS,
                )
                before = position
                position, rotation = correction.apply(position, rotation)
                aligned = (float(position[0] - before[0]), float(position[1] - before[1]))
        body = Pose(position, rotation_of(rotation))
        self.answered += 1
        camera = body.compose(frame.camera_in_body)
        self.bus.publish(self.topic, PoseEstimate(frame.stamp, camera, body, aligned))

    def drift(self, true_body_in_world: Pose) -> dict[str, float]:
        """How far the newest estimate is from the truth, and the distance walked.

        Returns ``estimator_position_drift_m``, ``estimator_heading_drift_deg``,
        ``estimator_distance_m``, ``estimator_height_drift_m`` (the vertical part, signed),
        ``estimator_position_sigma_m`` (the estimator's own 1-sigma horizontal error),
        ``estimator_slipped`` (foot readings left out), and ``estimator_corrections`` of
        ``estimator_correction_frames`` (depth images that corrected the estimate, of those
        registered).
        """
        e = self.estimator
        error = e.pose.position - true_body_in_world.position
        heading = (e.pose.rotation * true_body_in_world.rotation.inv()).as_euler("ZYX")[0]
        return {
            "estimator_position_drift_m": float(np.linalg.norm(error)),
            "estimator_heading_drift_deg": float(np.degrees(abs(heading))),
            "estimator_distance_m": e.distance_m,
            "estimator_height_drift_m": float(error[2]),
            "estimator_position_sigma_m": float(np.sqrt(e.covariance[0] + e.covariance[1])),
            "estimator_slipped": e.slipped,
            "estimator_corrections": 0 if self.correction is None else self.correction.applied,
            "estimator_correction_frames": 0 if self.correction is None else self.correction.frames,
        }


def start_pose(spec: HexapodSpec, state: RobotState) -> Pose:
    """Where the body stands when the robot starts: the world's frame.

    A robot that knows its place (the simulator, a motion-capture system) starts there; one
    that does not stands at the origin, heading along x, its height that of its body over
    its feet (levelled by the IMU).
    """
    attitude = state.orientation_body_in_world
    if state.position_body_in_world is not None:
        return Pose(np.asarray(state.position_body_in_world, dtype=np.float64), attitude)
    _, pitch, roll = attitude.as_euler("ZYX")
    rotation = Rotation.from_euler("ZYX", [0.0, pitch, roll])  # heading along x
    feet = rotation.apply(LegKinematics(spec).forward_in_body(state.joint_positions))
    height = -float(np.mean(feet[:, 2])) + spec.foot_radius
    return Pose(np.array([0.0, 0.0, height]), rotation)
