"""``footfall bench soak``: walk laps for a long time and watch memory and per-frame time.

The planned robot (camera, map, footholds) walks from a terrain's start towards its goal
and walks back to the start backwards, and so on, for a given wall-clock time: backwards,
its feet land where it walked before, on cells its camera has seen (turning on the spot at
an end puts feet beside the robot, where the camera never looked). So that those cells are
still in the rolling map on the way back, a lap stops short of the goal where the map
window would have scrolled the start out (``LAP_SHARE`` of its half-width). A robot that freezes for
want of a foothold backs off the way it came for a moment and tries again, as an operator
would. The run keeps bounded logs (the per-tick record and the touchdowns as ring
buffers). Every ``sample_seconds`` it samples the resident memory, the mean per-frame
mapping time and per-tick control time since the last sample (wall and CPU time: the CPU
time leaves out the waits when other processes share the machine, though not a slower
machine), and the number of live Python objects. ``soak.json`` holds the samples, the
slope of each over time (least squares, per minute) and its growth from the
first to the last window (``window_minutes``, ten minutes, or a third of a shorter run).

A machine's own speed drifts over an hour (a virtual machine shares its host: the same
process measured 4.5 ms per frame at the start of one hour and 6.2 ms in a fresh process
at its end), and CPU time drifts with it. So each sample also times a fixed workload,
:class:`ReferenceWork` (the soak's first depth frame fused into an empty map and scored),
and gives the per-frame and per-tick CPU times as ratios to it: the ratios grow only
when the soak itself gets slower.
"""

from __future__ import annotations

import gc
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from footfall.errors import ConfigError
from footfall.mapping.engine import HeightMapConfig
from footfall.mapping.height_map import HeightMap
from footfall.messages import DepthFrame, GaitState, PoseEstimate, WalkCommand
from footfall.robot.spec import HexapodSpec, load_spec
from footfall.runtime.bus import InProcessBus
from footfall.runtime.scheduler import SimulatedScheduler
from footfall.scoring.walkability import ScoreConfig, score_map
from footfall.sim.assembly import WalkingRobot
from footfall.sim.task import TerrainTask
from footfall.sim.terrains import make_terrain
from footfall.sim.walk_settings import WalkSettings

# Rows of the per-tick record and touchdowns kept during a soak.
LOG_TICKS = 2_000
# Heading correction: yaw rate per radian of heading error, and its limit [1/s], [rad/s].
YAW_GAIN = 1.0
YAW_RATE = 0.3
# A lap reaches at most this share of the map's half-width from its start.
LAP_SHARE = 0.8
# An end of the lap counts as reached this close to it [m].
END_TOLERANCE = 0.15
# A frozen robot backs off the way it came this long before it tries again [s].
BACK_OFF_S = 3.0
# A soak that stays frozen this long, backing off or not, has failed [s of walk time].
FROZEN_LIMIT_S = 30.0
# Runs of the reference workload at each sample; the fastest counts.
REFERENCE_RUNS = 3
QUANTITIES = (
    "rss_mb",
    "map_ms",
    "map_cpu_ms",
    "control_ms",
    "control_cpu_ms",
    "objects",
    "reference_cpu_ms",
    "map_per_reference",
    "control_per_reference",
)


def resident_mb() -> float:
    """Resident memory of this process [MiB] (``/proc``; peak RSS where there is none)."""
    try:
        with open("/proc/self/statm") as f:
            pages = int(f.read().split()[1])
        import resource

        return pages * resource.getpagesize() / 2**20
    except OSError:
        import resource

        return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


@dataclass(frozen=True)
class ReferenceWork:
    """A fixed mapping workload: one depth frame fused into an empty map and scored.

    Timed at every sample of a soak, it measures the machine's speed at that moment with
    the same kernels the soak runs.

    Args:
        frame: The depth frame (the soak's first).
        pose: Its pose estimate.
        map_config: The map's configuration.
        score_config: The scoring's configuration.
    """

    frame: DepthFrame
    pose: PoseEstimate
    map_config: HeightMapConfig
    score_config: ScoreConfig

    def cpu_ms(self) -> float:
        """CPU time of the workload, the fastest of ``REFERENCE_RUNS`` [ms]."""
        body = self.pose.body_in_world.position
        best = math.inf
        for _ in range(REFERENCE_RUNS):
            height_map = HeightMap(self.map_config, centre=(float(body[0]), float(body[1])))
            cpu0 = time.thread_time()
            height_map.integrate_depth(
                self.frame.depth,
                self.frame.intrinsics,
                self.pose.camera_in_world,
                depth_scale=self.frame.depth_scale,
            )
            score_map(height_map.snapshot(), self.score_config)
            best = min(best, 1e3 * (time.thread_time() - cpu0))
        return best


