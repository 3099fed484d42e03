"""A walk request resolved against its robot and terrain: what ``footfall walk`` walks.

Below the reports (the benchmarks set up their walks with it as ``footfall walk`` does).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

from footfall.errors import ConfigError, UnreachableTargetError
from footfall.messages import WalkCommand
from footfall.motion.gait import DEFAULT_SPEED_MPS, GaitConfig
from footfall.robot.kinematics import LegKinematics
from footfall.robot.spec import HexapodSpec, load_spec
from footfall.runtime.fault_spec import FaultSpec
from footfall.sim.model import CameraMount
from footfall.sim.overrides import Setting, apply_settings, apply_walk_settings
from footfall.sim.terrain import Terrain
from footfall.sim.terrains import TERRAINS, difficulty_parameters, make_terrain
from footfall.sim.walk_settings import WalkSettings

# A walk with no --seconds gets this many times the straight line's time, and at least
# MIN_DEFAULT_SECONDS [s].
DEFAULT_TIME_MARGIN = 2.0
MIN_DEFAULT_SECONDS = 60.0
# Terrain parameters a walk may set by their own option (``--rise``, ``--groove``).
TERRAIN_OPTIONS = ("rise", "groove")


@dataclass(frozen=True)
class WalkRequest:
    """What to walk (the options of ``footfall walk``).

    Attributes:
        terrain: Terrain name.
        seconds: Longest walking time [s]; None for :func:`default_seconds`.
        speed: Body speed [m/s]; None for the default.
        gait: Gait name.
        robot: Built-in robot name or a robot TOML file.
        blind: The thesis' baseline (no camera, nominal footholds, no feedback).
        swing: ``"flow"`` or ``"polynomial"``.
        height: Body height [m]; None for the robot's.
        stride: Stride [m]; None for the robot's.
        control_rate_hz: Controller rate [Hz].
        image_size: Depth image width and height [px].
        seed: Terrain seed.
        rise: Stairs' step height [m], or None.
        groove: Cobblestones' groove width [m], or None.
        difficulty: The terrain's difficulty parameter (``Terrain.difficulty``), or
            None for its default.
        straight: Walk the straight line to the goal (the thesis' behaviour) instead of
            planned routes.
        goal: Goal ``(x, y)`` in the world [m]; None for the terrain's.
        realtime: Pace the walk to the wall clock.
        record: An ``.mcap`` file to record every bus message to.
        rerun: An ``.rrd`` file to log the walk to for the rerun viewer.
        rerun_spawn: Open a rerun viewer on the walk.
        faults: Faults to inject, as ``footfall walk --faults`` writes them ("" for none).
        backend: The robot backend (a name in ``BACKENDS``).
        backend_options: Settings for the backend.
        camera: The camera source (a name in ``CAMERAS``), or None to walk blind.
        pose: The pose source (a name in ``POSES``).
        camera_options: Settings for the camera source.
        pose_options: Settings for the pose source.
        overrides: Configuration fields set by name (``--set``, :mod:`footfall.sim.overrides`),
            as ``(name, value)`` pairs.
    """

    terrain: str = "stairs"
    seconds: float | None = None
    speed: float | None = None
    gait: str = "tripod"
    robot: str = "default"
    blind: bool = False
    swing: str = "flow"
    height: float | None = None
    stride: float | None = None
    control_rate_hz: float = 100.0
    image_size: tuple[int, int] = (320, 240)
    seed: int = 0
    rise: float | None = None
    groove: float | None = None
    difficulty: float | None = None
    straight: bool = False
    goal: tuple[float, float] | None = None
    realtime: bool = False
    record: Path | None = None
    rerun: Path | None = None
    rerun_spawn: bool = False
    faults: str = ""
    backend: str = "sim"
    backend_options: dict[str, str] = field(default_factory=dict)
    camera: str | None = "sim"
    pose: str = "sim"
    camera_options: dict[str, str] = field(default_factory=dict)
    pose_options: dict[str, str] = field(default_factory=dict)
    overrides: tuple[Setting, ...] = ()


@dataclass(frozen=True)
class WalkJob:
    """A walk request resolved against its robot and terrain.

    Attributes:
        request: The request.
        spec: The robot.
        settings: The simulation settings.
        terrain: The terrain.
        terrain_params: The terrain parameters the request set.
    """

    request: WalkRequest
    spec: HexapodSpec
    settings: WalkSettings
    terrain: Terrain
    terrain_params: dict[str, float]

    @property
    def speed(self) -> float:
        """Commanded body speed [m/s]."""
        return self.settings.command.speed


def default_seconds(
    terrain: Terrain, speed: float, goal: tuple[float, float] | None = None
) -> float:
    """A walk's longest time when none is asked for [s].

    Twice what the straight line from the start to the goal takes at ``speed`` (room for
    routes round obstacles, slowed steps and freezes that clear), and never less than
    ``MIN_DEFAULT_SECONDS``: a slow gait gets the time to reach its goal.
    """
    goal = terrain.goal if goal is None else goal
    distance = math.dist(terrain.start, goal)
    return max(MIN_DEFAULT_SECONDS, DEFAULT_TIME_MARGIN * distance / speed)


def _check_stance(spec: HexapodSpec, height: float) -> None:
    """That the robot can stand at ``height``: every foot at rest within reach and limits.

    Raises:
        ConfigError: Naming the robot, the height and the leg that cannot reach.
    """
    feet = spec.rest_feet_in_body(height)
    feet[:, 2] += spec.foot_radius
    try:
        LegKinematics(spec).inverse_in_body(feet)
    except UnreachableTargetError as exc:
        raise ConfigError(
            f"robot {spec.name!r} cannot stand at body height {height:g} m: {exc}"
        ) from exc


def prepare_walk(request: WalkRequest) -> WalkJob:
    """Resolve a request: the robot, the speed, the terrain and its parameters.

    Raises:
        ConfigError: A speed above the gait's top speed, a body height the robot cannot
            stand at, or a terrain parameter given for another terrain.
    """
    spec = apply_settings(load_spec(request.robot), "robot", request.overrides)
    gait = GaitConfig(kind=request.gait, swing=request.swing, stride_length=request.stride)
    gait = apply_settings(gait, "gait", request.overrides)
    max_speed = gait.for_robot(spec).max_speed
    speed = min(DEFAULT_SPEED_MPS, 0.75 * max_speed) if request.speed is None else request.speed
    if speed > max_speed + 1e-12:
        raise ConfigError(
            f"--speed {speed} m/s is above the {request.gait} gait's top speed "
            f"{max_speed:.3f} m/s for robot {spec.name!r} (stride over the shortest step); "
            "lower it or use a faster gait"
        )
    params = {}
    owners = {parameter: terrain for terrain, parameter in difficulty_parameters().items()}
    for name in TERRAIN_OPTIONS:
        value = getattr(request, name)
        if value is not None:
            if owners.get(name) != request.terrain:
                raise ConfigError(f"--{name} applies to --terrain {owners.get(name)} only")
            params[name] = value
    if request.difficulty is not None:
        name = TERRAINS.get(request.terrain).difficulty
        if name is None:
            raise ConfigError(
                f"terrain {request.terrain!r} has no difficulty parameter; terrains with one: "
                f"{', '.join(difficulty_parameters())}"
            )
        if name in params and params[name] != request.difficulty:
            raise ConfigError(f"--difficulty and --{name} disagree")
        params[name] = request.difficulty
    if request.straight and request.blind:
        raise ConfigError("--straight is for planned walking; a blind walk always goes straight")
    terrain = make_terrain(request.terrain, request.seed, **params)
    seconds = request.seconds
    if seconds is None:
        seconds = default_seconds(terrain, speed, request.goal)
    height = spec.body_height if request.height is None else request.height
    _check_stance(spec, height)
    width, image_height = request.image_size
    settings = WalkSettings(
        terrain=request.terrain,
        seconds=seconds,
        command=WalkCommand(speed=speed, body_height=height),
        gait=gait,
        blind=request.blind or request.camera is None,
        camera=CameraMount(width=width, height=image_height),
        control_rate_hz=request.control_rate_hz,
        seed=request.seed,
        stop_at_goal=True,
        realtime=request.realtime,
        faults=FaultSpec.parse(request.faults),
        straight=request.straight,
        goal=request.goal,
        backend=request.backend,
        backend_options=dict(request.backend_options),
        camera_source=request.camera or "sim",
        pose_source=request.pose,
        camera_options=dict(request.camera_options),
        pose_options=dict(request.pose_options),
    )
    settings = apply_walk_settings(settings, request.overrides)
    return WalkJob(request, spec, settings, terrain, params)
