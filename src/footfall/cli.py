"""The ``footfall`` command line: thin wrappers that parse, call the library and print."""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn
from rich.table import Table

from footfall.errors import FootfallError
from footfall.motion.gait import GaitConfig, GaitKind, WalkCommand
from footfall.robot.spec import BUILTIN_ROBOTS, load_spec

# Largest height range within a flat map cell in one frame for recorded data [m]: a real
# depth sensor's noise spans several millimetres (the simulated camera is noise-free).
REAL_MAX_CELL_SPREAD = 0.01

DEFAULT_SPEED_MPS = 0.10


def _sim_progress(console: Console) -> Progress:
    """A progress bar over simulated seconds."""
    return Progress(
        TextColumn("simulating"),
        BarColumn(),
        TextColumn("{task.completed:.1f}/{task.total:.0f} s"),
        TimeRemainingColumn(),
        console=console,
        transient=True,
    )


def _walk_parser(subparsers: argparse._SubParsersAction) -> None:
    from footfall.sim.walk import TERRAINS

    p = subparsers.add_parser(
        "walk",
        help="simulate the hexapod walking across a terrain and measure it",
        description=(
            "Simulate the hexapod in MuJoCo walking to the far end of a terrain with the full "
            "loop: depth camera -> height map -> walkability scores -> footholds -> gait -> "
            "joints (or --blind, the thesis' baseline). Writes metrics.json, walk.png (body "
            "height, roll and pitch, one foot's path) and footholds.png (every foothold over "
            "the score map) to --out."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    p.add_argument("--terrain", choices=TERRAINS, default="stairs", help="terrain to cross")
    p.add_argument(
        "--seconds",
        type=float,
        default=60.0,
        help="longest walking time in seconds; the walk ends at the goal",
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
    p.add_argument("--gait", choices=[g.value for g in GaitKind], default="tripod", help="gait")
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
        choices=("flow", "polynomial"),
        default="flow",
        help="swing trajectory: the thesis' flow function or its polynomial-arc baseline",
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
    p.add_argument("--out", type=Path, default=Path("footfall-out/walk"), help="output folder")
    p.set_defaults(handler=_walk)


def _walk(args: argparse.Namespace, console: Console) -> int:
    from footfall.plots import plot_footholds, plot_walk
    from footfall.sim.model import CameraMount
    from footfall.sim.terrain import make_terrain
    from footfall.sim.walk import TrueScores, WalkSettings, simulate_walk

    spec = load_spec(args.robot)
    gait = GaitConfig(kind=args.gait, swing=args.swing, stride_length=args.stride)
    max_speed = gait.for_robot(spec.stride_length, spec.max_step_height).max_speed
    speed = min(DEFAULT_SPEED_MPS, 0.75 * max_speed) if args.speed is None else args.speed
    if speed > max_speed + 1e-12:
        raise FootfallError(
            f"--speed {speed} m/s is above the {args.gait} gait's top speed "
            f"{max_speed:.3f} m/s for robot {spec.name!r} (stride over the shortest step); "
            "lower it or use a faster gait"
        )
    height = spec.body_height if args.height is None else args.height
    width, image_height = args.image_size
    terrain_params = {}
    for option, value, kind in (
        ("rise", args.rise, "stairs"),
        ("groove", args.groove, "cobblestones"),
    ):
        if value is not None:
            if args.terrain != kind:
                raise FootfallError(f"--{option} applies to --terrain {kind} only")
            terrain_params[option] = value
    terrain = make_terrain(args.terrain, args.seed, **terrain_params)
    settings = WalkSettings(
        terrain=args.terrain,
        seconds=args.seconds,
        command=WalkCommand(speed=speed, body_height=height),
        gait=gait,
        blind=args.blind,
        camera=CameraMount(width=width, height=image_height),
        control_rate_hz=args.control_rate,
        seed=args.seed,
        stop_at_goal=True,
    )
    mode = "blind (thesis baseline)" if args.blind else "with camera, map and foothold planning"
    console.print(
        f"Walking robot [bold]{spec.name}[/] across [bold]{args.terrain}[/] terrain, {mode}: "
        f"{args.gait} gait at {speed:.3f} m/s, at most {args.seconds:g} s"
    )
    with _sim_progress(console) as progress:
        task = progress.add_task("walk", total=args.seconds)
        result = simulate_walk(
            spec, settings, on_tick=lambda t: progress.update(task, completed=t), terrain=terrain
        )

    out: Path = args.out
    out.mkdir(parents=True, exist_ok=True)
    metrics = dict(result.metrics)
    metrics["mujoco_warnings"] = result.warnings
    metrics["terrain_params"] = terrain_params
    (out / "metrics.json").write_text(json.dumps(metrics, indent=2) + "\n")
    title = f"{spec.name}: {args.gait} gait at {speed:.3f} m/s on {args.terrain} terrain"
    plot_walk(
        result.log,
        out / "walk.png",
        leg=0,
        leg_name=spec.leg_names[0],
        ground=result.terrain.height,
        title=title + (" (blind)" if args.blind else ""),
    )
    path_xy = result.log.array("body_position_in_world")[:, :2]
    if result.scores is not None:
        scores = result.scores
        background = (scores.score, scores.valid, scores.origin, scores.resolution)
        label = "the robot's score map"
    else:
        goal_x = result.terrain.goal[0]
        truth = TrueScores(
            result.terrain, settings.map.resolution, settings.score, (-1.0, goal_x + 1.0, -1.5, 1.5)
        )
        background = (truth.score, truth.valid, truth.origin, truth.resolution)
        label = "the true terrain's score map"
    plot_footholds(
        result.touchdowns,
        *background,
        out / "footholds.png",
        path_xy,
        title=f"footholds over {label}",
    )
    _print_summary(console, metrics)
    if metrics["reached_goal"]:
        console.print(
            f"[green]Reached the goal[/] with {metrics['invalid_footholds']} invalid footholds."
        )
    elif metrics["fell"]:
        console.print("[red]The robot fell.[/]")
    elif metrics["frozen"]:
        console.print(f"[yellow]The robot froze safely:[/] {metrics['frozen_reason']}")
    else:
        console.print(f"Time ran out {metrics['goal_distance_m']:.2f} m short of the goal.")
    console.print(f"Wrote {out / 'metrics.json'}, {out / 'walk.png'} and {out / 'footholds.png'}")
    return 0


def _print_summary(console: Console, metrics: dict[str, object]) -> None:
    table = Table(title="walk summary", show_header=True)
    table.add_column("metric")
    table.add_column("value", justify="right")
    rows = [
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
        ("distance to goal", "goal_distance_m", "{:.3f} m"),
        ("invalid footholds", "invalid_footholds", "{}"),
        ("footholds adjusted", "footholds_adjusted", "{}"),
        ("min swing clearance", "min_clearance_m", "{:.4f} m"),
        ("real-time factor", "realtime_factor", "{:.1f}x"),
    ]
    for label, key, fmt in rows:
        value = metrics[key]
        text = fmt.format(value) if not (isinstance(value, float) and math.isnan(value)) else "n/a"
        table.add_row(label, text)
    console.print(table)


def _map_parser(subparsers: argparse._SubParsersAction) -> None:
    from footfall.sim.survey import NOISE_MODELS
    from footfall.sim.terrain import TERRAIN_NAMES

    p = subparsers.add_parser(
        "map",
        help="build a height map and score map, in simulation or from a recorded sequence",
        description=(
            "Walk the simulated hexapod across a terrain while its depth camera builds the "
            "rolling height map, or map a recorded TUM-layout sequence (--tum). Writes "
            "heightmap.png, scoremap.png and metrics.json to --out."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    p.add_argument(
        "--terrain", choices=TERRAIN_NAMES, default="course", help="terrain to walk and map"
    )
    p.add_argument("--seconds", type=float, default=20.0, help="walking time in seconds")
    p.add_argument(
        "--noise",
        choices=NOISE_MODELS,
        default="none",
        help="pose estimate: true, or SLAM-like drift and jitter",
    )
    p.add_argument("--seed", type=int, default=0, help="seed of the terrain and the pose noise")
    p.add_argument(
        "--image-size",
        type=int,
        nargs=2,
        metavar=("W", "H"),
        default=(640, 480),
        help="depth image size in pixels",
    )
    p.add_argument(
        "--fusion",
        choices=("latest", "max", "variance"),
        default="latest",
        help="per-cell fusion rule",
    )
    p.add_argument(
        "--max-cell-spread",
        type=float,
        default=None,
        help="height range in m within one cell in one frame (beyond its slope) above which "
        "the cell straddles an edge; default: the score's for the simulated camera, "
        f"{REAL_MAX_CELL_SPREAD} for a recorded sequence (a real sensor's noise spans mm)",
    )
    p.add_argument(
        "--tum", type=Path, default=None, help="map this TUM-layout sequence instead of simulating"
    )
    p.add_argument(
        "--intrinsics",
        type=float,
        nargs=4,
        metavar=("FX", "FY", "CX", "CY"),
        default=(525.0, 525.0, 319.5, 239.5),
        help="depth camera intrinsics in pixels (with --tum)",
    )
    p.add_argument(
        "--up",
        type=float,
        nargs=3,
        metavar=("X", "Y", "Z"),
        default=(0.0, 0.0, 1.0),
        help="the recorded world's up axis (with --tum); TUM and Redwood worlds are not z-up",
    )
    p.add_argument(
        "--depth-scale", type=float, default=1.0 / 5000.0, help="metres per depth unit (with --tum)"
    )
    p.add_argument("--out", type=Path, default=Path("footfall-out/map"), help="output folder")
    p.set_defaults(handler=_map)


def _map(args: argparse.Namespace, console: Console) -> int:
    from footfall.mapping.height_map import HeightMapConfig
    from footfall.plots import plot_height_map, plot_score_map
    from footfall.scoring.walkability import ScoreConfig

    map_config = HeightMapConfig(fusion=args.fusion)
    score_config = ScoreConfig()
    if args.max_cell_spread is not None or args.tum is not None:
        spread = REAL_MAX_CELL_SPREAD if args.max_cell_spread is None else args.max_cell_spread
        score_config = ScoreConfig(max_cell_spread=spread)
    out: Path = args.out
    if args.tum is not None:
        from footfall.datasets.tum import map_tum_sequence
        from footfall.sensing.camera import PinholeCamera

        fx, fy, cx, cy = args.intrinsics
        first = next(iter(sorted((args.tum / "depth").glob("*.png"))), None)
        if first is None:
            raise FootfallError(f"no depth/*.png in {args.tum}")
        from footfall.datasets.tum import load_depth_png

        height, width = load_depth_png(first).shape
        camera = PinholeCamera(fx, fy, cx, cy, width, height)
        console.print(f"Mapping recorded sequence {args.tum}")
        result = map_tum_sequence(
            args.tum, camera, args.up, map_config, score_config, args.depth_scale
        )
        snapshot, scores, path_xy, metrics = (
            result.snapshot,
            result.scores,
            result.camera_path_xy,
            result.metrics,
        )
        path_label = "camera path"
    else:
        from footfall.sim.model import CameraMount
        from footfall.sim.survey import MappingSettings, simulate_mapping

        width, height = args.image_size
        settings = MappingSettings(
            terrain=args.terrain,
            seconds=args.seconds,
            noise=args.noise,
            seed=args.seed,
            camera=CameraMount(width=width, height=height),
            map=map_config,
            score=score_config,
        )
        console.print(
            f"Mapping [bold]{args.terrain}[/] terrain for {args.seconds:g} s "
            f"({width}x{height} depth at {settings.camera.rate_hz:g} Hz, pose noise: {args.noise})"
        )
        with _sim_progress(console) as progress:
            task = progress.add_task("map", total=args.seconds)
            survey = simulate_mapping(
                load_spec("default"), settings, on_tick=lambda t: progress.update(task, completed=t)
            )
        snapshot, scores, path_xy, metrics = (
            survey.snapshot,
            survey.scores,
            survey.path_xy,
            survey.metrics,
        )
        path_label = "robot path"
    out.mkdir(parents=True, exist_ok=True)
    plot_height_map(
        snapshot.heights,
        snapshot.origin,
        snapshot.resolution,
        out / "heightmap.png",
        path_xy,
        path_label=path_label,
    )
    plot_score_map(
        scores.score,
        scores.valid,
        snapshot.origin,
        snapshot.resolution,
        score_config.threshold,
        out / "scoremap.png",
        path_xy,
        path_label=path_label,
    )
    (out / "metrics.json").write_text(json.dumps(metrics, indent=2) + "\n")
    table = Table(title="map summary")
    table.add_column("metric")
    table.add_column("value", justify="right")
    for key, value in metrics.items():
        if isinstance(value, float):
            table.add_row(key, f"{value:.4g}")
        elif isinstance(value, int | str):
            table.add_row(key, str(value))
    console.print(table)
    console.print(
        f"Wrote {out / 'heightmap.png'}, {out / 'scoremap.png'} and {out / 'metrics.json'}"
    )
    return 0


def _convert_parser(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "convert",
        help="convert recorded data into the TUM RGB-D layout",
        description="Convert recorded data into the TUM RGB-D layout `footfall map --tum` reads.",
    )
    kinds = p.add_subparsers(dest="kind", metavar="KIND", required=True)
    redwood = kinds.add_parser(
        "redwood",
        help="a Redwood/Open3D sequence (depth/*.png in mm, trajectory.log)",
        description=(
            "Convert a Redwood sequence: depth PNGs in millimetres become TUM units (1/5000 m), "
            "trajectory.log camera-to-world matrices become groundtruth.txt, frames are "
            "stamped i / fps."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    redwood.add_argument("source", type=Path, help="the Redwood folder")
    redwood.add_argument("destination", type=Path, help="output folder (TUM layout)")
    redwood.add_argument("--fps", type=float, default=30.0, help="frame rate for the timestamps")
    redwood.set_defaults(handler=_convert_redwood)


def _convert_redwood(args: argparse.Namespace, console: Console) -> int:
    from footfall.datasets.redwood import convert_redwood

    frames = convert_redwood(args.source, args.destination, args.fps)
    console.print(f"Wrote {frames} frames in the TUM layout to {args.destination}")
    return 0


def _bench_parser(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "bench",
        help="measure footfall's speed",
        description="Measure footfall's speed against baselines timed in the same run.",
    )
    kinds = p.add_subparsers(dest="suite", metavar="SUITE", required=True)
    mapping = kinds.add_parser(
        "mapping",
        help="depth frame -> map update, and scoring, against plain NumPy",
        description=(
            "Time one 640x480 depth frame -> points -> map update and the scoring of a "
            "256x256 map, against plain-NumPy baselines; writes bench.json to --out."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    mapping.add_argument("--repeats", type=int, default=30, help="timed repetitions per figure")
    mapping.add_argument(
        "--out", type=Path, default=Path("footfall-out/bench"), help="output folder"
    )
    mapping.set_defaults(handler=_bench_mapping)
    terrain = kinds.add_parser(
        "terrain",
        help="planned against blind walking over a difficulty sweep",
        description=(
            "Walk stairs (rise 0.02-0.08 m), cobblestones (groove 0.01-0.06 m) and the course, "
            "planned and blind, --seeds runs each; writes bench.json and bench.png to --out. "
            "Success = reached the goal, no fall, zero invalid footholds."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    terrain.add_argument(
        "--seeds", type=int, default=10, help="runs per terrain, difficulty and mode"
    )
    terrain.add_argument("--seconds", type=float, default=90.0, help="longest walk in seconds")
    terrain.add_argument(
        "--jobs", type=int, default=1, help="walks simulated at once, one process each"
    )
    terrain.add_argument(
        "--out", type=Path, default=Path("footfall-out/bench-terrain"), help="output folder"
    )
    terrain.set_defaults(handler=_bench_terrain)


def _bench_mapping(args: argparse.Namespace, console: Console) -> int:
    from footfall.benchmarking import run_mapping_benchmark

    results = run_mapping_benchmark(repeats=args.repeats)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "bench.json").write_text(json.dumps(results, indent=2) + "\n")
    table = Table(title="mapping benchmark (one core)")
    table.add_column("figure")
    table.add_column("value", justify="right")
    for key, value in results.items():
        table.add_row(key, f"{value:,.3f}" if isinstance(value, float) else str(value))
    console.print(table)
    console.print(f"Wrote {args.out / 'bench.json'}")
    return 0


def _bench_terrain(args: argparse.Namespace, console: Console) -> int:
    from footfall.benchmarking import run_terrain_benchmark, terrain_benchmark_runs
    from footfall.plots import plot_terrain_benchmark

    if args.seeds < 1:
        raise FootfallError(f"--seeds must be at least 1, got {args.seeds}")
    if args.jobs < 1:
        raise FootfallError(f"--jobs must be at least 1, got {args.jobs}")
    with Progress(
        TextColumn("{task.description}"),
        BarColumn(),
        TextColumn("{task.completed}/{task.total} walks"),
        TimeRemainingColumn(),
        console=console,
    ) as progress:
        task = progress.add_task("walking", total=terrain_benchmark_runs(args.seeds))
        bench = run_terrain_benchmark(
            args.seeds,
            args.seconds,
            on_run=lambda label: progress.update(task, advance=1, description=label),
            jobs=args.jobs,
        )
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "bench.json").write_text(json.dumps(bench, indent=2) + "\n")
    plot_terrain_benchmark(bench, args.out / "bench.png")
    table = Table(title=f"terrain benchmark, {args.seeds} seeds")
    for column in (
        "terrain",
        "difficulty",
        "mode",
        "success",
        "falls",
        "invalid",
        "frozen",
        "tilt (median)",
    ):
        table.add_column(column)
    for r in bench["results"]:
        table.add_row(
            r["terrain"],
            f"{r['difficulty']} {r['value']:g}" if r["difficulty"] != "none" else "-",
            r["mode"],
            f"{r['successes']}/{r['runs']}",
            str(r["falls"]),
            str(r["invalid_footholds"]),
            str(r["frozen"]),
            f"{r['median_tilt_max_deg']:.2f} deg",
        )
    console.print(table)
    planned, blind = bench["planned_success_rate"], bench["blind_success_rate"]
    rates = f"planned success {planned:.0%}, blind {blind:.0%}"
    console.print(f"{rates}; wrote {args.out / 'bench.json'} and {args.out / 'bench.png'}")
    return 0


def _plan_parser(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "plan",
        help="plan a biped's path, footsteps and centre-of-mass pattern around obstacles",
        description=(
            "Plan the humanoid's walk (dissertation §6.3): a path around circular obstacles, "
            "footsteps along it and the Linear Inverted Pendulum pattern over them. Writes "
            "plan.json and plan.png to --out."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    source = p.add_mutually_exclusive_group(required=True)
    source.add_argument("--map", type=Path, help="a JSON map file (see footfall.biped.maps)")
    source.add_argument("--case", type=int, help="one of the dissertation's 11 test maps")
    source.add_argument(
        "--cloud", type=Path, help="a point cloud (.pcd, .ply, .npy): detect obstacles, then plan"
    )
    _cloud_options(p)
    p.add_argument(
        "--start", type=float, nargs=2, metavar=("X", "Y"), help="start instead of the map's [m]"
    )
    p.add_argument(
        "--goal", type=float, nargs=2, metavar=("X", "Y"), help="goal instead of the map's [m]"
    )
    p.add_argument("--out", type=Path, default=Path("footfall-out/plan"), help="output folder")
    p.set_defaults(handler=_plan)


def _plan(args: argparse.Namespace, console: Console) -> int:
    from footfall.biped.maps import dissertation_map, load_map
    from footfall.biped.planner import plan_walk
    from footfall.plots import plot_plan

    if args.cloud is not None:
        from footfall.biped.maps import PlanMap

        if args.goal is None:
            raise FootfallError("planning on a point cloud needs --goal X Y")
        detection = _detect(args)
        start = (0.0, 0.0) if args.start is None else tuple(args.start)
        plan_map = PlanMap(args.cloud.stem, start, tuple(args.goal), tuple(detection.circles))
    else:
        plan_map = load_map(args.map) if args.map is not None else dissertation_map(args.case)
        plan_map = plan_map.with_endpoints(args.start, args.goal)
    plan = plan_walk(plan_map)
    out: Path = args.out
    out.mkdir(parents=True, exist_ok=True)
    (out / "plan.json").write_text(json.dumps(plan.to_json(), indent=2) + "\n")
    plot_plan(plan, out / "plan.png")
    console.print(
        f"{plan_map.name}: path {plan.path.length:.2f} m, "
        f"{len(plan.path.waypoints) - 2} waypoints, "
        f"{len(plan.footsteps.positions)} footsteps, planned in {plan.plan_ms:.2f} ms, "
        f"{plan.collisions} collisions"
    )
    console.print(f"Wrote {out / 'plan.json'} and {out / 'plan.png'}")
    return 0


def _cloud_options(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--frame",
        choices=("camera", "map"),
        default="camera",
        help="frame the cloud's points are in",
    )
    p.add_argument(
        "--ground",
        choices=("plane", "ransac", "cone"),
        default="plane",
        help="ground removal: known plane z = 0, RANSAC's dominant plane, or inverted cones",
    )
    p.add_argument(
        "--camera-height", type=float, default=0.0, help="camera height above the ground in m"
    )
    p.add_argument(
        "--cluster-tolerance", type=float, default=0.30, help="Euclidean clustering radius in m"
    )
    p.add_argument("--min-cluster-size", type=int, default=5, help="smallest obstacle in points")


def _detect(args: argparse.Namespace):
    from footfall.biped.obstacles import DetectionConfig, detect_obstacles
    from footfall.io.clouds import read_points

    points = read_points(args.cloud)
    config = DetectionConfig(
        ground=args.ground,
        cluster_tolerance=args.cluster_tolerance,
        min_cluster_size=args.min_cluster_size,
    )
    return detect_obstacles(
        points, args.frame, config, camera_in_base=(0.0, 0.0, args.camera_height)
    )


def _obstacles_parser(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "obstacles",
        help="detect obstacles in a point cloud",
        description=(
            "Detect obstacles in a point cloud (dissertation §6.3.1): pass-through filter, ground "
            "removal, Euclidean clustering, principal-axes boxes and circles. Writes "
            "obstacles.json and obstacles.png (top view) to --out."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    p.add_argument("--cloud", type=Path, required=True, help="point cloud file (.pcd, .ply, .npy)")
    _cloud_options(p)
    p.add_argument("--out", type=Path, default=Path("footfall-out/obstacles"), help="output folder")
    p.set_defaults(handler=_obstacles)


def _obstacles(args: argparse.Namespace, console: Console) -> int:
    from footfall.plots import plot_obstacles

    detection = _detect(args)
    out: Path = args.out
    out.mkdir(parents=True, exist_ok=True)
    clusters = [
        {
            "centroid": c.centroid.tolist(),
            "box": {
                "x": float(c.centre[0]),
                "y": float(c.centre[1]),
                "width": c.width,
                "depth": c.depth,
                "height": c.height,
                "yaw_rad": c.yaw,
            },
            "points": c.points,
            "circles": [{"x": k.x, "y": k.y, "r": k.r} for k in c.circles],
        }
        for c in detection.clusters
    ]
    summary = {
        "cloud": str(args.cloud),
        "frame": args.frame,
        "ground": args.ground,
        "points": len(detection.points_in_map),
        "obstacle_points": int(detection.obstacle_mask.sum()),
        "clusters": clusters,
    }
    (out / "obstacles.json").write_text(json.dumps(summary, indent=2) + "\n")
    plot_obstacles(detection, out / "obstacles.png")
    console.print(f"{len(clusters)} obstacles from {len(detection.points_in_map)} points")
    console.print(f"Wrote {out / 'obstacles.json'} and {out / 'obstacles.png'}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    """The ``footfall`` argument parser."""
    parser = argparse.ArgumentParser(
        prog="footfall",
        description="Legged robots walking over uneven terrain, simulated and recorded.",
    )
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    _walk_parser(subparsers)
    _map_parser(subparsers)
    _convert_parser(subparsers)
    _bench_parser(subparsers)
    _plan_parser(subparsers)
    _obstacles_parser(subparsers)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of the ``footfall`` console script."""
    args = build_parser().parse_args(argv)
    console = Console()
    try:
        return args.handler(args, console)
    except FootfallError as exc:
        console.print(f"[red]error:[/] {exc}")
        return 2


if __name__ == "__main__":
    sys.exit(main())
