"""Figures of the biped.

Its plans, the obstacles found in a cloud, and a walk in MuJoCo (top view, COM and ZMP
against the support, joints).
"""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

from footfall.biped.body import JOINTS, SIDES
from footfall.plots import save_figure


def add_rectangle(ax, centre, heading: float, length: float, width: float, **style) -> None:
    """A rectangle centred at ``centre`` [m], its length along ``heading`` [rad]."""
    from matplotlib.patches import Rectangle

    c, s = np.cos(heading), np.sin(heading)
    corner = np.asarray(centre) - np.array([[c, -s], [s, c]]) @ [0.5 * length, 0.5 * width]
    ax.add_patch(Rectangle(tuple(corner), length, width, angle=float(np.degrees(heading)), **style))


def plot_plan(plan, path: Path, title: str = "") -> Path:
    """Top view of a biped plan in the dissertation's colours.

    Obstacles red with their inflated outline, path blue, footsteps green, the COM black.

    Args:
        plan: A :class:`footfall.biped.planner.WalkPlan`.
        path: Output PNG.
        title: Figure title.
    """
    from matplotlib.patches import Circle as CirclePatch

    from footfall.biped.planner import FOOT_LENGTH, FOOT_WIDTH

    m = plan.map
    fig, ax = plt.subplots(figsize=(8, 8), constrained_layout=True)
    for c, grown in zip(m.obstacles, m.inflated, strict=True):
        ax.add_patch(CirclePatch((c.x, c.y), c.r, color="red", alpha=0.6))
        ax.add_patch(
            CirclePatch((grown.x, grown.y), grown.r, fill=False, ls="--", color="red", lw=0.8)
        )
    for p, h in zip(plan.footsteps.positions, plan.footsteps.headings, strict=True):
        add_rectangle(ax, p, h, FOOT_LENGTH, FOOT_WIDTH, fill=False, color="green", lw=1.0)
    w = plan.path.waypoints
    ax.plot(
        w[:, 0], w[:, 1], "-o", color="blue", ms=4, lw=1.5, label=f"path {plan.path.length:.2f} m"
    )
    ax.plot(
        plan.pattern.com[:, 0],
        plan.pattern.com[:, 1],
        color="black",
        lw=0.8,
        label="centre of mass",
    )
    ax.plot(*m.start, "s", color="blue", ms=8, label="start")
    ax.plot(*m.goal, "*", color="blue", ms=12, label="goal")
    ax.plot([], [], color="green", label="footsteps")
    ax.plot([], [], color="red", alpha=0.6, lw=6, label="obstacles (dashed: inflated)")
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.grid(alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    ax.set_title(
        title
        or f"{m.name}: {len(plan.footsteps.positions)} footsteps, planned in {plan.plan_ms:.1f} ms"
    )
    return save_figure(fig, path)


def plot_obstacles(detection, path: Path) -> Path:
    """Top view of a detection.

    Ground points grey, obstacle points blue, each cluster's circles in red.

    Args:
        detection: A :class:`footfall.biped.obstacles.Detection`.
        path: Output PNG.
    """
    from matplotlib.patches import Circle as CirclePatch

    p = detection.points_in_map
    step = max(1, len(p) // 60000)
    fig, ax = plt.subplots(figsize=(8, 8), constrained_layout=True)
    ground = p[~detection.obstacle_mask][::step]
    ax.scatter(ground[:, 0], ground[:, 1], s=0.3, color="0.75", label="ground / removed")
    obstacle = p[detection.obstacle_mask][::step]
    ax.scatter(obstacle[:, 0], obstacle[:, 1], s=0.3, color="tab:blue", label="obstacle points")
    for cluster in detection.clusters:
        for c in cluster.circles:
            ax.add_patch(CirclePatch((c.x, c.y), c.r, fill=False, color="red", lw=1.2))
        ax.plot(*cluster.centroid[:2], "+", color="red")
    ax.plot([], [], color="red", label=f"{len(detection.clusters)} obstacles (circles)")
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.grid(alpha=0.3)
    ax.legend(loc="best", fontsize=8, markerscale=10)
    ax.set_title("obstacles seen from above")
    return save_figure(fig, path)


def plot_biped_top(walk, path: Path) -> Path:
    """Obstacles red, path blue, planned footsteps green, actual feet black."""
    from matplotlib.patches import Circle as CirclePatch

    fig, ax = plt.subplots(figsize=(9, 7), constrained_layout=True)
    for o in walk.obstacles:
        if o.kind == "cylinder":
            ax.add_patch(CirclePatch((o.x, o.y), 0.5 * o.size_x, color="red", alpha=0.6))
        else:
            add_rectangle(ax, (o.x, o.y), o.yaw, o.size_x, o.size_y, color="red", alpha=0.6)
    seen = walk.segments[-1].seen if walk.segments else ()  # a room's detected circles
    for c in seen:
        ax.add_patch(CirclePatch((c.x, c.y), c.r, fill=False, ls="--", color="red", lw=0.8))
    size = (walk.spec.foot_length, walk.spec.foot_width)
    for k, seg in enumerate(walk.segments):
        w = seg.plan.path.waypoints
        if seg.stretch is None:
            ax.plot(w[:, 0], w[:, 1], "-", color="blue", lw=1.2, label="path" if k == 0 else None)
        else:  # a room: the stretch walked, and the rest of that look's plan
            label = "path (dotted: the rest of each look's plan)" if k == 0 else None
            ax.plot(*seg.stretch.T, "-", color="blue", lw=1.2, label=label)
            ax.plot(w[:, 0], w[:, 1], ":", color="blue", lw=0.6)
        f = seg.plan.footsteps
        for p, h in zip(f.positions, f.headings, strict=True):
            add_rectangle(ax, p, h, *size, fill=False, color="green", lw=0.9)
        for p, h in zip(
            seg.run.actual_footholds, f.headings[1 : 1 + len(seg.run.actual_footholds)], strict=True
        ):
            add_rectangle(ax, p, h, *size, fill=False, color="black", lw=0.7)
        com = np.asarray(seg.run.log.com)
        ax.plot(com[:, 0], com[:, 1], color="grey", lw=0.6, label="COM" if k == 0 else None)
    ax.plot(*walk.plan_map.start, "s", color="blue", ms=8, label="start")
    ax.plot(*walk.plan_map.goal, "*", color="blue", ms=12, label="goal")
    ax.plot([], [], color="green", label="planned footsteps")
    ax.plot([], [], color="black", label="actual feet")
    ax.plot([], [], color="red", alpha=0.6, lw=6, label="obstacles")
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.grid(alpha=0.3)
    # beside the axes: inside, a long straight walk leaves it no free corner
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0, fontsize=8)
    state = "reached the goal" if walk.reached_goal else ("fell" if walk.fell else "stopped")
    ax.set_title(f"{walk.name}: {state}, {walk.collisions} collisions")
    return save_figure(fig, path)


def _concat(walk, key: str):
    t0, out_t, out = 0.0, [], []
    for seg in walk.segments:
        a = seg.run.log.arrays()
        out_t.append(a["time"] + t0)
        out.append(a[key])
        t0 += seg.run.sim_seconds
    if not out:
        return np.zeros(0), np.zeros((0, 2))
    return np.concatenate(out_t), np.concatenate(out)


def plot_biped_balance(walk, path: Path) -> Path:
    """COM and ZMP (measured and planned) in x and y over time inside the support's extent."""
    fig, axes = plt.subplots(3, 1, figsize=(10, 8), sharex=True, constrained_layout=True)
    t, com = _concat(walk, "com")
    _, zmp = _concat(walk, "zmp")
    _, ref = _concat(walk, "zmp_ref")
    _, margin = _concat(walk, "zmp_margin")
    lo, hi = [], []
    for seg in walk.segments:
        for hull in seg.run.log.support_polygon:
            lo.append(hull.min(axis=0) if hull is not None else (np.nan, np.nan))
            hi.append(hull.max(axis=0) if hull is not None else (np.nan, np.nan))
    lo, hi = np.array(lo).reshape(-1, 2), np.array(hi).reshape(-1, 2)
    for axis, ax in enumerate(axes[:2]):
        if len(t):
            ax.fill_between(t, lo[:, axis], hi[:, axis], color="green", alpha=0.2, label="support")
            ax.plot(t, com[:, axis], color="black", lw=1.0, label="COM")
            ax.plot(t, zmp[:, axis], color="red", lw=0.6, label="ZMP measured")
            ax.plot(t, ref[:, axis], color="blue", lw=0.8, ls="--", label="ZMP planned")
        ax.set_ylabel(f"{'xy'[axis]} [m]")
        ax.grid(alpha=0.3)
        ax.legend(loc="upper left", fontsize=7)
    axes[2].plot(t, 100 * margin, color="purple", lw=0.8)
    axes[2].axhline(0.0, color="red", lw=0.8)
    axes[2].set_ylabel("ZMP margin [cm]")
    axes[2].set_xlabel("time [s]")
    axes[2].grid(alpha=0.3)
    axes[0].set_title(f"{walk.name}: centre of mass and ZMP against the support polygon")
    return save_figure(fig, path)


def plot_biped_joints(walk, path: Path) -> Path:
    """The twelve joint angles over time, measured."""
    fig, axes = plt.subplots(2, 1, figsize=(10, 7), sharex=True, constrained_layout=True)
    t, q = _concat(walk, "joints")
    for k, side in enumerate(SIDES):
        for j, name in enumerate(JOINTS):
            if len(t):
                axes[k].plot(t, np.degrees(q[:, 6 * k + j]), lw=0.8, label=name)
        axes[k].set_ylabel(f"{side} [deg]")
        axes[k].grid(alpha=0.3)
        axes[k].legend(loc="upper right", fontsize=7, ncol=3)
    axes[1].set_xlabel("time [s]")
    axes[0].set_title(f"{walk.name}: joint angles")
    return save_figure(fig, path)
