"""``footfall walk``: the simulated hexapod crossing a terrain with the full loop."""

from __future__ import annotations

import argparse
from pathlib import Path

from rich.console import Console

from footfall.cli.commands import summary
from footfall.cli.common import (
    add_recording_options,
    format_value,
    key_values,
    print_table,
    sim_progress,
    wrote,
)
from footfall.errors import ConfigError
from footfall.motion.gait import DEFAULT_SPEED_MPS, GAITS
from footfall.motion.swing import SWINGS
from footfall.robot.spec import BUILTIN_ROBOTS

SUMMARY = (
    ("distance", "distance_m", "{:.3f} m"),
    ("mean speed", "mean_speed_mps", "{:.4f} m/s"),
    ("commanded speed", "commanded_speed_mps", "{:.4f} m/s"),
    ("fell", "fell", "{}"),
    ("frozen", "frozen", "{}"),
    ("body height error (mean)", "body_height_error_mean_m", "{:+.4f} m"),
    ("body height oscillation", "body_height_oscillation_ratio", "{:.1%}"),
    ("tilt max", "tilt_max_deg", "{:.2f} deg"),
    ("tilt rms", "tilt_rms_deg", "{:.2f} deg"),
    ("stance slip max", "stance_slip_max_m", "{:.4f} m"),
    ("swing apex (median)", "swing_apex_median_m", "{:.3f} m"),
    ("steps", "steps", "{}"),
    ("reached goal", "reached_goal", "{}"),
    ("no route", "no_route", "{}"),
    ("distance to goal", "goal_distance_m", "{:.3f} m"),
    ("invalid footholds", "invalid_footholds", "{}"),
    ("footholds adjusted", "footholds_adjusted", "{}"),
    ("min swing clearance", "min_clearance_m", "{:.4f} m"),
    ("real-time factor", "realtime_factor", "{:.1f}x"),
    ("estimator distance", "estimator_distance_m", "{:.3f} m"),
    ("estimator position drift", "estimator_position_drift_m", "{:.4f} m"),
    ("estimator heading drift", "estimator_heading_drift_deg", "{:.2f} deg"),
)


