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

DEFAULT_SPEED_MPS = 0.10


def _walk_parser(subparsers: argparse._SubParsersAction) -> None:
    from footfall.sim.walk import TERRAINS

    p = subparsers.add_parser(
        "walk",
        help="simulate the hexapod walking and measure it",
        description=(
            "Simulate the hexapod in MuJoCo walking straight ahead, then write metrics.json "
            "and walk.png (body height, roll and pitch, and one foot's path) to --out."
        ),
        formatter_class=argparse.ArgumentDefaultsHelpFormatter,
    )
    p.add_argument("--terrain", choices=TERRAINS, default="flat", help="terrain to walk on")
    p.add_argument("--seconds", type=float, default=20.0, help="walking time in seconds")
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
        "--seed",
        type=int,
        default=0,
        help="seed for random terrain and sensor noise; runs with the same seed are identical",
    )
    p.add_argument("--out", type=Path, default=Path("footfall-out/walk"), help="output folder")
    p.set_defaults(handler=_walk)


def _walk(args: argparse.Namespace, console: Console) -> int:
    from footfall.plots import plot_walk
    from footfall.sim.walk import WalkSettings, simulate_walk

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
    settings = WalkSettings(
        terrain=args.terrain,
        seconds=args.seconds,
        command=WalkCommand(speed=speed, body_height=height),
        gait=gait,
        control_rate_hz=args.control_rate,
        seed=args.seed,
    )
    console.print(
        f"Walking robot [bold]{spec.name}[/] on [bold]{args.terrain}[/] terrain: "
        f"{args.gait} gait at {speed:.3f} m/s for {args.seconds:g} s"
    )
    with Progress(
        TextColumn("simulating"),
        BarColumn(),
        TextColumn("{task.completed:.1f}/{task.total:.0f} s"),
        TimeRemainingColumn(),
        console=console,
        transient=True,
    ) as progress:
        task = progress.add_task("walk", total=args.seconds)
        result = simulate_walk(spec, settings, on_tick=lambda t: progress.update(task, completed=t))

    out: Path = args.out
    out.mkdir(parents=True, exist_ok=True)
    metrics = dict(result.metrics)
    metrics["mujoco_warnings"] = result.warnings
    (out / "metrics.json").write_text(json.dumps(metrics, indent=2) + "\n")
    plot_walk(
        result.log,
        out / "walk.png",
        leg=0,
        leg_name=spec.leg_names[0],
        title=f"{spec.name}: {args.gait} gait at {speed:.3f} m/s on {args.terrain} terrain",
    )
    _print_summary(console, metrics)
    if metrics["frozen"]:
        console.print(f"[yellow]The robot froze safely:[/] {metrics['frozen_reason']}")
    elif metrics["fell"]:
        console.print("[red]The robot fell.[/]")
    console.print(f"Wrote {out / 'metrics.json'} and {out / 'walk.png'}")
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
        ("real-time factor", "realtime_factor", "{:.1f}x"),
    ]
    for label, key, fmt in rows:
        value = metrics[key]
        text = fmt.format(value) if not (isinstance(value, float) and math.isnan(value)) else "n/a"
        table.add_row(label, text)
    console.print(table)


def build_parser() -> argparse.ArgumentParser:
    """The ``footfall`` argument parser."""
    parser = argparse.ArgumentParser(
        prog="footfall",
        description="Legged robots walking over uneven terrain, simulated and recorded.",
    )
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    _walk_parser(subparsers)
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
