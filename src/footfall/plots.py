"""Figures of a walk, in the style of the hexapod thesis (Fig. 8.2), and of the benchmarks.

The matplotlib backend is set here, for every figure the CLI writes (the biped's are in
:mod:`footfall.plots_biped`).
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only; never needs a display

import matplotlib.pyplot as plt
import numpy as np

from footfall.control_loop import WalkLog
from footfall.metrics import GroundHeight, flat_ground


def save_figure(fig, path: Path) -> Path:
    """Write a figure as a PNG (creating its folder) and release it."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def plot_walk(
    log: WalkLog,
    path: Path,
    leg: int = 0,
    leg_name: str = "LF",
    ground: GroundHeight = flat_ground,
    title: str = "",
) -> Path:
    """Body height, roll and pitch, and one foot's height over time and side view, as a PNG.

    Args:
        log: The record of the walk.
        path: Output file.
        leg: Index of the leg whose foot is drawn.
        leg_name: Its name, for the legend.
        ground: Ground height, to plot the body height above it.
        title: Figure title.

    Returns:
        The path written.
    """
    t = log.array("time")
    body = log.array("body_position_in_world")
    height = body[:, 2] - ground(body[:, 0], body[:, 1])
    feet = log.array("feet_in_world")[:, leg]

    commanded_feet = log.array("feet_commanded_in_world")[:, leg]

    fig, axes = plt.subplots(4, 1, figsize=(9, 11), constrained_layout=True)
    ax = axes[0]
    ax.plot(t, 100 * body[:, 2], label="body z, measured")
    ax.plot(
        t, 100 * log.array("reference_body_z"), "--", label="body z, reference (floor + height)"
    )
    ax.plot(t, 100 * (body[:, 2] - height), color="0.5", lw=1, label="ground under the body")
    ax.set_ylabel("height in the world [cm]")
    ax.set_xlabel("time [s]")
    ax.legend(loc="lower right")
    ax.grid(alpha=0.3)

    ax = axes[1]
    ax.plot(t, np.degrees(log.array("roll")), label="roll")
    ax.plot(t, np.degrees(log.array("pitch")), label="pitch")
    ax.set_ylabel("body tilt [deg]")
    ax.set_xlabel("time [s]")
    ax.legend(loc="lower right")
    ax.grid(alpha=0.3)

    ax = axes[2]
    ax.plot(t, 100 * feet[:, 2], label=f"{leg_name} foot z, measured")
    ax.plot(t, 100 * commanded_feet[:, 2], ":", color="gray", label=f"{leg_name} foot z, commanded")
    ax.set_ylabel("foot height [cm]")
    ax.set_xlabel("time [s]")
    ax.legend(loc="upper right")
    ax.grid(alpha=0.3)

    ax = axes[3]
    ax.plot(100 * feet[:, 0], 100 * feet[:, 2], label=f"{leg_name} foot, measured")
    ax.plot(
        100 * commanded_feet[:, 0],
        100 * commanded_feet[:, 2],
        ":",
        color="gray",
        label=f"{leg_name} foot, commanded",
    )
    ax.set_xlabel("foot x in the world [cm]")
    ax.set_ylabel("foot z [cm]")
    ax.set_aspect("equal", adjustable="datalim")
    ax.legend(loc="upper right")
    ax.grid(alpha=0.3)
    if title:
        fig.suptitle(title)
    return save_figure(fig, path)


def _map_axes(
    ax,
    known: np.ndarray,
    origin: tuple[float, float],
    resolution: float,
    path_xy: np.ndarray | None,
) -> list[float]:
    """Label the axes, and zoom on the known cells and the path (with a margin)."""
    x0, y0 = origin
    size = known.shape[0]
    extent = [x0, x0 + size * resolution, y0, y0 + size * resolution]
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_aspect("equal")
    cells = np.argwhere(known)
    if cells.size:
        lo = np.asarray(origin) + cells.min(axis=0) * resolution
        hi = np.asarray(origin) + (cells.max(axis=0) + 1) * resolution
        if path_xy is not None and len(path_xy):
            lo, hi = np.minimum(lo, path_xy.min(axis=0)), np.maximum(hi, path_xy.max(axis=0))
        margin = 0.15
        ax.set_xlim(max(extent[0], lo[0] - margin), min(extent[1], hi[0] + margin))
        ax.set_ylim(max(extent[2], lo[1] - margin), min(extent[3], hi[1] + margin))
    return extent