def add_parser(subparsers: argparse._SubParsersAction) -> None:
    """Add ``walk``."""
    from footfall.nodes.sources import POSES
    from footfall.sim.terrains import TERRAINS, difficulty_parameters

    p = subparsers.add_parser(
        "walk",
        help=summary("walk"),
        description=(
            "Simulate the hexapod in MuJoCo walking to the far end of a terrain with the full "
            "loop: depth camera -> height map -> walkability scores -> footholds -> gait -> "
            "joints (or --blind, the thesis' baseline). Writes metrics.json, walk.png (body "
            "height, roll and pitch, one foot's path) and footholds.png (every foothold over "
            "the score map) to --out."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    p.add_argument("--terrain", choices=TERRAINS.names(), default="stairs", help="terrain to cross")
    p.add_argument(
        "--seconds",
        type=float,
        help="longest walking time in seconds; the walk ends at the goal [default: twice the "
        "straight line's time to the goal at the commanded speed, at least 60 s]",
    )
    p.add_argument(
        "--speed",
        type=float,
        default=None,
        help=(
            f"body speed in m/s; default {DEFAULT_SPEED_MPS} m/s, or 3/4 of the gait's top speed "
            "(stride over the shortest step) when that is lower"
        ),
    )
    p.add_argument("--gait", choices=GAITS.names(), default="tripod", help="gait")
    p.add_argument(
        "--robot",
        default="default",
        help=f"built-in robot ({', '.join(BUILTIN_ROBOTS)}) or a robot description TOML file",
    )
    p.add_argument(
        "--blind",
        action="store_true",
        help="the thesis' baseline: no camera, nominal footholds on a flat floor, no feedback",
    )
    p.add_argument(
        "--swing",
        choices=SWINGS.names(),
        default="flow",
        help="swing trajectory: the thesis' flow function, its polynomial-arc baseline, or "
        "one you registered",
    )
    p.add_argument(
        "--height", type=float, default=None, help="body height in m (robot's nominal by default)"
    )
    p.add_argument("--stride", type=float, default=None, help="stride in m (robot's by default)")
    p.add_argument("--control-rate", type=float, default=100.0, help="controller rate in Hz")
    p.add_argument(
        "--image-size",
        type=int,
        nargs=2,
        metavar=("W", "H"),
        default=(320, 240),
        help="depth image size in pixels",
    )
    p.add_argument(
        "--seed",
        type=int,
        default=0,
        help="seed of the terrain (lays the cobblestones, shifts the stairs' start by up to "
        "10 cm); runs with the same seed are identical",
    )
    p.add_argument("--rise", type=float, help="stairs: step height in m (default 0.04)")
    p.add_argument(
        "--groove", type=float, help="cobblestones: groove width between stones in m (0.03)"
    )
    p.add_argument(
        "--difficulty",
        type=float,
        help=(
            "the terrain's difficulty parameter: "
            + ", ".join(
                f"{t} {n} [{TERRAINS.get(t).difficulty_unit}]"
                for t, n in difficulty_parameters().items()
            )
        ),
    )
    p.add_argument(
        "--straight",
        action="store_true",
        help=(
            "walk the straight line from the start to the goal, as the thesis did, instead of "
            "routes planned round what cannot be crossed"
        ),
    )
    p.add_argument(
        "--goal",
        type=float,
        nargs=2,
        metavar=("X", "Y"),
        help="goal in the world in m (default: the terrain's)",
    )
    p.add_argument(
        "--realtime",
        action="store_true",
        help="pace the control loop to the wall clock, as on a real robot (overruns counted)",
    )
    p.add_argument(
        "--faults",
        default="",
        metavar="SPEC",
        help=(
            "inject faults between the nodes, comma-separated name=value items: drop=0.3 "
            "(fraction of depth frames lost), delay=0.2 (seconds every frame arrives late), "
            "repeat=0.1 (fraction of frames repeating the previous image), nan=0.05 (fraction "
            "of each image covered by NaN and zero patches), drift=slam (SLAM-like pose drift "
            "and jitter; drift=slam:5 five times as much), jump=0.1:5@8 (the pose jumps 0.1 m "
            "and 5 degrees at t = 8 s; repeatable), pose_loss=1.0@10 (no pose for 1 s from "
            "t = 10 s), overrun=0.05 (fraction of control ticks running late by one to three "
            "periods)"
        ),
    )
    p.add_argument(
        "--pose",
        choices=POSES.names(),
        default="sim",
        help="the pose source placing the camera's images: sim (the simulator's truth), "
        "estimator (footfall's own, from the legs and the IMU, which read as a real robot's; "
        "metrics.json gains estimator_position_drift_m, estimator_heading_drift_deg and "
        "estimator_distance_m), or one you registered",
    )
    p.add_argument(
        "--pose-option",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="a setting for the pose source (estimator: noise=realistic|none, seed=N); repeatable",
    )
    p.add_argument(
        "--servo-bus",
        choices=("protocol1", "protocol2"),
        help=(
            "drive the simulated robot's joints through an emulated Dynamixel bus on a "
            "pseudo-terminal (dynamixel-sdk on one end, emulated servos on the other), with "
            "the robot's [hardware] table or, without one, AX-12A (protocol1) or XM430-W350 "
            "(protocol2) servos; metrics.json gains servo_bus"
        ),
    )
    p.add_argument(
        "--servo-fault",
        action="append",
        default=[],
        metavar="KIND:ID@SECONDS",
        help="with --servo-bus: a servo fault (silent, overheat, checksum, port); repeatable",
    )
    p.add_argument(
        "--set",
        action="append",
        dest="sets",
        metavar="NAME=VALUE",
        help="set a field of the robot, gait, scoring, mapping, planner, navigation or "
        "feedback configuration by its name, e.g. scoring.threshold=0.4 (repeatable; units "
        "SI, tuples as A:B)",
    )
    add_recording_options(p)
    p.add_argument("--out", type=Path, default=Path("footfall-out/walk"), help="output folder")
    p.set_defaults(handler=run)


def run(args: argparse.Namespace, console: Console) -> int:
    """Walk, write the outputs, print the summary."""
    from footfall.reports.walk import run_walk
    from footfall.sim.overrides import walk_settings
    from footfall.sim.walk_request import WalkRequest, prepare_walk

    backend, options = "sim", {}
    if args.servo_bus is not None:
        backend = "servo-bus"
        options = {"protocol": args.servo_bus.removeprefix("protocol"), "robot": args.robot}
        options["control_period"] = str(1.0 / args.control_rate)
        if args.servo_fault:
            options["fault"] = ",".join(args.servo_fault)
    elif args.servo_fault:
        raise ConfigError("--servo-fault goes with --servo-bus")
    job = prepare_walk(
        WalkRequest(
            terrain=args.terrain,
            seconds=args.seconds,
            speed=args.speed,
            gait=args.gait,
            robot=args.robot,
            blind=args.blind,
            swing=args.swing,
            height=args.height,
            stride=args.stride,
            control_rate_hz=args.control_rate,
            image_size=tuple(args.image_size),
            seed=args.seed,
            rise=args.rise,
            groove=args.groove,
            difficulty=args.difficulty,
            straight=args.straight,
            goal=tuple(args.goal) if args.goal is not None else None,
            realtime=args.realtime,
            record=args.record,
            rerun=args.rerun,
            rerun_spawn=args.rerun_spawn,
            faults=args.faults,
            backend=backend,
            backend_options=options,
            pose=args.pose,
            pose_options=key_values("--pose-option", args.pose_option),
            overrides=walk_settings(args.sets),
        )
    )
    if args.blind:
        mode = "blind (thesis baseline)"
    elif args.straight:
        mode = "with camera, map and foothold planning, on the straight line"
    else:
        mode = "with camera, map, foothold planning and route planning"
    console.print(
        f"Walking robot [bold]{job.spec.name}[/] across [bold]{args.terrain}[/] terrain, {mode}: "
        f"{args.gait} gait at {job.speed:.3f} m/s, at most {job.settings.seconds:g} s"
    )
    with sim_progress(console) as progress:
        task = progress.add_task("walk", total=job.settings.seconds)
        report = run_walk(job, on_tick=lambda t: progress.update(task, completed=t))
    paths = report.write(args.out)
    metrics = report.to_json()
    print_table(
        console,
        "walk summary",
        [(label, format_value(metrics[key], fmt)) for label, key, fmt in SUMMARY if key in metrics],
    )
    if "faults" in metrics:
        injected = ", ".join(
            f"{k.replace('_', ' ')} {v}" for k, v in metrics["faults"].items() if v
        )
        console.print(
            f"Faults injected: {injected or 'none'}. Caught: {metrics['pose_jumps_detected']} "
            f"pose jumps ({metrics['pose_jumps_refuted']} more suspected and refuted by the "
            f"map), {metrics['frames_inconsistent']} inconsistent frames, "
            f"{metrics['frames_repeated']} repeated images; stood {metrics['stale_stops']} "
            f"times for a stale pose or map; froze {metrics['freezes']} times."
        )
    if metrics["reached_goal"]:
        console.print(
            f"[green]Reached the goal[/] with {metrics['invalid_footholds']} invalid footholds."
        )
    elif metrics["fell"]:
        console.print("[red]The robot fell.[/]")
    elif metrics.get("no_route"):
        console.print(f"[yellow]The robot stood still:[/] {metrics['no_route_reason']}")
    elif metrics["frozen"]:
        console.print(f"[yellow]The robot froze safely:[/] {metrics['frozen_reason']}")
    else:
        console.print(f"Time ran out {metrics['goal_distance_m']:.2f} m short of the goal.")
    wrote(console, paths)
    return 0