@dataclass
class LapTask:
    """Walk forwards from the first end of a terrain to the second, and backwards to the first.

    Args:
        ends: The two ends, world ``(x, y)`` [m]; the body faces from the first to the second.
        command: Speed and body height.
    """

    ends: tuple[np.ndarray, np.ndarray]
    command: WalkCommand
    laps: int = 0
    back_offs: int = 0
    _target: int = 1
    _back_off_until: float = -math.inf
    _back_off_kind: int = -1  # 0: walk the other way, 1, 2: turn left, right

    def next_command(
        self, x: float, y: float, yaw: float, t: float, frozen: bool = False
    ) -> WalkCommand:
        """The command for a body at ``(x, y, yaw)`` at time ``t``.

        A frozen robot gets a new command for ``BACK_OFF_S``, as an operator would give:
        first walk the other way, over ground it has just crossed; when it froze again, turn
        on the spot one way, then the other (a foot at the end of its reach gets back into
        it), and so on; it then heads for its end again.
        """
        if frozen and t >= self._back_off_until:
            self.back_offs += 1
            self._back_off_until = t + BACK_OFF_S
            self._back_off_kind = (self._back_off_kind + 1) % 3
        elif not frozen and t >= self._back_off_until + BACK_OFF_S:
            self._back_off_kind = -1  # walking again: the next freeze starts with backing off
        target = self.ends[self._target]
        if math.hypot(target[0] - x, target[1] - y) < END_TOLERANCE:
            self._target = 1 - self._target
            self.laps += self._target == 1  # back at the start: one lap done
            target = self.ends[self._target]
        forwards = self._target == 1
        if t < self._back_off_until:
            if self._back_off_kind > 0:
                return WalkCommand(
                    speed=0.0,
                    body_height=self.command.body_height,
                    yaw_rate=YAW_RATE if self._back_off_kind == 1 else -YAW_RATE,
                    stamp=t,
                )
            forwards = not forwards
        # Backwards, the body keeps facing the second end: the way to go is behind it.
        heading = math.atan2(target[1] - y, target[0] - x) + (0.0 if self._target else math.pi)
        error = math.atan2(math.sin(heading - yaw), math.cos(heading - yaw))
        return WalkCommand(
            direction=(1.0, 0.0) if forwards else (-1.0, 0.0),
            speed=self.command.speed,
            body_height=self.command.body_height,
            yaw_rate=float(np.clip(YAW_GAIN * error, -YAW_RATE, YAW_RATE)),
            stamp=t,
        )


def trends(samples: list[dict[str, float]], window_minutes: float) -> dict[str, object]:
    """Slope per minute and first-to-last-window growth of every sampled quantity."""
    minutes = np.array([s["wall_minutes"] for s in samples])
    slopes, growth, first, last = {}, {}, {}, {}
    early = minutes <= minutes[0] + window_minutes
    late = minutes >= minutes[-1] - window_minutes
    for name in QUANTITIES:
        values = np.array([s[name] for s in samples], dtype=np.float64)
        ok = np.isfinite(values)
        slopes[name] = (
            float(np.polyfit(minutes[ok], values[ok], 1)[0]) if ok.sum() >= 2 else math.nan
        )
        a = float(np.nanmean(values[early & ok])) if (early & ok).any() else math.nan
        b = float(np.nanmean(values[late & ok])) if (late & ok).any() else math.nan
        first[name], last[name] = a, b
        growth[name] = (b - a) / a if a else math.nan
    return {
        "slope_per_minute": slopes,
        "first_window_mean": first,
        "last_window_mean": last,
        "growth": growth,
    }