def _grid(ax, values: np.ndarray, extent: list[float], **style):
    """Draw a map grid (index ``[i, j]`` along x and y) with unknown (NaN) cells left blank."""
    return ax.imshow(
        np.ma.masked_invalid(values.T),
        origin="lower",
        extent=extent,
        interpolation="nearest",
        **style,
    )


def _invalid_overlay(
    ax, score: np.ndarray, valid: np.ndarray, extent: list[float], alpha: float
) -> None:
    """Tint the known cells that are not valid footholds red."""
    _grid(
        ax, np.where(np.isfinite(score) & ~valid, 1.0, np.nan), extent, cmap="autumn", alpha=alpha
    )


def _draw_path(ax, path_xy: np.ndarray | None, label: str) -> None:
    if path_xy is None or len(path_xy) == 0:
        return
    ax.plot(path_xy[:, 0], path_xy[:, 1], color="cyan", lw=1.5, label=label)
    ax.plot(*path_xy[0], "o", color="cyan", ms=5)
    ax.plot(*path_xy[-1], ">", color="cyan", ms=7)
    ax.legend(loc="upper right", fontsize=8)


def plot_height_map(
    heights: np.ndarray,
    origin: tuple[float, float],
    resolution: float,
    path: Path,
    path_xy: np.ndarray | None = None,
    title: str = "height map",
    path_label: str = "robot path",
) -> Path:
    """Top view of a height map [m] with a colour bar; unknown cells grey.

    Args:
        heights: Shape (N, N), index ``[i, j]`` along world x and y [m]; NaN unknown.
        origin: World ``(x, y)`` of the corner of cell ``[0, 0]`` [m].
        resolution: Cell side [m].
        path: Output PNG.
        path_xy: Robot or camera path to draw, shape (n, 2) [m].
        title: Figure title.
        path_label: Legend of the path.
    """
    fig, ax = plt.subplots(figsize=(8, 7), constrained_layout=True)
    extent = _map_axes(ax, np.isfinite(heights), origin, resolution, path_xy)
    ax.set_facecolor("0.75")
    image = _grid(ax, heights, extent, cmap="terrain")
    fig.colorbar(image, ax=ax, label="height [m]", shrink=0.8)
    _draw_path(ax, path_xy, path_label)
    ax.set_title(f"{title} (grey: unknown)")
    return save_figure(fig, path)


def plot_score_map(
    score: np.ndarray,
    valid: np.ndarray,
    origin: tuple[float, float],
    resolution: float,
    threshold: float,
    path: Path,
    path_xy: np.ndarray | None = None,
    title: str = "walkability score",
    path_label: str = "robot path",
) -> Path:
    """Top view of a score map: dark is walkable (thesis Figs. 6.6-6.8), invalid in red.

    Args:
        score: Shape (N, N); NaN unknown.
        valid: Shape (N, N).
        origin: World ``(x, y)`` of the corner of cell ``[0, 0]`` [m].
        resolution: Cell side [m].
        threshold: Score threshold, for the colour bar's range.
        path: Output PNG.
        path_xy: Robot or camera path to draw, shape (n, 2) [m].
        title: Figure title.
        path_label: Legend of the path.
    """
    fig, ax = plt.subplots(figsize=(8, 7), constrained_layout=True)
    extent = _map_axes(ax, np.isfinite(score), origin, resolution, path_xy)
    ax.set_facecolor("0.75")
    image = _grid(ax, score, extent, cmap="gray", vmin=0.0, vmax=2.0 * threshold)
    fig.colorbar(
        image, ax=ax, label=f"score (lower is better; invalid at >= {threshold:g})", shrink=0.8
    )
    _invalid_overlay(ax, score, valid, extent, 0.45)
    _draw_path(ax, path_xy, path_label)
    ax.set_title(f"{title} (red: invalid, grey: unknown)")
    return save_figure(fig, path)


