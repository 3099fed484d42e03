"""Sensor and timing faults injected between nodes, on demand.

A :class:`~footfall.runtime.fault_spec.FaultSpec` is parsed from ``name=value`` items
(``footfall walk --faults``):

=============  ==================================================================
``drop=F``     a fraction F of depth frames is lost
``delay=S``    every depth frame arrives S seconds late
``repeat=F``   a fraction F of frames repeats the previous image (a frozen camera)
``nan=F``      NaN and zero-depth patches cover a fraction F of every image
``drift=slam`` SLAM-like drift and jitter on the pose (``footfall map --noise slam``);
               ``drift=slam:K`` K times as much
``jump=D:A@T`` the pose estimate jumps by D metres and A degrees at T seconds
               (repeatable); the translation is horizontal, the rotation about an
               axis drawn at random (seeded), both about the camera
``pose_loss=S@T``  no pose estimate for S seconds from T seconds on
``overrun=F``  a fraction F of control ticks runs late, by one to three periods
=============  ==================================================================

:class:`FaultyLink` is the sensors' side of a faulty link: the camera and the pose source
publish through it; nodes that subscribe through it see the true stream (the pose source
answers every image taken), the bus behind it gets the faulted one. Every fault draws
from one seeded generator, so a run repeats exactly.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np
import numpy.typing as npt
from scipy.spatial.transform import Rotation

from footfall.messages import DepthFrame, PoseEstimate
from footfall.messages.codec import Message
from footfall.runtime.bus import Bus, Callback, Handler
from footfall.runtime.fault_spec import FaultSpec, PoseJump
from footfall.sensing.pose import Pose, SlamNoise

# A late control tick is late by one to this many periods.
MAX_OVERRUN_PERIODS = 3
# Side of one NaN or zero patch, as a fraction of the image's shorter side.
PATCH_FRACTION = 0.08


@dataclass
class FaultCounts:
    """What the injector did.

    Attributes:
        frames_dropped: Depth frames lost.
        frames_delayed: Depth frames delivered late.
        frames_repeated: Depth frames that carried the previous image.
        frames_patched: Depth frames with NaN and zero patches.
        poses_lost: Pose estimates withheld.
        jumps: Pose jumps applied.
        ticks_late: Control ticks that ran late.
    """

    frames_dropped: int = 0
    frames_delayed: int = 0
    frames_repeated: int = 0
    frames_patched: int = 0
    poses_lost: int = 0
    jumps: int = 0
    ticks_late: int = 0


def cover_with_patches(
    depth: npt.NDArray, fraction: float, rng: np.random.Generator
) -> npt.NDArray:
    """A copy of ``depth`` with square patches of NaN (float) or zero covering ``fraction``."""
    out = np.array(depth, copy=True)
    if fraction <= 0.0:
        return out
    h, w = out.shape
    side = max(1, round(PATCH_FRACTION * min(h, w)))
    covered = np.zeros((h, w), dtype=bool)
    target = fraction * h * w
    floating = np.issubdtype(out.dtype, np.floating)
    for _ in range(10_000):  # bounded: patches overlap, a few more than the area needs
        if covered.sum() >= target:
            break
        i, j = (
            int(rng.integers(0, max(h - side, 0) + 1)),
            int(rng.integers(0, max(w - side, 0) + 1)),
        )
        value = np.nan if floating and rng.random() < 0.5 else 0
        out[i : i + side, j : j + side] = value
        covered[i : i + side, j : j + side] = True
    return out


class FaultyLink:
    """The sensors' end of a link that loses, delays, corrupts and shifts their messages.

    Args:
        bus: The bus the faulted messages go on to.
        spec: The faults.
        seed: Seed of every random draw.
        pose_topic: The topic pose estimates travel on.
    """

    def __init__(
        self, bus: Bus, spec: FaultSpec, seed: int = 0, pose_topic: str = PoseEstimate.RAW_TOPIC
    ) -> None:
        self.bus = bus
        self.spec = spec
        self.pose_topic = pose_topic
        self.rng = np.random.default_rng([seed, 0x0FA17])
        self.counts = FaultCounts()
        self._local: dict[str, list[Callback]] = {DepthFrame.TOPIC: [], pose_topic: []}
        self._held: list[tuple[float, str, Message]] = []
        self._previous_depth: npt.NDArray | None = None
        self._drift = SlamNoise(spec.drift, self.rng) if spec.drift is not None else None
        self._jumps = sorted(spec.jumps, key=lambda j: j.at_s)
        self._jump_error = Pose.identity()  # world-frame error applied to every estimate
        self._jumps_done = 0
        self._late_until = -math.inf

    # The Bus protocol, sensor side ---------------------------------------------------------
    def publish(self, topic: str, message: Message) -> None:
        """Publish ``message``: true to the sensor side, faulted to the bus."""
        for callback in tuple(self._local.get(topic, ())):
            callback(message)
        if topic == DepthFrame.TOPIC and isinstance(message, DepthFrame):
            self._depth(message)
        elif topic == self.pose_topic and isinstance(message, PoseEstimate):
            self._pose(message)
        else:
            self.bus.publish(topic, message)

    def subscribe(self, topic: str, callback: Callback, last: bool = False) -> None:
        """Subscribe; to the depth and pose topics, on the sensor side (the true stream)."""
        if topic in self._local:
            self._local[topic].append(callback)
        else:
            self.bus.subscribe(topic, callback, last=last)

    def serve(self, service: str, handler: Handler) -> None:
        """Serve on the bus."""
        self.bus.serve(service, handler)

    def request(self, service: str, message: Message, timeout: float = 1.0) -> Message:
        """Request over the bus."""
        return self.bus.request(service, message, timeout)

    def spin(self, timeout: float = 0.0) -> int:
        """Spin the bus."""
        return self.bus.spin(timeout)

    # Time ----------------------------------------------------------------------------------
    def advance(self, t: float) -> None:
        """Deliver the held messages due by time ``t`` [s], oldest first."""
        due = [held for held in self._held if held[0] <= t + 1e-9]
        if not due:
            return
        self._held = [held for held in self._held if held[0] > t + 1e-9]
        for _, topic, message in sorted(due, key=lambda held: held[0]):
            self.bus.publish(topic, message)

    def tick_late(self, period_s: float) -> float:
        """How late the control tick about to run is [s]: 0, or one to three periods."""
        if self.spec.overrun <= 0.0 or self.rng.random() >= self.spec.overrun:
            return 0.0
        self.counts.ticks_late += 1
        return period_s * int(self.rng.integers(1, MAX_OVERRUN_PERIODS + 1))

    # Faults --------------------------------------------------------------------------------
    def _depth(self, frame: DepthFrame) -> None:
        s, rng = self.spec, self.rng
        previous, self._previous_depth = self._previous_depth, frame.depth
        if s.drop > 0.0 and rng.random() < s.drop:
            self.counts.frames_dropped += 1
            return
        depth = frame.depth
        if s.repeat > 0.0 and previous is not None and rng.random() < s.repeat:
            self.counts.frames_repeated += 1
            depth = previous
        if s.nan > 0.0:
            self.counts.frames_patched += 1
            depth = cover_with_patches(depth, s.nan, rng)
        if depth is not frame.depth:
            frame = replace(frame, depth=depth)
        if s.delay_s > 0.0:
            self.counts.frames_delayed += 1
            self._held.append((frame.stamp + s.delay_s, DepthFrame.TOPIC, frame))
            return
        self.bus.publish(DepthFrame.TOPIC, frame)

    def _pose(self, estimate: PoseEstimate) -> None:
        s = self.spec
        if s.pose_loss is not None:
            duration, start = s.pose_loss
            if start <= estimate.stamp < start + duration:
                self.counts.poses_lost += 1
                return
        camera_in_body = estimate.body_in_world.inverse().compose(estimate.camera_in_world)
        camera = estimate.camera_in_world
        if self._drift is not None:
            camera = self._drift.estimate(camera, estimate.stamp)
        while self._jumps_done < len(self._jumps) and self._jumps[self._jumps_done].at_s <= (
            estimate.stamp
        ):
            self._jump_error = self._jump(self._jumps[self._jumps_done], camera).compose(
                self._jump_error
            )
            self._jumps_done += 1
            self.counts.jumps += 1
        camera = self._jump_error.compose(camera)
        body = camera.compose(camera_in_body.inverse())
        self.bus.publish(self.pose_topic, PoseEstimate(estimate.stamp, camera, body))

    def _jump(self, jump: PoseJump, camera: Pose) -> Pose:
        """The world-frame transform of one jump, about the camera's estimated position."""
        heading = self.rng.uniform(0.0, 2.0 * math.pi)
        axis = self.rng.normal(size=3)
        axis /= max(float(np.linalg.norm(axis)), 1e-12)
        rotation = Rotation.from_rotvec(axis * math.radians(jump.angle_deg))
        shift = jump.distance_m * np.array([math.cos(heading), math.sin(heading), 0.0])
        # Rotate about the camera, then shift: p -> R (p - c) + c + shift.
        centre = camera.position
        return Pose(centre + shift - rotation.apply(centre), rotation)


@dataclass
class TickFaults:
    """Control-tick overruns for a simulated loop: which ticks a late one swallows.

    Args:
        link: The faulty link whose generator draws the overruns.
        period_s: Control period [s].
    """

    link: FaultyLink
    period_s: float
    _busy_until: float = field(default=-math.inf)

    def skips(self, t: float) -> bool:
        """Whether the tick due at ``t`` [s] is lost to an earlier tick's overrun."""
        if t + 1e-9 < self._busy_until:
            return True
        late = self.link.tick_late(self.period_s)
        if late > 0.0:
            self._busy_until = t + self.period_s + late
        return False


FaultFactory = Callable[[Bus], FaultyLink]
