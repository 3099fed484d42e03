"""``footfall walk-biped``: Archie walks a plan in MuJoCo, on a map or through a seeded room.

A dissertation map or a map file brings its obstacles (standing cylinders where the map
has circles) and its goal: the whole walk is planned once (path, footsteps, LIPM pattern,
§6.3) and executed. In a room the robot knows nothing in advance: it looks with its head
camera, detects obstacles in the point cloud (§6.3.1), plans from where it stands to the
goal around every obstacle seen so far, walks at most ``look_ahead_m`` of that path, stops
with its feet together and looks again; a new obstacle in view changes the next plan.

Planning uses the body's footprint, not the map's nominal hip width: obstacles grow by
the widest reach of the feet and hip from the COM path plus a margin, so a body that
follows its footsteps does not touch them.

Frames: the world (map) frame, z up, start at the map's start.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import NamedTuple

import mujoco
import numpy as np
import numpy.typing as npt

from footfall.biped.avoidance import AvoidancePath, Circle
from footfall.biped.body import SIDES, BipedSpec, load_biped_spec, mean_heading
from footfall.biped.footsteps import (
    Footsteps,
    StepLimits,
    footsteps_from_parameters,
    plan_footsteps,
)
from footfall.biped.gait import GaitConfig, GaitPattern, gait_pattern
from footfall.biped.lipm import LipmConfig, WalkParameter, lipm_pattern
from footfall.biped.maps import FOOT_LENGTH, PlanMap, dissertation_map, load_map
from footfall.biped.planner import WalkPlan, plan_walk
from footfall.errors import ConfigError, PlanningError
from footfall.sim.biped_model import Obstacle, biped_mjcf, camera_mount
from footfall.sim.biped_room import Room, make_room
from footfall.sim.biped_sim import BipedSimulation
from footfall.sim.biped_walk import BipedRun, StabiliserConfig, run_pattern, stand
from footfall.sim.model import CameraMount

OBSTACLE_HEIGHT = 0.5  # cylinders standing for a map's circles [m]
CLEARANCE = 0.05  # margin between the body's reach and an obstacle [m]
GOAL_TOLERANCE = 0.25  # the walk reached its goal when the COM ends this close [m]


@dataclass(frozen=True)
class WalkBipedRequest:
    """What to walk: exactly one of a case, a map file and a room seed.

    Attributes:
        case: One of the dissertation's 11 maps.
        map: A JSON map file.
        room: Seed of a random room seen through the camera.
        kajita: Kajita's straight textbook walk (s_x 0.3 m, 4 steps) on a bare floor.
        goal: Goal instead of the source's [m].
        spec: Biped spec name or TOML file.
        stabiliser: Stabiliser gains.
        look_ahead_m: In a room, how far to walk between looks [m].
        max_looks: In a room, the most looks before giving up.
    """

    case: int | None = None
    map: Path | None = None
    room: int | None = None
    kajita: bool = False
    goal: tuple[float, float] | None = None
    spec: str = "archie"
    stabiliser: StabiliserConfig = field(default_factory=StabiliserConfig)
    look_ahead_m: float = 1.0
    max_looks: int = 16

    def __post_init__(self) -> None:
        sources = (self.case, self.map, self.room, True if self.kajita else None)
        if sum(v is not None for v in sources) != 1:
            raise ConfigError("walk-biped needs exactly one of --case, --map, --room and --kajita")


def body_radius(spec: BipedSpec, step_width: float) -> float:
    """The farthest the body reaches from the COM path: a foot's corner or the hip's [m]."""
    foot = 0.5 * step_width + math.hypot(0.5 * spec.foot_length, 0.5 * spec.foot_width)
    hip = math.hypot(0.5 * spec.pelvis_size[0], 0.5 * spec.pelvis_size[1])
    return max(foot, hip)


def body_plan_map(plan_map: PlanMap, spec: BipedSpec) -> PlanMap:
    """The map with its hip width grown so inflation covers the body (see the module doc)."""
    reach = body_radius(spec, plan_map.limits.width) + CLEARANCE
    hip_width = max(plan_map.hip_width, 2.0 * reach - FOOT_LENGTH)
    return replace(plan_map, hip_width=hip_width)


def _cylinders(circles: tuple[Circle, ...]) -> tuple[Obstacle, ...]:
    return tuple(Obstacle("cylinder", c.x, c.y, 2 * c.r, 2 * c.r, OBSTACLE_HEIGHT) for c in circles)


@dataclass
class Segment:
    """One planned and walked piece of the walk."""

    plan: WalkPlan
    pattern: GaitPattern
    run: BipedRun
    seen: tuple[Circle, ...] = ()
    stretch: npt.NDArray[np.float64] | None = None  # the part of the path walked


@dataclass
class BipedWalk:
    """A finished ``walk-biped``."""

    name: str
    plan_map: PlanMap
    obstacles: tuple[Obstacle, ...]
    segments: list[Segment]
    reached_goal: bool
    fell: bool
    collisions: int
    no_route: str | None
    spec: BipedSpec

    def metrics(self) -> dict[str, object]:
        """The ``metrics.json`` content."""
        logs = [s.run.log.arrays() for s in self.segments]
        margin = np.concatenate([a["zmp_margin"] for a in logs]) if logs else np.array([np.nan])
        com_err = np.concatenate(
            [np.linalg.norm(a["com"] - a["com_ref"], axis=1) for a in logs]
        ) if logs else np.array([np.nan])  # fmt: skip
        errors = []
        for s in self.segments:
            planned = s.pattern.footholds[1 : 1 + len(s.run.actual_footholds)]
            errors += list(np.linalg.norm(s.run.actual_footholds - planned, axis=1))
        sim_s = sum(s.run.sim_seconds for s in self.segments)
        wall_s = sum(s.run.wall_seconds for s in self.segments)
        finite = margin[np.isfinite(margin)]
        return {
            "name": self.name,
            "reached_goal": self.reached_goal,
            "fell": self.fell,
            "collisions": self.collisions,
            "zmp_margin_min_m": float(finite.min()) if len(finite) else None,
            "footstep_error_mean_m": float(np.mean(errors)) if errors else None,
            "footstep_error_max_m": float(np.max(errors)) if errors else None,
            "com_tracking_error_max_m": (
                float(np.nanmax(com_err)) if np.isfinite(com_err).any() else None
            ),
            "realtime_factor": sim_s / wall_s if wall_s > 0 else None,
            "sim_seconds": sim_s,
            "footsteps": int(sum(len(s.run.actual_footholds) for s in self.segments)),
            "plans": len(self.segments),
            "no_route": self.no_route,
            "stopped": next((s.run.stopped for s in self.segments if s.run.stopped), None),
            "goal": list(self.plan_map.goal),
            "final_com": (self.segments[-1].run.log.com[-1].tolist() if self.segments else None),
            "simulator_warnings": int(sum(s.run.warnings for s in self.segments)),
        }


def standing_feet(
    sim: BipedSimulation,
) -> tuple[dict[str, tuple[float, float, float]], npt.NDArray[np.float64], float]:
    """The feet where they stand, their midpoint and heading."""
    feet = {}
    for side in SIDES:
        p, r = sim.sole(side), sim.sole_rotation(side)
        feet[side] = (float(p[0]), float(p[1]), math.atan2(r[1, 0], r[0, 0]))
    mid = 0.5 * (np.array(feet["left"][:2]) + np.array(feet["right"][:2]))
    return feet, mid, mean_heading(feet["left"][2], feet["right"][2])


def ideal_feet(start, heading: float, width: float) -> dict[str, tuple[float, float, float]]:
    """Feet side by side, ``width`` apart, about ``start`` facing ``heading`` [m], [rad]."""
    normal = np.array([-math.sin(heading), math.cos(heading)])
    s = np.asarray(start, dtype=np.float64)
    left, right = s + 0.5 * width * normal, s - 0.5 * width * normal
    return {"left": (*left, heading), "right": (*right, heading)}


def gait_config(spec: BipedSpec, lipm: LipmConfig) -> GaitConfig:
    """The gait's timing and step height for a robot and its pendulum settings."""
    return GaitConfig(step_time=lipm.support_time, step_height=spec.step_height)