def run_soak(
    minutes: float,
    terrain: str = "cobblestones",
    sample_seconds: float = 10.0,
    spec: HexapodSpec | None = None,
    on_sample: Callable[[dict[str, float]], None] | None = None,
) -> dict[str, object]:
    """Walk laps for ``minutes`` of wall time, sampling memory and per-frame times.

    Returns:
        The ``soak.json`` content (see the module docstring).

    Raises:
        ConfigError: A run shorter than two samples.
    """
    if not (math.isfinite(minutes) and minutes * 60.0 >= 2 * sample_seconds > 0):
        raise ConfigError(
            f"a soak needs at least two samples: --minutes {minutes} with a sample every "
            f"{sample_seconds} s"
        )
    spec = spec or load_spec("default")
    settings = WalkSettings(terrain=terrain, seconds=1e9, blind=False)
    bus = InProcessBus()
    first: dict[str, DepthFrame | PoseEstimate] = {}
    bus.subscribe(DepthFrame.TOPIC, lambda m: first.setdefault("frame", m))
    bus.subscribe(PoseEstimate.TOPIC, lambda m: first.setdefault("pose", m))
    ground = make_terrain(settings.terrain, seed=settings.seed)
    robot = WalkingRobot.build(spec, settings, ground, bus, log_ticks=LOG_TICKS)
    mapping = robot.mapping
    assert mapping is not None
    frame, pose = first["frame"], first["pose"]  # the robot's first frame and its pose
    assert isinstance(frame, DepthFrame) and isinstance(pose, PoseEstimate)
    reference = ReferenceWork(
        replace(frame, depth=np.array(frame.depth)), pose, settings.map, settings.score
    )
    # The terrain task only judges (a fall, a robot frozen too long); the laps steer.
    judge = TerrainTask(bus, ground, settings.command, frozen_timeout=FROZEN_LIMIT_S)
    start, goal = np.array(ground.start, dtype=float), np.array(ground.goal, dtype=float)
    way = goal - start
    reach = min(float(np.hypot(*way)), LAP_SHARE * 0.5 * settings.map.extent)
    laps = LapTask((start, start + reach * way / np.hypot(*way)), settings.command)
    judge.begin()
    scheduler = SimulatedScheduler(settings.control_rate_hz)
    dt = scheduler.period
    samples: list[dict[str, float]] = []
    wall_start = time.perf_counter()
    next_sample = wall_start + sample_seconds
    frames_seen = 0
    tick_ms: list[float] = []
    tick_cpu_ms: list[float] = []
    sim_seconds = 0.0
    end_reason = ""

    def tick(t: float) -> bool:
        nonlocal next_sample, frames_seen, end_reason, sim_seconds
        assert judge.status is not None
        pose = judge.status.body_pose
        frozen = judge.status.state is GaitState.FROZEN
        bus.publish(WalkCommand.TOPIC, laps.next_command(pose.x, pose.y, pose.yaw, t, frozen))
        robot.step(t, dt)
        tick_ms.append(1e3 * robot.control_seconds)
        tick_cpu_ms.append(1e3 * robot.control_cpu_seconds)
        sim_seconds = t + dt
        if judge.should_stop(t + dt):
            frozen = judge.status.state is GaitState.FROZEN
            end_reason = (
                f"frozen for {FROZEN_LIMIT_S:g} s: {judge.status.frozen_reason}"
                if frozen
                else "the robot fell"
            )
            return True
        now = time.perf_counter()
        if now < next_sample:
            return now - wall_start >= minutes * 60.0
        new_frames = mapping.frames - frames_seen
        frames_seen = mapping.frames
        recent = list(mapping.update_ms)[-new_frames:] if new_frames > 0 else []
        recent_cpu = list(mapping.update_cpu_ms)[-new_frames:] if new_frames > 0 else []
        sample = {
            "wall_minutes": (now - wall_start) / 60.0,
            "sim_seconds": t + dt,
            "laps": laps.laps,
            "rss_mb": resident_mb(),
            "map_ms": float(np.mean(recent)) if recent else math.nan,
            "map_cpu_ms": float(np.mean(recent_cpu)) if recent_cpu else math.nan,
            "control_ms": float(np.mean(tick_ms)) if tick_ms else math.nan,
            "control_cpu_ms": float(np.mean(tick_cpu_ms)) if tick_cpu_ms else math.nan,
            "objects": float(len(gc.get_objects())),
        }
        sample["reference_cpu_ms"] = reference.cpu_ms()
        sample["map_per_reference"] = sample["map_cpu_ms"] / sample["reference_cpu_ms"]
        sample["control_per_reference"] = sample["control_cpu_ms"] / sample["reference_cpu_ms"]
        tick_ms.clear()
        tick_cpu_ms.clear()
        samples.append(sample)
        if on_sample is not None:
            on_sample(sample)
        next_sample += sample_seconds
        return now - wall_start >= minutes * 60.0

    scheduler.run(tick, settings.seconds)
    robot.close()
    window = min(10.0, minutes / 3.0)
    figures: dict[str, object] = {
        "minutes": minutes,
        "terrain": terrain,
        "sample_seconds": sample_seconds,
        "window_minutes": window,
        "laps": laps.laps,
        "back_offs": laps.back_offs,
        "sim_seconds": sim_seconds,
        "fell": end_reason == "the robot fell",
        "ended_early": end_reason,
        "log_ticks_kept": len(robot.graph.recorder.log.time),
        "samples": samples,
    }
    if len(samples) >= 2:
        figures.update(trends(samples, window))
    return figures