def plot_footholds(
    touchdowns: list,
    score: np.ndarray,
    valid: np.ndarray,
    origin: tuple[float, float],
    resolution: float,
    path: Path,
    path_xy: np.ndarray | None = None,
    title: str = "footholds",
) -> Path:
    """Every touchdown over a score map, like thesis Fig. 6.8: nominal red, chosen green.

    Args:
        touchdowns: :class:`~footfall.messages.Touchdown` records.
        score: Score map, shape (N, N); NaN unknown.
        valid: Validity, shape (N, N).
        origin: World ``(x, y)`` of the corner of cell ``[0, 0]`` [m].
        resolution: Cell side [m].
        path: Output PNG.
        path_xy: Body path, shape (n, 2) [m].
        title: Figure title.
    """
    fig, ax = plt.subplots(figsize=(10, 6), constrained_layout=True)
    extent = _map_axes(ax, np.isfinite(score), origin, resolution, path_xy)
    ax.set_facecolor("0.75")
    _grid(ax, score, extent, cmap="gray", vmin=0.0, vmax=1.0)
    _invalid_overlay(ax, score, valid, extent, 0.35)
    if touchdowns:
        nominal = np.array([t.nominal_in_world[:2] for t in touchdowns])
        chosen = np.array([t.chosen_in_world[:2] for t in touchdowns])
        for a, b in zip(nominal, chosen, strict=True):
            if np.hypot(*(a - b)) > 1e-3:
                ax.plot([a[0], b[0]], [a[1], b[1]], color="yellow", lw=0.8)
        ax.plot(nominal[:, 0], nominal[:, 1], "x", color="red", ms=5, label="nominal foothold")
        ax.plot(
            chosen[:, 0], chosen[:, 1], "o", mfc="none", color="lime", ms=5, label="chosen foothold"
        )
    if path_xy is not None and len(path_xy):
        ax.plot(path_xy[:, 0], path_xy[:, 1], color="cyan", lw=1.2, label="body path")
    ax.legend(loc="upper right", fontsize=8)
    ax.set_title(f"{title} (score: dark is walkable, red invalid, grey unknown)")
    return save_figure(fig, path)


def _difficulty_unit(terrain: str) -> str:
    """The unit of a terrain's difficulty parameter, as the terrain declares it."""
    from footfall.sim.terrains import TERRAINS

    return TERRAINS.get(terrain).difficulty_unit if terrain in TERRAINS else "m"


def plot_terrain_benchmark(bench: dict, path: Path) -> Path:
    """Success rate against difficulty for each mode, one panel a terrain.

    Where the benchmark walked several variants (robots, gaits, settings), each has its
    colour and each mode its line style.
    """
    rows = bench["results"]
    terrains = list(dict.fromkeys(r["terrain"] for r in rows))
    modes = list(dict.fromkeys(r["mode"] for r in rows))
    variants = list(dict.fromkeys(r["variant"] for r in rows))
    lines_of = [(v, m) for v in variants for m in modes]
    several = len(variants) > 1
    columns = min(len(terrains), 4)
    lines = -(-len(terrains) // columns)
    fig, axes = plt.subplots(
        lines, columns, figsize=(4.2 * columns, 3.6 * lines), constrained_layout=True, squeeze=False
    )
    styles = {"planned": "o-", "straight": "^-.", "blind": "s--"}
    for ax in axes.flat[len(terrains) :]:
        ax.axis("off")
    for ax, terrain in zip(axes.flat, terrains, strict=False):
        difficulty = next(r["difficulty"] for r in rows if r["terrain"] == terrain)
        sel_all = [r for r in rows if r["terrain"] == terrain]
        single = len({r["value"] for r in sel_all}) == 1
        for k, (variant, mode) in enumerate(lines_of):
            sel = [r for r in sel_all if r["mode"] == mode and r["variant"] == variant]
            y = [r["successes"] / max(r["runs"], 1) for r in sel]
            falls = sum(r["falls"] for r in sel)
            name = f"{variant} {mode}" if several else mode
            label = f"{name} ({falls} falls)" if falls else name
            color = f"C{variants.index(variant) if several else k}"
            if single:  # one layout: a bar per line
                ax.bar([k], y, width=0.6, color=color, label=label)
            else:
                ax.plot(
                    [r["value"] for r in sel], y, styles.get(mode, "o-"), color=color, label=label
                )
        ax.set_title(terrain)
        if single:
            names = [f"{v} {m}" if several else m for v, m in lines_of]
            ax.set_xticks(range(len(lines_of)), names, rotation=60 if several else 0, fontsize=7)
            value = sel_all[0]["value"]
            ax.set_xlabel("(single layout)" if difficulty == "none" else f"{difficulty} {value:g}")
        else:
            ax.set_xlabel(f"{difficulty} [{_difficulty_unit(terrain)}]")
        ax.set_ylabel("success rate")
        ax.set_ylim(-0.05, 1.05)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7 if several else 8)
    rates = ", ".join(
        f"{mode} {bench[f'{mode}_success_rate']:.0%}"
        for mode in modes
        if f"{mode}_success_rate" in bench
    )
    fig.suptitle(
        f"{bench['seeds']} seeds: {rates} (success: goal, no fall, no invalid foothold; "
        "where no route exists: stood still and said why)"
    )
    return save_figure(fig, path)