def gait_for(
    spec: BipedSpec, footsteps: Footsteps, feet, z_c: float, lipm: LipmConfig
) -> GaitPattern:
    """The gait that walks ``footsteps`` from standing on ``feet``."""
    return gait_pattern(footsteps, feet, z_c, gait_config(spec, lipm))


def walk_plan_map(
    plan_map: PlanMap, spec: BipedSpec, stabiliser: StabiliserConfig, name: str
) -> BipedWalk:
    """Plan a known map once and walk it."""
    obstacles = _cylinders(plan_map.obstacles)
    feet = ideal_feet(plan_map.start, 0.0, plan_map.limits.width)
    sim = BipedSimulation(spec, mujoco.MjModel.from_xml_string(biped_mjcf(spec, obstacles)))
    z_c = stand(sim, feet)
    lipm = LipmConfig(com_height=z_c)
    try:
        plan = plan_walk(body_plan_map(plan_map, spec), lipm)
    except PlanningError as exc:
        return BipedWalk(name, plan_map, obstacles, [], False, False, 0, str(exc), spec)
    return _walk(sim, plan, feet, z_c, lipm, stabiliser, name, obstacles)


def _walk(sim, plan: WalkPlan, feet, z_c: float, lipm: LipmConfig, stabiliser, name, obstacles):
    """Walk one plan from standing on ``feet``."""
    pattern = gait_for(sim.spec, plan.footsteps, feet, z_c, lipm)
    run = run_pattern(sim, pattern, stabiliser)
    reached = not run.fell and near_goal(sim.com()[:2], plan.map.goal)
    segment = Segment(plan, pattern, run)
    return BipedWalk(
        name, plan.map, obstacles, [segment], reached, run.fell, run.collisions, None, sim.spec
    )


KAJITA_STEPS = (0.0, 0.3, 0.3, 0.3, 0.0)  # s_x of the textbook example [m], s_y 0.2 m


def walk_kajita(spec: BipedSpec, stabiliser: StabiliserConfig) -> BipedWalk:
    """Kajita's example (the dissertation's Fig. 29): 0.3 m steps, 0.2 m apart, T_sup 0.8 s.

    The walk parameters go straight to the footsteps (eqs. 96-98), with the LIPM pattern
    over them kept in the plan as ``footfall plan`` computes it.
    """
    params = [WalkParameter(sx, 0.2) for sx in KAJITA_STEPS]
    footsteps = footsteps_from_parameters(params, (0.0, 0.0), first_step_left=False)
    feet = ideal_feet((0.0, 0.0), 0.0, 0.2)
    sim = BipedSimulation(spec, mujoco.MjModel.from_xml_string(biped_mjcf(spec)))
    z_c = stand(sim, feet)
    lipm = LipmConfig(com_height=z_c)
    support = footsteps.positions.copy()
    support[0] = (0.0, 0.0)
    pattern = lipm_pattern(params, lipm, footsteps=support, first_step_left=False)
    goal = (float(sum(KAJITA_STEPS)), 0.0)
    path = AvoidancePath(np.array([(0.0, 0.0), goal]), goal[0], 0)
    plan = WalkPlan(PlanMap("kajita", (0.0, 0.0), goal, ()), path, footsteps, pattern, 0.0, 0)
    return _walk(sim, plan, feet, z_c, lipm, stabiliser, "kajita", ())


def near_goal(point, goal) -> bool:
    """Whether a COM point ends close enough to the goal."""
    return float(np.hypot(*(np.asarray(point) - np.asarray(goal)))) <= GOAL_TOLERANCE


def truncate_path(waypoints: npt.NDArray[np.float64], length: float) -> npt.NDArray[np.float64]:
    """The path's first ``length`` metres."""
    out = [waypoints[0]]
    left = length
    for a, b in itertools.pairwise(waypoints):
        d = float(np.hypot(*(b - a)))
        if d >= left:
            out.append(a + (b - a) * (left / d) if d > 0 else b)
            return np.array(out)
        out.append(b)
        left -= d
    return np.array(out)


class RoomStand(NamedTuple):
    """Archie standing at a room's start.

    Its model, simulation and head camera's mount, the step limits, the COM's height and
    the pendulum's settings.
    """

    model: mujoco.MjModel
    sim: BipedSimulation
    mount: CameraMount
    limits: StepLimits
    z_c: float
    lipm: LipmConfig


def stand_in_room(room: Room, spec: BipedSpec) -> RoomStand:
    """Build the room with Archie in it and stand him at its start, facing +x."""
    mount = camera_mount(spec)
    model = mujoco.MjModel.from_xml_string(biped_mjcf(spec, room.obstacles, mount))
    sim = BipedSimulation(spec, model)
    limits = PlanMap(room.name, room.start, room.goal, ()).limits
    z_c = stand(sim, ideal_feet(room.start, 0.0, limits.width))
    return RoomStand(model, sim, mount, limits, z_c, LipmConfig(com_height=z_c))


def walk_room(room: Room, spec: BipedSpec, request: WalkBipedRequest) -> BipedWalk:
    """Look, plan, walk a stretch, repeat: the room seen only through the head camera."""
    from footfall.sim.biped_look import look

    model, sim, mount, limits, z_c, lipm = stand_in_room(room, spec)
    seen: list[Circle] = []
    segments: list[Segment] = []
    no_route = None
    from footfall.sim.camera import SimDepthCamera

    camera = SimDepthCamera(model, mount)
    try:
        for _ in range(request.max_looks):
            seen = look(camera, sim, seen)
            feet, here, heading = standing_feet(sim)
            if near_goal(here, room.goal):
                break
            plan_map = body_plan_map(PlanMap(room.name, tuple(here), room.goal, tuple(seen)), spec)
            try:
                full = plan_walk(plan_map, lipm)
            except PlanningError as exc:
                no_route = str(exc)
                break
            stretch = truncate_path(full.path.waypoints, request.look_ahead_m)
            footsteps = plan_footsteps(stretch, limits, initial_heading=heading)
            plan = replace(full, footsteps=footsteps)
            pattern = gait_for(spec, footsteps, feet, z_c, lipm)
            run = run_pattern(sim, pattern, request.stabiliser)
            segments.append(Segment(plan, pattern, run, tuple(seen), stretch))
            if run.fell or run.stopped:
                break
    finally:
        camera.close()
    fell = any(s.run.fell for s in segments)
    reached = not fell and near_goal(sim.com()[:2], room.goal)
    full_map = PlanMap(room.name, room.start, room.goal, tuple(seen))
    return BipedWalk(
        room.name, full_map, room.obstacles, segments, reached, fell, sim.collisions, no_route, spec
    )


def walk_biped(request: WalkBipedRequest) -> BipedWalk:
    """Run the walk a request asks for."""
    spec = load_biped_spec(request.spec)
    if request.kajita:
        return walk_kajita(spec, request.stabiliser)
    if request.room is not None:
        room = make_room(request.room)
        if request.goal is not None:
            room = replace(room, goal=request.goal)
        return walk_room(room, spec, request)
    if request.case is not None:
        plan_map, name = dissertation_map(request.case), f"case {request.case}"
    else:
        plan_map, name = load_map(request.map), Path(request.map).stem
    plan_map = plan_map.with_endpoints(goal=request.goal)
    return walk_plan_map(plan_map, spec, request.stabiliser, name)
